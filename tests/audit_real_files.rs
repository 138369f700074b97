//! `gloffuse audit` on materials built the way real files build them (textured by UV, a
//! named UV map, UV-tangent anisotropy, generated and position-dependent coordinates, glass
//! and an absorbing volume, transparency, Add layering, a partly metallic Principled BSDF),
//! judged by a second furnace written in the test (`tests/blender/real_probes.py`, none of
//! gloffuse's code): a closed radius-1 UV sphere seen from the front on an opaque film.
//! One test per Blender, so a failure in one does not hide the others.
//!
//! Each test checks: the audit's mean agrees with the second furnace within 2 points (but
//! for a material that reads its place in the world); its verdict is the one physics expects
//! (or, where the probe leaves it open, the second furnace's); the rules the probe needs are
//! reported; a material invisible everywhere is not judged; and after `--fix` the second
//! furnace, run on the fixed copy, finds every fixed material at 100 % and every untouched
//! one unchanged, and a probe that has a conserving twin in every Blender is fixed.
//!
//! Tier: blender (needs the Blenders and tools `scripts/test.sh` installs).

mod common;

use std::path::Path;

use serde_json::Value;

use common::audit_json as audit;
use common::blender::{real_blender, run_in_blender};

/// Points of brightness (in 1.0 = 100 %) the audit and the second furnace may differ by.
const AGREE: f64 = 0.02;
/// Where a probe leaves its verdict open, the second furnace decides: above 100 % by more
/// than this creates energy; anything else is ok (a material darker than 100 % loses only
/// against a twin, and a probe whose lobes lose says so itself).
const ABOVE: f64 = 0.01;

fn probes_script() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/blender/real_probes.py")
}

fn run_probes(blender: &Path, label: &str, args: &[&str]) {
    let args: Vec<&std::ffi::OsStr> = args.iter().map(std::ffi::OsStr::new).collect();
    let out = run_in_blender(blender, &probes_script(), &args);
    assert!(
        out.status.success(),
        "Blender {label}: real_probes.py {args:?} failed\n{}\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
}

/// The second furnace's mean of every material of `file`.
fn second_furnace(blender: &Path, label: &str, file: &Path, out: &Path) -> Value {
    run_probes(
        blender,
        label,
        &[
            "furnace",
            "--file",
            file.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ],
    );
    let result: Value = serde_json::from_str(&std::fs::read_to_string(out).unwrap()).unwrap();
    for (name, m) in result.as_object().unwrap() {
        let world = m["world"].as_f64().unwrap();
        assert!(
            (world - 1.0).abs() < 1e-3,
            "Blender {label}: the second furnace's world reads {world} around {name}, not 1"
        );
    }
    result
}

fn mean_of(furnace: &Value, name: &str) -> f64 {
    furnace[name]["mean"]
        .as_f64()
        .unwrap_or_else(|| panic!("the second furnace has no {name}"))
}

fn verdict_from(mean: f64) -> &'static str {
    if mean > 1.0 + ABOVE { "creates" } else { "ok" }
}

fn real_files(label: &str) {
    let Some(blender) = real_blender(label) else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let made = dir.path().join("made");
    run_probes(&blender, label, &["make", "--out", made.to_str().unwrap()]);
    let file = made.join("probes.blend");
    let probes: Value =
        serde_json::from_str(&std::fs::read_to_string(made.join("probes.json")).unwrap()).unwrap();
    let before = second_furnace(&blender, label, &file, &dir.path().join("before.json"));

    let fixed = dir.path().join("probes-fixed.blend");
    let (code, report, stderr) = audit(
        &blender,
        &["--fix".as_ref(), fixed.as_os_str(), file.as_os_str()],
    );
    assert!(
        report.is_object(),
        "Blender {label}: no JSON report (exit {code})\n{stderr}"
    );
    let after = second_furnace(&blender, label, &fixed, &dir.path().join("after.json"));

    let materials = report["materials"].as_array().unwrap();
    let expected = probes["materials"].as_object().unwrap();
    assert_eq!(
        materials.len(),
        expected.len(),
        "Blender {label}: the report's materials: {materials:#?}"
    );
    for m in materials {
        let name = m["material"].as_str().unwrap();
        let want = &expected[name];
        check_material(
            label,
            m,
            want,
            mean_of(&before, name),
            mean_of(&after, name),
        );
    }
}

