//! The verdict of a verify run, as data: what was rendered, what came out, what was
//! expected, and whether each sphere passes. `crate::report` renders it.

use serde::Serialize;

use super::plan::Role;
use super::render::{RenderInfo, Rendered};
use super::stats::SphereStats;
use crate::Error;
use crate::fit::{Coefficients, ColorSpace, preset_for};
use crate::generate::Mode;
use crate::measure::{AlbedoIntegrator, BlenderVersion, Distribution, Glossy, Roughness};

/// Rings with fewer fully covered pixels than this are too noisy to judge flatness by (at
/// 64 px per sphere, the outermost ring, μ ∈ [0.3, 0.4), holds 72 pixels: at 32 spp its
/// mean scatters by ±2 % in multiscatter mode, while at 512 spp every ring is within 0.3 %).
pub const MIN_RING_PIXELS: usize = 150;

/// The thresholds a corrected sphere is judged by.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Judging {
    /// Allowed |mean − 100 %| of a corrected sphere, in percent.
    pub tolerance_percent: f64,
    /// In the view modes: allowed |ring mean − 100 %| of every view-cosine ring with at
    /// least [`MIN_RING_PIXELS`] pixels, in percent.
    pub ring_tolerance_percent: f64,
}

impl Default for Judging {
    fn default() -> Self {
        Judging {
            // 1 %: five times the largest standard error of a sphere's mean at 32 spp.
            tolerance_percent: 1.0,
            // 1.5 %: a ring holds fewer pixels than a sphere, so it is noisier.
            ring_tolerance_percent: 1.5,
        }
    }
}

/// One distribution at one roughness: the plain Glossy sphere and the corrected one.
#[derive(Clone, Debug, Serialize)]
pub struct Row {
    pub distribution: Distribution,
    pub roughness: f64,
    pub uncorrected: SphereStats,
    pub corrected: SphereStats,
    /// The integrator's E_avg(r) for this Blender's masking (0–1).
    pub predicted_uncorrected: f64,
    /// gain(r) · E_avg(r): what the coefficients should give (0–1).
    pub predicted_corrected: f64,
    /// Largest |ring mean − 1| of the corrected sphere over its view-cosine rings.
    pub worst_ring: f64,
    /// |corrected mean − 1| ≤ tolerance (and, in the view modes, every ring within the ring
    /// tolerance).
    pub pass: bool,
}

/// Blender's Multiscatter GGX at one roughness (the energy-conserving peer).
#[derive(Clone, Debug, Serialize)]
pub struct ReferenceSphere {
    pub roughness: f64,
    pub stats: SphereStats,
}

#[derive(Clone, Debug, Serialize)]
pub struct VerifyReport {
    pub coefficients: String,
    pub mode: Mode,
    /// Allowed |ring mean − 100 %| in the view modes, in percent.
    pub ring_tolerance_percent: f64,
    pub render: RenderInfo,
    /// Allowed |mean − 100 %| of a corrected sphere, in percent.
    pub tolerance_percent: f64,
    pub rows: Vec<Row>,
    pub reference: Vec<ReferenceSphere>,
    /// Explanations for the reader (display-referred coefficients, masking mismatch, …).
    pub notes: Vec<String>,
    pub pass: bool,
}

/// The largest |ring mean − 100 %| over the view-cosine rings of a sphere.
fn worst_ring(s: &SphereStats) -> f64 {
    s.rings
        .iter()
        .filter(|r| r.pixels >= MIN_RING_PIXELS)
        .map(|r| (r.mean - 1.0).abs())
        .fold(0.0, f64::max)
}

/// What a verify sweep checks: the coefficients (and the name they were loaded by), the
/// distributions and roughness values rendered, and the correction mode.
pub struct Sweep<'a> {
    pub coefficients: &'a Coefficients,
    pub source: &'a str,
    pub distributions: &'a [Distribution],
    pub roughness: &'a [f64],
    pub mode: Mode,
}

