//! `contact-sheet.png` of `verify --report`: the rendered furnace grid, labelled with the
//! spheres and their roughness.

use std::path::Path;

use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use crate::error::{Error, Field};
use crate::generate::Mode;
use crate::report::png::{
    FAMILY, LABEL_BACKGROUND, LABEL_TEXT, backend, over_background, register_font, text_size,
    write_error, write_png,
};
use crate::verify::image::Rgba;
use crate::verify::plan::Plan;

/// Row and column labels of a plan's grid in `mode`, for [`contact_sheet`]:
/// `GGX uncorrected`, `GGX corrected`, …, `Multiscatter GGX` (layered mode: `GGX Mix
/// Shader, IOR 1.5`, …); the roughness values of the first row.
pub fn sheet_labels(plan: &Plan, mode: Mode) -> (Vec<String>, Vec<String>) {
    let columns = plan.columns.max(1);
    let rows = plan
        .cells
        .chunks(columns)
        .map(|row| match row[0].block {
            Some(b) => format!("{}, {}", row[0].role.label(mode), b.label()),
            None => row[0].role.label(mode),
        })
        .collect();
    let cols = plan
        .cells
        .iter()
        .take(columns)
        .map(|c| format_roughness(c.roughness.get()))
        .collect();
    (rows, cols)
}

/// `0.5`, `0.25`, `0.125`: at most three decimals, no trailing zeros.
fn format_roughness(r: f64) -> String {
    let s = format!("{r:.3}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s.is_empty() || s == "-" {
        "0".into()
    } else {
        s.into()
    }
}

/// Contact sheet: the rendered furnace grid (scene-linear RGBA premultiplied by alpha, row 0
/// at the top; rows as in [`Plan::verify`], columns are roughness values) composited over
/// [`BACKGROUND`](crate::report::png::BACKGROUND) grey, display-encoded with the sRGB transfer function (clamped to [0, 1]),
/// with a label column on the left and a header row of `column_labels`, written as PNG
/// atomically. The grid's pixels are exact: one image pixel per sheet pixel, no filtering.
pub fn contact_sheet(
    image: &Rgba,
    cell: usize,
    row_labels: &[String],
    column_labels: &[String],
    out: &Path,
) -> Result<(), Error> {
    check_sheet_geometry(image, cell, row_labels, column_labels)?;
    register_font().map_err(|m| write_error(out, m))?;
    let layout = SheetLayout::new(image, cell, row_labels, column_labels, out)?;
    let mut rgb = composite_sheet(image, &layout);
    draw_sheet_labels(&mut rgb, &layout, row_labels, column_labels, out)?;
    write_png(&rgb, layout.size(), out)
}

/// The label in the contact sheet's top-left corner, over the row labels.
const SHEET_CORNER: &str = "roughness";

/// Checks that `image` is a non-empty grid of `cell`-pixel cells with one label per row and
/// one per column.
fn check_sheet_geometry(
    image: &Rgba,
    cell: usize,
    row_labels: &[String],
    column_labels: &[String],
) -> Result<(), Error> {
    let geometry =
        |value: String, expected: &str| Error::input(Field::ContactSheet, value, expected);
    if cell == 0 || image.width == 0 || image.height == 0 {
        return Err(geometry(
            format!("{}×{} image, cell {cell}", image.width, image.height),
            "a non-empty image and a cell of at least 1 pixel",
        ));
    }
    if image.pixels.len() != image.width * image.height {
        return Err(geometry(
            format!(
                "{} pixels for {}×{}",
                image.pixels.len(),
                image.width,
                image.height
            ),
            "width × height pixels",
        ));
    }
    let (rows, columns) = (image.height.div_ceil(cell), image.width.div_ceil(cell));
    if row_labels.len() != rows || column_labels.len() != columns {
        return Err(geometry(
            format!(
                "{} row and {} column labels",
                row_labels.len(),
                column_labels.len()
            ),
            &format!(
                "one label per row and column of the {rows}×{columns} grid of {cell}-pixel cells"
            ),
        ));
    }
    Ok(())
}

