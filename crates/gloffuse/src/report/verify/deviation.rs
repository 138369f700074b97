//! The false-colour view of how far every pixel of a corrected sphere is from what the
//! correction promises: `pixel / target − 1` on a diverging scale around 0 (blue darker,
//! red brighter, white right), where the contact sheet's display encoding clips every
//! corrected sphere to flat white. The target of a pixel is its view-cosine ring's (see
//! [`crate::verify::Row::ring_targets`]).

use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use std::path::Path;

use super::words;
use crate::Error;
use crate::report::false_colour::{SCALE, colour};
use crate::report::png::{
    FAMILY, LABEL_BACKGROUND, LABEL_TEXT, backend, register_font, text_size, write_error, write_png,
};
use crate::verify::stats::RINGS;
use crate::verify::{Rendered, VerifyReport};

/// The deviation of every pixel of grid cell `index` from its ring's target, the channels
/// averaged; NaN outside the sphere (alpha below 0.5). Row-major, `cell × cell`.
pub fn cell_deviation(rendered: &Rendered, index: usize, targets: &[[f64; 3]]) -> Vec<f64> {
    let plan = &rendered.plan;
    let cell = plan.settings.cell as usize;
    let image = &rendered.image;
    let (x0, y0) = ((index % plan.columns) * cell, (index / plan.columns) * cell);
    let radius = plan.settings.radius_fraction * cell as f64 / 2.0;
    let centre = cell as f64 / 2.0;
    let mut out = vec![f64::NAN; cell * cell];
    for y in 0..cell {
        for x in 0..cell {
            let p = image.pixels[(y0 + y) * image.width + x0 + x];
            if p[3] < 0.5 {
                continue;
            }
            let (dx, dy) = (x as f64 + 0.5 - centre, y as f64 + 0.5 - centre);
            let d2 = (dx * dx + dy * dy) / (radius * radius);
            let mu = (1.0 - d2).max(0.0).sqrt();
            let ring = ((mu * RINGS as f64) as usize).min(RINGS - 1);
            let Some(target) = targets.get(ring) else {
                continue;
            };
            let ratio: f64 = (0..3)
                .map(|c| f64::from(p[c]) / f64::from(p[3]) / target[c])
                .sum::<f64>()
                / 3.0;
            out[y * cell + x] = ratio - 1.0;
        }
    }
    out
}

/// The deviation view of cell `index` as RGB bytes, `cell × cell`.
pub fn cell_image(rendered: &Rendered, index: usize, targets: &[[f64; 3]]) -> Vec<u8> {
    cell_deviation(rendered, index, targets)
        .into_iter()
        .flat_map(colour)
        .collect()
}

/// `deviation.png`: a title (Blender version, coefficients, samples; in roughness mode
/// what that mode leaves off target), one row per distribution of its corrected spheres in
/// false colour, a column per roughness labelled with it, and the scale's legend.
pub fn sheet(report: &VerifyReport, rendered: &Rendered, out: &Path) -> Result<(), Error> {
    register_font().map_err(|m| write_error(out, m))?;
    let layout = Layout::new(report, rendered, out)?;
    let mut rgb = vec![0u8; layout.width * layout.height * 3];
    for px in rgb.chunks_exact_mut(3) {
        px.copy_from_slice(&[LABEL_BACKGROUND.0, LABEL_BACKGROUND.1, LABEL_BACKGROUND.2]);
    }
    paint_cells(&mut rgb, report, rendered, &layout);
    paint_colour_bar(&mut rgb, &layout);
    draw_text(&mut rgb, report, &layout, out)?;
    write_png(&rgb, layout.size(), out)
}

/// Text size of the series labels.
const LABEL_PX: f64 = 14.0;
/// Space around the sheet's parts, and between its cells.
const PAD: usize = 10;
const GAP: usize = 4;
/// Heights of the title (two lines; a third in roughness mode), of the roughness labels
/// over the columns, and of the scale's legend below the cells.
const TITLE_H: usize = 54;
const SCOPE_H: usize = 18;
const COLUMN_LABEL_H: usize = 20;
const LEGEND_H: usize = 64;

