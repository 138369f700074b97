//! The layered glossy-over-diffuse groups in real Blender (`verify --mode layered`): a white
//! base reflects 100 % at every view-cosine ring for all three distributions, three indices
//! of refraction and five roughness values, in every Blender; the hand-made Mix Shader next
//! to them renders what the integrator predicts for it (a check of the Fresnel-weighted
//! physics by Blender's own nodes); and over a grey base the GGX group agrees with
//! Principled BSDF, Blender 4.x's own layering, ring by ring.
//!
//! Tier: blender (needs the Blenders and tools `scripts/test.sh` installs).

mod common;

use serde_json::Value;
use std::path::{Path, PathBuf};

fn verify(blender: &Path, extra: &[&str]) -> (i32, Value) {
    common::verify_json(blender, &[&["--mode", "layered"], extra].concat())
}

fn f(v: &Value) -> f64 {
    v.as_f64().unwrap_or(f64::NAN)
}

fn name(r: &Value) -> String {
    format!(
        "{} IOR {} r={}",
        r["distribution"], r["ior"], r["roughness"]
    )
}

fn a_white_layered_sphere_reflects_everything_and_the_mix_shader_is_predicted(
    label: &'static str,
    blender: PathBuf,
) {
    let (code, v) = verify(&blender, &[]);
    assert_eq!(code, 0, "Blender {label}: {v:#}");
    let rows = v["rows"].as_array().unwrap();
    // 3 distributions × IOR {1.33, 1.5, 2} × r {0.1, 0.25, 0.5, 0.75, 1}.
    assert_eq!(rows.len(), 45, "Blender {label}");
    for r in rows {
        assert!(
            (f(&r["brightness"]) - 1.0).abs() <= 0.01 && f(&r["worst_ring"]) <= 0.015,
            "Blender {label} {}: mean {} worst ring {}",
            name(r),
            r["brightness"],
            r["worst_ring"]
        );
        // The Mix Shader is Blender's Fresnel node, Diffuse and Glossy; the prediction
        // F E + (1 − F) is the integrator's. They agree to within the noise.
        let (rendered, predicted) = (
            f(&r["uncorrected_brightness"]),
            f(&r["predicted_uncorrected"]),
        );
        assert!(
            (rendered - predicted).abs() <= 0.004,
            "Blender {label} {} Mix Shader: rendered {rendered} predicted {predicted}",
            name(r)
        );
    }
    // The hand-made Mix Shader loses energy where the layered group does not: GGX at
    // IOR 2, r = 1 renders about 91 % (see docs/RESULTS.md's layered table).
    let ggx = rows
        .iter()
        .find(|r| r["distribution"] == "ggx" && r["ior"] == 2.0 && r["roughness"] == 1.0)
        .unwrap();
    assert!(f(&ggx["uncorrected_brightness"]) < 0.93, "{ggx:#}");
    let principled: Vec<f64> = v["reference"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|s| s["ior"] == 1.5)
        .map(|s| f(&s["brightness"]))
        .collect();
    assert_eq!(principled.len(), 5);
    if label == "3.4" {
        // 3.4's Principled adds its diffuse base without taking off what the specular
        // reflects: 105–109 % at IOR 1.5.
        assert!(principled.iter().all(|&b| b > 1.03), "{principled:?}");
    } else {
        // 4.x/5.0's Principled layers by albedo scaling: the same 100 %.
        assert!(
            principled.iter().all(|&b| (b - 1.0).abs() < 0.01),
            "{principled:?}"
        );
    }
}

common::blender::per_blender!(
    a_white_layered_sphere_reflects_everything_and_the_mix_shader_is_predicted
);

/// Grey base 0.5 in Blender 4.5: every ring of `Gloffuse Layered (GGX)` within 2 % of
/// Principled BSDF's ring at the same roughness and index.
#[test]
fn over_a_grey_base_the_ggx_group_agrees_with_principled() {
    let Some(blender) = common::blender::real_blender("4.5") else {
        return;
    };
    let (code, v) = verify(&blender, &["--color", "0.5,0.5,0.5", "-d", "ggx"]);
    assert_eq!(code, 0, "{v:#}");
    let rows = v["rows"].as_array().unwrap();
    let references = v["reference"].as_array().unwrap();
    assert_eq!(rows.len(), 15);
    let mut worst: f64 = 0.0;
    for row in rows {
        let principled = references
            .iter()
            .find(|s| s["ior"] == row["ior"] && s["roughness"] == row["roughness"])
            .unwrap();
        let rings = |s: &Value| s["rings"].as_array().unwrap().clone();
        let (ours, theirs) = (rings(&row["corrected"]), rings(&principled["stats"]));
        let mut judged = 0;
        for (a, b) in ours.iter().zip(&theirs) {
            if a["pixels"].as_u64().unwrap() < 150 {
                continue;
            }
            judged += 1;
            for c in 0..3 {
                let ratio = f(&a["mean_rgb"][c]) / f(&b["mean_rgb"][c]);
                worst = worst.max((ratio - 1.0).abs());
                assert!(
                    (ratio - 1.0).abs() <= 0.02,
                    "{} ring {:?}: layered {} vs Principled {}",
                    name(row),
                    a["mu"],
                    a["mean_rgb"][c],
                    b["mean_rgb"][c]
                );
            }
        }
        assert!(judged >= 5, "{judged} rings judged");
        // A grey base is not 100 %: the target is A + 0.5 (1 − A), between 0.5 and 1.
        let target = f(&row["target"][0]);
        assert!(
            target > 0.5 && target < 0.75,
            "{}: target {target}",
            name(row)
        );
    }
    println!("worst ring of Gloffuse Layered (GGX) vs Principled BSDF: {worst:.4}");
}
