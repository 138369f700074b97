//! The Glass and Refraction albedo against Blender itself: one rough interface at a time,
//! rendered by Cycles with Blender's own BSDF (tests/blender/glass_interface.py: the first
//! surface a ray meets is the BSDF, the second a white Emission, the world white), so each
//! pixel is what the interface returns, `E(μ, r, η)` at the pixel's view cosine, from
//! outside (η = IOR) and from inside (η = 1/IOR). Every ring must agree with the integrator
//! within the render's noise, in each Blender's own form of the BSDF (3.4: two closures
//! weighted by the Fresnel at the normal; 4.5 and 5.0: one closure with a per-microfacet
//! Fresnel), and must not agree with the other version's form where they differ.

mod common;

use common::blender::render_cases;
use gloffuse::measure::{
    BlenderVersion, Dielectric, DielectricIntegrator, DielectricNode, Distribution, Roughness,
};

const PX: usize = 64;
const SAMPLES: u32 = 512;
const RINGS: usize = 5;
/// Per ring, |render − predicted| (absolute albedo). Measured at 512 spp: ≤ 0.0015 in 4.5
/// and 5.0. Blender 3.4 renders a little more than its lobes return in two places: inside
/// the glass past the critical angle (GGX: 0.004, where the refraction closure weighs 1e-4
/// but is still picked), and with Beckmann (up to 0.013; its sampler draws the visible
/// normals from a table and masks the view with the exact Λ, while it weights with
/// Walter's approximation).
fn ring_tolerance(version: &str, d: Distribution) -> f64 {
    match (version, d) {
        ("3.4", Distribution::Beckmann) => 0.015,
        ("3.4", _) => 0.006,
        _ => 0.004,
    }
}

struct Case {
    node: DielectricNode,
    distribution: Distribution,
    roughness: f64,
    ior: f64,
    inside: bool,
}

fn case(node: DielectricNode, d: Distribution, roughness: f64, ior: f64, inside: bool) -> Case {
    Case {
        node,
        distribution: d,
        roughness,
        ior,
        inside,
    }
}

fn cases() -> Vec<Case> {
    use DielectricNode::{Glass, Refraction};
    use Distribution::{Beckmann, Ggx};
    vec![
        case(Glass, Ggx, 0.7, 1.5, false),
        case(Glass, Ggx, 0.7, 1.5, true),
        case(Glass, Ggx, 1.0, 2.4, false),
        case(Glass, Beckmann, 0.8, 1.33, true),
        case(Refraction, Ggx, 0.6, 1.5, false),
        case(Refraction, Beckmann, 0.9, 1.5, true),
    ]
}

/// The view cosine of pixel (col, row) on the unit sphere, if its centre is on the sphere
/// within μ ≥ 0.22 (the rim beyond is a sliver of pixels that mix the sphere and the world).
fn view_cosine(col: usize, row: usize) -> Option<f64> {
    let x = (col as f64 + 0.5) / PX as f64 * 2.0 - 1.0;
    let z = (row as f64 + 0.5) / PX as f64 * 2.0 - 1.0;
    let rr = x * x + z * z;
    (rr <= 0.95).then(|| (1.0 - rr).sqrt())
}

fn check(label: &str, version: &str, other_version: &str) {
    let cases = cases();
    let node_key = |n: DielectricNode| match n {
        DielectricNode::Glass => "glass",
        DielectricNode::Refraction => "refraction",
    };
    let request = serde_json::json!({
        "px": PX,
        "samples": SAMPLES,
        "cases": cases.iter().map(|c| serde_json::json!({
            "node": node_key(c.node),
            "distribution": c.distribution.blender_enum(),
            "roughness": c.roughness,
            "ior": c.ior,
            "inside": c.inside,
        })).collect::<Vec<_>>(),
    });
    let Some(renders) = render_cases(label, "glass_interface.py", &request, PX) else {
        return;
    };
    let q = DielectricIntegrator::default();
    let version: BlenderVersion = version.parse().unwrap();
    let other: BlenderVersion = other_version.parse().unwrap();
    let mut farthest_other: f64 = 0.0;
    let mut misses = Vec::new();
    for (c, pixels) in cases.iter().zip(&renders) {
        let roughness = Roughness::new(c.roughness).unwrap();
        let bsdf = Dielectric::new(c.node, c.distribution, roughness, version);
        let other_bsdf = Dielectric::new(c.node, c.distribution, roughness, other);
        let eta = if c.inside { 1.0 / c.ior } else { c.ior };
        // (render, predicted, other form, pixels) per ring
        let mut rings = [(0.0, 0.0, 0.0, 0usize); RINGS];
        for row in 0..PX {
            for col in 0..PX {
                let Some(mu) = view_cosine(col, row) else {
                    continue;
                };
                let ring = &mut rings[((mu * RINGS as f64) as usize).min(RINGS - 1)];
                ring.0 += pixels[row * PX + col];
                ring.1 += q.directional_albedo(&bsdf, mu, eta);
                ring.2 += q.directional_albedo(&other_bsdf, mu, eta);
                ring.3 += 1;
            }
        }
        let what = format!(
            "Blender {label} {:?} {} r {} η {:.3}",
            c.node, c.distribution, c.roughness, eta
        );
        for (k, &(render, predicted, other, n)) in rings.iter().enumerate() {
            if n == 0 {
                continue;
            }
            let (render, predicted, other) =
                (render / n as f64, predicted / n as f64, other / n as f64);
            println!(
                "{what} ring {k}: render {render:.4}, integrator {predicted:.4} (other form {other:.4})"
            );
            if (render - predicted).abs() > ring_tolerance(label, c.distribution) {
                misses.push(format!(
                    "{what}: ring {k} renders {render:.4}, the integrator predicts {predicted:.4}"
                ));
            }
            farthest_other = farthest_other.max((render - other).abs());
        }
    }
    assert!(misses.is_empty(), "{}", misses.join("\n"));
    assert!(
        farthest_other > 0.03,
        "Blender {label}: every ring is within 3 % of Blender {other_version}'s form too, so \
         these cases cannot tell the forms apart"
    );
}

#[test]
fn blender_34_glass_renders_what_the_integrator_predicts() {
    check("3.4", "3.4", "4.5");
}

#[test]
fn blender_45_glass_renders_what_the_integrator_predicts() {
    check("4.5", "4.5", "3.4");
}

#[test]
fn blender_50_glass_renders_what_the_integrator_predicts() {
    check("5.0", "5.0", "3.4");
}
