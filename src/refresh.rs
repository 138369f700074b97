//! `gloffuse refresh`: coefficients measured in the user's own Blender (render plain
//! furnace spheres, fit them, write the file, verify it).

use serde::Serialize;
use std::path::PathBuf;

use crate::Error;
use crate::blender::{Blender, BlenderOptions};
use crate::fit::coefficients::{INTEGRATOR_DEGREE, today};
use crate::fit::{Coefficients, FitSpec, Point, Provenance, Source, Target, Weighting};
use crate::generate::{ColorModel, Curves, GenerateParams, Mode};
use crate::measure::{AlbedoIntegrator, Distribution, Glossy, Roughness};
use crate::output::check_destination;
use crate::progress::Progress;
use crate::verify::{
    Plan, RenderSettings, Rendered, Role, VerifyOptions, VerifyReport, render, verify_with,
};

/// What `refresh` measures and where it writes the result.
#[derive(Clone, Debug, PartialEq)]
pub struct RefreshOptions {
    /// The coefficients file to write (atomically).
    pub out: PathBuf,
    /// Polynomial degree in r.
    pub degree: usize,
    /// How the measurement is rendered (the verify run uses verify's own samples).
    pub render: RenderSettings,
    /// Verify the new coefficients afterwards.
    pub verify: bool,
    pub blender: BlenderOptions,
}

impl Default for RefreshOptions {
    fn default() -> Self {
        RefreshOptions {
            out: PathBuf::from("coefficients.json"),
            degree: INTEGRATOR_DEGREE,
            // 64 spp: twice verify's, so the fit's own noise stays below the check's.
            render: RenderSettings {
                samples: 64,
                ..RenderSettings::default()
            },
            verify: true,
            blender: BlenderOptions::default(),
        }
    }
}

/// Measured and predicted brightness disagreeing by more than this (relative) is a warning.
pub const DISAGREEMENT: f64 = 0.005;

#[derive(Debug, Serialize)]
pub struct Measurement {
    pub distribution: Distribution,
    pub roughness: f64,
    pub measured: f64,
    pub standard_error: f64,
    pub predicted: f64,
}

#[derive(Debug, Serialize)]
pub struct Refreshed {
    pub blender_version: String,
    pub out: String,
    pub measurements: Vec<Measurement>,
    pub warnings: Vec<String>,
    pub coefficients: Coefficients,
    pub verify: Option<VerifyReport>,
}

/// The measurement grid: r = 0.05 … 1 (r = 0 is pinned by the curve's f(0) = 100).
fn grid() -> Vec<f64> {
    (1..=20).map(|i| i as f64 / 20.0).collect()
}

/// Measures, fits, writes `a.out` and (unless `a.verify` is off) verifies it.
pub fn refresh(a: &RefreshOptions, progress: &dyn Progress) -> Result<Refreshed, Error> {
    // The output is checked before Blender is looked for: bad input fails fast.
    check_destination(&a.out)?;
    let blender = a.blender.find(progress)?;
    let rs = grid();
    let plan = Plan::measure(&Distribution::ALL, &rs, a.render);
    // Plain spheres need no groups; the furnace script still builds them from a preset.
    let groups = GenerateParams::new(
        Curves::Presets,
        &[blender.version.masking()],
        &[Mode::Roughness],
        ColorModel::Exact,
    )?;
    let Rendered { stats, .. } = render(
        &blender,
        &plan,
        &groups,
        Mode::Roughness,
        [1.0; 3],
        a.blender.timeout,
        progress,
    )?;

    let integrator = AlbedoIntegrator::default();
    let masking = blender.version.masking();
    let mut measurements = Vec::new();
    let mut warnings = Vec::new();
    for (cell, s) in plan.cells.iter().zip(&stats) {
        let Role::Uncorrected(d) = cell.role else {
            continue;
        };
        let predicted =
            integrator.average_albedo(&Glossy::new(d, masking, Roughness::new(cell.roughness)?));
        if (s.mean / predicted - 1.0).abs() > DISAGREEMENT {
            warnings.push(format!(
                "{} r = {}: Blender {} renders {:.2} %, the integrator predicts {:.2} % ({:+.2} %)",
                d.label(),
                cell.roughness,
                blender.version_string,
                100.0 * s.mean,
                100.0 * predicted,
                100.0 * (s.mean / predicted - 1.0)
            ));
        }
        measurements.push(Measurement {
            distribution: d,
            roughness: cell.roughness,
            measured: s.mean,
            standard_error: s.standard_error,
            predicted,
        });
    }

    let spec = FitSpec {
        degree: a.degree,
        weighting: Weighting::Relative,
        target: Target::Mean,
        masking,
        provenance: Provenance {
            source: Source::Blender,
            blender_version: Some(blender.version_string.clone()),
            samples: Some(format!("{} spp", a.render.samples)),
            resolution: Some(a.render.cell),
            points: 0,
            date: Some(today()),
            note: Some("mean of rendered white furnace spheres (Σ RGB / Σ alpha)".into()),
        },
    };
    let points = Distribution::ALL.map(|d| {
        let points = measurements
            .iter()
            .filter(|m| m.distribution == d)
            .map(|m| Point {
                roughness: m.roughness,
                percent: 100.0 * m.measured,
            })
            .collect();
        (d, points)
    });
    let coefficients = Coefficients::fit(
        format!("measured in Blender {}", blender.version_string),
        format!(
            "Mean brightness of white glossy furnace spheres rendered in Blender {} ({} spp, {} px), fitted by gloffuse refresh; gain = 100 / f(r).",
            blender.version_string, a.render.samples, a.render.cell
        ),
        &spec,
        points,
    )?;
    coefficients.write(&a.out)?;

    let verify = if a.verify {
        Some(verify_new(&blender, a, progress)?)
    } else {
        None
    };
    Ok(Refreshed {
        blender_version: blender.version_string.clone(),
        out: a.out.display().to_string(),
        measurements,
        warnings,
        coefficients,
        verify,
    })
}

/// The verify sweep with the new file, at verify's own defaults and the measurement's
/// resolution, with a different seed so the check sees fresh noise.
fn verify_new(
    blender: &Blender,
    a: &RefreshOptions,
    progress: &dyn Progress,
) -> Result<VerifyReport, Error> {
    let v = VerifyOptions {
        coefficients: Some(a.out.display().to_string()),
        render: RenderSettings {
            cell: a.render.cell,
            seed: 1,
            ..RenderSettings::default()
        },
        blender: a.blender.clone(),
        ..VerifyOptions::default()
    };
    Ok(verify_with(blender, &v, progress)?.report)
}
