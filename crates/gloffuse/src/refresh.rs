//! `gloffuse refresh`: coefficients measured in the user's own Blender (render plain
//! furnace spheres, fit them, write the file, verify it).

use serde::Serialize;
use std::path::PathBuf;

use crate::Error;
use crate::blender::{Blender, BlenderOptions};
use crate::fit::coefficients::{INTEGRATOR_DEGREE, today};
use crate::fit::{Coefficients, FitSpec, Point, Provenance, Source, Target, Weighting};
use crate::generate::{ColorModel, Curves, GenerateParams, Mode};
use crate::measure::{AlbedoIntegrator, Distribution, Engine, Roughness};
use crate::output::check_destination;
use crate::progress::Progress;
use crate::verify::stats::SphereStats;
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
    /// The engine to measure (and verify in).
    pub engine: Engine,
    /// Pixels per sphere cell, of the measurement and the verify run.
    pub cell: u32,
    /// Samples per pixel of the measurement (`None`: the engine's, [`measure_samples`]; the
    /// verify run uses verify's own).
    pub samples: Option<u32>,
    /// Verify the new coefficients afterwards.
    pub verify: bool,
    pub blender: BlenderOptions,
}

impl Default for RefreshOptions {
    fn default() -> Self {
        let render = RenderSettings::default();
        RefreshOptions {
            out: PathBuf::from("coefficients.json"),
            degree: INTEGRATOR_DEGREE,
            engine: render.engine,
            cell: render.cell,
            samples: None,
            verify: true,
            blender: BlenderOptions::default(),
        }
    }
}

impl RefreshOptions {
    /// How the measurement is rendered: the engine's samples unless some are set.
    pub fn render(&self) -> RenderSettings {
        RenderSettings {
            cell: self.cell,
            samples: self.samples.unwrap_or(measure_samples(self.engine)),
            ..RenderSettings::for_engine(self.engine)
        }
    }
}

/// Samples per pixel of the measurement: Cycles 64, twice verify's, so the fit's own noise
/// stays below the check's; EEVEE's furnace has no noise (verify's 1).
pub fn measure_samples(engine: Engine) -> u32 {
    match engine {
        Engine::Cycles => 64,
        Engine::Eevee => crate::verify::spec(Mode::Roughness).eevee.samples,
    }
}

/// Measured and predicted brightness disagreeing by more than this (relative) is a warning.
pub const DISAGREEMENT: f64 = 0.005;

#[derive(Debug, Serialize)]
pub struct Measurement {
    pub distribution: Distribution,
    pub roughness: Roughness,
    /// The sphere's mean, relative to the white Diffuse sphere in EEVEE.
    pub measured: f64,
    pub standard_error: f64,
    pub predicted: f64,
}

#[derive(Debug, Serialize)]
pub struct Refreshed {
    pub blender_version: String,
    pub engine: Engine,
    /// EEVEE: the white Diffuse sphere's mean, which every measurement is divided by.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lighting: Option<f64>,
    pub out: String,
    pub measurements: Vec<Measurement>,
    pub warnings: Vec<String>,
    pub coefficients: Coefficients,
    pub verify: Option<VerifyReport>,
}

/// The measurement grid: r = 0.05 … 1 (r = 0 is pinned by the curve's f(0) = 100).
fn grid() -> Vec<Roughness> {
    (1..=20)
        .map(|i| Roughness::new(i as f64 / 20.0).expect("in [0, 1]"))
        .collect()
}

/// Measures, fits, writes `a.out` and (unless `a.verify` is off) verifies it.
pub fn refresh(a: &RefreshOptions, progress: &dyn Progress) -> Result<Refreshed, Error> {
    // The output is checked before Blender is looked for: bad input fails fast.
    check_destination(&a.out)?;
    let engine = a.engine;
    let blender = a.blender.find(progress)?;
    let plan = Plan::measure(&Distribution::ALL, &grid(), a.render());
    let stats = render_plain(&blender, &plan, a, progress)?;
    // EEVEE Next's world lighting is 0.8 % dark for every material: the curve corrects the
    // BSDF's loss, measured against a white Diffuse sphere in the same image.
    let lighting = plan.lighting().map(|cell| stats[cell].mean);
    let (measurements, warnings) = compare(&blender, &plan, &stats, engine, lighting);
    let coefficients = fit_measured(&blender, a, lighting, &measurements)?;
    coefficients.write(&a.out)?;

    let verify = if a.verify {
        Some(verify_new(&blender, a, progress)?)
    } else {
        None
    };
    Ok(Refreshed {
        blender_version: blender.version_string.clone(),
        engine,
        lighting,
        out: a.out.display().to_string(),
        measurements,
        warnings,
        coefficients,
        verify,
    })
}

