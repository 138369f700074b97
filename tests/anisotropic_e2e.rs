//! The anisotropic integrator against Blender itself: white furnace spheres with Blender's
//! own anisotropic glossy BSDF (3.4's Anisotropic BSDF, 4.5's and 5.0's Glossy Anisotropy),
//! rendered by Cycles, and per pixel the albedo `E(μ, φ, αx, αy)` the integrator predicts
//! for that pixel's view cosine and azimuth from the tangent (radial about Z, as Cycles
//! builds it when no tangent is linked). On a convex sphere in the furnace a pixel is that
//! albedo exactly, so the rings must agree within the render's noise, and must not agree
//! with the isotropic albedo (which is what the test would see if anisotropy were ignored).

mod common;

use common::blender::{real_blender, run_in_blender};
use glam::DVec3;
use gloffuse::measure::anisotropic::view;
use gloffuse::measure::{
    AnisotropicIntegrator, AnisotropicLobe, Anisotropy, BlenderVersion, Distribution, Roughness,
};
use std::path::Path;

const PX: usize = 64;
const SAMPLES: u32 = 512;
/// Rings by view cosine: [0, 0.2), [0.2, 0.4), … [0.8, 1].
const RINGS: usize = 5;
/// Per ring, |render − predicted| (absolute albedo). Measured: ≤ 0.0015 at 1,024 spp.
const RING_TOLERANCE: f64 = 0.004;

struct Case {
    distribution: Distribution,
    roughness: f64,
    anisotropy: f64,
    /// Whether Blender renders the lobe's albedo. Blender 3.0–3.4's anisotropic Beckmann
    /// does not: its sampler draws an isotropic lobe of width αx
    /// (`microfacet_sample_stretched(kg, local_I, alpha_x, alpha_x, …)` in
    /// `bsdf_microfacet.h`) while it evaluates the anisotropic one, so gloffuse refuses
    /// that combination; the case shows the refusal is still needed.
    renders_the_lobe: bool,
}

/// The pixel's local view direction (in the BSDF's frame X, Y, N) on the unit sphere, or
/// none off the sphere and at its very rim (where a pixel mixes the sphere and the world).
fn local_view(col: usize, row: usize) -> Option<DVec3> {
    let x = (col as f64 + 0.5) / PX as f64 * 2.0 - 1.0;
    let z = (row as f64 + 0.5) / PX as f64 * 2.0 - 1.0;
    let rr = x * x + z * z;
    if rr > 0.95 {
        return None;
    }
    let normal = DVec3::new(x, -(1.0 - rr).sqrt(), z);
    let to_camera = DVec3::new(0.0, -1.0, 0.0);
    // Radial tangent about Z; Cycles: Y = normalize(N × T), X = Y × N.
    let tangent = DVec3::new(-normal.y, normal.x, 0.0);
    let y = normal.cross(tangent).normalize();
    let x_axis = y.cross(normal);
    Some(DVec3::new(
        to_camera.dot(x_axis),
        to_camera.dot(y),
        to_camera.dot(normal),
    ))
}

