//! The shipped presets: the seed reproduces its published numbers, and the linear presets
//! keep the gain within 0.1 % of 1/E_avg on [0, 1] for their Blender family.
//!
//! Tier: fast (no Blender; `scripts/test.sh --fast` runs it).

use gloffuse::fit::Weighting;
use gloffuse::fit::{Coefficients, Target};
use gloffuse::measure::BlenderVersion;
use gloffuse::measure::{AlbedoIntegrator, Distribution, Engine, Glossy, Masking, Roughness};

#[test]
fn seed_preset_holds_the_hand_made_cubics() {
    let c = Coefficients::load("seed").unwrap();
    let b = &c.distributions[&Distribution::Beckmann].curve;
    assert_eq!(b.numerator, vec![100.0, 0.0, 5.0, -34.0]);
    assert_eq!((b.percent(0.5), b.percent(1.0)), (97.0, 71.0));
    let g = &c.distributions[&Distribution::Ggx].curve;
    assert_eq!((g.percent(0.5), g.percent(1.0)), (85.0, 59.0));
}

#[test]
fn linear_presets_are_within_a_tenth_of_a_percent() {
    let q = AlbedoIntegrator::default();
    // EEVEE renders every distribution as GGX with separable masking: its preset must hold
    // that BSDF's E_avg, whatever the distribution's name.
    for (name, masking, engine) in [
        ("blender-3", Masking::Separable, Engine::Cycles),
        ("blender-4", Masking::HeightCorrelated, Engine::Cycles),
        ("eevee", Masking::Separable, Engine::Eevee),
    ] {
        let c = Coefficients::load(name).unwrap();
        for d in Distribution::ALL {
            let e = &c.distributions[&d];
            assert_eq!((e.masking, e.engine), (masking, engine));
            let model = match engine {
                Engine::Cycles => d,
                Engine::Eevee => Distribution::Ggx,
            };
            for i in 0..=300 {
                let r = i as f64 / 300.0;
                let avg =
                    q.average_albedo(&Glossy::new(model, masking, Roughness::new(r).unwrap()));
                let err = (e.curve.gain(r) * avg - 1.0).abs();
                assert!(err < 1e-3, "{name} {d} r={r}: gain error {err}");
            }
        }
    }
}

#[test]
fn shipped_presets_match_a_fresh_fit() {
    for (name, engine, version) in [
        ("blender-3", Engine::Cycles, "3.4"),
        ("blender-4", Engine::Cycles, "4.5"),
        ("eevee", Engine::Eevee, "4.5"),
    ] {
        let shipped = Coefficients::load(name).unwrap();
        let v: BlenderVersion = version.parse().unwrap();
        let fresh =
            Coefficients::from_integrator(engine, v, 6, Target::Mean, Weighting::Relative, None)
                .unwrap();
        for d in Distribution::ALL {
            let (a, b) = (
                &shipped.distributions[&d].curve,
                &fresh.distributions[&d].curve,
            );
            for (x, y) in a.numerator.iter().zip(&b.numerator) {
                assert!(
                    (x - y).abs() < 1e-9,
                    "{name} {d}: regenerate presets/ ({x} vs {y})"
                );
            }
        }
    }
}

#[test]
fn coefficient_files_are_byte_identical_for_equal_inputs() {
    let v: BlenderVersion = "4.5".parse().unwrap();
    let a = Coefficients::from_integrator(
        Engine::Cycles,
        v,
        6,
        Target::Mean,
        Weighting::Relative,
        Some("2026-01-01".into()),
    )
    .unwrap();
    let b = Coefficients::from_integrator(
        Engine::Cycles,
        v,
        6,
        Target::Mean,
        Weighting::Relative,
        Some("2026-01-01".into()),
    )
    .unwrap();
    assert_eq!(a.to_json(), b.to_json());
}