/// Where the contact sheet's labels and grid go, in pixels.
struct SheetLayout {
    cell: usize,
    /// Text size of the row labels and the corner.
    label_px: f64,
    /// Text size of the column labels.
    header_px: f64,
    pad: u32,
    /// The grid's top-left corner: the label column's width and the header's height.
    left: usize,
    top: usize,
    width: usize,
    height: usize,
}

impl SheetLayout {
    /// Labels sized to the cell, within readable limits; the header shrinks further if the
    /// roughness values would not fit over their columns.
    fn new(
        image: &Rgba,
        cell: usize,
        row_labels: &[String],
        column_labels: &[String],
        out: &Path,
    ) -> Result<Self, Error> {
        let label_px = (cell as f64 * 0.25).clamp(12.0, 18.0);
        let pad = (label_px * 0.6).round() as u32;
        let width_of = |text: &str| -> Result<u32, Error> {
            text_size(text, label_px)
                .map(|(w, _)| w)
                .map_err(|e| write_error(out, e))
        };
        let mut label_w = width_of(SHEET_CORNER)?;
        for l in row_labels {
            label_w = label_w.max(width_of(l)?);
        }
        let mut widest_column = 1;
        for l in column_labels {
            widest_column = widest_column.max(width_of(l)?);
        }
        let header_px =
            (label_px * (cell as f64 - 4.0).max(1.0) / widest_column as f64).clamp(8.0, label_px);
        let left = (label_w + 2 * pad) as usize;
        let top = (label_px * 1.5).round() as usize + pad as usize;
        Ok(SheetLayout {
            cell,
            label_px,
            header_px,
            pad,
            left,
            top,
            width: left + image.width,
            height: top + image.height,
        })
    }

    fn size(&self) -> (u32, u32) {
        (self.width as u32, self.height as u32)
    }
}

/// The sheet's RGB bytes before the labels: label background, with the grid composited
/// over [`BACKGROUND`](crate::report::png::BACKGROUND) and sRGB-encoded in its place.
fn composite_sheet(image: &Rgba, layout: &SheetLayout) -> Vec<u8> {
    let (w, h) = (layout.width, layout.height);
    let (left, top) = (layout.left, layout.top);
    let mut rgb = vec![0u8; w * h * 3];
    for (i, px) in rgb.chunks_exact_mut(3).enumerate() {
        px.copy_from_slice(&[LABEL_BACKGROUND.0, LABEL_BACKGROUND.1, LABEL_BACKGROUND.2]);
        let (x, y) = (i % w, i / w);
        if x >= left && y >= top {
            px.copy_from_slice(&over_background(
                image.pixels[(y - top) * image.width + (x - left)],
            ));
        }
    }
    rgb
}

/// Draws the corner label, the column labels over their columns and the row labels beside
/// their rows onto the sheet's bytes.
fn draw_sheet_labels(
    rgb: &mut [u8],
    layout: &SheetLayout,
    row_labels: &[String],
    column_labels: &[String],
    out: &Path,
) -> Result<(), Error> {
    let root = backend(rgb, layout.size(), out)?.into_drawing_area();
    let draw = |text: &str, px: f64, anchor: Pos, at: (i32, i32)| {
        let style = TextStyle::from((FAMILY, px).into_font())
            .color(&LABEL_TEXT)
            .pos(anchor);
        root.draw_text(text, &style, at)
            .map_err(|e| write_error(out, format!("cannot draw the label '{text}': {e}")))
    };
    let right = Pos::new(HPos::Right, VPos::Center);
    let centre = Pos::new(HPos::Center, VPos::Center);
    let (left, top, cell) = (layout.left, layout.top, layout.cell);
    let label_x = left as i32 - layout.pad as i32;
    let header_y = (top / 2) as i32;
    draw(SHEET_CORNER, layout.label_px, right, (label_x, header_y))?;
    for (j, l) in column_labels.iter().enumerate() {
        let x = left + j * cell + cell / 2;
        draw(l, layout.header_px, centre, (x as i32, header_y))?;
    }
    for (i, l) in row_labels.iter().enumerate() {
        let y = top + i * cell + cell / 2;
        draw(l, layout.label_px, right, (label_x, y as i32))?;
    }
    root.present().map_err(|e| write_error(out, e))
}
