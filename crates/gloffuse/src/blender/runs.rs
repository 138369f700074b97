//! Where a Blender run keeps its script, log and output: a directory per run under the
//! per-user cache, so that the command printed for a failure can be rerun as it is.

use std::path::PathBuf;

use crate::Error;

/// How many run directories are kept; older ones are removed when a new one is made.
pub const KEEP: usize = 20;

/// Makes `<cache>/gloffuse/runs/<job>-<time>-<pid>/` and prunes old runs.
pub fn new_run_dir(job: &str) -> Result<PathBuf, Error> {
    let env = super::environment::Environment::from_process();
    let root = super::environment::cache_dir(&env)
        .unwrap_or_else(|| std::env::temp_dir().join("gloffuse"))
        .join("runs");
    let stamp = humantime::format_rfc3339_seconds(std::time::SystemTime::now())
        .to_string()
        .replace(':', "");
    let dir = root.join(format!("{job}-{stamp}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).map_err(|e| Error::Write {
        path: dir.clone(),
        message: e.to_string(),
    })?;
    prune(&root);
    Ok(dir)
}

/// Removes all but the newest [`KEEP`] run directories (best effort: a run of another
/// gloffuse process may be removing them too).
fn prune(root: &std::path::Path) {
    let Ok(entries) = std::fs::read_dir(root) else {
        return;
    };
    let mut dirs: Vec<(std::time::SystemTime, PathBuf)> = entries
        .flatten()
        .filter(|e| e.file_type().is_ok_and(|t| t.is_dir()))
        .filter_map(|e| Some((e.metadata().ok()?.modified().ok()?, e.path())))
        .collect();
    dirs.sort();
    let excess = dirs.len().saturating_sub(KEEP);
    for (_, d) in dirs.into_iter().take(excess) {
        let _ = std::fs::remove_dir_all(d);
    }
}
