//! The Glass and Refraction albedo `E(μ, r, η)` against independent oracles: a brute-force
//! midpoint rule over the outgoing direction that evaluates each lobe's BSDF (D, G2, the
//! refraction Jacobian; the integrator never evaluates D), and the limits: a smooth
//! interface and a matched index return everything.
//!
//! Tier: fast (no Blender; `scripts/test.sh --fast` runs it).

use glam::DVec3;
use gloffuse::measure::fresnel;
use gloffuse::measure::{
    BlenderVersion, Dielectric, DielectricIntegrator, DielectricNode, Distribution, GlassForm,
    Roughness, Sampler,
};
use rayon::prelude::*;
use std::f64::consts::PI;

/// The lobe itself, drawn exactly: the oracles here evaluate the BSDF, not 3.0–3.4's Beckmann
/// slope table (`measure::beckmann_table` checks that against a Monte Carlo walk through it).
fn bsdf(node: DielectricNode, d: Distribution, r: f64, version: &str) -> Dielectric {
    let version: BlenderVersion = version.parse().unwrap();
    Dielectric {
        sampler: Sampler::Exact,
        ..Dielectric::new(node, d, Roughness::new(r).unwrap(), version)
    }
}

/// `f cos` of the lobe toward `l` for the view `v`, evaluated as a BSDF: reflection
/// `D G2 / (4μ)`, refraction `η² D G2 |v·h| |l·h| / (μ |ηl + v|²)` with the generalised half
/// vector, each with its Fresnel weight; zero where no microfacet connects the two.
fn eval_cos(b: &Dielectric, v: DVec3, l: DVec3, eta: f64) -> f64 {
    let m = b.microfacet;
    let mu = v.z;
    let g2 = b.masking.g2(m.lambda(mu), m.lambda(l.z.abs()));
    let macro_f = fresnel::dielectric(mu, eta);
    let mut reflected = 0.0;
    if l.z > 0.0 {
        let h = (v + l).normalize();
        let f = match (b.node, b.form) {
            (DielectricNode::Refraction, _) => 0.0,
            (DielectricNode::Glass, GlassForm::TwoClosures) => macro_f,
            (DielectricNode::Glass, GlassForm::OneClosure) => fresnel::dielectric(v.dot(h), eta),
        };
        reflected = f * m.d(h.z) * g2 / (4.0 * mu);
        // From 3.6 a refraction only goes below the surface.
        if b.form == GlassForm::OneClosure {
            return reflected;
        }
    }
    reflected + refracted_cos(b, v, l, eta, g2, macro_f)
}

/// The refracted lobe's `f cos` toward `l`, through the microfacet that connects it to `v`.
fn refracted_cos(b: &Dielectric, v: DVec3, l: DVec3, eta: f64, g2: f64, macro_f: f64) -> f64 {
    let (m, mu) = (b.microfacet, v.z);
    let ht = -(eta * l + v);
    let h = ht.normalize() * ht.z.signum();
    if v.dot(h) <= 0.0 || l.dot(h) >= 0.0 {
        return 0.0;
    }
    let f = match (b.node, b.form) {
        (DielectricNode::Refraction, _) => 1.0,
        (DielectricNode::Glass, GlassForm::TwoClosures) => (1.0 - macro_f).max(1e-4),
        (DielectricNode::Glass, GlassForm::OneClosure) => 1.0 - fresnel::dielectric(v.dot(h), eta),
    };
    f * eta * eta * m.d(h.z) * g2 * v.dot(h) * l.dot(h).abs() / (mu * ht.length_squared())
}

/// `∫ f cos dω` over the whole sphere by the midpoint rule (n polar × n azimuth cells over
/// the half sphere of azimuths, mirrored).
fn brute_force(b: &Dielectric, mu: f64, eta: f64, n: usize) -> f64 {
    let v = DVec3::new((1.0 - mu * mu).sqrt(), 0.0, mu);
    let (dt, dp) = (PI / n as f64, PI / n as f64);
    (0..n)
        .into_par_iter()
        .map(|i| {
            let theta = (i as f64 + 0.5) * dt;
            let (s, c) = theta.sin_cos();
            (0..n)
                .map(|j| {
                    let phi = (j as f64 + 0.5) * dp;
                    let l = DVec3::new(s * phi.cos(), s * phi.sin(), c);
                    eval_cos(b, v, l, eta) * s * dt * dp * 2.0
                })
                .sum::<f64>()
        })
        .sum()
}

#[test]
fn matches_a_brute_force_over_the_outgoing_direction() {
    let q = DielectricIntegrator::default();
    let mut worst: f64 = 0.0;
    for version in ["3.4", "4.5"] {
        for node in [DielectricNode::Glass, DielectricNode::Refraction] {
            for d in [Distribution::Ggx, Distribution::Beckmann] {
                for (r, mu, eta) in [
                    (0.4, 0.9, 1.5),
                    (0.7, 0.5, 1.5),
                    (1.0, 0.2, 1.5),
                    (0.6, 0.7, 1.0 / 1.5),
                    (0.9, 0.3, 1.0 / 1.5),
                    (0.5, 0.4, 2.4),
                    (0.8, 0.8, 1.0 / 1.33),
                ] {
                    let b = bsdf(node, d, r, version);
                    let e = q.directional_albedo(&b, mu, eta);
                    let brute = brute_force(&b, mu, eta, 1500);
                    let what = format!("{version} {node:?} {d:?} r {r} μ {mu} η {eta:.3}");
                    println!("{what}: {e:.5} vs {brute:.5}");
                    worst = worst.max((e - brute).abs());
                    assert!(
                        (e - brute).abs() < 1e-3,
                        "{what}: {e} vs brute force {brute}"
                    );
                }
            }
        }
    }
    println!("worst {worst:.2e}");
}

