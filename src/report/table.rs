//! The terminal table of a verify report.

use std::fmt::Write as _;

use crate::generate::Mode;
use crate::verify::VerifyReport;

/// The verdict as a terminal table: a title line, one row per sphere, the references,
/// the verdict line, notes, and the log and rerun command when something failed.
pub fn render(report: &VerifyReport) -> String {
    let i = &report.render;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "Blender {} ({} masking) · coefficients {} · {} px per sphere, {} spp, seed {} · rendered in {:.1} s",
        i.blender_version,
        i.masking,
        report.coefficients,
        i.cell,
        i.samples,
        i.seed,
        i.render_seconds
    );
    let _ = writeln!(
        s,
        "{:<18} {:>5} {:>12} {:>11} {:>7} {:>10} {:>7} {:>8}  status",
        "distribution", "r", "uncorrected", "corrected", "±SE", "predicted", "centre", "ring Δ"
    );
    for r in &report.rows {
        let _ = writeln!(
            s,
            "{:<18} {:>5} {:>11.2}% {:>10.2}% {:>6.2}% {:>9.2}% {:>6.1}% {:>7.2}%  {}",
            r.distribution.label(),
            r.roughness,
            100.0 * r.uncorrected.mean,
            100.0 * r.corrected.mean,
            100.0 * r.corrected.standard_error,
            100.0 * r.predicted_corrected,
            100.0 * r.corrected.center,
            100.0 * r.worst_ring,
            if r.pass { "ok" } else { "FAIL" }
        );
    }
    for r in &report.reference {
        let _ = writeln!(
            s,
            "{:<18} {:>5} {:>11.2}% {:>10} {:>6.2}% {:>10} {:>6.1}%  reference",
            "Multiscatter GGX",
            r.roughness,
            100.0 * r.stats.mean,
            "",
            100.0 * r.stats.standard_error,
            "",
            100.0 * r.stats.center
        );
    }
    let failed = report.rows.iter().filter(|r| !r.pass).count();
    let rings = match report.mode {
        Mode::Roughness => String::new(),
        _ => format!(
            ", every view-cosine ring within ±{} %",
            report.ring_tolerance_percent
        ),
    };
    let _ = writeln!(
        s,
        "{}: {} of {} corrected spheres ({:?} mode) within ±{} % of 100 %{rings}",
        if report.pass { "PASS" } else { "FAIL" },
        report.rows.len() - failed,
        report.rows.len(),
        report.mode,
        report.tolerance_percent
    );
    for n in &report.notes {
        let _ = writeln!(s, "note: {n}");
    }
    if !report.pass {
        let _ = writeln!(s, "log: {}\nrerun: {}", i.log, i.command);
    }
    s
}
