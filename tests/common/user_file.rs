//! A user's own .blend, made and read back inside real Blender by
//! `tests/blender/user_file.py`, independently of gloffuse's package; and a folder's
//! listing, to show that nothing was left beside a user's file.

use std::ffi::OsStr;
use std::path::Path;

use serde_json::Value;

fn script() -> &'static Path {
    concat!(env!("CARGO_MANIFEST_DIR"), "/tests/blender/user_file.py").as_ref()
}

/// A user's scene (a cube and the material "Chair Paint"), saved by `blender` at `path`;
/// `extra` are user_file.py's options (`--group NAME`, `--texture`, `--compress`).
pub fn make(blender: &Path, path: &Path, extra: &[&str]) {
    let mut args: Vec<&OsStr> = vec!["--make".as_ref(), path.as_os_str()];
    args.extend(extra.iter().map(OsStr::new));
    let run = super::blender::run_in_blender(blender, script(), &args);
    assert!(
        run.status.success() && path.is_file(),
        "user_file.py --make {extra:?} failed:\n{}",
        String::from_utf8_lossy(&run.stderr)
    );
}

/// What `blender` sees in the .blend at `path` (user_file.py --inspect).
pub fn inspect(blender: &Path, path: &Path) -> Value {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("inspect.json");
    let run = super::blender::run_in_blender(
        blender,
        script(),
        &[
            "--inspect".as_ref(),
            path.as_os_str(),
            "--out".as_ref(),
            out.as_os_str(),
        ],
    );
    assert!(
        run.status.success(),
        "user_file.py --inspect failed:\n{}",
        String::from_utf8_lossy(&run.stderr)
    );
    serde_json::from_str(&std::fs::read_to_string(out).unwrap()).unwrap()
}

/// The names in `dir`, sorted.
pub fn listing(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    names.sort();
    names
}
