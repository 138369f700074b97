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
            let (uncorrected, corrected) = (stats(slot.uncorrected), stats(slot.corrected));
            let p = predict(&predictor, sweep, slot, &corrected);
            judge_row(slot, uncorrected, corrected, p, judging, sweep.mode)
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
        notes: notes(
            sweep,
            engine,
            version,
            lighting,
            &rows,
            plan.settings.samples,
        ),
        pass: rows.iter().all(|r| r.pass),
        rows,
        reference,
    }
}

/// The prediction for a plan row, ring by ring over the rendered `corrected` sphere's rings.
fn predict(
    predictor: &Predictor,
    sweep: &Sweep,
    slot: &PlanRow,
    corrected: &SphereStats,
) -> Prediction {
    let rings: Vec<_> = corrected.rings.iter().map(|r| r.mu).collect();
    let curve = &sweep.coefficients.distributions[&slot.distribution].curve;
    predictor.predict(curve, slot.distribution, slot.roughness, slot.block, &rings)
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
    let (worst_ring, ring_error) = worst_ring(&corrected, &p.ring_targets);
    let (tolerance, ring_tolerance) = (
        judging.tolerance_percent / 100.0,
        judging.ring_tolerance_percent / 100.0,
    );
    let mean_fails = deviation > tolerance;
    let rings_fail = mode.per_pixel() && worst_ring > ring_tolerance;
    let mean_error = relative_error(corrected.standard_error, p.target);
    // Off by no more than NOISE_ERRORS standard errors beyond the tolerance (NaN: never).
    let within = |off: f64, tolerance: f64, error: f64| off - tolerance <= NOISE_ERRORS * error;
    let within_noise = (mean_fails || rings_fail)
        && (!mean_fails || within(deviation, tolerance, mean_error))
        && (!rings_fail || within(worst_ring, ring_tolerance, ring_error));
    Row {
        id: slot.id,
        distribution: slot.distribution,
        roughness: slot.roughness,
        block: slot.block,
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
        pass: !mean_fails && !rings_fail,
        within_noise,
    }
}

/// A failing sphere whose every failing mean (the sphere's, its worst ring's) is off by no
/// more than this many of its standard errors beyond the tolerance could pass with more
/// samples: its verdict is the noise's as much as the group's.
const NOISE_ERRORS: f64 = 3.0;

/// A reference sphere: its mean relative to what it promises.
pub fn reference(r: &PlanReference, stats: SphereStats, predictor: &Predictor) -> ReferenceSphere {
    let promise = predictor.reference_target(r.roughness, r.block);
    ReferenceSphere {
        roughness: r.roughness,
        block: r.block,
        cell: r.cell,
        brightness: relative(stats.mean_rgb, promise).0,
        stats,
    }
}

/// The largest |ring mean / its target − 1| over the view-cosine rings (with at least
/// [`MIN_RING_PIXELS`] pixels) and channels of a sphere, and that ring's standard error
/// relative to its target.
fn worst_ring(s: &SphereStats, targets: &[[f64; 3]]) -> (f64, f64) {
    s.rings
        .iter()
        .zip(targets)
        .filter(|(r, _)| r.pixels >= MIN_RING_PIXELS)
        .map(|(r, t)| {
            (
                relative(r.mean_rgb, *t).1,
                relative_error(r.standard_error, *t),
            )
        })
        .fold(
            (0.0, f64::NAN),
            |worst, ring| if ring.0 > worst.0 { ring } else { worst },
        )
}

