//! Finding the real Blenders the end-to-end tests run in, and running a script in one.
//!
//! Each Blender comes from an environment variable that `scripts/test.sh` sets, else from
//! where that script installs it. A missing one fails the test, unless
//! `GLOFFUSE_SKIP_BLENDER_TESTS=1` is set: then the test says what it skipped and passes.

use std::path::{Path, PathBuf};

use gloffuse::blender::{Run, probe, run};

/// Set to `1` to skip the tests that need a real Blender (each says what it skipped).
pub const SKIP_VAR: &str = "GLOFFUSE_SKIP_BLENDER_TESTS";

/// Where `scripts/test.sh` installs the bpy wheels: `$GLOFFUSE_TEST_CACHE`, else
/// `${XDG_CACHE_HOME:-$HOME/.cache}/gloffuse/test-blenders`.
fn test_cache() -> PathBuf {
    if let Some(dir) = std::env::var_os("GLOFFUSE_TEST_CACHE") {
        return dir.into();
    }
    let cache = std::env::var_os("XDG_CACHE_HOME")
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| Path::new(&h).join(".cache")))
        .unwrap_or_else(|| PathBuf::from("/nonexistent"));
    cache.join("gloffuse").join("test-blenders")
}

/// The real Blenders, as (label, program): 3.4 (Debian's binary), bpy 4.5 and bpy 5.0.
pub fn real_blenders() -> Vec<(&'static str, PathBuf)> {
    let cache = test_cache();
    let known = [
        (
            "3.4",
            "GLOFFUSE_TEST_BLENDER_34",
            PathBuf::from("/usr/bin/blender"),
        ),
        (
            "4.5",
            "GLOFFUSE_TEST_BPY_45",
            cache.join("bpy-4.5/bin/python"),
        ),
        (
            "5.0",
            "GLOFFUSE_TEST_BPY_50",
            cache.join("bpy-5.0/bin/python"),
        ),
    ];
    let skip = std::env::var_os(SKIP_VAR).is_some_and(|v| v == "1");
    let mut found = Vec::new();
    for (label, var, default) in known {
        let path = std::env::var_os(var).map_or(default, PathBuf::from);
        if path.exists() {
            found.push((label, path));
            continue;
        }
        let why = format!(
            "Blender {label}: {} not found (set {var}, or run scripts/test.sh)",
            path.display()
        );
        assert!(
            skip,
            "{why}; set {SKIP_VAR}=1 to skip the tests that need it"
        );
        eprintln!("skipped ({SKIP_VAR}=1): {why}");
    }
    found
}

/// The real Blender labelled `label` (`"3.4"`, `"4.5"`, `"5.0"`), under the rules of
/// [`real_blenders`]: `None` only when it is missing and skipping was asked for.
pub fn real_blender(label: &str) -> Option<PathBuf> {
    real_blenders()
        .into_iter()
        .find(|(l, _)| *l == label)
        .map(|(_, path)| path)
}

/// Runs a Python file inside `blender` (an executable or a bpy Python) with script args,
/// with the command line gloffuse itself uses (the library builds it).
pub fn run_in_blender(
    blender: &Path,
    script: &Path,
    args: &[&std::ffi::OsStr],
) -> std::process::Output {
    let blender = probe(blender).expect("a working Blender");
    let argv = run::argv(&Run {
        blender: &blender,
        script,
        args: args.iter().map(|a| a.to_os_string()).collect(),
        timeout: std::time::Duration::from_secs(600),
        cancel: Default::default(),
        log: PathBuf::new(),
    });
    std::process::Command::new(&argv[0])
        .args(&argv[1..])
        .output()
        .expect("Blender starts")
}

/// Runs `tests/blender/<script>` with the cases `request` asks for in the real Blender
/// `label` (the script writes `{"renders": [[R of every pixel, bottom row first], …]}`):
/// each render's `px × px` pixels; none when that Blender is missing and skipping was asked
/// for.
pub fn render_cases(
    label: &str,
    script: &str,
    request: &serde_json::Value,
    px: usize,
) -> Option<Vec<Vec<f64>>> {
    let blender = real_blender(label)?;
    let dir = tempfile::tempdir().unwrap();
    let (request_path, out) = (dir.path().join("cases.json"), dir.path().join("out.json"));
    std::fs::write(&request_path, request.to_string()).unwrap();
    let script = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/blender")
        .join(script);
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
    let renders: Vec<Vec<f64>> = result["renders"]
        .as_array()
        .unwrap()
        .iter()
        .map(|render| {
            render
                .as_array()
                .unwrap()
                .iter()
                .map(|v| v.as_f64().unwrap())
                .collect()
        })
        .collect();
    assert!(renders.iter().all(|pixels| pixels.len() == px * px));
    Some(renders)
}