/// Where the deviation sheet's parts go, in pixels.
struct Layout {
    /// The distributions (with their index of refraction), one row each, in report order.
    series: Vec<String>,
    cell: usize,
    columns: usize,
    /// The roughness over each column (`r = 0.5`), blank where no corrected sphere is.
    column_labels: Vec<String>,
    /// Where the cells start: below the title, the scope line and the column labels.
    top: usize,
    /// Width of the label column: where the cells start.
    left: usize,
    width: usize,
    height: usize,
    /// The colour bar: x, width, y, height.
    bar: (usize, usize, usize, usize),
}

impl Layout {
    fn new(report: &VerifyReport, rendered: &Rendered, out: &Path) -> Result<Self, Error> {
        let plan = &rendered.plan;
        let cell = plan.settings.cell as usize;
        let mut series: Vec<_> = report.rows.iter().map(|r| r.series()).collect();
        series.dedup();
        let columns = plan.columns.max(1);
        let mut column_labels = vec![String::new(); columns];
        for row in &report.rows {
            let j = plan.rows[row.id].corrected % columns;
            column_labels[j] = format!("r = {}", row.roughness);
        }
        let scope = if report.mode.per_pixel() { 0 } else { SCOPE_H };
        let top = TITLE_H + scope + COLUMN_LABEL_H;
        let mut label_w = 0;
        for name in &series {
            label_w = label_w.max(
                text_size(name, LABEL_PX)
                    .map_err(|e| write_error(out, e))?
                    .0,
            );
        }
        let left = label_w as usize + 2 * PAD;
        // As wide as the cells, and as the lines over them: a narrow sweep's title and scope
        // line would otherwise run off the picture.
        let mut text_w = 0;
        for (text, px) in title_lines(report) {
            text_w = text_w.max(text_size(&text, px).map_err(|e| write_error(out, e))?.0);
        }
        let width = (left + columns * (cell + GAP) + PAD)
            .max(text_w as usize + 2 * PAD)
            .max(640);
        let height = top + series.len() * (cell + GAP) + LEGEND_H;
        let bar = (PAD + 60, width - 2 * PAD - 120, height - LEGEND_H + 10, 14);
        Ok(Layout {
            series,
            cell,
            columns,
            column_labels,
            top,
            left,
            width,
            height,
            bar,
        })
    }

    fn size(&self) -> (u32, u32) {
        (self.width as u32, self.height as u32)
    }

    /// The top of row `k`.
    fn row_y(&self, k: usize) -> usize {
        self.top + k * (self.cell + GAP)
    }
}

/// Each report row's corrected sphere in false colour, in its series' row and its
/// roughness' column.
fn paint_cells(rgb: &mut [u8], report: &VerifyReport, rendered: &Rendered, layout: &Layout) {
    let (cell, w) = (layout.cell, layout.width);
    for row in &report.rows {
        let index = rendered.plan.rows[row.id].corrected;
        let k = layout
            .series
            .iter()
            .position(|name| *name == row.series())
            .expect("listed above");
        let j = index % layout.columns;
        let pixels = cell_image(rendered, index, &row.ring_targets);
        let (ox, oy) = (layout.left + j * (cell + GAP), layout.row_y(k));
        for y in 0..cell {
            for x in 0..cell {
                let at = ((oy + y) * w + ox + x) * 3;
                rgb[at..at + 3].copy_from_slice(&pixels[(y * cell + x) * 3..][..3]);
            }
        }
    }
}

