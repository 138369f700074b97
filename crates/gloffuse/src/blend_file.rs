//! The one place gloffuse reads a .blend's bytes without Blender: its header (the Blender
//! that saved it, its compression), whether it ends as a complete file does, and how many
//! ID blocks of one kind it holds (`audit` counts materials before any Blender starts, for
//! its progress and cost). `user_blend` (changing a user's file safely) builds on it.
//!
//! A .blend is a header, then blocks, each a block header and its bytes, up to `ENDB`. The
//! header comes in two forms: 12 bytes, `BLENDER-v405` (pointer size `-` 8 bytes or `_` 4,
//! endianness `v` little or `V` big, a 3-digit version), and the form Blender 5.0
//! introduced, `BLENDER17-01v0500` (header size, pointer size, format version, endianness,
//! a 4-digit version). Three block-header layouts follow from it: 20 bytes (4-byte
//! pointers), 24 bytes (8-byte pointers) and the 32 bytes of format 01 (code, SDNA index,
//! old pointer, then a 64-bit length). Every ID block's header carries the ID's two-letter
//! code (`MA\0\0` for a material). A compressed .blend is gzip (before 3.0) or, from 3.0, a
//! zstd stream of many frames (Blender writes one per 256 KiB) ending in a skippable frame
//! holding their seek table: the count reads every frame.

use std::io::{BufRead, BufReader, Read};
use std::path::Path;

use ruzstd::decoding::errors::{FrameDecoderError, ReadFrameHeaderError};
use ruzstd::decoding::{BlockDecodingStrategy, FrameDecoder};

use crate::measure::BlenderVersion;

/// The ID code of a material block.
pub const MATERIAL: [u8; 4] = *b"MA\0\0";

/// The zstd frame magic, the gzip magic.
const ZSTD_MAGIC: [u8; 4] = [0x28, 0xb5, 0x2f, 0xfd];
const GZIP_MAGIC: [u8; 2] = [0x1f, 0x8b];

/// The magic that ends Zstandard's seekable format, which Blender's compressed .blend
/// files end with (its seek table, little-endian 0x8F92EAB1).
const SEEKABLE_FOOTER: [u8; 4] = [0xb1, 0xea, 0x92, 0x8f];

/// How a .blend's bytes are stored.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Compression {
    None,
    /// Zstandard: Blender 3.0 and later.
    Zstd,
    /// Gzip: Blender before 3.0.
    Gzip,
}

/// What the first bytes of a .blend say.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BlendHeader {
    /// The Blender that saved it; `None` for a gzip file, which only Blender before 3.0
    /// wrote (older than every Blender gloffuse runs).
    pub version: Option<BlenderVersion>,
    pub compression: Compression,
}

/// The layout of a file's block headers, read from its header.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Layout {
    header_len: usize,
    /// 20, 24 or 32 bytes per block header.
    bhead_len: usize,
    big_endian: bool,
}

/// What a .blend's first bytes announce: the Blender that saved it, and the layout of its
/// block headers where gloffuse knows it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Start {
    version: BlenderVersion,
    layout: Option<Layout>,
}

/// The start of the .blend bytes `head` (the file's first 17 bytes, decompressed), if they
/// are a .blend header of either form.
fn parse_start(head: &[u8]) -> Option<Start> {
    let rest = head.strip_prefix(b"BLENDER")?;
    let endian = |c: Option<&u8>| match c {
        Some(b'v') => Some(false),
        Some(b'V') => Some(true),
        _ => None,
    };
    let (digits, layout) = match *rest.first()? {
        pointer @ (b'-' | b'_') => {
            let layout = endian(rest.get(1)).map(|big_endian| Layout {
                header_len: 12,
                bhead_len: if pointer == b'-' { 24 } else { 20 },
                big_endian,
            });
            (rest.get(2..5)?, layout)
        }
        b'0'..=b'9' => {
            let header_len: usize = std::str::from_utf8(rest.get(..2)?).ok()?.parse().ok()?;
            // 7 (BLENDER) + 2 (size) + 1 (pointer) + 2 (format) + 1 (endianness) + digits.
            let digits = rest.get(6..header_len.checked_sub(7)?)?;
            // Pointer size '-' (8 bytes), format "01" (the large block header), endianness.
            let layout = (rest.get(2..5) == Some(b"-01"))
                .then(|| endian(rest.get(5)))
                .flatten()
                .map(|big_endian| Layout {
                    header_len,
                    bhead_len: 32,
                    big_endian,
                });
            (digits, layout)
        }
        _ => return None,
    };
    if !digits.iter().all(u8::is_ascii_digit) || digits.len() < 3 {
        return None;
    }
    let number: u32 = std::str::from_utf8(digits).ok()?.parse().ok()?;
    let version = BlenderVersion {
        major: number / 100,
        minor: number % 100,
    };
    Some(Start { version, layout })
}

