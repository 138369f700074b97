//! The check that tells a complete .blend Blender saved from a truncated one, before it is
//! renamed into place.

use std::path::Path;

use crate::blend_file::{ends_complete, read_header};

/// Why the .blend Blender saved at `path` is unusable, if it is: missing or empty, not a
/// .blend, or cut short: an uncompressed file lacks the `ENDB` block that closes every
/// complete .blend in its last bytes, a compressed one the seek table that ends it.
pub fn incomplete_blend(path: &Path) -> Option<String> {
    let shown = path.display();
    let len = std::fs::metadata(path).map(|m| m.len()).unwrap_or(0);
    if len == 0 {
        return Some(format!("wrote no .blend ({shown} is empty)"));
    }
    let header = match read_header(path) {
        Ok(header) => header,
        Err(why) => {
            return Some(format!(
                "the .blend it wrote is truncated or corrupt ({shown} {why})"
            ));
        }
    };
    (!ends_complete(path, &header)).then(|| {
        format!(
            "the .blend it wrote is truncated or corrupt ({shown} lacks the end a complete .blend has)"
        )
    })
}
