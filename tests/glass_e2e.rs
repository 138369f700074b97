//! The Glass and Refraction albedo against Blender itself: one rough interface at a time,
//! rendered by Cycles with Blender's own BSDF (tests/blender/glass_interface.py: the first
//! surface a ray meets is the BSDF, the second a white Emission, the world white), so each
//! pixel is what the interface returns, `E(μ, r, η)` at the pixel's view cosine, from
//! outside (η = IOR) and from inside (η = 1/IOR). Every ring must agree with the integrator
//! within the render's noise, in each Blender's own form of the BSDF (3.4: two closures
//! weighted by the Fresnel at the normal; 4.5 and 5.0: one closure with a per-microfacet
//! Fresnel), and must not agree with the other version's form where they differ.
//!
//! Tier: blender (needs the Blenders and tools `scripts/test.sh` installs).

mod common;

use std::path::PathBuf;

use common::blender::render_cases;
use gloffuse::measure::{
    BlenderVersion, Dielectric, DielectricIntegrator, DielectricNode, Distribution, Roughness,
};

const PX: usize = 64;
const SAMPLES: u32 = 512;
const RINGS: usize = 5;
/// Per ring, |render − predicted| (absolute albedo). Measured at 512 spp: ≤ 0.0015 in 4.5
/// and 5.0. Blender 3.4 renders a little more than its lobes return inside the glass past
/// the critical angle (GGX: 0.004, Beckmann: 0.0086, where the refraction closure weighs
/// 1e-4 but is still picked); elsewhere within 0.0013, its Beckmann sampler's slope table
/// (up to 0.013 more than the exact lobe) in the prediction (docs/PHYSICS.md §15).
fn ring_tolerance(version: &str, d: Distribution) -> f64 {
    match (version, d) {
        ("3.4", Distribution::Beckmann) => 0.01,
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

/// A furnace case of a solid sphere: its shader, and whether its normal is bumped.
#[derive(Clone, Copy)]
struct Solid {
    group: Option<&'static str>,
    node: DielectricNode,
    distribution: &'static str,
    roughness: f64,
    ior: f64,
    bump: bool,
}

const fn solid(
    group: Option<&'static str>,
    node: DielectricNode,
    distribution: &'static str,
    roughness: f64,
    ior: f64,
) -> Solid {
    Solid {
        group,
        node,
        distribution,
        roughness,
        ior,
        bump: false,
    }
}

/// A sphere's mean and its rings' means (μ ≥ 0.22, by fifths of μ), and the rim's: the
/// pixels at μ 0.05–0.22. Outside μ 0.05 (the outermost pixel of each row) a pixel centre
/// lies within 0.0013 of the silhouette, inside the 0.005 by which the 32-sided UV sphere
/// misses the round one, so what it sees depends on the mesh.
struct Rendered {
    mean: f64,
    rings: Vec<f64>,
    rim: f64,
}

/// The view cosine of pixel (col, row) of a solid sphere when it is in the rim.
fn rim_cosine(col: usize, row: usize) -> Option<f64> {
    let x = (col as f64 + 0.5) / PX as f64 * 2.0 - 1.0;
    let z = (row as f64 + 0.5) / PX as f64 * 2.0 - 1.0;
    let mu = (1.0 - x * x - z * z).max(0.0).sqrt();
    (view_cosine(col, row).is_none() && mu >= 0.05).then_some(mu)
}

/// Renders solid spheres (every face the shader, 1,024 bounces) in Blender `label` with the
/// groups of a `generate --mode glass` script built there, or none when that Blender is
/// skipped.
fn solid_spheres(label: &str, cases: &[Solid], samples: u32) -> Option<Vec<Rendered>> {
    let dir = tempfile::tempdir().unwrap();
    let script = dir.path().join("glass.py");
    let out = common::gloffuse()
        .args(["generate", "--mode", "glass", "--script"])
        .arg(&script)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let node_key = |n: DielectricNode| match n {
        DielectricNode::Glass => "glass",
        DielectricNode::Refraction => "refraction",
    };
    let request = serde_json::json!({
        "px": PX,
        "samples": samples,
        "script": script,
        "cases": cases.iter().map(|c| serde_json::json!({
            "node": node_key(c.node),
            "distribution": c.distribution,
            "roughness": c.roughness,
            "ior": c.ior,
            "solid": true,
            "bump": c.bump,
            "group": c.group,
        })).collect::<Vec<_>>(),
    });
    let renders = render_cases(label, "glass_interface.py", &request, PX)?;
    Some(
        renders
            .iter()
            .map(|pixels| {
                let mut rings = [(0.0, 0usize); RINGS];
                for row in 0..PX {
                    for col in 0..PX {
                        if let Some(mu) = view_cosine(col, row) {
                            let ring = &mut rings[((mu * RINGS as f64) as usize).min(RINGS - 1)];
                            ring.0 += pixels[row * PX + col];
                            ring.1 += 1;
                        }
                    }
                }
                let total: f64 = rings.iter().map(|r| r.0).sum();
                let count: usize = rings.iter().map(|r| r.1).sum();
                let rim: Vec<f64> = (0..PX * PX)
                    .filter(|&p| rim_cosine(p % PX, p / PX).is_some())
                    .map(|p| pixels[p])
                    .collect();
                Rendered {
                    rim: rim.iter().sum::<f64>() / rim.len() as f64,
                    mean: total / count as f64,
                    rings: rings
                        .iter()
                        .filter(|r| r.1 > 0)
                        .map(|r| r.0 / r.1 as f64)
                        .collect(),
                }
            })
            .collect(),
    )
}

const GROUPS: [Solid; 8] = [
    solid(
        Some("Gloffuse Glass (GGX)"),
        DielectricNode::Glass,
        "GGX",
        0.1,
        1.5,
    ),
    solid(
        Some("Gloffuse Glass (GGX)"),
        DielectricNode::Glass,
        "GGX",
        0.5,
        1.1,
    ),
    solid(
        Some("Gloffuse Glass (GGX)"),
        DielectricNode::Glass,
        "GGX",
        0.7,
        1.5,
    ),
    solid(
        Some("Gloffuse Glass (GGX)"),
        DielectricNode::Glass,
        "GGX",
        1.0,
        1.5,
    ),
    solid(
        Some("Gloffuse Glass (GGX)"),
        DielectricNode::Glass,
        "GGX",
        0.6,
        2.4,
    ),
    solid(
        Some("Gloffuse Glass (Beckmann)"),
        DielectricNode::Glass,
        "BECKMANN",
        0.5,
        1.33,
    ),
    solid(
        Some("Gloffuse Glass (Beckmann)"),
        DielectricNode::Glass,
        "BECKMANN",
        0.9,
        1.8,
    ),
    solid(
        Some("Gloffuse Refraction (GGX)"),
        DielectricNode::Refraction,
        "GGX",
        0.5,
        1.33,
    ),
];

/// Blender's own glass beside them: single-scatter GGX and Multiscatter GGX at r 0.7,
/// IOR 1.5.
const BLENDERS_OWN: [Solid; 2] = [
    solid(None, DielectricNode::Glass, "GGX", 0.7, 1.5),
    solid(None, DielectricNode::Glass, "MULTI_GGX", 0.7, 1.5),
];

/// What a group's solid sphere must do in Blender `label`: (mean, every ring, the rim)
/// within these of 100 %. The goal is 2 %, 3 % and 3 %. Blender 3.4 misses it at the rim
/// of its Refraction group (GGX r 0.5, IOR 1.33: 96.63 % at 512 spp, where 4.5.15 and 5.0.1
/// give 99.3–99.6 %; not explained yet). (Its Beckmann glass, 2.3 % bright before the
/// tables modelled its sampler's slope table, now meets the goal.)
fn solid_tolerance(label: &str, c: &Solid) -> (f64, f64, f64) {
    match (label, c.distribution, c.node) {
        ("3.4", _, DielectricNode::Refraction) => (0.02, 0.03, 0.04),
        _ => (0.02, 0.03, 0.03),
    }
}

/// The bumped pair (Noise > Bump, strength 1, distance 0.3): the GGX group and Blender's
/// Multiscatter GGX glass at r 0.7, IOR 1.5, beside the flat ones in `GROUPS` and
/// `BLENDERS_OWN`. Cycles drops light under a bumped normal (its own loss); the group must
/// lose what Blender's energy-conserving glass loses.
fn bumped() -> [Solid; 2] {
    [
        Solid {
            bump: true,
            ..GROUPS[2]
        },
        Solid {
            bump: true,
            ..BLENDERS_OWN[1]
        },
    ]
}

fn check_solid(label: &str) {
    let cases: Vec<Solid> = GROUPS
        .into_iter()
        .chain(BLENDERS_OWN)
        .chain(bumped())
        .collect();
    let Some(results) = solid_spheres(label, &cases, 512) else {
        return;
    };
    let mut misses = Vec::new();
    for (c, r) in cases.iter().zip(&results) {
        let lo = r.rings.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = r.rings.iter().copied().fold(0.0, f64::max);
        let what = format!(
            "Blender {label} {}{} {:?} {} r {} IOR {}: mean {:.2} %, rings {:.2}–{:.2} %, rim {:.2} %",
            c.group.unwrap_or("plain"),
            if c.bump { " bumped" } else { "" },
            c.node,
            c.distribution,
            c.roughness,
            c.ior,
            100.0 * r.mean,
            100.0 * lo,
            100.0 * hi,
            100.0 * r.rim
        );
        println!("{what}");
        let judged = match (c.bump, c.group, c.distribution) {
            (true, ..) => true, // judged as a pair below
            (false, Some(_), _) => {
                let (m, ring, rim) = solid_tolerance(label, c);
                (r.mean - 1.0).abs() <= m
                    && (lo - 1.0).abs() <= ring
                    && (hi - 1.0).abs() <= ring
                    && (r.rim - 1.0).abs() <= rim
            }
            // Blender's single-scatter glass loses a third of the light.
            (false, None, "GGX") => r.mean < 0.7,
            // Multiscatter GGX glass: 3.4's random walk keeps everything; 4.5's and
            // 5.0's tables leave the rim a few per cent dark (measured 93.8–93.9 %).
            (false, None, _) if label == "3.4" => (r.mean - 1.0).abs() < 0.005,
            (false, None, _) => r.mean < 0.99 && lo < 0.97 && r.rim < 0.96,
        };
        if !judged {
            misses.push(what);
        }
    }
    // Under bump, ring by ring: group / Multiscatter as without bump, within 2.5 % (measured:
    // 1.7 % at most, the group a little brighter under bump; Multiscatter GGX glass is
    // itself 1–4 % short without bump in 4.5 and 5.0). Not in 3.4, whose random-walk
    // Multiscatter glass keeps everything even there.
    if label != "3.4" {
        let n = GROUPS.len() + BLENDERS_OWN.len();
        let (flat_group, flat_ms) = (&results[2], &results[GROUPS.len() + 1]);
        let (bumped_group, bumped_ms) = (&results[n], &results[n + 1]);
        for k in 0..flat_group.rings.len() {
            let flat = flat_group.rings[k] / flat_ms.rings[k];
            let bumped = bumped_group.rings[k] / bumped_ms.rings[k];
            println!(
                "Blender {label} ring {k}: group / Multiscatter {flat:.4} flat, {bumped:.4} bumped"
            );
            if (bumped / flat - 1.0).abs() > 0.025 {
                misses.push(format!(
                    "Blender {label} ring {k}: group / Multiscatter GGX glass is {flat:.4} flat but {bumped:.4} bumped"
                ));
            }
        }
        assert!(
            bumped_group.mean < 0.99,
            "Blender {label}: Cycles' bump loss is gone"
        );
    }
    assert!(misses.is_empty(), "{}", misses.join("\n"));
}

#[test]
fn blender_34_solid_glass() {
    check_solid("3.4");
}

#[test]
fn blender_45_solid_glass() {
    check_solid("4.5");
}

#[test]
fn blender_50_solid_glass() {
    check_solid("5.0");
}

/// `verify --mode glass` in every Blender: solid spheres of Blender's Glass BSDF, the glass
/// groups and Multiscatter GGX glass in one furnace render (1,024 bounces, 256 spp). Every
/// group sphere within the verdict's ±2 % and its rings within ±3 %, Blender's own glass
/// visibly short, no uncorrected prediction claimed; Multiscatter GGX glass at 100 % in
/// 3.4 (its random walk) and short of it in 4.5 and 5.0 (its tables).
fn verify_judges_the_glass_groups_in_every_blender(label: &'static str, blender: PathBuf) {
    let args = ["--mode", "glass", "--roughness", "0.7", "--ior", "1.6"];
    let (code, v) = common::verify_json(&blender, &args);
    assert_eq!(code, 0, "Blender {label}: {v:#}");
    assert_eq!(v["pass"], true, "Blender {label}");
    assert_eq!(v["render"]["samples"], 256, "Blender {label}");
    let rows = v["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 2, "Blender {label}");
    for r in rows {
        let what = format!(
            "Blender {label} {} r {} IOR {}",
            r["distribution"], r["roughness"], r["ior"]
        );
        assert_eq!(r["ior"], 1.6, "{what}");
        assert!(r.get("predicted_uncorrected").is_none(), "{what}");
        let plain = r["uncorrected_brightness"].as_f64().unwrap();
        assert!(
            plain < 0.95,
            "{what}: Blender's glass loses energy ({plain})"
        );
        assert!(r["deviation"].as_f64().unwrap() <= 0.02, "{what}");
        assert!(r["worst_ring"].as_f64().unwrap() <= 0.03, "{what}");
    }
    for m in v["reference"].as_array().unwrap() {
        let what = format!(
            "Blender {label} Multiscatter GGX glass r {}",
            m["roughness"]
        );
        let brightness = m["brightness"].as_f64().unwrap();
        if label == "3.4" {
            assert!((brightness - 1.0).abs() < 0.005, "{what}: {brightness}");
        } else {
            assert!((0.9..0.995).contains(&brightness), "{what}: {brightness}");
        }
    }
}

common::blender::per_blender!(verify_judges_the_glass_groups_in_every_blender);