/// Reads the header of the .blend at `path` (decompressing the start of a zstd file).
pub fn read_header(path: &Path) -> Result<BlendHeader, String> {
    let mut file = std::fs::File::open(path).map_err(|e| format!("cannot be read ({e})"))?;
    let mut head = [0u8; 17];
    let n = read_up_to(&mut file, &mut head).map_err(|e| format!("cannot be read ({e})"))?;
    let head = &head[..n];
    let not_blend = || "does not start with a .blend header".to_string();
    if head.starts_with(&GZIP_MAGIC) {
        return Ok(BlendHeader {
            version: None,
            compression: Compression::Gzip,
        });
    }
    if head.starts_with(&ZSTD_MAGIC) {
        let file = std::fs::File::open(path).map_err(|e| format!("cannot be read ({e})"))?;
        let mut decoder = ruzstd::decoding::StreamingDecoder::new(file)
            .map_err(|e| format!("is compressed, but its zstd stream cannot be read ({e})"))?;
        let mut inner = [0u8; 17];
        let n = read_up_to(&mut decoder, &mut inner)
            .map_err(|e| format!("is compressed, but its zstd stream cannot be read ({e})"))?;
        let version = parse_start(&inner[..n]).ok_or_else(not_blend)?.version;
        return Ok(BlendHeader {
            version: Some(version),
            compression: Compression::Zstd,
        });
    }
    let version = parse_start(head).ok_or_else(not_blend)?.version;
    Ok(BlendHeader {
        version: Some(version),
        compression: Compression::None,
    })
}

/// Fills `buf` as far as the reader goes; returns how many bytes were read.
fn read_up_to(reader: &mut impl Read, buf: &mut [u8]) -> std::io::Result<usize> {
    let mut filled = 0;
    while filled < buf.len() {
        match reader.read(&mut buf[filled..])? {
            0 => break,
            n => filled += n,
        }
    }
    Ok(filled)
}

/// Whether the .blend at `path`, of header `header`, ends as a complete file does: an
/// uncompressed one with the `ENDB` block in its last bytes, a zstd one with the seek table
/// (a gzip one is taken as complete).
pub fn ends_complete(path: &Path, header: &BlendHeader) -> bool {
    use std::io::{Seek, SeekFrom};
    let len = std::fs::metadata(path).map(|m| m.len()).unwrap_or(0);
    let mut tail = vec![0u8; len.min(64) as usize];
    let read = std::fs::File::open(path).and_then(|mut f| {
        f.seek(SeekFrom::End(-(tail.len() as i64)))?;
        f.read_exact(&mut tail)
    });
    read.is_ok()
        && match header.compression {
            Compression::None => tail.windows(4).any(|w| w == b"ENDB"),
            Compression::Zstd => tail.ends_with(&SEEKABLE_FOOTER),
            Compression::Gzip => true,
        }
}

/// How many blocks with ID code `code` the .blend at `path` holds (plain or zstd); an
/// error says why the file cannot be walked (gzip, a cut-off file, not a .blend).
pub fn count_blocks(path: &Path, code: [u8; 4]) -> Result<usize, String> {
    let unreadable = |e: std::io::Error| format!("cannot be read ({e})");
    let mut magic = [0u8; 4];
    let mut file = std::fs::File::open(path).map_err(unreadable)?;
    read_up_to(&mut file, &mut magic).map_err(unreadable)?;
    let file = std::fs::File::open(path).map_err(unreadable)?;
    if magic == ZSTD_MAGIC {
        count_in(Frames::new(BufReader::new(file)), code)
    } else {
        count_in(BufReader::new(file), code)
    }
}

