//! Where a Blender run keeps its script, log and output: a directory per run under the
//! per-user cache, so that the command printed for a failure can be rerun as it is.
//!
//! Parallel gloffuse processes (CI jobs) share the cache, so a run directory is marked live
//! while its process lives: an exclusive `flock` on [`LOCK_FILE`] inside it, taken before
//! the directory gets its name and held until the process ends (the kernel releases it
//! however the process ends). Pruning removes only directories whose lock it can take.

use std::fs::File;
use std::os::fd::AsRawFd;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

use crate::Error;

/// How many run directories are kept; older ones are removed when a new one is made,
/// unless their process is still running.
pub const KEEP: usize = 20;

/// The file in a run directory whose `flock` marks the run live.
pub const LOCK_FILE: &str = ".gloffuse-run.lock";

/// The locks of this process's run directories, held until the process ends: a run's
/// files (log, script, output) are read after the run, up to the end of the command.
static LIVE: Mutex<Vec<File>> = Mutex::new(Vec::new());

/// Makes `<cache>/gloffuse/runs/<job>-<time>-<pid>/`, marked live, and prunes old runs.
pub fn new_run_dir(job: &str) -> Result<PathBuf, Error> {
    let env = super::environment::Environment::from_process();
    let root = super::environment::cache_dir(&env)
        .unwrap_or_else(|| std::env::temp_dir().join("gloffuse"))
        .join("runs");
    new_run_dir_in(&root, job)
}

/// [`new_run_dir`] under `root`.
pub fn new_run_dir_in(root: &Path, job: &str) -> Result<PathBuf, Error> {
    let write_error = |path: &Path, e: std::io::Error| Error::Write {
        path: path.to_path_buf(),
        message: e.to_string(),
    };
    std::fs::create_dir_all(root).map_err(|e| write_error(root, e))?;
    let stamp = humantime::format_rfc3339_nanos(std::time::SystemTime::now())
        .to_string()
        .replace(':', "");
    let dir = root.join(format!("{job}-{stamp}-{}", std::process::id()));
    // Locked under a hidden name (which pruning ignores) and only then renamed: no other
    // process ever sees this run unlocked.
    let tmp = tempfile::Builder::new()
        .prefix(".new-run-")
        .tempdir_in(root)
        .map_err(|e| write_error(root, e))?;
    let lock = File::create(tmp.path().join(LOCK_FILE)).map_err(|e| write_error(&dir, e))?;
    if !try_lock(&lock) {
        return Err(write_error(&dir, std::io::Error::last_os_error()));
    }
    std::fs::rename(tmp.path(), &dir).map_err(|e| write_error(&dir, e))?;
    let _ = tmp.keep();
    LIVE.lock().unwrap_or_else(|p| p.into_inner()).push(lock);
    prune(root);
    Ok(dir)
}

/// Takes the exclusive lock on `file` without waiting; false if another open file holds it.
fn try_lock(file: &File) -> bool {
    // SAFETY: flock only locks the open file the descriptor refers to.
    unsafe { libc::flock(file.as_raw_fd(), libc::LOCK_EX | libc::LOCK_NB) == 0 }
}

/// Removes the run directories older than the newest [`KEEP`] whose process has ended
/// (their lock can be taken; a directory without a lock file is from an older gloffuse).
/// Best effort: another gloffuse may be pruning too, and whatever it removed first is
/// skipped.
fn prune(root: &Path) {
    let Ok(entries) = std::fs::read_dir(root) else {
        return;
    };
    let mut dirs: Vec<(std::time::SystemTime, PathBuf)> = entries
        .flatten()
        .filter(|e| !e.file_name().to_string_lossy().starts_with('.'))
        .filter(|e| e.file_type().is_ok_and(|t| t.is_dir()))
        .filter_map(|e| Some((e.metadata().ok()?.modified().ok()?, e.path())))
        .collect();
    dirs.sort_by(|a, b| b.cmp(a));
    for (_, dir) in dirs.into_iter().skip(KEEP) {
        match File::open(dir.join(LOCK_FILE)) {
            // Removed while locked by us, so no other pruner is half-way through it.
            Ok(lock) if try_lock(&lock) => {
                let _ = std::fs::remove_dir_all(&dir);
            }
            Ok(_) => {} // live: its process holds the lock
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
                let _ = std::fs::remove_dir_all(&dir);
            }
            Err(_) => {}
        }
    }
}
