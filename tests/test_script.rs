//! `scripts/test.sh` on a fresh machine (issue 20, case 17): its steps, sourced and run one
//! by one in a temporary environment (never the whole suite, never the real caches).
//! Not tested here: installing python3-venv or Debian's blender with apt-get (that needs a
//! machine without them, and root).
//!
//! Tier: blender (needs the Blenders and tools `scripts/test.sh` installs).

mod common;

use std::path::{Path, PathBuf};
use std::process::Output;

fn script() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/test.sh")
}

/// `bash -c 'source scripts/test.sh; BODY'` with `env`; the output.
fn run(body: &str, env: &[(&str, &Path)]) -> Output {
    let mut cmd = std::process::Command::new("/bin/bash");
    cmd.arg("-c")
        .arg(format!("source \"$1\"; {body}"))
        .arg("test-steps")
        .arg(script())
        .env_remove("GLOFFUSE_TEST_BLENDER_34")
        .env_remove("GLOFFUSE_TEST_CACHE")
        // Any download attempt fails instead of fetching 400 MB.
        .env("PIP_NO_INDEX", "1");
    for (k, v) in env {
        cmd.env(k, v);
    }
    cmd.output().unwrap()
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

#[test]
fn a_blender_on_path_that_is_not_3_4_is_not_used() {
    let (Some(b34), Some(bpy50)) = (
        common::blender::real_blender("3.4"),
        common::blender::real_blender("5.0"),
    ) else {
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    // A `blender` on PATH that is not 3.4 (the real bpy 5.0's Python, under that name).
    std::os::unix::fs::symlink(&bpy50, tmp.path().join("blender")).unwrap();
    let path = format!("{}:/usr/bin:/bin", tmp.path().display());
    let out = run(
        "find_blender_34; echo \"BLENDER $blender34\"",
        &[("PATH", Path::new(&path))],
    );
    let (stdout, stderr) = (text(&out.stdout), text(&out.stderr));
    assert!(out.status.success(), "{stderr}");
    assert!(
        stderr.contains(&format!("not using {}/blender", tmp.path().display())),
        "{stderr}"
    );
    // Debian's 3.4 is used instead (the suite's 3.4 is Debian's /usr/bin/blender).
    assert_eq!(b34, Path::new("/usr/bin/blender"));
    assert!(stdout.contains("BLENDER /usr/bin/blender"), "{stdout}");
}

#[test]
fn a_python_that_is_not_3_11_is_refused_clearly() {
    let tmp = tempfile::tempdir().unwrap();
    // A python3 that reports 3.12 (a stand-in interpreter, no Blender involved).
    let fake = tmp.path().join("python3");
    std::fs::write(&fake, "#!/bin/sh\necho 3.12\n").unwrap();
    std::fs::set_permissions(&fake, std::os::unix::fs::PermissionsExt::from_mode(0o755)).unwrap();
    let out = run("find_python", &[("PATH", tmp.path())]);
    let stderr = text(&out.stderr);
    assert!(!out.status.success());
    assert!(
        stderr.contains("is Python 3.12, but the bpy wheels exist for CPython 3.11 only"),
        "{stderr}"
    );
    // The real one passes.
    let out = run("find_python; echo \"PY $python\"", &[]);
    assert!(out.status.success(), "{}", text(&out.stderr));
}

#[test]
fn bpy_4_5_is_shared_with_gloffuse_not_downloaded_twice() {
    let Some(bpy45) = common::blender::real_blender("4.5") else {
        return;
    };
    let venv = bpy45
        .parent()
        .unwrap()
        .parent()
        .unwrap()
        .canonicalize()
        .unwrap();
    // gloffuse's own install exists (here: a link to the suite's real one); the suite's
    // does not: the suite's becomes a link to gloffuse's, twice over, with no install.
    let tmp = tempfile::tempdir().unwrap();
    let main = tmp.path().join("gloffuse/bpy-4.5");
    std::fs::create_dir_all(main.parent().unwrap()).unwrap();
    std::os::unix::fs::symlink(&venv, &main).unwrap();
    let env = [("XDG_CACHE_HOME", tmp.path())];
    for _ in 0..2 {
        let out = run("find_python; mkdir -p \"$cache\"; share_bpy_45", &env);
        let (stdout, stderr) = (text(&out.stdout), text(&out.stderr));
        assert!(out.status.success(), "{stdout}{stderr}");
        assert!(!stdout.contains("installing"), "{stdout}");
        let test = tmp.path().join("gloffuse/test-blenders/bpy-4.5");
        assert_eq!(std::fs::read_link(&test).unwrap(), main);
    }
    // The reverse: only the suite's exists; gloffuse's becomes a link to it.
    let tmp = tempfile::tempdir().unwrap();
    let test = tmp.path().join("gloffuse/test-blenders/bpy-4.5");
    std::fs::create_dir_all(test.parent().unwrap()).unwrap();
    std::os::unix::fs::symlink(&venv, &test).unwrap();
    let out = run(
        "find_python; share_bpy_45",
        &[("XDG_CACHE_HOME", tmp.path())],
    );
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(!text(&out.stdout).contains("installing"));
    let main = tmp.path().join("gloffuse/bpy-4.5");
    assert_eq!(std::fs::read_link(&main).unwrap(), venv);
    assert_eq!(std::fs::read_link(&test).unwrap(), venv);
}

/// `cargo_test` runs every test file even after a failure (`--no-fail-fast`), hands cargo a
/// fresh `$GLOFFUSE_TEST_SKIPS` file, lists what the tests wrote into it after cargo's own
/// summary (which counts a skip as `ok`), removes it, and returns cargo's exit status
/// unchanged; with no skips it adds nothing. (A stand-in `cargo` writes the lines
/// `common::skip` writes.)
#[test]
fn the_summary_lists_the_skipped_tests_and_keeps_cargos_status() {
    let tmp = tempfile::tempdir().unwrap();
    let env = [("TMPDIR", tmp.path())];
    let skipping = r#"cargo() {
        echo "ARGS $*"
        echo "verify_e2e::sweeps::in_blender_5_0: Blender 5.0: /nope not found" >>"$GLOFFUSE_TEST_SKIPS"
        echo "python_lint::lint: ruff: GLOFFUSE_TEST_RUFF is not set" >>"$GLOFFUSE_TEST_SKIPS"
        return 101
    }
    cargo_test --locked --test verify_e2e || echo "STATUS $?""#;
    let out = run(skipping, &env);
    let stdout = text(&out.stdout);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(
        stdout.contains("ARGS test --no-fail-fast --locked --test verify_e2e\n"),
        "{stdout}"
    );
    let summary = stdout
        .split_once("== skipped: 2 tests")
        .unwrap_or_else(|| panic!("no summary: {stdout}"))
        .1;
    let lines: Vec<&str> = summary.lines().skip(1).map(str::trim).collect();
    assert_eq!(
        lines,
        [
            "python_lint::lint: ruff: GLOFFUSE_TEST_RUFF is not set",
            "verify_e2e::sweeps::in_blender_5_0: Blender 5.0: /nope not found",
            "STATUS 101",
        ],
        "{stdout}"
    );
    assert_eq!(
        std::fs::read_dir(tmp.path()).unwrap().count(),
        0,
        "left behind"
    );

    let out = run("cargo() { :; }; cargo_test; echo \"STATUS $?\"", &env);
    assert_eq!(text(&out.stdout), "STATUS 0\n");
}
