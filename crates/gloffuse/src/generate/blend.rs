//! The .blend files gloffuse writes: a temporary file beside the destination, and the
//! checks that tell a complete .blend from a truncated one before it is renamed into place.

use std::path::Path;

use crate::Error;

/// A temporary file next to `dest`, removed on drop unless persisted.
pub fn temp_beside(dest: &Path, suffix: &str) -> Result<tempfile::TempPath, Error> {
    let dir = match dest.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    if !dir.is_dir() {
        return Err(Error::Write {
            path: dest.to_path_buf(),
            message: format!("the directory {} does not exist", dir.display()),
        });
    }
    tempfile::Builder::new()
        .prefix(".gloffuse-")
        .suffix(suffix)
        .tempfile_in(dir)
        .map(|f| f.into_temp_path())
        .map_err(|e| Error::Write {
            path: dest.to_path_buf(),
            message: e.to_string(),
        })
}

/// Whether `path` opens like a .blend: `BLENDER` (uncompressed), or the gzip (before 3.0)
/// or zstd (3.0 and later) magic of a compressed one.
pub fn starts_like_blend(path: &Path) -> bool {
    use std::io::Read;
    let mut head = [0u8; 7];
    std::fs::File::open(path)
        .and_then(|mut f| f.read_exact(&mut head))
        .is_ok_and(|()| {
            head.starts_with(b"BLENDER")
                || head.starts_with(&[0x1f, 0x8b])
                || head.starts_with(&[0x28, 0xb5, 0x2f, 0xfd])
        })
}

/// Why the .blend Blender saved at `path` is unusable, if it is: missing or empty, not a
/// .blend, or (saved uncompressed, as `save_blend` does) without the `ENDB` block that
/// closes every complete .blend in its last 24 or 32 bytes.
pub fn incomplete_blend(path: &Path) -> Option<String> {
    use std::io::{Read, Seek, SeekFrom};
    let shown = path.display();
    let len = std::fs::metadata(path).map(|m| m.len()).unwrap_or(0);
    if len == 0 {
        return Some(format!("wrote no .blend ({shown} is empty)"));
    }
    if !starts_like_blend(path) {
        return Some(format!(
            "the .blend it wrote is truncated or corrupt ({shown} does not start with a .blend header)"
        ));
    }
    let mut tail = vec![0u8; len.min(64) as usize];
    let compressed = std::fs::File::open(path)
        .and_then(|mut f| {
            let mut head = [0u8; 7];
            f.read_exact(&mut head)?;
            f.seek(SeekFrom::End(-(tail.len() as i64)))?;
            f.read_exact(&mut tail)?;
            Ok(&head != b"BLENDER")
        })
        .unwrap_or(false);
    if !compressed && !tail.windows(4).any(|w| w == b"ENDB") {
        return Some(format!(
            "the .blend it wrote is truncated or corrupt ({shown} lacks the ENDB block that ends a .blend)"
        ));
    }
    None
}
