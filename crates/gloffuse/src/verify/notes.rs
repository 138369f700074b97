//! Which notes a verdict carries: each a check of the sweep and its outcome that returns a
//! [`Note`] (data; `crate::report::verify::notes` words it).

use super::verdict::{Note, Row, Sweep, WorstSphere};
use crate::fit::{ColorSpace, preset_for};
use crate::measure::{BlenderVersion, Engine};

/// The notes for a sweep rendered in `engine` of Blender `version`, with the white Diffuse
/// sphere's brightness `lighting` (EEVEE) and the judged `rows`, in a fixed order.
pub fn notes(
    sweep: &Sweep,
    engine: Engine,
    version: BlenderVersion,
    lighting: Option<f64>,
    rows: &[Row],
    samples: u32,
) -> Vec<Note> {
    let lighting = lighting.map(|brightness| Note::Lighting { engine, brightness });
    lighting
        .into_iter()
        .chain(foreign_groups(sweep, engine, version))
        .chain(masking_mismatches(sweep, engine, version))
        .chain(display_referred(sweep, rows))
        .chain(within_noise(rows, samples))
        .collect()
}

/// Failing spheres whose verdict more samples could change, rendered with `samples`.
fn within_noise(rows: &[Row], samples: u32) -> Option<Note> {
    let count = rows.iter().filter(|r| r.within_noise).count();
    (count > 0).then(|| Note::WithinNoise {
        count,
        failing: rows.iter().filter(|r| !r.pass).count(),
        samples,
    })
}

/// The groups are calibrated for another engine than the one rendering.
fn foreign_groups(sweep: &Sweep, engine: Engine, version: BlenderVersion) -> Option<Note> {
    let groups_engine = sweep.coefficients.engine();
    (groups_engine != engine).then(|| Note::ForeignGroups {
        coefficients: sweep.source.to_string(),
        groups_engine,
        engine,
        suggested: preset_for(engine, version),
    })
}

/// Every checked distribution whose linear Cycles curve was fitted for the other masking
/// family than `version`'s (judged in Cycles only: EEVEE renders its own GGX).
fn masking_mismatches(sweep: &Sweep, engine: Engine, version: BlenderVersion) -> Vec<Note> {
    let masking = version.masking();
    sweep
        .coefficients
        .distributions
        .iter()
        .filter(|(d, e)| {
            e.masking != masking
                && e.engine == Engine::Cycles
                && engine == Engine::Cycles
                && e.color_space == ColorSpace::Linear
                && sweep.distributions.contains(d)
        })
        .map(|(&distribution, e)| Note::MaskingMismatch {
            distribution,
            fitted: e.masking,
            blender: version,
            masking,
            suggested: preset_for(engine, version),
        })
        .collect()
}

