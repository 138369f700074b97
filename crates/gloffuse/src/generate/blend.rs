//! The check that tells a complete .blend Blender saved from a truncated one, before it is
//! renamed into place.

use std::path::Path;

use crate::user_blend::{Compression, read_header};

/// The magic that ends Zstandard's seekable format, which Blender's compressed .blend
/// files end with (its seek table, little-endian 0x8F92EAB1).
const SEEKABLE_FOOTER: [u8; 4] = [0xb1, 0xea, 0x92, 0x8f];

/// Why the .blend Blender saved at `path` is unusable, if it is: missing or empty, not a
/// .blend, or cut short: an uncompressed file lacks the `ENDB` block that closes every
/// complete .blend in its last bytes, a compressed one the seek table that ends it.
pub fn incomplete_blend(path: &Path) -> Option<String> {
    use std::io::{Read, Seek, SeekFrom};
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
    let mut tail = vec![0u8; len.min(64) as usize];
    let read = std::fs::File::open(path).and_then(|mut f| {
        f.seek(SeekFrom::End(-(tail.len() as i64)))?;
        f.read_exact(&mut tail)
    });
    let complete = read.is_ok()
        && match header.compression {
            Compression::None => tail.windows(4).any(|w| w == b"ENDB"),
            Compression::Zstd => tail.ends_with(&SEEKABLE_FOOTER),
            Compression::Gzip => true,
        };
    (!complete).then(|| {
        format!(
            "the .blend it wrote is truncated or corrupt ({shown} lacks the end a complete .blend has)"
        )
    })
}