fn check(label: &str, version: &str, cases: &[Case]) {
    let Some(blender) = real_blender(label) else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let request = serde_json::json!({
        "px": PX,
        "samples": SAMPLES,
        "cases": cases.iter().map(|c| serde_json::json!({
            "distribution": c.distribution.blender_enum(),
            "roughness": c.roughness,
            "anisotropy": c.anisotropy,
        })).collect::<Vec<_>>(),
    });
    let (request_path, out) = (dir.path().join("cases.json"), dir.path().join("out.json"));
    std::fs::write(&request_path, request.to_string()).unwrap();
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/blender/anisotropic_sphere.py");
    let output = run_in_blender(
        &blender,
        &script,
        &[request_path.as_os_str(), out.as_os_str()],
    );
    assert!(
        output.status.success() && out.exists(),
        "Blender {label}: {}\n{}",
        String::from_utf8_lossy(&output.stdout),
        String::from_utf8_lossy(&output.stderr)
    );
    let result: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    let masking = version.parse::<BlenderVersion>().unwrap().masking();
    let q = AnisotropicIntegrator::default();
    for (case, render) in cases.iter().zip(result["renders"].as_array().unwrap()) {
        let pixels: Vec<f64> = render
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        assert_eq!(pixels.len(), PX * PX);
        let roughness = Roughness::new(case.roughness).unwrap();
        let lobe = AnisotropicLobe::from_glossy_node(
            case.distribution,
            masking,
            roughness,
            Anisotropy::new(case.anisotropy).unwrap(),
        )
        .unwrap();
        let alpha = roughness.alpha();
        let isotropic = AnisotropicLobe::new(case.distribution, masking, alpha, alpha).unwrap();
        // (render, predicted, isotropic, pixels) per ring
        let mut rings = [(0.0, 0.0, 0.0, 0usize); RINGS];
        for row in 0..PX {
            for col in 0..PX {
                let Some(wo) = local_view(col, row) else {
                    continue;
                };
                let ring = &mut rings[((wo.z * RINGS as f64) as usize).min(RINGS - 1)];
                ring.0 += pixels[row * PX + col];
                ring.1 += q.directional_albedo(&lobe, wo);
                ring.2 += q.directional_albedo(&isotropic, view(wo.z, 0.0));
                ring.3 += 1;
            }
        }
        let what = format!(
            "Blender {label} {} r {} anisotropy {}",
            case.distribution, case.roughness, case.anisotropy
        );
        let mut farthest_isotropic: f64 = 0.0;
        let mut farthest: f64 = 0.0;
        for (k, &(render, predicted, iso, n)) in rings.iter().enumerate() {
            if n == 0 {
                continue;
            }
            let (render, predicted, iso) =
                (render / n as f64, predicted / n as f64, iso / n as f64);
            eprintln!(
                "{what}: ring {k}: render {render:.4}, predicted {predicted:.4}, isotropic {iso:.4} ({n} px)"
            );
            assert!(
                !case.renders_the_lobe || (render - predicted).abs() < RING_TOLERANCE,
                "{what}: ring {k} renders {render:.4}, the integrator predicts {predicted:.4}"
            );
            farthest = farthest.max((render - predicted).abs());
            farthest_isotropic = farthest_isotropic.max((render - iso).abs());
        }
        if !case.renders_the_lobe {
            assert!(
                farthest > 0.1,
                "{what}: renders within 0.1 of the lobe's albedo in every ring: Blender may render this lobe now"
            );
            continue;
        }
        assert!(
            farthest_isotropic > 0.03,
            "{what}: the render is within 3 % of the isotropic lobe's albedo, so this case cannot tell whether anisotropy is modelled"
        );
    }
}

#[test]
fn blender_34_anisotropic_bsdf_renders_what_the_integrator_predicts() {
    check(
        "3.4",
        "3.4",
        &[
            Case {
                distribution: Distribution::Ggx,
                roughness: 0.8,
                anisotropy: 0.5,
                renders_the_lobe: true,
            },
            Case {
                distribution: Distribution::Beckmann,
                roughness: 0.6,
                anisotropy: -0.9,
                renders_the_lobe: false,
            },
        ],
    );
}

#[test]
fn blender_45_glossy_anisotropy_renders_what_the_integrator_predicts() {
    check(
        "4.5",
        "4.5",
        &[
            Case {
                distribution: Distribution::Ggx,
                roughness: 0.7,
                anisotropy: 0.8,
                renders_the_lobe: true,
            },
            Case {
                distribution: Distribution::Beckmann,
                roughness: 1.0,
                anisotropy: 0.3,
                renders_the_lobe: true,
            },
        ],
    );
}

#[test]
fn blender_50_glossy_anisotropy_renders_what_the_integrator_predicts() {
    check(
        "5.0",
        "5.0",
        &[
            Case {
                distribution: Distribution::Ggx,
                roughness: 0.5,
                anisotropy: -0.7,
                renders_the_lobe: true,
            },
            Case {
                distribution: Distribution::Beckmann,
                roughness: 0.9,
                anisotropy: -0.6,
                renders_the_lobe: true,
            },
        ],
    );
}