/// Judges a rendered verify sweep: every corrected sphere against 100 % (and, in the view
/// modes, ring by ring), next to the integrator's prediction for `version`'s masking, with
/// notes where the coefficients do not suit this Blender.
pub fn judge(
    rendered: &Rendered,
    sweep: &Sweep,
    judging: Judging,
    version: BlenderVersion,
) -> Result<VerifyReport, Error> {
    let Sweep {
        coefficients,
        source,
        distributions,
        roughness,
        mode,
    } = *sweep;
    let plan = &rendered.plan;
    let masking = version.masking();
    let integrator = AlbedoIntegrator::default();
    let tolerance = judging.tolerance_percent / 100.0;
    let find = |role: Role, r: f64| {
        plan.cells
            .iter()
            .position(|c| c.role == role && c.roughness == r)
            .map(|i| rendered.stats[i].clone())
            .expect("the plan holds every role at every roughness")
    };
    let mut rows = Vec::new();
    for &d in distributions {
        let curve = &coefficients.distributions[&d].curve;
        for &r in roughness {
            let e_avg = integrator.average_albedo(&Glossy::new(d, masking, Roughness::new(r)?));
            let corrected = find(Role::Corrected(d), r);
            let worst_ring = worst_ring(&corrected);
            let rings_flat =
                mode == Mode::Roughness || worst_ring <= judging.ring_tolerance_percent / 100.0;
            rows.push(Row {
                distribution: d,
                roughness: r,
                uncorrected: find(Role::Uncorrected(d), r),
                pass: (corrected.mean - 1.0).abs() <= tolerance && rings_flat,
                worst_ring,
                corrected,
                predicted_uncorrected: e_avg,
                predicted_corrected: match mode {
                    Mode::Roughness => curve.gain(r) * e_avg,
                    Mode::View | Mode::Multiscatter => 1.0,
                },
            });
        }
    }
    let reference = roughness
        .iter()
        .map(|&r| ReferenceSphere {
            roughness: r,
            stats: find(Role::Reference, r),
        })
        .collect();
    let pass = rows.iter().all(|r| r.pass);
    let mut notes = Vec::new();
    for (d, e) in &coefficients.distributions {
        if e.masking != masking && e.color_space == ColorSpace::Linear && distributions.contains(d)
        {
            notes.push(format!(
                "{}: the coefficients were fitted for {} masking, but Blender {} uses {} masking; use --coefficients {}.",
                d.label(),
                e.masking,
                version,
                masking,
                preset_for(version)
            ));
        }
    }
    if coefficients
        .distributions
        .values()
        .any(|e| e.color_space == ColorSpace::Display)
    {
        let worst = rows.iter().filter(|r| !r.pass).max_by(|a, b| {
            (a.corrected.mean - 1.0)
                .abs()
                .total_cmp(&(b.corrected.mean - 1.0).abs())
        });
        let mut note = format!(
            "The coefficients '{source}' are display-referred: their percentages are sRGB-encoded brightness read off a screen (sRGB(0.305) ≈ 0.59 is GGX's centre at r = 1), but a shader gain acts on linear light, so 100/f(r) under-corrects rough spheres."
        );
        if let Some(w) = worst {
            note.push_str(&format!(
                " Worst: {} r = {} comes out at {:.1} % (gain {:.3}; 1/E_avg = {:.3} is needed).",
                w.distribution.label(),
                w.roughness,
                100.0 * w.corrected.mean,
                coefficients.distributions[&w.distribution]
                    .curve
                    .gain(w.roughness),
                1.0 / w.predicted_uncorrected
            ));
        }
        notes.push(note);
    }
    Ok(VerifyReport {
        coefficients: source.to_string(),
        mode,
        ring_tolerance_percent: judging.ring_tolerance_percent,
        render: rendered.info.clone(),
        tolerance_percent: judging.tolerance_percent,
        rows,
        reference,
        notes,
        pass,
    })
}