/// The decompressed bytes of every frame of a zstd stream, one after the other, skippable
/// frames skipped (ruzstd's `StreamingDecoder` stops after the first frame).
struct Frames<R> {
    source: R,
    decoder: FrameDecoder,
    /// A frame is being decoded (its header read).
    in_frame: bool,
}

impl<R: BufRead> Frames<R> {
    fn new(source: R) -> Self {
        Frames {
            source,
            decoder: FrameDecoder::new(),
            in_frame: false,
        }
    }
}

impl<R: BufRead> Read for Frames<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        if buf.is_empty() {
            return Ok(0);
        }
        loop {
            if self.in_frame {
                while self.decoder.can_collect() == 0 && !self.decoder.is_finished() {
                    self.decoder
                        .decode_blocks(&mut self.source, BlockDecodingStrategy::UptoBlocks(1))
                        .map_err(unreadable_zstd)?;
                }
                let n = self.decoder.read(buf)?;
                if n > 0 {
                    return Ok(n);
                }
                self.in_frame = false;
            }
            // The stream ends between frames only.
            if self.source.fill_buf()?.is_empty() {
                return Ok(0);
            }
            match self.decoder.init(&mut self.source) {
                Ok(()) => self.in_frame = true,
                Err(FrameDecoderError::ReadFrameHeaderError(ReadFrameHeaderError::SkipFrame {
                    length,
                    ..
                })) => {
                    let skipped = std::io::copy(
                        &mut (&mut self.source).take(u64::from(length)),
                        &mut std::io::sink(),
                    )?;
                    if skipped != u64::from(length) {
                        return Err(unreadable_zstd(FrameDecoderError::FailedToSkipFrame));
                    }
                }
                Err(e) => return Err(unreadable_zstd(e)),
            }
        }
    }
}

fn unreadable_zstd(e: FrameDecoderError) -> std::io::Error {
    std::io::Error::other(format!("has a zstd stream that cannot be read ({e})"))
}

fn count_in(mut reader: impl Read, code: [u8; 4]) -> Result<usize, String> {
    let cut = || "ends before its last block".to_string();
    let mut head = [0u8; 17];
    let n = read_up_to(&mut reader, &mut head).map_err(|e| e.to_string())?;
    let layout = parse_start(&head[..n])
        .and_then(|start| start.layout)
        .ok_or("does not start with a .blend header")?;
    // The header may be shorter than what was read: the rest starts the first block.
    let mut pending: Vec<u8> = head[layout.header_len.min(n)..n].to_vec();
    let mut count = 0;
    loop {
        let mut bhead = [0u8; 32];
        let bhead = &mut bhead[..layout.bhead_len];
        let take = pending.len().min(bhead.len());
        bhead[..take].copy_from_slice(&pending[..take]);
        pending.drain(..take);
        if read_up_to(&mut reader, &mut bhead[take..]).map_err(|e| e.to_string())?
            < bhead.len() - take
        {
            return Err(cut());
        }
        let block_code = [bhead[0], bhead[1], bhead[2], bhead[3]];
        if &block_code == b"ENDB" {
            return Ok(count);
        }
        count += usize::from(block_code == code);
        let mut skip = block_len(bhead, layout).saturating_sub(pending.len() as u64);
        pending.clear();
        skip = std::io::copy(&mut (&mut reader).take(skip), &mut std::io::sink())
            .map_err(|e| e.to_string())?
            .abs_diff(skip);
        if skip != 0 {
            return Err(cut());
        }
    }
}

