//! The audit in a studio's pipeline: `--baseline` (fail only on what is new or worse than an
//! earlier report) and `--sarif` (a SARIF 2.1.0 log), on files made in each real Blender by
//! `tests/blender/baseline_materials.py`, with the rules alone (`--no-render`). The states
//! are what the test built (a material added, made worse, made better, left alone); the
//! SARIF log is checked against the SARIF 2.1.0 schema (tests/python/validate_sarif.py) and
//! against the JSON report of the same run.
//!
//! Tier: blender (needs the Blenders and tools `scripts/test.sh` installs).

mod common;

use std::ffi::OsStr;
use std::path::{Path, PathBuf};
use std::process::Command;

use serde_json::{Value, json};

use common::audit_json as audit;
use common::audit_material as material;

/// Writes `out` in `blender` with one material per entry of `materials`.
fn make_file(blender: &Path, out: &Path, materials: Value) {
    let spec = out.with_extension("json");
    std::fs::write(&spec, materials.to_string()).unwrap();
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/blender/baseline_materials.py");
    let made = common::blender::run_in_blender(
        blender,
        &script,
        &["--".as_ref(), out.as_os_str(), spec.as_os_str()],
    );
    assert!(made.status.success() && out.exists(), "{made:?}");
}

fn glossy(name: &str, roughness: f64) -> Value {
    json!({"name": name, "shader": "glossy", "roughness": roughness, "ignore": null})
}

/// A rough glossy that its own `gloffuse_ignore` waives.
fn waived(name: &str) -> Value {
    json!({"name": name, "shader": "glossy", "roughness": 0.8,
           "ignore": "glossy-single-scatter: the art director approved the look"})
}

fn diffuse(name: &str) -> Value {
    json!({"name": name, "shader": "diffuse", "roughness": 0.0, "ignore": null})
}

/// Each material's baseline state, by name.
fn states(report: &Value) -> Vec<(String, String)> {
    let mut states: Vec<(String, String)> = report["materials"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| {
            (
                m["material"].as_str().unwrap().to_string(),
                m["baseline"].as_str().unwrap_or("none").to_string(),
            )
        })
        .collect();
    states.sort();
    states
}

fn os(s: &str) -> &OsStr {
    s.as_ref()
}

/// `audit --no-render --baseline BASELINE --sarif SARIF FILE`.
fn against(blender: &Path, baseline: &Path, sarif: &Path, file: &Path) -> (i32, Value, String) {
    audit(
        blender,
        &[
            os("--no-render"),
            os("--baseline"),
            baseline.as_os_str(),
            os("--sarif"),
            sarif.as_os_str(),
            file.as_os_str(),
        ],
    )
}

fn baseline_and_sarif(label: &'static str, blender: PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let library = dir.path().join("library.blend");
    let first = [
        glossy("rough", 0.8),
        diffuse("worse-later"),
        diffuse("fine"),
        glossy("fixed-later", 0.9),
        waived("approved"),
    ];
    make_file(&blender, &library, json!(first));

    // The first audit fails (rough and fixed-later lose): it becomes the baseline.
    let (code, old, stderr) = audit(&blender, &[os("--no-render"), library.as_os_str()]);
    assert_eq!(code, 1, "{label}: {stderr}");
    let baseline = dir.path().join("baseline.json");
    std::fs::write(&baseline, old.to_string()).unwrap();

    // The same file against it: everything unchanged, so the check passes.
    let sarif = dir.path().join("same.sarif");
    let (code, same, stderr) = against(&blender, &baseline, &sarif, &library);
    assert_eq!(code, 0, "{label}: {stderr}");
    assert!(
        states(&same).iter().all(|(_, s)| s == "unchanged"),
        "{label}: {:?}",
        states(&same)
    );
    assert_eq!(material(&same, "rough")["verdict"], "loses");
    check_sarif(&sarif, &same, label);

    // A new version of the library: one material added, one made a rough glossy (worse),
    // one made a diffuse (better), the rest as they were.
    std::fs::remove_file(&library).unwrap();
    let second = [
        glossy("rough", 0.8),
        glossy("worse-later", 0.7),
        diffuse("fine"),
        diffuse("fixed-later"),
        glossy("added", 0.6),
        waived("approved"),
    ];
    make_file(&blender, &library, json!(second));
    let sarif = dir.path().join("next.sarif");
    let (code, next, stderr) = against(&blender, &baseline, &sarif, &library);
    assert_eq!(code, 1, "{label}: new and worse materials fail: {stderr}");
    assert_eq!(
        states(&next),
        [
            ("added".to_string(), "new".to_string()),
            ("approved".to_string(), "unchanged".to_string()),
            ("fine".to_string(), "unchanged".to_string()),
            ("fixed-later".to_string(), "better".to_string()),
            ("rough".to_string(), "unchanged".to_string()),
            ("worse-later".to_string(), "worse".to_string()),
        ],
        "{label}"
    );
    let summary = &next["baseline"];
    assert_eq!(
        (
            &summary["new"],
            &summary["worse"],
            &summary["better"],
            &summary["unchanged"]
        ),
        (&json!(1), &json!(1), &json!(1), &json!(3)),
        "{label}: {summary}"
    );
    // Failing materials count only when new or worse.
    assert_eq!(material(&next, "rough")["fails"], true);
    assert_eq!(next["passed"], false);
    check_sarif(&sarif, &next, label);

    // Only the unchanged failure left (two materials gone): it passes against the
    // baseline, and fails without it.
    let accepted = [glossy("rough", 0.8), diffuse("fine"), waived("approved")];
    std::fs::remove_file(&library).unwrap();
    make_file(&blender, &library, json!(accepted));
    let (code, kept, stderr) = audit(
        &blender,
        &[
            os("--no-render"),
            os("--baseline"),
            baseline.as_os_str(),
            library.as_os_str(),
        ],
    );
    assert_eq!(code, 0, "{label}: {stderr}");
    let absent: Vec<&str> = kept["baseline"]["absent"]
        .as_array()
        .unwrap()
        .iter()
        .map(|a| a.as_str().unwrap())
        .collect();
    let file = library.display().to_string();
    assert_eq!(
        absent,
        [
            format!("{file} ▸ fixed-later"),
            format!("{file} ▸ worse-later")
        ],
        "{label}"
    );
    let (code, _, _) = audit(&blender, &[os("--no-render"), library.as_os_str()]);
    assert_eq!(code, 1, "{label}: without the baseline it fails");
}

