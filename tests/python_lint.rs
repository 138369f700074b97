//! ruff on the Blender-side Python: the package `blender/gloffuse_blender/`, the tests'
//! Blender scripts in `tests/blender/`, the tests' plain Python in `tests/python/`, and
//! every single-file script the bundler makes (a job's, and the material test's), so that
//! no module and no bundle uses a name it does not define or import (ruff's F821; nothing
//! suppresses it, see `ruff.toml`).
//!
//! ruff comes from `$GLOFFUSE_TEST_RUFF`, which `scripts/test.sh` sets after installing
//! ruff from PyPI. Unset, the test fails, unless `GLOFFUSE_SKIP_RUFF_TESTS=1` is set:
//! then it records the skip (`common::skip`) and passes.
//!
//! Tier: fast (no Blender; `scripts/test.sh --fast` runs it).

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

use gloffuse::generate::{Job, assemble, assemble_with_main};

/// Set to `1` to skip the lint when ruff is not installed.
const SKIP_VAR: &str = "GLOFFUSE_SKIP_RUFF_TESTS";
const RUFF_VAR: &str = "GLOFFUSE_TEST_RUFF";

fn ruff() -> Option<PathBuf> {
    let why = match std::env::var_os(RUFF_VAR) {
        Some(path) if Path::new(&path).exists() => return Some(path.into()),
        Some(path) => format!("ruff: {} not found", Path::new(&path).display()),
        None => format!("ruff: {RUFF_VAR} is not set (run scripts/test.sh, which installs it)"),
    };
    common::skip(
        SKIP_VAR,
        &format!(
            "{why}; not checked: blender/, tests/blender/, tests/python/ and the bundled scripts"
        ),
    );
    None
}

fn check(ruff: &Path, extra: &[&str], paths: &[PathBuf]) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let out = Command::new(ruff)
        .current_dir(root)
        .args(["check", "--no-cache", "--config"])
        .arg(root.join("ruff.toml"))
        .args(extra)
        .args(paths)
        .output()
        .expect("ruff runs");
    assert!(
        out.status.success(),
        "ruff check {paths:?}:\n{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn the_package_and_the_test_scripts_pass_ruff() {
    let Some(ruff) = ruff() else { return };
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    check(
        &ruff,
        &[],
        &[
            root.join("blender"),
            root.join("tests/blender"),
            root.join("tests/python"),
        ],
    );
}

#[test]
fn every_bundled_script_passes_ruff() {
    let Some(ruff) = ruff() else { return };
    let dir = tempfile::tempdir().unwrap();
    let document = serde_json::json!({"groups": []});
    let scripts = [
        ("generate.py", assemble(&document, Job::Generate)),
        ("furnace.py", assemble(&document, Job::Furnace)),
        ("audit.py", assemble(&document, Job::Audit)),
        ("bench_library.py", assemble(&document, Job::BenchLibrary)),
        (
            "material_scene.py",
            assemble_with_main(
                &document,
                "material_scene.py",
                include_str!("blender/material_scene.py"),
            )
            .unwrap(),
        ),
    ];
    let mut paths = Vec::new();
    for (name, text) in scripts {
        let path = dir.path().join(name);
        std::fs::write(&path, text).unwrap();
        paths.push(path);
    }
    // A bundle imports where each of its modules did, below the code of the modules
    // before it (E402); everything else holds as in the package.
    check(&ruff, &["--extend-ignore", "E402"], &paths);
}
