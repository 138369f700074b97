//! Processes that end when their work ends, in real Blender 3.4, bpy 4.5 and bpy 5.0, and
//! exit codes that tell the truth (src/cli/mod.rs has the rules):
//!
//! - a file with a Python-evaluated driver does not keep Blender alive after its job;
//! - success is the exit status and the result line: a folder named like a traceback in
//!   every path does not fail a run;
//! - SIGTERM and SIGHUP stop Blender like Ctrl-C: exit 128 + the signal, the user's file
//!   byte-identical, no temporary file beside it;
//! - a closed stdout keeps the verdict: a failing `verify` still exits 1, a passing one 0.
//!
//! Tier: blender (needs the Blenders and tools `scripts/test.sh` installs).

mod common;

use std::fs;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

/// Saves a .blend with a cube whose X location is driven by a Python expression (a
/// scripted driver, evaluated by Python at every frame change) as `sys.argv`'s last item.
const DRIVEN_BLEND: &str = r#"
import os
import sys

import bpy

bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.mesh.primitive_cube_add()
curve = bpy.context.object.driver_add("location", 0)
curve.driver.type = "SCRIPTED"
curve.driver.expression = "[0.1, 0.2][0] * frame"
bpy.ops.wm.save_as_mainfile(filepath=sys.argv[-1])
sys.stdout.flush()
if not bpy.app.binary_path:
    # This very file would hang bpy 4.5 at exit: the case under test.
    os._exit(0)
"#;

