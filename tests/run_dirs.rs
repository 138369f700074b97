//! Run folders under the shared cache (issue 20, case 10): pruning keeps the newest
//! `KEEP`, removes older ones whose process has ended, and never touches a live run — a
//! real `gloffuse verify` rendering in real Blender 3.4 while 25 newer runs are made.
//!
//! Tier: blender (needs the Blenders and tools `scripts/test.sh` installs).

mod common;

use std::fs;
use std::path::{Path, PathBuf};
use std::process::Stdio;
use std::time::{Duration, Instant, SystemTime};

use gloffuse::blender::runs::{KEEP, LOCK_FILE, new_run_dir_in};

/// The run folders under `root` (hidden ones are not runs).
fn runs(root: &Path) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = fs::read_dir(root)
        .unwrap()
        .flatten()
        .filter(|e| !e.file_name().to_string_lossy().starts_with('.'))
        .map(|e| e.path())
        .collect();
    v.sort();
    v
}

/// Sets a folder's modification time `age` into the past, so it sorts as an old run.
fn backdate(dir: &Path, age: Duration) {
    fs::File::open(dir)
        .unwrap()
        .set_modified(SystemTime::now() - age)
        .unwrap();
}

/// Old runs whose process has ended: one with its lock file (nobody holds it), one from an
/// older gloffuse without one.
fn dead_runs(root: &Path) -> Vec<PathBuf> {
    let with_lock = root.join("verify-dead-with-lock");
    let without = root.join("generate-dead-without-lock");
    for d in [&with_lock, &without] {
        fs::create_dir_all(d).unwrap();
        fs::write(d.join("blender.log"), "old").unwrap();
    }
    fs::write(with_lock.join(LOCK_FILE), "").unwrap();
    for d in [&with_lock, &without] {
        backdate(d, Duration::from_secs(7200));
    }
    vec![with_lock, without]
}

const HELPER_ROOT: &str = "GLOFFUSE_TEST_RUN_ROOT";

/// Not a test: run by [`run_in_another_process`] in a child process, it makes one run folder
/// under `$GLOFFUSE_TEST_RUN_ROOT` (pruning as gloffuse does), prints it and exits.
#[test]
#[ignore = "a helper run in a child process"]
fn helper_make_one_run() {
    if let Some(root) = std::env::var_os(HELPER_ROOT) {
        let dir = new_run_dir_in(Path::new(&root), "test").unwrap();
        println!("RUN {}", dir.display());
    }
}

/// One run folder made by another process that has ended since (so its run is dead).
fn run_in_another_process(root: &Path) -> PathBuf {
    let out = std::process::Command::new(std::env::current_exe().unwrap())
        .args(["--exact", "helper_make_one_run", "--ignored", "--nocapture"])
        .env(HELPER_ROOT, root)
        .output()
        .unwrap();
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    let line = text.lines().find_map(|l| l.strip_prefix("RUN "));
    PathBuf::from(line.expect("the helper printed its run folder"))
}

#[test]
fn a_live_run_of_another_process_survives_25_newer_runs() {
    let Some(blender) = common::blender::real_blender("3.4") else {
        return;
    };
    let cache = tempfile::tempdir().unwrap();
    let root = cache.path().join("gloffuse/runs");
    fs::create_dir_all(&root).unwrap();
    let dead = dead_runs(&root);
    let mut verify = std::process::Command::new(env!("CARGO_BIN_EXE_gloffuse"))
        .args([
            "verify",
            "--no-provision",
            "-d",
            "ggx",
            "-r",
            "0.5",
            "--spp",
            "256",
        ])
        .arg("--blender")
        .arg(&blender)
        .env("XDG_CACHE_HOME", cache.path())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Its run folder, once it exists (the dead ones are there already).
    let started = Instant::now();
    let live = loop {
        // Once Blender runs (its log is made just before): nothing more is written into the
        // folder, so its backdated time holds, until the render's EXR.
        let found = runs(&root).into_iter().find(|d| !dead.contains(d));
        if let Some(d) = found.filter(|d| d.join("blender.log").exists()) {
            break d;
        }
        assert!(started.elapsed() < Duration::from_secs(60), "no run folder");
        std::thread::sleep(Duration::from_millis(10));
    };
    // Older than every dead one, so only its lock can save it.
    backdate(&live, Duration::from_secs(3 * 7200));
    let newer: Vec<PathBuf> = (0..25).map(|_| run_in_another_process(&root)).collect();
    assert!(
        verify.try_wait().unwrap().is_none(),
        "verify ended before the 25 runs were made: the test proved nothing"
    );
    let left = runs(&root);
    assert!(left.contains(&live), "the live run was pruned: {left:?}");
    for d in &dead {
        assert!(!d.exists(), "a dead run was kept: {}", d.display());
    }
    // The newest KEEP of the 25 stay, the 5 oldest went; plus the live one.
    assert_eq!(left.len(), KEEP + 1, "{left:?}");
    assert!(newer[..25 - KEEP].iter().all(|d| !d.exists()));
    assert!(newer[25 - KEEP..].iter().all(|d| d.exists()));
    let out = verify.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    // 0 or 1 is a verdict; 2 would be the verify broken by its folder going away.
    assert!(
        matches!(out.status.code(), Some(0 | 1)),
        "verify failed: {:?}\n{stderr}",
        out.status
    );
    assert!(live.join("blender.log").exists());
    // Once its process has ended, the same folder (old again: the EXR renewed its time)
    // is prunable.
    backdate(&live, Duration::from_secs(3 * 7200));
    run_in_another_process(&root);
    assert!(!live.exists(), "a run whose process ended was kept");
}

/// Parallel gloffuse processes prune the same folder at once: none fails because another
/// removed a folder first, and the live ones (all of this process's) are all kept.
#[test]
fn concurrent_pruning_never_fails_and_keeps_live_runs() {
    let cache = tempfile::tempdir().unwrap();
    let root = cache.path().join("runs");
    fs::create_dir_all(&root).unwrap();
    // 40 dead runs from an older gloffuse to fight over.
    for i in 0..40 {
        let d = root.join(format!("verify-dead-{i:02}"));
        fs::create_dir(&d).unwrap();
        backdate(&d, Duration::from_secs(3600));
    }
    let threads: Vec<_> = (0..4)
        .map(|_| {
            let root = root.clone();
            std::thread::spawn(move || {
                (0..10)
                    .map(|_| new_run_dir_in(&root, "job"))
                    .collect::<Result<Vec<_>, _>>()
            })
        })
        .collect();
    let made: Vec<PathBuf> = threads
        .into_iter()
        .flat_map(|t| t.join().unwrap().expect("a run folder could not be made"))
        .collect();
    assert_eq!(made.len(), 40);
    // Every run this process made is live (its lock is held until the process ends).
    assert!(made.iter().all(|d| d.exists()));
    let left = runs(&root);
    assert_eq!(left.len(), 40, "only the dead runs go: {left:?}");
    assert!(left.iter().all(|d| made.contains(d)));
    // No hidden half-made folder is left behind.
    let hidden = fs::read_dir(&root)
        .unwrap()
        .flatten()
        .filter(|e| e.file_name().to_string_lossy().starts_with('.'))
        .count();
    assert_eq!(hidden, 0);
}