/// The length of the block whose header is `bhead`.
fn block_len(bhead: &[u8], layout: Layout) -> u64 {
    if layout.bhead_len == 32 {
        let bytes: [u8; 8] = bhead[16..24].try_into().expect("8 bytes");
        return if layout.big_endian {
            u64::from_be_bytes(bytes)
        } else {
            u64::from_le_bytes(bytes)
        };
    }
    let bytes: [u8; 4] = bhead[4..8].try_into().expect("4 bytes");
    u64::from(if layout.big_endian {
        u32::from_be_bytes(bytes)
    } else {
        u32::from_le_bytes(bytes)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The version a header announces.
    fn version(head: &[u8]) -> Option<BlenderVersion> {
        parse_start(head).map(|start| start.version)
    }

    fn v(major: u32, minor: u32) -> Option<BlenderVersion> {
        Some(BlenderVersion { major, minor })
    }

    #[test]
    fn both_header_forms_give_the_version() {
        // The first bytes of files saved by Blender 3.4.1, bpy 4.5 and bpy 5.0 (uncompressed).
        assert_eq!(version(b"BLENDER-v304RENDH"), v(3, 4));
        assert_eq!(version(b"BLENDER-v405RENDH"), v(4, 5));
        assert_eq!(version(b"BLENDER_V279"), v(2, 79));
        assert_eq!(version(b"BLENDER17-01v0500"), v(5, 0));
        assert_eq!(version(b"BLENDER17-01v0502"), v(5, 2));
        assert_eq!(version(b"BLENDER17-01v1203"), v(12, 3));
    }

    #[test]
    fn what_is_not_a_header_gives_none() {
        for bad in [
            &b""[..],
            b"BLENDER",
            b"BLENDER-v4",
            b"BLENDER-vabc",
            b"BLENDEX-v405",
            b"BLENDER17-01v05",
            b"BLENDER03-01v0500",
            b"PK\x03\x04",
        ] {
            assert_eq!(version(bad), None, "{:?}", String::from_utf8_lossy(bad));
        }
    }

    fn block(code: &[u8; 4], body: &[u8]) -> Vec<u8> {
        let mut b = code.to_vec();
        b.extend((body.len() as u32).to_le_bytes());
        b.extend([0u8; 16]); // old pointer, SDNA index, count
        b.extend(body);
        b
    }

    #[test]
    fn counts_the_blocks_of_one_code_in_a_small_header_file() {
        let mut bytes = b"BLENDER-v405".to_vec();
        bytes.extend(block(b"MA\0\0", &[1; 40]));
        bytes.extend(block(b"DATA", &[2; 7]));
        bytes.extend(block(b"MA\0\0", &[]));
        bytes.extend(block(b"ENDB", &[]));
        assert_eq!(count_in(bytes.as_slice(), MATERIAL), Ok(2));
        bytes.truncate(bytes.len() - 30);
        assert!(count_in(bytes.as_slice(), MATERIAL).is_err());
    }

    #[test]
    fn the_large_block_header_of_5_0_has_its_length_after_the_pointer() {
        let mut bytes = b"BLENDER17-01v0500".to_vec();
        for (code, len) in [(b"MA\0\0", 5u64), (b"OB\0\0", 3), (b"ENDB", 0)] {
            bytes.extend(code);
            bytes.extend([0u8; 4 + 8]); // SDNA index, old pointer
            bytes.extend(len.to_le_bytes());
            bytes.extend([0u8; 8]); // count
            bytes.extend(vec![9u8; len as usize]);
        }
        assert_eq!(count_in(bytes.as_slice(), MATERIAL), Ok(1));
        assert_eq!(parse_start(b"BLENDER17-02v0500").unwrap().layout, None);
        assert!(count_in(&b"PK\x03\x04 not a blend at all"[..], MATERIAL).is_err());
    }

    /// As Blender writes a compressed file: frames, then a skippable frame (its seek table).
    #[test]
    fn a_zstd_file_is_read_through_all_its_frames() {
        use ruzstd::encoding::{CompressionLevel, compress_to_vec};
        let mut bytes = b"BLENDER-v405".to_vec();
        for i in 0..300 {
            bytes.extend(block(
                if i % 3 == 0 { b"MA\0\0" } else { b"DATA" },
                &[7; 100],
            ));
        }
        bytes.extend(block(b"ENDB", &[]));
        let mut stream = Vec::new();
        // Frames cut mid-block, and an empty one.
        for part in [
            &bytes[..5000],
            &bytes[5000..5000],
            &bytes[5000..20001],
            &bytes[20001..],
        ] {
            stream.extend(compress_to_vec(part, CompressionLevel::Fastest));
        }
        stream.extend(0x184D_2A5E_u32.to_le_bytes());
        stream.extend(6u32.to_le_bytes());
        stream.extend(b"seek!!");
        let file = tempfile::NamedTempFile::new().unwrap();
        std::fs::write(file.path(), &stream).unwrap();
        assert_eq!(count_blocks(file.path(), MATERIAL), Ok(100));
        std::fs::write(file.path(), &stream[..stream.len() / 2]).unwrap();
        assert!(count_blocks(file.path(), MATERIAL).is_err(), "a cut stream");
    }
}
