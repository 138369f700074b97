//! The terminal table of a verify report.

use std::fmt::Write as _;

use crate::generate::ColorModel;
use crate::measure::Engine;
use crate::verify::{VerifyReport, spec};

use super::words;

/// The verdict as a terminal table: a title line, one row per sphere, the references,
/// the verdict line, notes, and the log and rerun command when something failed.
pub fn render(report: &VerifyReport) -> String {
    let mut s = String::new();
    write_title(&mut s, report);
    let spec = spec(report.mode);
    // Rows with an index name it too ("Ashikhmin-Shirley, IOR 1.33"), and so do the
    // references ("Multiscatter GGX glass, IOR 1.5").
    let w = if spec.takes_ior() { 32 } else { 18 };
    if let Some(legend) = spec.legend {
        let _ = writeln!(s, "{legend}");
    }
    // An EEVEE sweep shows, beside each plain sphere, what Cycles renders for it.
    let eevee = report.engine == Engine::Eevee;
    write_column_names(&mut s, w, spec.row_heading, eevee);
    write_spheres(&mut s, report, w, eevee);
    write_references(&mut s, report, w, eevee);
    write_verdict(&mut s, report);
    for n in &report.notes {
        let _ = writeln!(s, "note: {}", super::notes::sentence(n));
    }
    if !report.pass {
        let i = &report.render;
        let _ = writeln!(s, "log: {}\nrerun: {}", i.log, i.command);
    }
    s
}

/// How the sweep was rendered, and in which colour when it is not plain white.
fn write_title(s: &mut String, report: &VerifyReport) {
    let i = &report.render;
    let white = report.color == [1.0; 3];
    let colour = if white && report.color_model == ColorModel::Exact {
        String::new()
    } else {
        let rgb: Vec<String> = report.color.iter().map(|c| c.to_string()).collect();
        format!(
            " · colour {} ({} colour model; percentages are of what it promises)",
            rgb.join(","),
            report.color_model.key()
        )
    };
    let engine = match report.engine {
        Engine::Cycles => format!("{} masking", i.masking),
        Engine::Eevee => "EEVEE: every distribution renders as GGX".to_string(),
    };
    let _ = writeln!(
        s,
        "Blender {} ({engine}) · coefficients {} · {} px per sphere, {} spp, seed {} · rendered in {:.1} s{colour}",
        i.blender_version, report.coefficients, i.cell, i.samples, i.seed, i.render_seconds
    );
}

/// The table's header line; the first column `w` wide.
fn write_column_names(s: &mut String, w: usize, row_heading: &str, eevee: bool) {
    let _ = writeln!(
        s,
        "{:<w$} {:>5} {:>12}{} {:>11} {:>7} {:>10} {:>7} {:>8}  status",
        row_heading,
        "r",
        "uncorrected",
        if eevee {
            format!(" {:>10}", "in Cycles")
        } else {
            String::new()
        },
        "corrected",
        "±SE",
        "predicted",
        "centre",
        "ring Δ"
    );
}

/// One line per judged sphere.
fn write_spheres(s: &mut String, report: &VerifyReport, w: usize, eevee: bool) {
    for r in &report.rows {
        let _ = writeln!(
            s,
            "{:<w$} {:>5} {:>11.2}%{} {:>10.2}% {:>6.2}% {:>9.2}% {:>6.1}% {:>7.2}%  {}",
            r.series(),
            r.roughness,
            100.0 * r.uncorrected_brightness,
            cycles_column(eevee, r.cycles_uncorrected),
            100.0 * r.brightness,
            100.0 * r.corrected.standard_error / average(r.target),
            100.0 * r.predicted_corrected,
            100.0 * r.corrected.center / average(r.target),
            100.0 * r.worst_ring,
            if r.pass { "ok" } else { "FAIL" }
        );
    }
}

/// One line per reference sphere.
fn write_references(s: &mut String, report: &VerifyReport, w: usize, eevee: bool) {
    for r in &report.reference {
        let _ = writeln!(
            s,
            "{:<w$} {:>5} {:>11.2}%{} {:>10} {:>6.2}% {:>10} {:>6.1}%  reference",
            r.series(report.mode),
            r.roughness,
            100.0 * r.brightness,
            cycles_column(eevee, None),
            "",
            100.0 * r.stats.standard_error / average(report.color),
            "",
            100.0 * r.stats.center / average(report.color)
        );
    }
}

/// The verdict line, what the target is, what the mode judges, and what "predicted" is.
fn write_verdict(s: &mut String, report: &VerifyReport) {
    let _ = writeln!(s, "{}", words::headline(report));
    let _ = writeln!(
        s,
        "({}; predicted: {})",
        words::target(report),
        words::PREDICTED
    );
    // Where the rings are not judged, the table says why they look off target.
    if !report.mode.per_pixel() {
        let _ = writeln!(s, "{}", spec(report.mode).scope);
    }
}

/// The "in Cycles" column of an EEVEE sweep (blank where Cycles has no value); nothing
/// for a Cycles sweep.
fn cycles_column(eevee: bool, v: Option<f64>) -> String {
    match (eevee, v) {
        (false, _) => String::new(),
        (true, Some(v)) => format!(" {:>9.2}%", 100.0 * v),
        (true, None) => format!(" {:>10}", ""),
    }
}

fn average(v: [f64; 3]) -> f64 {
    v.iter().sum::<f64>() / 3.0
}