common::blender::per_blender!(baseline_and_sarif);

/// `--baseline` names a file that is no audit report: exit 2, the flag and the file named,
/// before any Blender runs.
#[test]
fn a_baseline_that_is_no_report_is_refused_by_name() {
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("old.json");
    std::fs::write(&bad, "{\"materials\": 3}").unwrap();
    let file = dir.path().join("x.blend");
    std::fs::write(&file, b"BLENDER-v304").unwrap();
    let out = common::gloffuse()
        .args(["audit", "--no-render", "--no-provision", "--blender"])
        .arg(dir.path().join("no-blender"))
        .arg("--baseline")
        .arg(&bad)
        .arg(&file)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("--baseline") && stderr.contains("old.json"),
        "{stderr}"
    );
}

/// The SARIF log at `path`, against the schema and against `report` (the JSON report of the
/// same run): every rule of the catalogue in the driver, every finding a result at its rule,
/// level, location and baseline state, a waiver a suppression.
fn check_sarif(path: &Path, report: &Value, label: &str) {
    validate(path);
    let log: Value = serde_json::from_slice(&std::fs::read(path).unwrap()).unwrap();
    assert_eq!(log["version"], "2.1.0");
    let run = &log["runs"][0];
    let rules = run["tool"]["driver"]["rules"].as_array().unwrap();
    let ids: Vec<&str> = rules.iter().map(|r| r["id"].as_str().unwrap()).collect();
    for rule in gloffuse::audit::rules::RULES {
        assert!(ids.contains(&rule.id), "{label}: {} in the driver", rule.id);
    }
    let results = run["results"].as_array().unwrap();
    for r in results {
        let index = r["ruleIndex"].as_u64().unwrap() as usize;
        assert_eq!(rules[index]["id"], r["ruleId"], "{label}: {r}");
    }
    for m in report["materials"].as_array().unwrap() {
        let name = m["material"].as_str().unwrap();
        let file = m["file"].as_str().unwrap();
        for f in m["findings"].as_array().unwrap() {
            let node = f["node"].as_str().unwrap();
            let at = format!("{file} ▸ {}", node);
            let found = results
                .iter()
                .find(|r| {
                    r["ruleId"] == f["rule"]
                        && r["locations"][0]["logicalLocations"][0]["fullyQualifiedName"] == at
                })
                .unwrap_or_else(|| panic!("{label}: {at} {} in the SARIF log", f["rule"]));
            let level = match f["severity"].as_str().unwrap() {
                "info" => "note",
                other => other,
            };
            assert_eq!(found["level"], level, "{label}: {found}");
            // A waiver is the result's suppression, with its reason; a property is in the
            // asset, a gloffuse.toml beside it.
            match f["waived"].as_object() {
                Some(w) => {
                    let s = &found["suppressions"][0];
                    assert_eq!(s["justification"], w["reason"], "{label}: {found}");
                    let kind = if w["from"] == "config" {
                        "external"
                    } else {
                        "inSource"
                    };
                    assert_eq!(s["kind"], kind, "{label}: {found}");
                }
                None => assert!(found.get("suppressions").is_none(), "{label}: {found}"),
            }
            assert_eq!(
                found["baselineState"],
                match m["baseline"].as_str() {
                    Some("new") => "new",
                    Some("unchanged") => "unchanged",
                    Some(_) => "updated",
                    None => panic!("{label}: {name} has a baseline state"),
                },
                "{label}: {found}"
            );
            assert_eq!(
                found["locations"][0]["physicalLocation"]["artifactLocation"]["uri"]
                    .as_str()
                    .unwrap()
                    .trim_start_matches('/'),
                file.trim_start_matches('/'),
                "{label}: a temporary path has no character to escape"
            );
        }
        let verdict = m["verdict"].as_str().unwrap();
        let verdicts = results
            .iter()
            .filter(|r| {
                r["ruleId"].as_str().unwrap().starts_with("verdict-")
                    && r["locations"][0]["logicalLocations"][0]["fullyQualifiedName"]
                        == format!("{file} ▸ {name}")
            })
            .count();
        assert_eq!(verdicts, usize::from(verdict != "ok"), "{label}: {name}");
    }
}

/// Runs the schema check; without its Python, fails unless `GLOFFUSE_SKIP_SARIF_TESTS=1`.
fn validate(path: &Path) {
    let Some(python) =
        std::env::var_os("GLOFFUSE_TEST_SARIF_PYTHON").filter(|p| Path::new(p).exists())
    else {
        common::skip(
            "GLOFFUSE_SKIP_SARIF_TESTS",
            "SARIF schema: GLOFFUSE_TEST_SARIF_PYTHON is not set (scripts/test.sh installs it)",
        );
        return;
    };
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/python/validate_sarif.py");
    let out = Command::new(python).arg(script).arg(path).output().unwrap();
    assert!(
        out.status.success(),
        "{}: {}{}",
        path.display(),
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
}
