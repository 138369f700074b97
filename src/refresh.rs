//! `gloffuse refresh`: coefficients measured in the user's own Blender, and `gloffuse bench`.

use serde::Serialize;
use std::time::Instant;

use crate::Error;
use crate::blender::Blender;
use crate::blender::script::{GenerateParams, Mode};
use crate::cli::{BenchArgs, RefreshArgs, VerifyArgs};
use crate::coefficients::{self, Coefficients, ColorSpace, Entry, Provenance, Target};
use crate::fit::{Point, Variable, Weighting, fit_polynomial};
use crate::furnace::plan::{Plan, RenderSettings};
use crate::furnace::report::VerifyReport;
use crate::generate::blender_from;
use crate::microfacet::{AlbedoIntegrator, Distribution, Glossy, Roughness};
use crate::output::{check_destination, write_atomic};
use crate::verify::{Rendered, render, verify_with};

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

pub fn refresh(a: &RefreshArgs) -> Result<Refreshed, Error> {
    // The output is checked before Blender is looked for: bad input fails fast.
    check_destination(&a.out)?;
    let blender = blender_from(&a.blender, a.json)?;
    let rs = grid();
    let settings = RenderSettings {
        cell: a.resolution,
        samples: a.spp,
        ..RenderSettings::default()
    };
    let plan = Plan::measure(&Distribution::ALL, &rs, settings);
    // Plain spheres need no groups; the furnace script still builds them from a preset.
    let groups = GenerateParams::new(
        &Coefficients::load(blender.version.preset_name())?,
        blender.version.preset_name(),
    );
    let Rendered { stats, .. } = render(
        &blender,
        &plan,
        &groups,
        Mode::Roughness,
        a.blender.timeout,
        a.json,
    )?;

    let integrator = AlbedoIntegrator::default();
    let masking = blender.version.masking();
    let mut measurements = Vec::new();
    let mut warnings = Vec::new();
    for (cell, s) in plan.cells.iter().zip(&stats) {
        let crate::furnace::plan::Role::Uncorrected(d) = cell.role else {
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

    let degree = a.degree as usize;
    let mut distributions = std::collections::BTreeMap::new();
    for d in Distribution::ALL {
        let points: Vec<Point> = measurements
            .iter()
            .filter(|m| m.distribution == d)
            .map(|m| Point {
                roughness: m.roughness,
                percent: 100.0 * m.measured,
            })
            .collect();
        let fit = fit_polynomial(&points, Variable::Roughness, degree, Weighting::Relative)?;
        distributions.insert(
            d,
            Entry {
                curve: fit.curve,
                degree,
                target: Target::Mean,
                color_space: ColorSpace::Linear,
                masking,
                weighting: Weighting::Relative,
                residuals: fit.residuals,
                provenance: Provenance {
                    source: "blender".into(),
                    blender_version: Some(blender.version_string.clone()),
                    samples: Some(format!("{} spp", a.spp)),
                    resolution: Some(a.resolution),
                    points: points.len(),
                    date: Some(coefficients::today()),
                    note: Some("mean of rendered white furnace spheres (Σ RGB / Σ alpha)".into()),
                },
            },
        );
    }
    let coefficients = Coefficients {
        format: coefficients::FORMAT.into(),
        format_version: coefficients::FORMAT_VERSION,
        name: format!("measured in Blender {}", blender.version_string),
        description: format!(
            "Mean brightness of white glossy furnace spheres rendered in Blender {} ({} spp, {} px), fitted by gloffuse refresh; gain = 100 / f(r).",
            blender.version_string, a.spp, a.resolution
        ),
        distributions,
    };
    let text = coefficients.to_json();
    Coefficients::parse(&text, &a.out.display().to_string())?;
    write_atomic(&a.out, text.as_bytes())?;

    let verify = if a.no_verify {
        None
    } else {
        Some(verify_new(&blender, a)?)
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

fn verify_new(blender: &Blender, a: &RefreshArgs) -> Result<VerifyReport, Error> {
    let v = VerifyArgs {
        coefficients: Some(a.out.display().to_string()),
        distribution: Vec::new(),
        roughness: (0..=10)
            .map(|i| Roughness::new(i as f64 / 10.0))
            .collect::<Result<_, _>>()?,
        spp: 32,
        resolution: a.resolution,
        tolerance: 1.0,
        seed: 1, // not the measurement's seed: the check sees fresh noise
        report: None,
        mode: Mode::Roughness,
        ring_tolerance: 1.5,
        blender: a.blender.clone(),
        json: a.json,
    };
    Ok(verify_with(blender, &v)?.0)
}

/// The measured curve beside the prediction, then the warnings.
pub fn table(r: &Refreshed) -> String {
    use std::fmt::Write as _;
    let mut s = format!(
        "Blender {}: measured furnace sphere means vs the integrator\n",
        r.blender_version
    );
    let _ = writeln!(
        s,
        "{:<18} {:>5} {:>9} {:>7} {:>10} {:>7}",
        "distribution", "r", "measured", "±SE", "predicted", "diff"
    );
    for m in &r.measurements {
        let _ = writeln!(
            s,
            "{:<18} {:>5} {:>8.2}% {:>6.2}% {:>9.2}% {:>+6.2}%",
            m.distribution.label(),
            m.roughness,
            100.0 * m.measured,
            100.0 * m.standard_error,
            100.0 * m.predicted,
            100.0 * (m.measured / m.predicted - 1.0)
        );
    }
    for w in &r.warnings {
        let _ = writeln!(s, "warning: {w}");
    }
    let _ = writeln!(s, "wrote {}", r.out);
    s
}

#[derive(Debug, Serialize)]
pub struct BenchResult {
    pub spheres: usize,
    pub one_process_seconds: f64,
    pub per_sphere_seconds: f64,
    pub ratio: f64,
}

/// Renders the verify sweep once as one Blender process and once as one process per sphere.
pub fn bench(b: &BenchArgs) -> Result<BenchResult, Error> {
    let blender = blender_from(&b.blender, false)?;
    let preset = blender.version.preset_name();
    let groups = GenerateParams::new(&Coefficients::load(preset)?, preset);
    let rs: Vec<f64> = b.roughness.iter().map(|r| r.get()).collect();
    let settings = RenderSettings {
        samples: b.spp,
        ..RenderSettings::default()
    };
    let plan = Plan::verify(&Distribution::ALL, &rs, settings, true);
    let start = Instant::now();
    render(
        &blender,
        &plan,
        &groups,
        Mode::Roughness,
        b.blender.timeout,
        true,
    )?;
    let one = start.elapsed().as_secs_f64();
    eprintln!("one process: {} spheres in {one:.1} s", plan.cells.len());
    let start = Instant::now();
    for (i, cell) in plan.cells.iter().enumerate() {
        let single = Plan {
            cells: vec![cell.clone()],
            columns: 1,
            settings,
        };
        render(
            &blender,
            &single,
            &groups,
            Mode::Roughness,
            b.blender.timeout,
            true,
        )?;
        eprint!("\rone process per sphere: {}/{}", i + 1, plan.cells.len());
    }
    eprintln!();
    let per = start.elapsed().as_secs_f64();
    Ok(BenchResult {
        spheres: plan.cells.len(),
        one_process_seconds: one,
        per_sphere_seconds: per,
        ratio: per / one,
    })
}