/// A standard error of a channel-averaged mean relative to the channels' average target.
fn relative_error(error: f64, target: [f64; 3]) -> f64 {
    error / (target.iter().sum::<f64>() / 3.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::measure::{Distribution, Roughness};
    use crate::verify::stats::{RINGS, Ring};

    /// A sphere of mean `mean` (every channel) whose rings have `ring_pixels` pixels each
    /// and means `ring_mean`.
    fn sphere(mean: f64, ring_mean: f64, ring_pixels: usize) -> SphereStats {
        SphereStats {
            mean,
            mean_rgb: [mean; 3],
            standard_error: 0.001,
            center: mean,
            coverage: 0.6,
            opacity: 1.0,
            rim: mean,
            rings: (0..RINGS)
                .map(|k| Ring {
                    mu: (k as f64 / RINGS as f64, (k + 1) as f64 / RINGS as f64),
                    pixels: ring_pixels,
                    mean: ring_mean,
                    standard_error: 0.001,
                    mean_rgb: [ring_mean; 3],
                })
                .collect(),
        }
    }

    fn prediction() -> Prediction {
        Prediction {
            target: [1.0; 3],
            ring_targets: vec![[1.0; 3]; RINGS],
            uncorrected_base: [1.0; 3],
            uncorrected: Some(0.5),
            corrected: 1.0,
            cycles_uncorrected: None,
        }
    }

    fn slot() -> PlanRow {
        PlanRow {
            id: 7,
            distribution: Distribution::Ggx,
            roughness: Roughness::new(0.5).unwrap(),
            block: None,
            uncorrected: 3,
            corrected: 4,
        }
    }

    /// Thresholds of 50 % and 25 %: exact in binary, so the boundary is exact.
    const JUDGING: Judging = Judging {
        tolerance_percent: 50.0,
        ring_tolerance_percent: 25.0,
    };

    fn row(mean: f64, ring_mean: f64, ring_pixels: usize, mode: Mode) -> Row {
        let (u, c) = (sphere(0.5, 0.5, 500), sphere(mean, ring_mean, ring_pixels));
        judge_row(&slot(), u, c, prediction(), JUDGING, mode)
    }

    /// A failing sphere is within its noise when each failing mean is off by no more than
    /// three standard errors beyond its tolerance (here 50 % and, in the view modes, 25 %).
    #[test]
    fn a_failure_within_three_standard_errors_is_within_noise() {
        let judged = |mean: f64, ring_mean: f64, error: f64, mode: Mode| {
            let mut c = sphere(mean, ring_mean, 500);
            c.standard_error = error;
            for ring in &mut c.rings {
                ring.standard_error = error;
            }
            judge_row(
                &slot(),
                sphere(0.5, 0.5, 500),
                c,
                prediction(),
                JUDGING,
                mode,
            )
        };
        // The mean 0.6 beyond the tolerance: within 3 × 0.25, not 3 × 0.1.
        assert!(judged(2.1, 1.0, 0.25, Mode::Roughness).within_noise);
        assert!(!judged(2.1, 1.0, 0.1, Mode::Roughness).within_noise);
        // A ring 0.15 beyond: within 3 × 0.06, not 3 × 0.04 (the mean passes).
        assert!(judged(1.0, 1.4, 0.06, Mode::View).within_noise);
        assert!(!judged(1.0, 1.4, 0.04, Mode::View).within_noise);
        // Both fail: both must be within.
        assert!(!judged(2.6, 1.4, 0.06, Mode::View).within_noise);
        // A pass is never within noise; an unknown error never.
        assert!(!judged(1.0, 1.0, 1.0, Mode::View).within_noise);
        assert!(!judged(2.1, 1.0, f64::NAN, Mode::Roughness).within_noise);
    }

    #[test]
    fn a_mean_on_the_tolerance_passes_and_beyond_fails() {
        let on = row(1.5, 1.0, 500, Mode::Roughness);
        assert_eq!((on.deviation, on.brightness), (0.5, 1.5));
        assert!(on.pass);
        assert!(row(0.5, 1.0, 500, Mode::Roughness).pass);
        assert!(!row(1.5000001, 1.0, 500, Mode::Roughness).pass);
        assert!(!row(0.4999999, 1.0, 500, Mode::Roughness).pass);
    }

    #[test]
    fn rings_are_judged_in_the_per_pixel_modes_only() {
        // Rings 30 % off: the roughness mode shows but does not judge them.
        let roughness = row(1.0, 1.3, 500, Mode::Roughness);
        assert!((roughness.worst_ring - 0.3).abs() < 1e-12);
        assert!(roughness.pass);
        assert!(!row(1.0, 1.3, 500, Mode::View).pass);
        assert!(row(1.0, 1.25, 500, Mode::View).pass);
        // Too few pixels to judge a ring by.
        let sparse = row(1.0, 1.3, MIN_RING_PIXELS - 1, Mode::View);
        assert_eq!(sparse.worst_ring, 0.0);
        assert!(sparse.pass);
    }

    #[test]
    fn a_row_carries_its_plan_row() {
        let r = row(1.0, 1.0, 500, Mode::Roughness);
        assert_eq!(r.id, 7);
        assert_eq!(r.roughness, Roughness::new(0.5).unwrap());
        assert_eq!(r.uncorrected_brightness, 0.5);
        assert_eq!(r.predicted_uncorrected, Some(0.5));
    }
}
