//! EXR encoding (the `exr` crate): one part, scan lines, ZIP compression (16 lines per
//! block, lossless), one channel per table channel (`R`, `G`[, `B`, `A`]) as half or float.
//! Row 0 of the table is the first (top) scan line.

use exr::prelude::*;
use std::io::Cursor;

use super::{Bits, Table};

/// Encodes `table` as an EXR file in memory.
pub fn encode(table: &Table, bits: Bits) -> std::result::Result<Vec<u8>, String> {
    let nc = table.channels.len();
    let channels: SmallVec<[AnyChannel<FlatSamples>; 4]> = table
        .channels
        .iter()
        .enumerate()
        .map(|(c, &name)| {
            let values = table.data.iter().skip(c).step_by(nc).copied();
            let samples = match bits {
                Bits::Half => FlatSamples::F16(values.map(f16::from_f32).collect()),
                Bits::Float => FlatSamples::F32(values.collect()),
            };
            AnyChannel {
                name: name.into(),
                sample_data: samples,
                // Data, not colour: a lossy codec should quantise it linearly (ZIP is lossless).
                quantize_linearly: true,
                sampling: Vec2(1, 1),
            }
        })
        .collect();
    let layer = Layer::new(
        (table.width, table.height),
        LayerAttributes::default(),
        Encoding {
            compression: Compression::ZIP16,
            blocks: Blocks::ScanLines,
            line_order: LineOrder::Increasing,
        },
        AnyChannels::sort(channels),
    );
    let mut bytes = Vec::new();
    Image::from_layer(layer)
        .write()
        .to_buffered(Cursor::new(&mut bytes))
        .map_err(|e| e.to_string())?;
    Ok(bytes)
}