/// Renders the plain spheres of `plan` and returns their statistics, in plan order.
fn render_plain(
    blender: &Blender,
    plan: &Plan,
    a: &RefreshOptions,
    progress: &dyn Progress,
) -> Result<Vec<SphereStats>, Error> {
    // Plain spheres need no groups; the furnace script still builds them from a preset.
    let groups = GenerateParams::new(
        Curves::Presets(&[Engine::Cycles]),
        &[blender.version.masking()],
        &[Mode::Roughness],
        ColorModel::Exact,
    )?;
    let Rendered { stats, .. } = render(
        blender,
        plan,
        &groups,
        Mode::Roughness,
        [1.0; 3],
        &a.blender,
        progress,
    )?;
    Ok(stats)
}

/// Each uncorrected sphere's mean (divided by `lighting`, if any) beside what the
/// integrator predicts for it, and a warning for each that disagrees by more than
/// [`DISAGREEMENT`].
fn compare(
    blender: &Blender,
    plan: &Plan,
    stats: &[SphereStats],
    engine: Engine,
    lighting: Option<f64>,
) -> (Vec<Measurement>, Vec<String>) {
    let integrator = AlbedoIntegrator::default();
    let masking = blender.version.masking();
    let scale = 1.0 / lighting.unwrap_or(1.0);
    let mut measurements = Vec::new();
    let mut warnings = Vec::new();
    for (cell, s) in plan.cells.iter().zip(stats) {
        let Role::Uncorrected(d) = cell.role else {
            continue;
        };
        let predicted = integrator.average_albedo(&engine.glossy(d, masking, cell.roughness));
        let measured = s.mean * scale;
        if (measured / predicted - 1.0).abs() > DISAGREEMENT {
            warnings.push(format!(
                "{} r = {}: {engine} in Blender {} renders {:.2} %, the integrator predicts {:.2} % ({:+.2} %)",
                d.label(),
                cell.roughness,
                blender.version_string,
                100.0 * measured,
                100.0 * predicted,
                100.0 * (measured / predicted - 1.0)
            ));
        }
        measurements.push(Measurement {
            distribution: d,
            roughness: cell.roughness,
            measured,
            standard_error: s.standard_error * scale,
            predicted,
        });
    }
    (measurements, warnings)
}

/// The coefficients fitted to `measurements`, named and described for where they were
/// measured.
fn fit_measured(
    blender: &Blender,
    a: &RefreshOptions,
    lighting: Option<f64>,
    measurements: &[Measurement],
) -> Result<Coefficients, Error> {
    let engine = a.engine;
    let points = Distribution::ALL.map(|d| {
        let points = measurements
            .iter()
            .filter(|m| m.distribution == d)
            .map(|m| Point {
                roughness: m.roughness.get(),
                percent: 100.0 * m.measured,
            })
            .collect();
        (d, points)
    });
    Coefficients::fit(
        format!("measured in {engine}, Blender {}", blender.version_string),
        format!(
            "Mean brightness of white glossy furnace spheres rendered in {engine}, Blender {} ({} spp, {} px), fitted by gloffuse refresh; gain = 100 / f(r).",
            blender.version_string,
            a.render().samples,
            a.cell
        ),
        &fit_spec(blender, a, lighting),
        points,
    )
}

/// How the measurements are fitted, and where they come from.
fn fit_spec(blender: &Blender, a: &RefreshOptions, lighting: Option<f64>) -> FitSpec {
    let engine = a.engine;
    FitSpec {
        degree: a.degree,
        weighting: Weighting::Relative,
        target: Target::Mean,
        // The masking of the BSDF the engine renders.
        masking: engine.masking(blender.version.masking()),
        engine,
        provenance: Provenance {
            source: Source::Blender,
            blender_version: Some(blender.version_string.clone()),
            samples: Some(format!("{} spp", a.render().samples)),
            resolution: Some(a.cell),
            points: 0,
            date: Some(today()),
            note: Some(match engine {
                Engine::Cycles => "mean of rendered white furnace spheres (Σ RGB / Σ alpha)".into(),
                Engine::Eevee => format!(
                    "mean of white furnace spheres rendered in EEVEE (Σ RGB / Σ alpha), divided by a white Diffuse sphere's ({:.4})",
                    lighting.unwrap_or(1.0)
                ),
            }),
        },
    }
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
        engine: a.engine,
        cell: a.cell,
        seed: 1,
        blender: a.blender.clone(),
        ..VerifyOptions::default()
    };
    Ok(verify_with(blender, &v, progress)?.report)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each engine with nothing set measures at its own samples: Cycles 64, EEVEE 1.
    #[test]
    fn each_engine_with_nothing_set_measures_at_its_samples() {
        for (engine, samples) in [(Engine::Cycles, 64), (Engine::Eevee, 1)] {
            let a = RefreshOptions {
                engine,
                ..RefreshOptions::default()
            };
            let render = a.render();
            assert_eq!(
                (render.engine, render.cell, render.samples, render.seed),
                (engine, 64, samples, 0)
            );
        }
    }
}
