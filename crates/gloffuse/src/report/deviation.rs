//! The false-colour view of how far every pixel of a corrected sphere is from what the
//! correction promises: `pixel / target − 1` on a diverging scale around 0 (blue darker,
//! red brighter, white right), where the contact sheet's display encoding clips every
//! corrected sphere to flat white. The target of a pixel is its view-cosine ring's (see
//! [`crate::verify::Row::ring_targets`]).

use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use std::path::Path;

use super::png::{
    BACKGROUND, FAMILY, LABEL_BACKGROUND, LABEL_TEXT, backend, register_font, srgb8, text_size,
    write_error, write_png,
};
use crate::Error;
use crate::verify::stats::RINGS;
use crate::verify::{Rendered, VerifyReport};

/// The deviation at which the scale saturates: ±5 %.
pub const SCALE: f64 = 0.05;

/// The diverging colour of a deviation `d` (RdBu: blue at −[`SCALE`], near-white at 0,
/// red at +[`SCALE`]; clamped beyond); NaN is the background grey.
///
/// ```
/// use gloffuse::report::deviation::colour;
/// assert_eq!(colour(0.0), [247, 247, 247]);
/// assert_eq!(colour(-1.0), [33, 102, 172]);
/// assert_eq!(colour(1.0), [178, 24, 43]);
/// ```
pub fn colour(d: f64) -> [u8; 3] {
    const LOW: [f64; 3] = [33.0, 102.0, 172.0];
    const MID: [f64; 3] = [247.0, 247.0, 247.0];
    const HIGH: [f64; 3] = [178.0, 24.0, 43.0];
    if d.is_nan() {
        let g = srgb8(BACKGROUND);
        return [g, g, g];
    }
    let t = (d / SCALE).clamp(-1.0, 1.0);
    let (from, to, f) = if t < 0.0 {
        (MID, LOW, -t)
    } else {
        (MID, HIGH, t)
    };
    [0, 1, 2].map(|c| (from[c] + (to[c] - from[c]) * f).round() as u8)
}

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

/// `deviation.png`: a title (Blender version, coefficients, samples), one row per
/// distribution of its corrected spheres in false colour, a column per roughness, and the
/// scale's legend.
pub fn sheet(report: &VerifyReport, rendered: &Rendered, out: &Path) -> Result<(), Error> {
    register_font().map_err(|m| write_error(out, m))?;
    let plan = &rendered.plan;
    let cell = plan.settings.cell as usize;
    let rows: Vec<_> = report
        .rows
        .iter()
        .map(|row| (row, plan.rows[row.id].corrected))
        .collect();
    let series: Vec<String> = {
        let mut s: Vec<_> = rows.iter().map(|(r, _)| r.series()).collect();
        s.dedup();
        s
    };
    let columns = plan.columns.max(1);
    let label_px = 14.0;
    let mut label_w = 0;
    for name in &series {
        label_w = label_w.max(
            text_size(name, label_px)
                .map_err(|e| write_error(out, e))?
                .0,
        );
    }
    let (pad, gap) = (10usize, 4usize);
    let left = label_w as usize + 2 * pad;
    let title_h = 54;
    let legend_h = 64;
    let grid_w = columns * (cell + gap);
    let w = (left + grid_w + pad).max(560);
    let h = title_h + series.len() * (cell + gap) + legend_h;
    let mut rgb = vec![0u8; w * h * 3];
    for px in rgb.chunks_exact_mut(3) {
        px.copy_from_slice(&[LABEL_BACKGROUND.0, LABEL_BACKGROUND.1, LABEL_BACKGROUND.2]);
    }
    for (row, index) in &rows {
        let k = series
            .iter()
            .position(|name| *name == row.series())
            .expect("listed above");
        let j = index % columns;
        let pixels = cell_image(rendered, *index, &row.ring_targets);
        let (ox, oy) = (left + j * (cell + gap), title_h + k * (cell + gap));
        for y in 0..cell {
            for x in 0..cell {
                let at = ((oy + y) * w + ox + x) * 3;
                rgb[at..at + 3].copy_from_slice(&pixels[(y * cell + x) * 3..][..3]);
            }
        }
    }
    // The legend's colour bar.
    let (bar_x, bar_w, bar_y, bar_h) = (pad + 60, w - 2 * pad - 120, h - legend_h + 10, 14);
    for x in 0..bar_w {
        let d = (2.0 * x as f64 / (bar_w - 1) as f64 - 1.0) * SCALE;
        let c = colour(d);
        for y in 0..bar_h {
            let at = ((bar_y + y) * w + bar_x + x) * 3;
            rgb[at..at + 3].copy_from_slice(&c);
        }
    }
    {
        let root = backend(&mut rgb, (w as u32, h as u32), out)?.into_drawing_area();
        let draw = |text: &str, px: f64, anchor: Pos, at: (usize, usize)| {
            let style = TextStyle::from((FAMILY, px).into_font())
                .color(&LABEL_TEXT)
                .pos(anchor);
            root.draw_text(text, &style, (at.0 as i32, at.1 as i32))
                .map_err(|e| write_error(out, format!("cannot draw '{text}': {e}")))
        };
        let left_mid = Pos::new(HPos::Left, VPos::Center);
        let right_mid = Pos::new(HPos::Right, VPos::Center);
        let centre = Pos::new(HPos::Center, VPos::Top);
        let info = &report.render;
        draw(
            "Corrected spheres: each pixel against what the correction promises",
            16.0,
            left_mid,
            (pad, 16),
        )?;
        draw(
            &format!(
                "Blender {} · coefficients {} · {} mode, {} colour · {} px, {} spp",
                info.blender_version,
                report.coefficients,
                report.mode.key(),
                report.color_model.key(),
                info.cell,
                info.samples
            ),
            12.0,
            left_mid,
            (pad, 38),
        )?;
        for (k, name) in series.iter().enumerate() {
            let y = title_h + k * (cell + gap) + cell / 2;
            draw(name, label_px, right_mid, (left - pad, y))?;
        }
        let ticks = [-SCALE, -SCALE / 2.0, 0.0, SCALE / 2.0, SCALE];
        for t in ticks {
            let x = bar_x + ((t / SCALE + 1.0) / 2.0 * (bar_w - 1) as f64).round() as usize;
            let text = if t == 0.0 {
                "0 (right)".to_string()
            } else {
                format!("{:+.1} %", 100.0 * t)
            };
            draw(&text, 12.0, centre, (x, bar_y + bar_h + 4))?;
        }
        draw("darker", 12.0, right_mid, (bar_x - 6, bar_y + bar_h / 2))?;
        draw(
            "brighter",
            12.0,
            left_mid,
            (bar_x + bar_w + 6, bar_y + bar_h / 2),
        )?;
        root.present().map_err(|e| write_error(out, e))?;
    }
    write_png(&rgb, (w as u32, h as u32), out)
}
