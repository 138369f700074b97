//! EEVEE in real Blender (Legacy in 3.4, Next in 4.5 and 5.0), rendered headless with Mesa:
//! the EEVEE groups bring every distribution's furnace sphere to 100 % ± 2 % at r = 0.25 …
//! 1; EEVEE renders Beckmann and Ashikhmin–Shirley exactly as GGX; the plain spheres are
//! what the integrator's separable GGX predicts; a white Diffuse sphere is within 1 % (the
//! lighting); ring by ring, the plain spheres are the brute-force separable GGX albedo and the
//! view and multiscatter groups bring every ring to the lighting; the Cycles groups in EEVEE
//! render what their descriptions quote; and `refresh --engine eevee` measures curves that
//! agree with the `eevee` preset.
//!
//! Tier: blender (needs the Blenders and tools `scripts/test.sh` installs).

mod common;

use gloffuse::generate::document::in_eevee;
use gloffuse::measure::{Distribution, Glossy, Masking, Roughness};
use gloffuse::verify::verdict::MIN_RING_PIXELS;
use serde_json::Value;
use std::path::{Path, PathBuf};

const ROUGHNESS: &str = "0.25,0.5,0.75,1";

fn verify(blender: &Path, extra: &[&str]) -> (i32, Value) {
    common::verify_json(
        blender,
        &[&["--engine", "eevee", "-r", ROUGHNESS], extra].concat(),
    )
}

fn f(v: &Value) -> f64 {
    v.as_f64().unwrap_or(f64::NAN)
}

fn rows_of<'a>(v: &'a Value, distribution: &str) -> Vec<&'a Value> {
    v["rows"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|r| r["distribution"] == distribution)
        .collect()
}