/// The legend's colour bar, −[`SCALE`] on the left to +[`SCALE`] on the right.
fn paint_colour_bar(rgb: &mut [u8], layout: &Layout) {
    let (bar_x, bar_w, bar_y, bar_h) = layout.bar;
    for x in 0..bar_w {
        let d = (2.0 * x as f64 / (bar_w - 1) as f64 - 1.0) * SCALE;
        let c = colour(d);
        for y in 0..bar_h {
            let at = ((bar_y + y) * layout.width + bar_x + x) * 3;
            rgb[at..at + 3].copy_from_slice(&c);
        }
    }
}

/// The lines over the cells, each with its text size: the title, the subtitle and, in
/// roughness mode, what the mode judges.
fn title_lines(report: &VerifyReport) -> Vec<(String, f64)> {
    let mut lines = vec![
        (
            "Corrected spheres: each pixel against what the correction promises".to_string(),
            16.0,
        ),
        (subtitle(report), 12.0),
    ];
    if !report.mode.per_pixel() {
        lines.push((words::ROUGHNESS_PICTURE.to_string(), 12.0));
    }
    lines
}

/// The title, the series labels and the scale's labels.
fn draw_text(
    rgb: &mut [u8],
    report: &VerifyReport,
    layout: &Layout,
    out: &Path,
) -> Result<(), Error> {
    let root = backend(rgb, layout.size(), out)?.into_drawing_area();
    let draw = |text: &str, px: f64, anchor: Pos, at: (usize, usize)| {
        let style = TextStyle::from((FAMILY, px).into_font())
            .color(&LABEL_TEXT)
            .pos(anchor);
        root.draw_text(text, &style, (at.0 as i32, at.1 as i32))
            .map_err(|e| write_error(out, format!("cannot draw '{text}': {e}")))
    };
    let left_mid = Pos::new(HPos::Left, VPos::Center);
    let right_mid = Pos::new(HPos::Right, VPos::Center);
    for ((text, px), y) in title_lines(report).iter().zip([16, 38, TITLE_H + 2]) {
        draw(text, *px, left_mid, (PAD, y))?;
    }
    let bottom_centre = Pos::new(HPos::Center, VPos::Bottom);
    for (j, label) in layout.column_labels.iter().enumerate() {
        let x = layout.left + j * (layout.cell + GAP) + layout.cell / 2;
        draw(label, 12.0, bottom_centre, (x, layout.top - 4))?;
    }
    for (k, name) in layout.series.iter().enumerate() {
        let y = layout.row_y(k) + layout.cell / 2;
        draw(name, LABEL_PX, right_mid, (layout.left - PAD, y))?;
    }
    let (bar_x, bar_w, bar_y, bar_h) = layout.bar;
    let centre = Pos::new(HPos::Center, VPos::Top);
    for t in [-SCALE, -SCALE / 2.0, 0.0, SCALE / 2.0, SCALE] {
        let x = bar_x + ((t / SCALE + 1.0) / 2.0 * (bar_w - 1) as f64).round() as usize;
        draw(&tick_label(t), 12.0, centre, (x, bar_y + bar_h + 4))?;
    }
    draw("darker", 12.0, right_mid, (bar_x - 6, bar_y + bar_h / 2))?;
    let after_bar = (bar_x + bar_w + 6, bar_y + bar_h / 2);
    draw("brighter", 12.0, left_mid, after_bar)?;
    root.present().map_err(|e| write_error(out, e))
}

/// The line under the title: Blender version, coefficients, mode, colour model, cell size
/// and samples.
fn subtitle(report: &VerifyReport) -> String {
    let info = &report.render;
    format!(
        "Blender {} · coefficients {} · {} mode, {} colour · {} px, {} spp",
        info.blender_version,
        report.coefficients,
        report.mode.key(),
        report.color_model.key(),
        info.cell,
        info.samples
    )
}

/// A colour bar tick's label: `-5.0 %`, …, `0 (right)`, …, `+5.0 %`.
fn tick_label(t: f64) -> String {
    if t == 0.0 {
        "0 (right)".to_string()
    } else {
        format!("{:+.1} %", 100.0 * t)
    }
}
