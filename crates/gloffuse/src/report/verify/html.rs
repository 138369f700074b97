//! `report.html`: the verdict as a page a person reads in a browser, in the spirit of
//! Blender's own render-test report: the verdict and its named thresholds first, the
//! commands to rerun, then one row per sphere — failures first — with its numbers and three
//! thumbnails (uncorrected, corrected, and the corrected sphere in false colour against what
//! it promises). One self-contained file: the thumbnails are inline PNGs.

use std::fmt::Write as _;

use super::{deviation, words};
use crate::report::page::{FAIL_COLOUR, PASS_COLOUR, banner, escape, page_css};
use crate::report::{false_colour, png};
use crate::verify::verdict::MIN_RING_PIXELS;
use crate::verify::{Rendered, Row, VerifyReport, spec};

/// `rerun` is the command line that reproduces the whole check (the CLI passes its own);
/// `files` are the report's other files, linked by name.
pub fn render(report: &VerifyReport, rendered: &Rendered, rerun: &str, files: &[String]) -> String {
    let verdict = if report.pass { "PASS" } else { "FAIL" };
    let mut s = String::new();
    write_head(&mut s, verdict, report.pass);
    write_banner(&mut s, report);
    write_thresholds(&mut s, report);
    write_rerun(&mut s, report, rerun);
    write_notes(&mut s, report);
    write_plot(&mut s, files);
    write_spheres(&mut s, report, rendered);
    write_reference(&mut s, report, rendered);
    write_files(&mut s, files);
    s.push_str("</main></body></html>\n");
    s
}

