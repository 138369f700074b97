//! PNG helpers every report picture shares: the grey background and its sRGB encoding,
//! the embedded font, the label colours, drawing onto RGB bytes, and atomic PNG writes.
//!
//! Text is drawn with DejaVu Sans, embedded in the binary (`assets/fonts/`, Bitstream Vera
//! licence), so no system fonts are needed.

use std::fmt::Display;
use std::path::Path;
use std::sync::OnceLock;

use image::{ExtendedColorType, ImageEncoder, codecs::png::PngEncoder};
use plotters::backend::RGBPixel;
use plotters::prelude::*;

use crate::error::Error;
use crate::output::write_output;
use crate::verify::image::Rgba;

/// Linear value of the background the spheres are composited over: 18 % grey, the
/// photographic middle grey, so a sphere brighter or darker than 100 % stands out either way.
pub const BACKGROUND: f32 = 0.18;

const FONT: &[u8] = include_bytes!("../../../../assets/fonts/DejaVuSans.ttf");
pub(super) const FAMILY: &str = "sans-serif";

/// Label column and header of the contact sheet (sRGB).
pub(super) const LABEL_BACKGROUND: RGBColor = RGBColor(40, 40, 40);
pub(super) const LABEL_TEXT: RGBColor = RGBColor(235, 235, 235);

/// The sRGB transfer function (IEC 61966-2-1) of a linear value clamped to [0, 1], as an
/// 8-bit code value. NaN gives 0.
///
/// ```
/// use gloffuse::report::png::srgb8;
/// assert_eq!(srgb8(0.18), 118);
/// assert_eq!(srgb8(0.5), 188);
/// assert_eq!(srgb8(2.0), 255);
/// assert_eq!(srgb8(f32::NAN), 0);
/// ```
pub fn srgb8(linear: f32) -> u8 {
    if linear.is_nan() {
        return 0;
    }
    let v = linear.clamp(0.0, 1.0);
    let encoded = if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    };
    (encoded * 255.0).round() as u8
}

/// A pixel of a render (scene-linear RGBA premultiplied by alpha) composited over
/// [`BACKGROUND`] and sRGB-encoded, as every picture shows the spheres.
pub fn over_background([r, g, b, a]: [f32; 4]) -> [u8; 3] {
    let under = (1.0 - a.clamp(0.0, 1.0)) * BACKGROUND;
    [srgb8(r + under), srgb8(g + under), srgb8(b + under)]
}

pub(super) fn write_error(out: &Path, message: impl Display) -> Error {
    Error::Write {
        path: out.to_path_buf(),
        message: message.to_string(),
    }
}

/// Registers the embedded DejaVu Sans as plotters' `sans-serif` (once per process).
pub(super) fn register_font() -> Result<(), String> {
    static REGISTERED: OnceLock<Result<(), String>> = OnceLock::new();
    REGISTERED
        .get_or_init(|| {
            plotters::style::register_font(FAMILY, FontStyle::Normal, FONT)
                .map_err(|_| "the embedded font DejaVuSans.ttf is unreadable".to_string())
        })
        .clone()
}

pub(super) fn text_size(text: &str, px: f64) -> Result<(u32, u32), String> {
    (FAMILY, px)
        .into_font()
        .box_size(text)
        .map_err(|e| format!("cannot lay out the label '{text}': {e}"))
}

pub(super) fn backend<'a>(
    rgb: &'a mut [u8],
    size: (u32, u32),
    out: &Path,
) -> Result<BitMapBackend<'a, RGBPixel>, Error> {
    BitMapBackend::with_buffer_and_format(rgb, size)
        .map_err(|e| write_error(out, format!("cannot draw: {e}")))
}

/// RGB bytes as a PNG file in memory.
pub fn encode_png(rgb: &[u8], (w, h): (u32, u32)) -> Result<Vec<u8>, String> {
    let mut bytes = Vec::new();
    PngEncoder::new(&mut bytes)
        .write_image(rgb, w, h, ExtendedColorType::Rgb8)
        .map_err(|e| format!("cannot encode PNG: {e}"))?;
    Ok(bytes)
}

pub(super) fn write_png(rgb: &[u8], size: (u32, u32), out: &Path) -> Result<(), Error> {
    let bytes = encode_png(rgb, size).map_err(|e| write_error(out, e))?;
    write_output(out, &bytes)
}

/// Grid cell `index` of a rendered sweep as the contact sheet shows it (over the grey
/// background, sRGB-encoded): RGB bytes, `cell × cell`; `None` if the image does not hold
/// that cell ([`Rgba::cell_origin`]).
pub fn cell_image(image: &Rgba, columns: usize, cell: usize, index: usize) -> Option<Vec<u8>> {
    let (x0, y0) = image.cell_origin(columns, cell, index)?;
    let mut rgb = Vec::with_capacity(cell * cell * 3);
    for y in 0..cell {
        for x in 0..cell {
            rgb.extend_from_slice(&over_background(
                image.pixels[(y0 + y) * image.width + x0 + x],
            ));
        }
    }
    Some(rgb)
}