/// A .blend with a Python driver at `path`, saved by `blender` itself.
fn driven_blend(blender: &Path, path: &Path) {
    let script = path.with_extension("py");
    fs::write(&script, DRIVEN_BLEND).unwrap();
    let out = common::blender::run_in_blender(blender, &script, &[path.as_os_str()]);
    assert!(
        out.status.success() && path.is_file(),
        "making {}: {}",
        path.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    fs::remove_file(script).unwrap();
}

/// `gloffuse generate --into FILE` in `blender`, with the cache in `cache`.
fn generate_into(blender: &Path, file: &Path, cache: &Path) -> Command {
    let mut cmd = Command::new(assert_cmd::cargo::cargo_bin("gloffuse"));
    cmd.arg("generate")
        .arg("--into")
        .arg(file)
        .arg("--blender")
        .arg(blender)
        .args(["--no-provision", "--timeout", "60"])
        .env("XDG_CACHE_HOME", cache)
        .env_remove("GLOFFUSE_BLENDER");
    cmd
}

fn text(out: &Output) -> String {
    format!(
        "{}\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    )
}

/// Files beside `file` whose names start with `.gloffuse-` (the temporary saves).
fn temporaries_beside(file: &Path) -> Vec<String> {
    fs::read_dir(file.parent().unwrap())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with(".gloffuse-"))
        .collect()
}

/// Case 2: bpy 4.5 used to save the file, print its result and then hang at interpreter
/// exit until the timeout (600 s by default). Every Blender must finish well inside the
/// 60 s timeout, exit 0, and leave the file changed with its backup beside it.
fn a_python_driver_does_not_keep_blender_alive(label: &'static str, blender: PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("driven.blend");
    driven_blend(&blender, &file);
    let before = fs::read(&file).unwrap();
    let start = Instant::now();
    let out = generate_into(&blender, &file, &dir.path().join("cache"))
        .output()
        .unwrap();
    let took = start.elapsed();
    assert_eq!(
        out.status.code(),
        Some(0),
        "Blender {label}: {}",
        text(&out)
    );
    assert!(took < Duration::from_secs(30), "Blender {label}: {took:?}");
    assert_ne!(fs::read(&file).unwrap(), before, "Blender {label}");
    assert!(temporaries_beside(&file).is_empty(), "Blender {label}");
}

common::blender::per_blender!(a_python_driver_does_not_keep_blender_alive);

/// Case 14: a folder named `Traceback (most recent call last):` holding the cache (so the
/// script, its log and every path Blender prints) and the file does not fail the run: the
/// log shows the words, and the run still succeeds by its exit status and result line. (A
/// real exception in a job still fails, its traceback quoted: tests/blender_runner.rs,
/// `real_*`.)
fn a_folder_named_like_a_traceback_does_not_fail_a_run(label: &'static str, blender: PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let odd = dir.path().join("Traceback (most recent call last):");
    fs::create_dir(&odd).unwrap();
    let file = odd.join("Error: scene.blend");
    driven_blend(&blender, &file);
    let cache = odd.join("cache");
    let out = generate_into(&blender, &file, &cache).output().unwrap();
    assert_eq!(
        out.status.code(),
        Some(0),
        "Blender {label}: {}",
        text(&out)
    );
    let runs: Vec<PathBuf> = fs::read_dir(cache.join("gloffuse/runs"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    assert_eq!(runs.len(), 1, "{runs:?}");
    let log = fs::read_to_string(runs[0].join("blender.log")).unwrap();
    assert!(
        log.contains("Traceback (most recent call last)"),
        "Blender {label}: the log should name the folder:\n{log}"
    );
}

common::blender::per_blender!(a_folder_named_like_a_traceback_does_not_fail_a_run);

/// The child of `pid` running the generate script (not a version probe), if any (Linux).
fn script_child(pid: u32) -> Option<u32> {
    fs::read_to_string(format!("/proc/{pid}/task/{pid}/children"))
        .unwrap_or_default()
        .split_whitespace()
        .filter_map(|p| p.parse().ok())
        .find(|child: &u32| {
            fs::read(format!("/proc/{child}/cmdline"))
                .is_ok_and(|c| String::from_utf8_lossy(&c).contains("gloffuse-generate.py"))
        })
}

/// Case 12: SIGTERM (`timeout`, a CI cancel) and SIGHUP while Blender works on the user's
/// file: gloffuse stops Blender (its whole process group), exits 128 + the signal, and the
/// file is byte-identical, with neither a backup nor a temporary file beside it.
fn sigterm_and_sighup_stop_blender_and_leave_the_file_alone(label: &'static str, blender: PathBuf) {
    for (signal, code) in [(libc::SIGTERM, 143), (libc::SIGHUP, 129)] {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("scene.blend");
        driven_blend(&blender, &file);
        let before = fs::read(&file).unwrap();
        let child = generate_into(&blender, &file, &dir.path().join("cache"))
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let pid = child.id();
        let deadline = Instant::now() + Duration::from_secs(30);
        let blender_pid = loop {
            if let Some(p) = script_child(pid) {
                break p;
            }
            assert!(Instant::now() < deadline, "Blender {label} never started");
            std::thread::sleep(Duration::from_millis(20));
        };
        // Freeze Blender mid-run so the signal cannot lose a race with a fast job (a
        // 400 ms pause once let bpy 4.5 finish first on CI); gloffuse must still stop
        // a stopped group.
        // SAFETY: killpg only sends a signal to the group of the Blender we found.
        assert_eq!(
            unsafe { libc::killpg(blender_pid as libc::pid_t, libc::SIGSTOP) },
            0,
            "Blender {label} ended before it could be frozen"
        );
        // SAFETY: kill only sends a signal to the child we spawned.
        assert_eq!(unsafe { libc::kill(pid as libc::pid_t, signal) }, 0);
        let out = child.wait_with_output().unwrap();
        let what = format!("Blender {label}, signal {signal}: {}", text(&out));
        assert_eq!(out.status.code(), Some(code), "{what}");
        assert!(text(&out).contains("interrupted"), "{what}");
        assert_eq!(fs::read(&file).unwrap(), before, "{what}");
        assert!(temporaries_beside(&file).is_empty(), "{what}");
        assert!(!dir.path().join("scene.blend1").exists(), "{what}");
        // SAFETY: signal 0 only asks whether the process group exists.
        let alive = unsafe { libc::killpg(blender_pid as libc::pid_t, 0) } == 0;
        assert!(!alive, "{what}: Blender's group outlived gloffuse");
    }
}

common::blender::per_blender!(sigterm_and_sighup_stop_blender_and_leave_the_file_alone: in_blender_3_4, in_blender_4_5);

/// `gloffuse ARGS` with a stdout whose reader is already gone (`… | true`): its exit code.
fn with_closed_stdout(args: &[&str], blender: &Path) -> (i32, String) {
    use std::os::fd::{FromRawFd, OwnedFd};
    let mut fds = [0; 2];
    // SAFETY: pipe() fills two new descriptors; each is owned exactly once below.
    assert_eq!(unsafe { libc::pipe(fds.as_mut_ptr()) }, 0);
    let (reader, writer) = unsafe { (OwnedFd::from_raw_fd(fds[0]), OwnedFd::from_raw_fd(fds[1])) };
    drop(reader);
    let out = Command::new(assert_cmd::cargo::cargo_bin("gloffuse"))
        .args(args)
        .arg("--blender")
        .arg(blender)
        .arg("--no-provision")
        .stdout(writer)
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// A small, fast verify sweep; with the seed coefficients GGX at r = 1 is 69 %: a failure
/// (4 samples are plenty for that); with the defaults it passes.
const FAILING: [&str; 10] = [
    "verify",
    "--coefficients",
    "seed",
    "-r",
    "1",
    "-d",
    "ggx",
    "--spp",
    "4",
    "--json",
];
const PASSING: [&str; 6] = ["verify", "-r", "1", "-d", "ggx", "--json"];

/// Case 3 for `refresh`: a closed stdout does not turn its verdict into an error (its
/// passing run, the 32 samples on 64 px spheres of tests/verify_e2e.rs, still exits 0). A
/// failing refresh cannot be made on purpose (its renders are not repeatable enough to fail
/// every time); its verdict takes the same path as verify's, tested below.
#[test]
fn a_closed_stdout_keeps_the_refresh_verdict() {
    let Some(blender) = common::blender::real_blender("4.5") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("measured.json");
    let args = [
        "refresh",
        "--json",
        "--spp",
        "32",
        "--out",
        out.to_str().unwrap(),
    ];
    let (code, stderr) = with_closed_stdout(&args, &blender);
    assert_eq!(code, 0, "{stderr}");
    assert!(!stderr.contains("standard output"), "{stderr}");
    assert!(out.is_file(), "{stderr}");
}

/// Case 3: the verdict survives a closed stdout (`| true`, and `| head -1` / `grep -q` under
/// pipefail in a real shell): a failing verify exits 1, a passing one 0, and nothing about
/// standard output is printed as an error.
#[test]
fn a_closed_stdout_keeps_the_verdict() {
    let Some(blender) = common::blender::real_blender("4.5") else {
        return;
    };
    for (args, code) in [(&FAILING[..], 1), (&PASSING[..], 0)] {
        let (got, stderr) = with_closed_stdout(args, &blender);
        assert_eq!(got, code, "{args:?}: {stderr}");
        assert!(!stderr.contains("standard output"), "{args:?}: {stderr}");
        for tail in ["head -1", "grep -q ."] {
            let line = format!(
                "set -o pipefail; \"$0\" {} --blender \"$1\" --no-provision | {tail}",
                args.join(" ")
            );
            let out = Command::new("bash")
                .arg("-c")
                .arg(&line)
                .arg(assert_cmd::cargo::cargo_bin("gloffuse"))
                .arg(&blender)
                .output()
                .unwrap();
            assert_eq!(out.status.code(), Some(code), "{line}: {}", text(&out));
        }
    }
}