fn check_material(label: &str, m: &Value, want: &Value, second: f64, second_after: f64) {
    let name = m["material"].as_str().unwrap();
    let what = format!("Blender {label}, {name} ({})", m["reason"]);
    let mean = m["mean"].as_f64();
    if want["verdict"] == "not judged" {
        assert_eq!(m["verdict"], "ok", "{what}");
        assert!(
            m["reason"].as_str().unwrap().contains("not judged"),
            "{what}: an invisible material is reported, not judged"
        );
        return;
    }
    let mean = mean.unwrap_or_else(|| panic!("{what}: not rendered"));
    if want["position"] != true {
        assert!(
            (mean - second).abs() <= AGREE,
            "{what}: the audit's mean {mean:.4} is not the second furnace's {second:.4}"
        );
    }
    let verdict = want["verdict"]
        .as_str()
        .unwrap_or_else(|| verdict_from(second));
    assert_eq!(
        m["verdict"], verdict,
        "{what}: the second furnace reads {second:.4}"
    );
    let found: Vec<&str> = m["findings"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f["rule"].as_str().unwrap())
        .collect();
    for rule in want["rules"].as_array().unwrap() {
        assert!(
            found.contains(&rule.as_str().unwrap()),
            "{what}: {rule} is not among its findings {found:?}"
        );
    }
    let position = want["position"] == true;
    if want["fixed"] == true {
        assert_eq!(
            m["after"]["rewritten"], true,
            "{what}: a conserving twin exists, yet the fix left it alone ({})",
            m["no_fix"]
        );
    }
    check_fix(&what, m, verdict, position, (second, second_after));
}

/// A fix is never worse: a rewritten material reads, in the second furnace, what the audit
/// measured its twin at, and nearer 100 % than before; one left alone reads what it read
/// before (and a failing one left alone says why).
fn check_fix(what: &str, m: &Value, verdict: &str, position: bool, second: (f64, f64)) {
    let (second, second_after) = second;
    if m["after"]["rewritten"] != true {
        assert!(
            (second_after - second).abs() <= AGREE,
            "{what}: not rewritten, yet the second furnace reads {second_after:.4} after, \
             {second:.4} before"
        );
        if verdict != "ok" {
            assert!(
                m["no_fix"].is_string(),
                "{what}: a failing material left unfixed says why"
            );
        }
        return;
    }
    assert_ne!(verdict, "ok", "{what}: a material judged ok was rewritten");
    if position {
        return;
    }
    let after = m["after"]["mean"].as_f64().unwrap();
    assert!(
        (after - second_after).abs() <= AGREE,
        "{what}: the audit's after {after:.4} is not the second furnace's {second_after:.4}"
    );
    // An Add Shader that creates is scaled by its own brightness, so it has no twin to read.
    let twin = m["twin_mean"]
        .as_f64()
        .filter(|t| *t <= 1.0 + ABOVE)
        .unwrap_or(1.0);
    assert!(
        (second_after - twin).abs() <= AGREE,
        "{what}: rewritten, the second furnace reads {second_after:.4}, not its twin's {twin:.4}"
    );
    assert!(
        (second_after - 1.0).abs() < (second - 1.0).abs(),
        "{what}: rewritten, the second furnace reads {second_after:.4}, no nearer 100 % than \
         {second:.4} before"
    );
}

#[test]
fn real_materials_in_blender_3_4() {
    real_files("3.4");
}

#[test]
fn real_materials_in_blender_4_5() {
    real_files("4.5");
}

#[test]
fn real_materials_in_blender_5_0() {
    real_files("5.0");
}
