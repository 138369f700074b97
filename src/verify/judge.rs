//! Judging a rendered verify sweep, in steps: predict each row (`super::predict`), judge it
//! against its prediction and the thresholds ([`judge_row`]), measure the reference spheres
//! ([`reference`]), then pick the notes (`super::notes`).

use super::notes::notes;
use super::plan::{PlanReference, PlanRow};
use super::predict::{Prediction, Predictor, relative};
use super::render::Rendered;
use super::stats::SphereStats;
use super::verdict::{Judging, MIN_RING_PIXELS, ReferenceSphere, Row, Sweep, VerifyReport};
use crate::generate::Mode;
use crate::measure::{AlbedoIntegrator, BlenderVersion};

/// Judges a rendered verify sweep: every corrected sphere against 100 % (and, in the view
/// modes, ring by ring), next to the integrator's prediction for `version`'s masking, with
/// notes where the coefficients do not suit this Blender.
pub fn judge(
    rendered: &Rendered,
    sweep: &Sweep,
    judging: Judging,
    version: BlenderVersion,
) -> VerifyReport {
    let plan = &rendered.plan;
    let engine = plan.settings.engine;
    let predictor = Predictor {
        integrator: AlbedoIntegrator::default(),
        engine,
        // Cycles groups may be rendered in EEVEE to show what they do there.
        groups_engine: sweep.coefficients.engine(),
        masking: version.masking(),
        mode: sweep.mode,
        color: sweep.color,
        color_model: sweep.color_model,
    };
    let stats = |cell: usize| rendered.stats[cell].clone();
    let rows: Vec<Row> = plan
        .rows
        .iter()
        .map(|slot| {
            let corrected = stats(slot.corrected);
            let rings: Vec<_> = corrected.rings.iter().map(|r| r.mu).collect();
            let curve = &sweep.coefficients.distributions[&slot.distribution].curve;
            let p = predictor.predict(curve, slot.distribution, slot.roughness, slot.ior, &rings);
            judge_row(slot, stats(slot.uncorrected), corrected, p, judging, sweep.mode)
        })
        .collect();
    let reference = plan
        .references
        .iter()
        .map(|r| reference(r, stats(r.cell), &predictor))
        .collect();
    let lighting = plan
        .lighting()
        .map(|cell| relative(rendered.stats[cell].mean_rgb, sweep.color).0);
    VerifyReport {
        coefficients: sweep.source.to_string(),
        engine,
        groups_engine: predictor.groups_engine,
        lighting,
        mode: sweep.mode,
        color: sweep.color,
        color_model: sweep.color_model,
        ring_tolerance_percent: judging.ring_tolerance_percent,
        render: rendered.info.clone(),
        tolerance_percent: judging.tolerance_percent,
        notes: notes(sweep, engine, version, lighting, &rows),
        pass: rows.iter().all(|r| r.pass),
        rows,
        reference,
    }
}

/// One row's verdict: the corrected sphere's mean against its target within the
/// tolerance and, in the per-pixel modes, every ring with enough pixels within the ring
/// tolerance.
pub fn judge_row(
    slot: &PlanRow,
    uncorrected: SphereStats,
    corrected: SphereStats,
    p: Prediction,
    judging: Judging,
    mode: Mode,
) -> Row {
    let (brightness, deviation) = relative(corrected.mean_rgb, p.target);
    let worst_ring = worst_ring(&corrected, &p.ring_targets);
    let rings_flat = !mode.per_pixel() || worst_ring <= judging.ring_tolerance_percent / 100.0;
    Row {
        id: slot.id,
        distribution: slot.distribution,
        roughness: slot.roughness,
        ior: slot.ior,
        uncorrected_brightness: relative(uncorrected.mean_rgb, p.uncorrected_base).0,
        uncorrected,
        corrected,
        target: p.target,
        brightness,
        deviation,
        predicted_uncorrected: p.uncorrected,
        cycles_uncorrected: p.cycles_uncorrected,
        predicted_corrected: p.corrected,
        ring_targets: p.ring_targets,
        worst_ring,
        pass: deviation <= judging.tolerance_percent / 100.0 && rings_flat,
    }
}

/// A reference sphere: its mean relative to what it promises.
pub fn reference(r: &PlanReference, stats: SphereStats, predictor: &Predictor) -> ReferenceSphere {
    let promise = predictor.reference_target(r.roughness, r.ior);
    ReferenceSphere {
        roughness: r.roughness,
        ior: r.ior,
        cell: r.cell,
        brightness: relative(stats.mean_rgb, promise).0,
        stats,
    }
}

/// The largest |ring mean / its target − 1| over the view-cosine rings (with at least
/// [`MIN_RING_PIXELS`] pixels) and channels of a sphere.
fn worst_ring(s: &SphereStats, targets: &[[f64; 3]]) -> f64 {
    s.rings
        .iter()
        .zip(targets)
        .filter(|(r, _)| r.pixels >= MIN_RING_PIXELS)
        .map(|(r, &t)| relative(r.mean_rgb, t).1)
        .fold(0.0, f64::max)
}
