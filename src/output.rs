//! Writing files so that a failure never leaves a partial file: write a temporary file in
//! the destination's directory, then rename it into place.

use std::io::Write;
use std::path::Path;

use crate::Error;

/// Checks that `path` can be an output file: not a directory, and in a directory that
/// exists. Commands call it before slow work (finding Blender, rendering), so that bad
/// input fails fast; returns the directory the file goes in.
pub fn check_destination(path: &Path) -> Result<&Path, Error> {
    let fail = |message: String| Error::Write {
        path: path.to_path_buf(),
        message,
    };
    if path.is_dir() {
        return Err(fail("it is a directory; give a file name".into()));
    }
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    if !dir.is_dir() {
        return Err(fail(format!(
            "the directory {} does not exist",
            dir.display()
        )));
    }
    Ok(dir)
}

/// Writes `bytes` to `path` atomically (temporary file + rename in the same directory).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), Error> {
    let fail = |message: String| Error::Write {
        path: path.to_path_buf(),
        message,
    };
    let dir = check_destination(path)?;
    let mut tmp = tempfile::Builder::new()
        .prefix(".gloffuse-")
        .suffix(".tmp")
        .tempfile_in(dir)
        .map_err(|e| fail(e.to_string()))?;
    tmp.write_all(bytes).map_err(|e| fail(e.to_string()))?;
    // Temporary files are created private (0600); an output file should be as readable as
    // any other file the user writes.
    {
        use std::os::unix::fs::PermissionsExt;
        let mode = if path.exists() {
            std::fs::metadata(path)
                .map(|m| m.permissions().mode())
                .unwrap_or(0o644)
        } else {
            0o644
        };
        tmp.as_file()
            .set_permissions(std::fs::Permissions::from_mode(mode))
            .map_err(|e| fail(e.to_string()))?;
    }
    tmp.as_file().sync_all().map_err(|e| fail(e.to_string()))?;
    tmp.persist(path).map_err(|e| fail(e.error.to_string()))?;
    Ok(())
}