#[test]
fn a_smooth_interface_and_a_matched_index_return_everything() {
    let q = DielectricIntegrator::default();
    for version in ["3.4", "4.5", "5.0"] {
        for d in [Distribution::Ggx, Distribution::Beckmann] {
            for mu in [0.1, 0.5, 1.0] {
                // A smooth glass, either way through; a matched index at any roughness.
                for eta in [1.5, 1.0 / 1.5] {
                    let glass = bsdf(DielectricNode::Glass, d, 0.0, version);
                    let e = q.directional_albedo(&glass, mu, eta);
                    // 3.0–3.5 weight the refraction of a totally reflecting view by 1e-4.
                    assert!(
                        (e - 1.0).abs() <= 1e-4,
                        "{version} {d:?} μ {mu} η {eta}: {e}"
                    );
                }
                for r in [0.3, 1.0] {
                    for node in [DielectricNode::Glass, DielectricNode::Refraction] {
                        let e = q.directional_albedo(&bsdf(node, d, r, version), mu, 1.0);
                        assert_eq!(e, 1.0, "{version} {node:?} {d:?} r {r} μ {mu}");
                    }
                }
                // Nearly smooth: the lobe returns almost everything.
                let glass = bsdf(DielectricNode::Glass, d, 0.05, version);
                let e = q.directional_albedo(&glass, mu.max(0.3), 1.5);
                assert!((e - 1.0).abs() < 2e-3, "{version} {d:?} r 0.05 μ {mu}: {e}");
            }
        }
    }
}

/// The leaving refraction tables' axis: `s = ½` is the critical cosine, where Snell's law
/// (sin θ = 1/IOR) and the Fresnel reaching 1 put it, `s = 0` is μ = 0 and `s = 1` is
/// μ = 1, the grid points crowd quadratically toward it from both sides, and the inverse
/// inverts. Across it, the refraction lobe leaving a nearly smooth glass falls from most of
/// the light to almost none within 0.02 of μ: what a table even in μ (steps of 1/15) would
/// blur. The other tables' axis is `μ = t^1.5`.
#[test]
fn the_leaving_axis_crowds_at_the_critical_angle() {
    use gloffuse::measure::{
        critical_cosine, critical_crowded, critical_crowded_coordinate, grazing_crowded,
        grazing_crowded_coordinate,
    };
    for ior in [1.0, 1.1, 1.5, 2.4, 3.0] {
        let c = critical_cosine(ior);
        // Snell: the sine of the critical angle is 1/IOR.
        assert!(
            ((1.0 - c * c).sqrt() - 1.0 / ior).abs() < 1e-12,
            "IOR {ior}"
        );
        if ior > 1.0 {
            assert_eq!(fresnel::dielectric(c - 1e-6, 1.0 / ior), 1.0, "IOR {ior}");
            assert!(fresnel::dielectric(c + 1e-3, 1.0 / ior) < 1.0, "IOR {ior}");
            assert!((critical_crowded(0.0, ior)).abs() < 1e-15);
            // A step of 1/15 from the middle moves μ by 1/225 of the side's span.
            let below = c - critical_crowded(0.5 - 1.0 / 30.0, ior);
            assert!((below - c / 225.0).abs() < 1e-12, "IOR {ior}: {below}");
        }
        assert!((critical_crowded(0.5, ior) - c).abs() < 1e-15);
        assert!((critical_crowded(1.0, ior) - 1.0).abs() < 1e-15);
        let above = critical_crowded(0.5 + 1.0 / 30.0, ior) - c;
        assert!(
            (above - (1.0 - c) / 225.0).abs() < 1e-12,
            "IOR {ior}: {above}"
        );
        for s in [0.0, 0.1, 0.3, 0.5, 0.6, 0.9, 1.0] {
            let back = critical_crowded_coordinate(critical_crowded(s, ior), ior);
            assert!(
                (back - s).abs() < 1e-9 || (ior == 1.0 && s < 0.5),
                "IOR {ior} s {s}: {back}"
            );
        }
    }
    for t in [0.0_f64, 0.25, 0.5, 1.0] {
        let mu = t * t.sqrt();
        assert!((grazing_crowded(t) - mu).abs() < 1e-15, "t {t}");
        assert!((grazing_crowded_coordinate(mu) - t).abs() < 1e-12, "t {t}");
    }
    let q = DielectricIntegrator::default();
    let c = critical_cosine(1.5);
    let lobe = bsdf(DielectricNode::Refraction, Distribution::Ggx, 0.1, "3.4");
    let (below, above) = (
        q.directional_albedo(&lobe, c - 0.01, 1.0 / 1.5),
        q.directional_albedo(&lobe, c + 0.01, 1.0 / 1.5),
    );
    assert!(below < 0.2 && above > 0.6, "T {below} → {above}");
}