fn eevee_groups_bring_every_distribution_to_100_percent_in_eevee(
    label: &'static str,
    blender: PathBuf,
) {
    let (code, v) = verify(&blender, &[]);
    assert_eq!(code, 0, "Blender {label}: {v:#}");
    assert_eq!(v["engine"], "eevee");
    let lighting = f(&v["lighting"]);
    assert!(
        (lighting - 1.0).abs() <= 0.01,
        "Blender {label}: white Diffuse {lighting}"
    );
    let rows = v["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 12, "Blender {label}");
    for r in rows {
        let b = f(&r["brightness"]);
        assert!(
            (b - 1.0).abs() <= 0.02,
            "Blender {label} {r:#}: corrected {b}"
        );
        // The plain sphere, relative to the lighting, is the integrator's separable GGX
        // (EEVEE's split-sum table) within 0.5 %; Cycles' prediction is shown beside it.
        let (plain, predicted) = (
            f(&r["uncorrected_brightness"]) / lighting,
            f(&r["predicted_uncorrected"]),
        );
        assert!(
            (plain / predicted - 1.0).abs() <= 0.005,
            "Blender {label} {} r={}: EEVEE {plain}, integrator {predicted}",
            r["distribution"],
            r["roughness"]
        );
        assert!(r["cycles_uncorrected"].is_number(), "{r:#}");
    }
    // EEVEE ignores the distribution: Beckmann and Ashikhmin-Shirley render as GGX.
    let ggx = rows_of(&v, "ggx");
    for d in ["beckmann", "ashikhmin-shirley"] {
        for (a, b) in rows_of(&v, d).iter().zip(&ggx) {
            // Identical shading; only the sphere's place in the grid differs (1e-8).
            let (a_mean, b_mean) = (f(&a["uncorrected"]["mean"]), f(&b["uncorrected"]["mean"]));
            assert!(
                (a_mean - b_mean).abs() <= 1e-6,
                "Blender {label}: {d} r={} renders {a_mean}, GGX {b_mean}",
                a["roughness"]
            );
        }
    }
}

common::blender::per_blender!(eevee_groups_bring_every_distribution_to_100_percent_in_eevee);

/// The mean of E(μ) over the pixels of an orthographic sphere whose view cosine is in
/// [lo, hi) (their density is ∝ μ), by a 16-point midpoint rule over the brute-force albedo.
fn ring_albedo(glossy: &Glossy, (lo, hi): (f64, f64)) -> f64 {
    let (mut num, mut den) = (0.0, 0.0);
    for i in 0..16 {
        let mu = lo + (hi - lo) * (i as f64 + 0.5) / 16.0;
        num += mu * common::oracle::brute_force_albedo(glossy, mu, 400, 96);
        den += mu;
    }
    num / den
}

fn ring_bounds(ring: &Value) -> (f64, f64) {
    (f(&ring["mu"][0]), f(&ring["mu"][1]))
}

/// EEVEE's own E(μ, r) is what the view groups read: every judged ring of a plain sphere,
/// relative to the lighting, is the separable GGX albedo over the ring within 0.6 %, and in
/// the view and multiscatter modes every corrected ring is the lighting within 1 % (with
/// the table read through EEVEE's mipmaps, the rim of r = 1 was 5 % dark).
fn eevee_view_groups_bring_every_ring_to_the_lighting(label: &'static str, blender: PathBuf) {
    // Every distribution renders as GGX in every version and mode: one prediction per
    // (roughness, ring).
    let mut predictions = std::collections::HashMap::new();
    for mode in ["view", "multiscatter"] {
        let (code, v) = verify(&blender, &["--mode", mode]);
        assert_eq!(code, 0, "Blender {label} --mode {mode}: {v:#}");
        let lighting = f(&v["lighting"]);
        for r in v["rows"].as_array().unwrap() {
            let roughness = f(&r["roughness"]);
            let rings = r["uncorrected"]["rings"].as_array().unwrap();
            let corrected = r["corrected"]["rings"].as_array().unwrap();
            let mut judged = 0;
            for (plain, fixed) in rings.iter().zip(corrected) {
                if plain["pixels"].as_u64().unwrap() < MIN_RING_PIXELS as u64 {
                    continue;
                }
                judged += 1;
                let bounds = ring_bounds(plain);
                let what = format!(
                    "Blender {label} --mode {mode} {} r={} ring {bounds:?}",
                    r["distribution"], r["roughness"]
                );
                let e = f(&plain["mean"]) / lighting;
                let key = (roughness.to_bits(), bounds.0.to_bits(), bounds.1.to_bits());
                let predicted = *predictions.entry(key).or_insert_with(|| {
                    let r = Roughness::new(roughness).unwrap();
                    ring_albedo(
                        &Glossy::new(Distribution::Ggx, Masking::Separable, r),
                        bounds,
                    )
                });
                assert!(
                    (e / predicted - 1.0).abs() <= 0.006,
                    "{what}: plain {e}, separable GGX {predicted}"
                );
                let level = f(&fixed["mean"]) / lighting;
                assert!((level - 1.0).abs() <= 0.01, "{what}: corrected {level}");
            }
            assert!(judged >= 5, "Blender {label}: {judged} rings judged: {r:#}");
        }
    }
}

common::blender::per_blender!(eevee_view_groups_bring_every_ring_to_the_lighting);

fn cycles_groups_in_eevee_render_what_their_descriptions_say(
    label: &'static str,
    blender: PathBuf,
) {
    let (code, v) = verify(&blender, &["--coefficients", "blender-4"]);
    // Beckmann and Ashikhmin-Shirley miss by far: the check fails, as it must.
    assert_eq!(code, 1, "Blender {label}: {v:#}");
    assert_eq!(v["groups_engine"], "cycles");
    // The notes: EEVEE's lighting, then the Cycles groups with EEVEE's own preset named.
    let notes = v["notes"].as_array().unwrap();
    assert_eq!(notes.len(), 2, "Blender {label}: {notes:?}");
    assert_eq!(notes[0]["kind"], "lighting");
    assert_eq!(notes[0]["brightness"], v["lighting"]);
    assert_eq!(notes[1]["kind"], "foreign-groups");
    assert_eq!(notes[1]["groups_engine"], "cycles");
    assert_eq!(notes[1]["engine"], "eevee");
    assert_eq!(notes[1]["suggested"], "eevee");
    for d in Distribution::ALL {
        let quoted = in_eevee(d, Masking::HeightCorrelated);
        for (r, q) in rows_of(&v, d.key()).iter().zip(quoted) {
            let b = 100.0 * f(&r["brightness"]);
            // Quoted from 4.5 (Next); Legacy has no 0.8 % lighting loss.
            assert!(
                (b - q).abs() <= 1.5,
                "Blender {label} {d} r={}: renders {b:.1} %, the description says {q} %",
                r["roughness"]
            );
        }
    }
}

common::blender::per_blender!(cycles_groups_in_eevee_render_what_their_descriptions_say);

#[test]
fn refresh_in_eevee_measures_the_eevee_preset() {
    let Some((label, blender)) = common::blender::real_blenders().into_iter().last() else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("eevee.json");
    let run = common::gloffuse()
        .args([
            "refresh",
            "--json",
            "--no-provision",
            "--no-verify",
            "--engine",
            "eevee",
        ])
        .arg("--out")
        .arg(&out)
        .arg("--blender")
        .arg(&blender)
        .output()
        .unwrap();
    assert_eq!(run.status.code(), Some(0), "Blender {label}: {run:?}");
    let v: Value = serde_json::from_slice(&run.stdout).unwrap();
    assert_eq!(v["engine"], "eevee");
    let measured = gloffuse::fit::Coefficients::load(out.to_str().unwrap()).unwrap();
    let preset = gloffuse::fit::Coefficients::load("eevee").unwrap();
    for d in Distribution::ALL {
        let (m, p) = (&measured.distributions[&d], &preset.distributions[&d]);
        assert_eq!(m.engine, gloffuse::measure::Engine::Eevee);
        for i in 1..=20 {
            let r = i as f64 / 20.0;
            let ratio = m.curve.gain(r) / p.curve.gain(r);
            assert!(
                (ratio - 1.0).abs() <= 0.01,
                "Blender {label} {d} r={r}: measured gain / preset gain = {ratio}"
            );
        }
    }
}
