//! What gloffuse reads of a .blend without Blender: how many ID blocks of one kind it holds
//! (`audit` counts materials before any Blender starts, for its progress and cost).
//!
//! A .blend is a header, then blocks, each a block header and its bytes, up to `ENDB`.
//! Three block-header layouts exist: 20 bytes (4-byte pointers, `BLENDER_v…`), 24 bytes
//! (8-byte pointers, `BLENDER-v…`) and the 32-byte form of Blender 5.0's 17-byte header
//! (`BLENDER17-01v0500`, format 01: code, SDNA index, old pointer, then a 64-bit length).
//! Every ID block's header carries the ID's two-letter code (`MA\0\0` for a material).
//! A compressed .blend (3.0+) is a zstd stream of many frames (Blender writes one per
//! 256 KiB) and a skippable frame holding their seek table: every frame is read.

use std::io::{BufRead, BufReader, Read};
use std::path::Path;

use ruzstd::decoding::errors::{FrameDecoderError, ReadFrameHeaderError};
use ruzstd::decoding::{BlockDecodingStrategy, FrameDecoder};

use crate::user_blend::read_up_to;

/// The ID code of a material block.
pub const MATERIAL: [u8; 4] = *b"MA\0\0";

const ZSTD_MAGIC: [u8; 4] = [0x28, 0xb5, 0x2f, 0xfd];

/// The layout of a file's block headers, read from its header.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Layout {
    header_len: usize,
    /// 20, 24 or 32 bytes per block header.
    bhead_len: usize,
    big_endian: bool,
}

/// The layout the first bytes `head` (at least 17, decompressed) announce.
fn layout(head: &[u8]) -> Option<Layout> {
    let rest = head.strip_prefix(b"BLENDER")?;
    let endian = |c: u8| match c {
        b'v' => Some(false),
        b'V' => Some(true),
        _ => None,
    };
    match *rest.first()? {
        b'-' => Some(Layout {
            header_len: 12,
            bhead_len: 24,
            big_endian: endian(*rest.get(1)?)?,
        }),
        b'_' => Some(Layout {
            header_len: 12,
            bhead_len: 20,
            big_endian: endian(*rest.get(1)?)?,
        }),
        b'0'..=b'9' => {
            let header_len: usize = std::str::from_utf8(rest.get(..2)?).ok()?.parse().ok()?;
            // Pointer size '-' (8 bytes), format "01" (the large block header), endianness.
            if rest.get(2..5)? != b"-01" {
                return None;
            }
            Some(Layout {
                header_len,
                bhead_len: 32,
                big_endian: endian(*rest.get(5)?)?,
            })
        }
        _ => None,
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
    let layout = layout(&head[..n]).ok_or("does not start with a .blend header")?;
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
        assert!(layout(b"BLENDER17-02v0500").is_none());
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
