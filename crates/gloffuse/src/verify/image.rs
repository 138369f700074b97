//! Reading the rendered EXR back: scene-linear RGBA, premultiplied by coverage.

use exr::prelude::{ReadChannels, ReadLayers, read};
use std::path::Path;

pub use crate::error::ExrError;

/// An RGBA float image, row 0 at the top.
pub struct Rgba {
    pub width: usize,
    pub height: usize,
    /// (r, g, b, a) per pixel, row-major.
    pub pixels: Vec<[f32; 4]>,
}

impl Rgba {
    /// The top-left pixel of cell `index` of a grid of `columns` cells of `cell` pixels when
    /// the whole cell lies inside the image; `None` for a grid the image does not hold (no
    /// columns, an empty cell, a cell past its edge, fewer pixels than its size says).
    pub fn cell_origin(&self, columns: usize, cell: usize, index: usize) -> Option<(usize, usize)> {
        let (column, row) = (index.checked_rem(columns)?, index / columns);
        let (x0, y0) = (column.checked_mul(cell)?, row.checked_mul(cell)?);
        let inside = cell > 0
            && x0.checked_add(cell)? <= self.width
            && y0.checked_add(cell)? <= self.height
            && self.pixels.len() >= self.width.checked_mul(self.height)?;
        inside.then_some((x0, y0))
    }
}

pub fn read_rgba(path: &Path) -> std::result::Result<Rgba, ExrError> {
    if !path.exists() {
        return Err(ExrError::Missing {
            path: path.to_path_buf(),
        });
    }
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_file(path)
        .map_err(|e| match e {
            exr::error::Error::NotSupported(what) => ExrError::Unsupported {
                path: path.to_path_buf(),
                why: what.to_string(),
            },
            other => ExrError::Corrupt {
                path: path.to_path_buf(),
                why: other.to_string(),
            },
        })?;
    let layer = &image.layer_data;
    // Lossy codecs (DWAA/DWAB, B44, PXR24) would bias a 0.1 %-level measurement: refuse them.
    let compression = layer.encoding.compression;
    if !compression.is_lossless_for(exr::meta::attribute::SampleType::F32) {
        return Err(ExrError::Unsupported {
            path: path.to_path_buf(),
            why: format!("lossy {compression} compression"),
        });
    }
    let size = layer.size;
    let channels = &layer.channel_data.list;
    let names: Vec<String> = channels.iter().map(|c| c.name.to_string()).collect();
    let find = |want: &'static str| {
        channels
            .iter()
            .find(|c| c.name.to_string() == want)
            .map(|c| c.sample_data.values_as_f32().collect::<Vec<f32>>())
            .ok_or_else(|| ExrError::MissingChannel {
                path: path.to_path_buf(),
                channel: want,
                found: names.join(", "),
            })
    };
    let (r, g, b, a) = (find("R")?, find("G")?, find("B")?, find("A")?);
    let pixels = (0..size.area()).map(|i| [r[i], g[i], b[i], a[i]]).collect();
    Ok(Rgba {
        width: size.width(),
        height: size.height(),
        pixels,
    })
}