/// The document's start: its title and the style sheet, up to the opening `<body>`.
fn write_head(s: &mut String, verdict: &str, pass: bool) {
    let _ = write!(
        s,
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\
         <title>gloffuse verify: {verdict}</title>\n<style>\n{}\
         table {{ border-collapse: collapse; margin: 8px 0 20px; }}\n\
         th, td {{ border-bottom: 1px solid #ddd; padding: 4px 10px; text-align: right; vertical-align: middle; }}\n\
         th {{ background: #eee; }} td.name {{ text-align: left; }}\n\
         tr.fail td {{ background: #fdecea; }}\n\
         td.fail {{ color: {FAIL_COLOUR}; font-weight: bold; }} td.ok {{ color: {PASS_COLOUR}; }}\n\
         img {{ image-rendering: pixelated; width: 96px; height: 96px; display: block; }}\n\
         img.plot {{ image-rendering: auto; width: auto; height: auto; max-width: 100%; }}\n\
         th small {{ display: block; font-weight: normal; max-width: 14em; }}\n\
         pre {{ background: #eee; padding: 6px 10px; white-space: pre-wrap; word-break: break-all; }}\n\
         .legend {{ width: 360px; margin: 4px 0 8px; }} .scope {{ max-width: 60em; }} .caption {{ white-space: nowrap; }}\n\
         .ticks {{ display: flex; justify-content: space-between; font-size: 12px; }}\n\
         .scale {{ width: 100%; height: 14px; background: linear-gradient(to right, {}, {}, {}); }}\n\
         </style></head><body>\n",
        page_css(pass),
        css(false_colour::colour(-false_colour::SCALE)),
        css(false_colour::colour(0.0)),
        css(false_colour::colour(false_colour::SCALE)),
    );
}

/// The coloured banner: the verdict in words and how the sweep was rendered; it opens
/// `<main>`.
fn write_banner(s: &mut String, report: &VerifyReport) {
    let info = &report.render;
    let detail = format!(
        "Blender {} ({} masking) · coefficients {} · {} mode · colour {} ({}) · {} px per sphere, {} spp, seed {} · rendered in {:.1} s",
        escape(&info.blender_version),
        escape(&info.masking),
        escape(&report.coefficients),
        report.mode.key(),
        report
            .color
            .iter()
            .map(|c| c.to_string())
            .collect::<Vec<_>>()
            .join(", "),
        report.color_model.key(),
        info.cell,
        info.samples,
        info.seed,
        info.render_seconds,
    );
    s.push_str(&banner(&words::headline(report), &detail));
}

/// The named thresholds the verdict applies, what they are measured against, and what
/// the mode judges.
fn write_thresholds(s: &mut String, report: &VerifyReport) {
    let rings = if report.mode.per_pixel() {
        format!(
            "<li><b>ring tolerance</b>: every view-cosine ring with at least {MIN_RING_PIXELS} \
             fully covered pixels within ±{} % of its target.</li>",
            report.ring_tolerance_percent
        )
    } else {
        "<li><b>rings</b>: not judged in this mode.</li>".to_string()
    };
    let _ = writeln!(
        s,
        "<h2>What is judged</h2><p class=\"scope\">{}</p><ul>\
         <li><b>tolerance</b>: every channel of a corrected sphere's mean within ±{} % of its target; {}.</li>\
         {rings}<li>The <b>predicted</b> column: {}.</li></ul>",
        escape(spec(report.mode).scope),
        report.tolerance_percent,
        escape(&words::target(report)),
        escape(words::PREDICTED),
    );
}

/// The commands that rerun the check and its Blender render, and the render's log.
fn write_rerun(s: &mut String, report: &VerifyReport, rerun: &str) {
    let info = &report.render;
    let _ = writeln!(
        s,
        "<h2>Rerun</h2><p>This check:</p><pre>{}</pre><p>Its Blender render (log: <code>{}</code>):</p><pre>{}</pre>",
        escape(rerun),
        escape(&info.log),
        escape(&info.command)
    );
}

/// The report's notes as a list; nothing when it has none.
fn write_notes(s: &mut String, report: &VerifyReport) {
    if report.notes.is_empty() {
        return;
    }
    s.push_str("<h2>Notes</h2><ul>");
    for n in &report.notes {
        let _ = write!(s, "<li>{}</li>", escape(&super::notes::sentence(n)));
    }
    s.push_str("</ul>\n");
}

/// The brightness plot (`brightness.png`, when the report has one) on the page itself: the
/// clearest picture of what the check found.
fn write_plot(s: &mut String, files: &[String]) {
    if files.iter().any(|f| f == PLOT) {
        let _ = writeln!(
            s,
            "<h2>Brightness against roughness</h2><img class=\"plot\" src=\"{PLOT}\" \
             alt=\"brightness against roughness, rendered and predicted\">"
        );
    }
}

/// The brightness plot's file name in a report folder.
pub const PLOT: &str = "brightness.png";

/// The spheres' table, failures first: numbers, two thumbnails and the false-colour one.
fn write_spheres(s: &mut String, report: &VerifyReport, rendered: &Rendered) {
    // Layered mode compares the hand-made Mix Shader with the layered group, glass mode
    // Blender's Glass BSDF with the glass group.
    let (plain, fixed) = (spec(report.mode).uncorrected, spec(report.mode).corrected);
    let (ring, deviation) = if report.mode.per_pixel() {
        ("worst ring", String::new())
    } else {
        // Where the eye lands on a coloured disc beside an ok: why it is coloured.
        (
            "worst ring (not judged)",
            format!("<small>{}</small>", escape(MEAN_ONLY)),
        )
    };
    s.push_str("<h2>Spheres</h2>");
    write_scale(s);
    let _ = writeln!(
        s,
        "<table><tr><th>status</th><th>sphere</th><th>{plain}</th>\
         <th>{fixed}</th><th>predicted</th><th>±SE</th><th>{ring}</th>\
         <th>{plain}</th><th>{fixed}</th><th>deviation{deviation}</th></tr>",
    );
    let mut rows: Vec<_> = report.rows.iter().collect();
    rows.sort_by_key(|r| r.pass);
    for row in rows {
        write_sphere_row(s, row, rendered);
    }
    s.push_str("</table>\n");
}

/// Why a sphere judged on its mean alone has a coloured deviation disc.
const MEAN_ONLY: &str = "this mode corrects the mean only: a passing sphere's centre stays \
                         darker and its rim brighter than 100 %, so its disc is coloured (the \
                         view mode corrects every pixel)";

/// One sphere's row of the spheres' table.
fn write_sphere_row(s: &mut String, row: &Row, rendered: &Rendered) {
    let cells = &rendered.plan.rows[row.id];
    let false_colour = png_tag(
        &deviation::cell_image(rendered, cells.corrected, &row.ring_targets),
        rendered.plan.settings.cell as usize,
    );
    let (class, status) = if row.pass {
        ("ok", "ok")
    } else {
        ("fail", "FAIL")
    };
    let _ = writeln!(
        s,
        "<tr class=\"{class}\"><td class=\"{class}\">{status}</td><td class=\"name\">{} r = {}</td>\
         <td>{:.2} %</td><td>{:.2} %</td><td>{:.2} %</td><td>{:.2} %</td><td>{:.2} %</td>\
         <td>{}</td><td>{}</td><td>{false_colour}</td></tr>",
        escape(&row.series()),
        row.roughness,
        100.0 * row.uncorrected_brightness,
        100.0 * row.brightness,
        100.0 * row.predicted_corrected,
        100.0 * row.corrected.standard_error,
        100.0 * row.worst_ring,
        thumbnail(rendered, cells.uncorrected),
        thumbnail(rendered, cells.corrected),
    );
}

/// The legend of the false-colour thumbnails, above the table they explain: the bar with
/// its end labels under its ends and the middle under its middle.
fn write_scale(s: &mut String) {
    let _ = writeln!(
        s,
        "<div class=\"legend\"><div class=\"caption\">Deviation column: each pixel of the corrected sphere against its target</div>\
         <div class=\"scale\"></div><div class=\"ticks\"><span>−{0} % (darker)</span><span>0</span>\
         <span>+{0} % (brighter)</span></div></div>",
        100.0 * false_colour::SCALE
    );
}

/// The reference spheres' table; nothing when the sweep has none.
fn write_reference(s: &mut String, report: &VerifyReport, rendered: &Rendered) {
    if report.reference.is_empty() {
        return;
    }
    let _ = writeln!(
        s,
        "<h2>Reference: Blender's {}</h2><table><tr><th>sphere</th><th>r</th><th>brightness</th><th>±SE</th><th>sphere</th></tr>",
        spec(report.mode).reference
    );
    for r in &report.reference {
        let _ = writeln!(
            s,
            "<tr><td class=\"name\">{}</td><td>{}</td><td>{:.2} %</td><td>{:.2} %</td><td>{}</td></tr>",
            escape(&r.series(report.mode)),
            r.roughness,
            100.0 * r.brightness,
            100.0 * r.stats.standard_error,
            thumbnail(rendered, r.cell)
        );
    }
    s.push_str("</table>\n");
}

/// Links to the report's other files; nothing when there are none.
fn write_files(s: &mut String, files: &[String]) {
    if files.is_empty() {
        return;
    }
    s.push_str("<h2>Files</h2><ul>");
    for f in files {
        let _ = write!(s, "<li><a href=\"{0}\">{0}</a></li>", escape(f));
    }
    s.push_str("</ul>\n");
}

/// The rendered cell `i` as an inline `<img>` (nothing if the image does not hold it).
fn thumbnail(rendered: &Rendered, i: usize) -> String {
    let plan = &rendered.plan;
    let cell = plan.settings.cell as usize;
    png::cell_image(&rendered.image, plan.columns, cell, i)
        .map_or_else(String::new, |rgb| png_tag(&rgb, cell))
}

fn css([r, g, b]: [u8; 3]) -> String {
    format!("rgb({r}, {g}, {b})")
}

/// An inline `<img>` of `cell × cell` RGB bytes.
fn png_tag(rgb: &[u8], cell: usize) -> String {
    match png::encode_png(rgb, (cell as u32, cell as u32)) {
        Ok(bytes) => format!(
            "<img alt=\"\" src=\"data:image/png;base64,{}\">",
            base64(&bytes)
        ),
        Err(_) => String::new(),
    }
}

/// Standard base64 with padding (RFC 4648).
fn base64(bytes: &[u8]) -> String {
    const TABLE: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for chunk in bytes.chunks(3) {
        let b = [
            chunk[0],
            *chunk.get(1).unwrap_or(&0),
            *chunk.get(2).unwrap_or(&0),
        ];
        let n = (u32::from(b[0]) << 16) | (u32::from(b[1]) << 8) | u32::from(b[2]);
        for k in 0..4 {
            if k <= chunk.len() {
                out.push(TABLE[((n >> (18 - 6 * k)) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_matches_rfc_4648() {
        for (text, encoded) in [
            ("", ""),
            ("f", "Zg=="),
            ("fo", "Zm8="),
            ("foo", "Zm9v"),
            ("foob", "Zm9vYg=="),
            ("fooba", "Zm9vYmE="),
            ("foobar", "Zm9vYmFy"),
        ] {
            assert_eq!(base64(text.as_bytes()), encoded);
        }
    }
}