/// Display-referred coefficients: the worst failing sphere on each side of 100 % (the
/// display-referred curve over-corrects some roughness values and under-corrects others).
fn display_referred(sweep: &Sweep, rows: &[Row]) -> Option<Note> {
    let c = sweep.coefficients;
    if !c
        .distributions
        .values()
        .any(|e| e.color_space == ColorSpace::Display)
    {
        return None;
    }
    let worst = |under: bool| {
        let failing = rows
            .iter()
            .filter(|r| !r.pass && (r.brightness < 1.0) == under);
        let count = failing.clone().count();
        let w = failing.max_by(|a, b| {
            (a.brightness - 1.0)
                .abs()
                .total_cmp(&(b.brightness - 1.0).abs())
        })?;
        Some(WorstSphere {
            count,
            distribution: w.distribution,
            roughness: w.roughness,
            brightness: w.brightness,
            gain: c.distributions[&w.distribution]
                .curve
                .gain(w.roughness.get()),
            needed_gain: 1.0 / w.predicted_uncorrected?,
        })
    };
    Some(Note::DisplayReferred {
        coefficients: sweep.source.to_string(),
        under: worst(true),
        over: worst(false),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fit::Coefficients;
    use crate::generate::{ColorModel, Mode};
    use crate::measure::{Distribution, Masking, Roughness};
    use crate::verify::plan::Block;
    use crate::verify::stats::SphereStats;

    fn version(v: &str) -> BlenderVersion {
        v.parse().unwrap()
    }

    /// The preset `name`'s coefficients, loaded once per test.
    fn preset(name: &'static str) -> (Coefficients, &'static str) {
        (Coefficients::load(name).unwrap(), name)
    }

    fn sweep<'a>(
        (c, source): &'a (Coefficients, &'static str),
        ds: &'a [Distribution],
        blocks: &'a [Block],
    ) -> Sweep<'a> {
        Sweep {
            coefficients: c,
            source,
            distributions: ds,
            roughness: &[],
            blocks,
            mode: if blocks.is_empty() {
                Mode::Roughness
            } else {
                Mode::Layered
            },
            color: [1.0; 3],
            color_model: ColorModel::Exact,
        }
    }

    fn row(d: Distribution, r: f64, brightness: f64, pass: bool) -> Row {
        let stats = SphereStats {
            mean: brightness,
            mean_rgb: [brightness; 3],
            standard_error: 0.0,
            center: brightness,
            coverage: 0.6,
            opacity: 1.0,
            rim: brightness,
            rings: vec![],
        };
        Row {
            id: 0,
            distribution: d,
            roughness: Roughness::new(r).unwrap(),
            block: None,
            uncorrected: stats.clone(),
            corrected: stats,
            target: [1.0; 3],
            uncorrected_brightness: 0.5,
            brightness,
            deviation: (brightness - 1.0).abs(),
            predicted_uncorrected: Some(0.5),
            cycles_uncorrected: None,
            predicted_corrected: 1.0,
            ring_targets: vec![],
            worst_ring: 0.0,
            pass,
            within_noise: false,
        }
    }

    /// The failing spheres within their noise are counted, the others not; none, no note.
    #[test]
    fn failing_spheres_within_their_noise_are_noted() {
        let c = preset("blender-4");
        let ds = [Distribution::Ggx];
        let mut rows = vec![
            row(Distribution::Ggx, 0.5, 1.0, true),
            row(Distribution::Ggx, 0.75, 0.97, false),
            row(Distribution::Ggx, 1.0, 0.95, false),
        ];
        let noted = |rows: &[Row]| {
            notes(
                &sweep(&c, &ds, &[]),
                Engine::Cycles,
                version("4.5"),
                None,
                rows,
                256,
            )
        };
        assert_eq!(noted(&rows), []);
        rows[2].within_noise = true;
        assert_eq!(
            noted(&rows),
            [Note::WithinNoise {
                count: 1,
                failing: 2,
                samples: 256
            }]
        );
    }

    #[test]
    fn the_preset_of_this_blender_needs_no_note() {
        let c = preset("blender-4");
        let ds = Distribution::ALL;
        let n = notes(
            &sweep(&c, &ds, &[]),
            Engine::Cycles,
            version("4.5"),
            None,
            &[],
            32,
        );
        assert_eq!(n, []);
    }

    #[test]
    fn another_masking_family_names_the_preset_that_suits() {
        let c = preset("blender-4");
        // Only the distributions checked are noted.
        let ds = [Distribution::Ggx];
        let n = notes(
            &sweep(&c, &ds, &[]),
            Engine::Cycles,
            version("3.4"),
            None,
            &[],
            32,
        );
        assert_eq!(
            n,
            [Note::MaskingMismatch {
                distribution: Distribution::Ggx,
                fitted: Masking::HeightCorrelated,
                blender: version("3.4"),
                masking: Masking::Separable,
                suggested: "blender-3",
            }]
        );
    }

    #[test]
    fn cycles_groups_in_eevee_come_after_the_lighting() {
        let c = preset("blender-4");
        let ds = Distribution::ALL;
        let s = sweep(&c, &ds, &[]);
        let n = notes(&s, Engine::Eevee, version("4.5"), Some(0.992), &[], 1);
        assert_eq!(
            n,
            [
                Note::Lighting {
                    engine: Engine::Eevee,
                    brightness: 0.992
                },
                Note::ForeignGroups {
                    coefficients: "blender-4".into(),
                    groups_engine: Engine::Cycles,
                    engine: Engine::Eevee,
                    suggested: "eevee",
                }
            ]
        );
        assert_eq!(n[1].suggested_preset(), Some("eevee"));
        assert_eq!(n[0].suggested_preset(), None);
    }

    #[test]
    fn display_referred_coefficients_name_the_worst_failure_on_each_side() {
        let c = preset("seed");
        let ds = [Distribution::Ggx];
        let rows = [
            row(Distribution::Ggx, 0.2, 1.02, false),
            row(Distribution::Ggx, 0.4, 1.047, false),
            row(Distribution::Ggx, 0.6, 0.999, true),
            row(Distribution::Ggx, 0.8, 0.9, false),
            row(Distribution::Ggx, 1.0, 0.694, false),
            // Passing spheres are not counted, however far off.
            row(Distribution::Ggx, 0.0, 0.5, true),
        ];
        let n = notes(
            &sweep(&c, &ds, &[]),
            Engine::Cycles,
            version("4.5"),
            None,
            &rows,
            32,
        );
        let [Note::DisplayReferred { under, over, .. }] = &n[..] else {
            panic!("{n:?}");
        };
        let (under, over) = (under.as_ref().unwrap(), over.as_ref().unwrap());
        assert_eq!((under.count, under.roughness.get()), (2, 1.0));
        assert_eq!((over.count, over.roughness.get()), (2, 0.4));
        assert_eq!(under.brightness, 0.694);
        assert_eq!(under.needed_gain, 2.0);
        assert_eq!(
            under.gain,
            c.0.distributions[&Distribution::Ggx].curve.gain(1.0)
        );
        // No failure above 100 %: no over-corrected sphere.
        let n = notes(
            &sweep(&c, &ds, &[]),
            Engine::Cycles,
            version("4.5"),
            None,
            &rows[3..],
            32,
        );
        assert!(matches!(
            &n[..],
            [Note::DisplayReferred {
                over: None,
                under: Some(_),
                ..
            }]
        ));
    }
}
