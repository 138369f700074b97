//! The audit inside Blender (issue 42): the extension `gloffuse generate --extension`
//! builds (in 4.5 and 5.0), or the classic add-on `--addon` builds (in 3.4, by 3.4),
//! installed as Blender installs it, gives every material of the audit's test
//! library (tests/blender/audit_library.py: rules.blend, nested.blend, unusual.blend)
//! through its operators the verdict, reason, findings and predictions `gloffuse audit
//! --no-render --json` gives on the same files (the oracle), fixes exactly what `gloffuse
//! audit --no-render --fix-dir` rewrites into exactly the trees of its fixed copies, is
//! undone by Blender's own undo, and its panels draw the verdict and every finding
//! (tests/blender/check_panel.py, one Blender run per version after the one that makes the
//! library).
//!
//! Tier: blender (needs the Blenders and tools `scripts/test.sh` installs).

mod common;

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use common::blender::{per_blender, real_blender, run_in_blender};
use serde_json::Value;

const FILES: [&str; 3] = ["rules.blend", "nested/deeper/nested.blend", "unusual.blend"];

/// What a Blender installs: the extension, built once per test process by bpy 4.5 (else
/// the Blender under test), the one zip each 4.2+ Blender installs as a user's would be;
/// before 4.2, the classic add-on built by that Blender. Returns the zip and whether it is
/// the classic add-on.
fn installable(label: &str, blender: &Path) -> (PathBuf, bool) {
    static ZIP: OnceLock<PathBuf> = OnceLock::new();
    let build = |flag: &str, builder: &Path, name: &str| {
        let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("blender-panel");
        std::fs::create_dir_all(&dir).unwrap();
        let zip = dir.join(name);
        let _ = std::fs::remove_file(&zip);
        common::gloffuse()
            .args([
                "generate",
                "--mode",
                "multiscatter,layered,anisotropic,glass",
                flag,
            ])
            .arg(&zip)
            .arg("--blender")
            .arg(builder)
            .args(["--no-provision", "--timeout", "300"])
            .assert()
            .success();
        zip
    };
    if label.starts_with("3.") {
        return (build("--addon", blender, "gloffuse-addon-3.zip"), true);
    }
    let zip = ZIP.get_or_init(|| {
        let builder = real_blender("4.5").unwrap_or_else(|| blender.to_path_buf());
        build("--extension", &builder, "gloffuse.zip")
    });
    (zip.clone(), false)
}

/// `gloffuse audit --no-render --json` on the library's files with `extra` arguments: the
/// report, written to `report`.
fn audit(blender: &Path, files: &[PathBuf], extra: &[&str], report: &Path) -> Value {
    let out = common::gloffuse()
        .args(["audit", "--json", "--no-provision", "--no-render"])
        .args(extra)
        .args(files)
        .arg("--blender")
        .arg(blender)
        .output()
        .unwrap();
    let json: Value = serde_json::from_slice(&out.stdout).unwrap_or_else(|e| {
        panic!(
            "audit {extra:?}: {e}\n{}",
            String::from_utf8_lossy(&out.stderr)
        )
    });
    std::fs::write(report, &out.stdout).unwrap();
    json
}

fn the_panel_agrees_with_the_audit(label: &'static str, blender: PathBuf) {
    let (zip, classic) = installable(label, &blender);
    let dir = tempfile::tempdir().unwrap();
    let library = dir.path().join("library");
    common::audit_library::make_library(&blender, &library, None);
    let files: Vec<PathBuf> = FILES.iter().map(|f| library.join(f)).collect();
    let oracle = dir.path().join("oracle.json");
    let report = audit(&blender, &files, &[], &oracle);
    let fixed = dir.path().join("fixed");
    let fix_report = dir.path().join("fix.json");
    let fixing = audit(
        &blender,
        &files,
        &["--fix-dir", fixed.to_str().unwrap()],
        &fix_report,
    );
    // The library holds what the issue names: a failing single-scatter glossy, a Principled
    // BSDF, a passing Multiscatter GGX, an Add Shader that creates energy.
    let verdict = |name: &str| common::audit_material(&report, name)["verdict"].clone();
    assert_eq!(verdict("glossy-ggx-r1"), "loses", "{label}");
    assert_eq!(verdict("glossy-multi-ggx-r1"), "ok", "{label}");
    assert_eq!(verdict("add-two-glossy"), "creates", "{label}");
    assert_ne!(verdict("principled-white-ggx"), "ok", "{label}");
    let rewritten = fixing["materials"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|m| m["after"]["rewritten"] == true)
        .count();
    assert!(rewritten >= 10, "{label}: the fix rewrote {rewritten}");

    let user = tempfile::tempdir().unwrap();
    let result = dir.path().join("panel.json");
    let checker = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/blender/check_panel.py");
    let mut args: Vec<&std::ffi::OsStr> = vec![
        "--zip".as_ref(),
        zip.as_os_str(),
        "--user-resources".as_ref(),
        user.path().as_os_str(),
        "--oracle".as_ref(),
        oracle.as_os_str(),
        "--fix-report".as_ref(),
        fix_report.as_os_str(),
        "--fixed-dir".as_ref(),
        fixed.as_os_str(),
        "--out".as_ref(),
        result.as_os_str(),
    ];
    if classic {
        args.push("--addon".as_ref());
    }
    args.extend(files.iter().map(|f| f.as_os_str()));
    let run = run_in_blender(&blender, checker.as_ref(), &args);
    let seen: Value = std::fs::read_to_string(&result)
        .ok()
        .and_then(|t| serde_json::from_str(&t).ok())
        .unwrap_or(Value::Null);
    assert!(
        run.status.success() && seen["failures"].as_array().is_some_and(|f| f.is_empty()),
        "Blender {label}: check_panel failed\nfailures: {:#}\nstderr:\n{}",
        seen["failures"],
        String::from_utf8_lossy(&run.stderr)
    );
    // The checks ran: every material of the report was judged by the panel, and undo ran.
    let judged: usize = seen["verdicts"].as_object().map_or(0, |v| v.len());
    assert!(judged >= 5, "{label}: {seen}");
    for (file, undo) in seen["undo"].as_object().unwrap() {
        assert_eq!(undo["undo_restored"], true, "{label} {file}");
    }
    assert_eq!(
        seen["fixed"][files[0].to_str().unwrap()]
            .as_array()
            .map(Vec::len),
        Some(rewritten_in(&fixing, "rules.blend") - 1),
        "{label}: every rewritten material of rules.blend but the undo's is fixed in the loop"
    );
}

/// How many materials of the file named `name` the fix rewrote.
fn rewritten_in(report: &Value, name: &str) -> usize {
    report["materials"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|m| m["file"].as_str().is_some_and(|f| f.ends_with(name)))
        .filter(|m| m["after"]["rewritten"] == true)
        .count()
}

per_blender!(the_panel_agrees_with_the_audit);
