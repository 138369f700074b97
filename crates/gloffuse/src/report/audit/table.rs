//! The audit verdict for a terminal: one line per material (failures first), then its
//! findings, the file findings, and the counts. Every name and message in it comes from
//! users' files (or a shard's report.json) and is shown through [`terminal`], so none can
//! drive the terminal or start a line of its own.

use crate::audit::{AuditReport, AuditedFile, AuditedMaterial, Verdict};
use crate::report::escape::terminal;

/// A brightness in percent, or a dash where there is none.
pub(super) fn pct(x: Option<f64>) -> String {
    x.map_or_else(|| "—".to_string(), |x| format!("{:.1} %", 100.0 * x))
}

/// Failures first (creates, loses, error), then the rest, each in report order, with its
/// index in the report.
pub fn order(report: &AuditReport) -> Vec<(usize, &AuditedMaterial)> {
    let mut ms: Vec<(usize, &AuditedMaterial)> = report.materials.iter().enumerate().collect();
    ms.sort_by_key(|(_, m)| m.verdict);
    ms
}

pub fn render(report: &AuditReport) -> String {
    let mut s = format!(
        "Audit of {} materials in {} files, Blender {} ({} px, {} spp)\n\n",
        report.counts.materials,
        report.counts.files,
        terminal(&report.blender_version),
        report.settings.cell,
        report.settings.samples
    );
    s.push_str(&format!(
        "{:<8} {:>8} {:>8} {:>8}  {}\n",
        "verdict", "mean", "rim", "twin", "material (file) — findings"
    ));
    for (_, m) in order(report) {
        let rules: Vec<&str> = m.findings.iter().map(|f| f.rule.as_str()).collect();
        s.push_str(&format!(
            "{:<8} {:>8} {:>8} {:>8}  {} ({}){}\n",
            m.verdict.key(),
            pct(m.mean),
            pct(m.rim),
            pct(m.twin_mean),
            terminal(&m.material),
            terminal(short(&m.file)),
            if rules.is_empty() {
                String::new()
            } else {
                format!(" — {}", terminal(&rules.join(", ")))
            }
        ));
        if m.verdict != Verdict::Ok {
            s.push_str(&format!("{:<36}{}\n", "", terminal(&m.reason)));
        }
        if let Some(after) = m.after.as_ref().filter(|_| m.replaced > 0) {
            s.push_str(&format!(
                "{:<36}after the fix: {} at {}\n",
                "",
                after.verdict.key(),
                pct(after.mean)
            ));
        }
    }
    for f in &report.files {
        s.push_str(&file_lines(f));
    }
    let c = &report.counts;
    let failing: Vec<&str> = report.settings.fail_on.iter().map(|v| v.key()).collect();
    let unread = match c.files_failed {
        0 => String::new(),
        1 => ", 1 file could not be audited".to_string(),
        n => format!(", {n} files could not be audited"),
    };
    s.push_str(&format!(
        "\n{}: {} ok, {} lose energy, {} create energy, {} errors{unread} (failing on: {})\n",
        if report.passed { "PASS" } else { "FAIL" },
        c.ok,
        c.loses,
        c.creates,
        c.error,
        failing.join(", ")
    ));
    s
}

/// A file's error, its own findings and its fix, each on a line of its own.
fn file_lines(f: &AuditedFile) -> String {
    let mut s = String::new();
    let file = terminal(&f.file);
    if let Some(e) = &f.error {
        s.push_str(&format!("\nerror   {file}: {}\n", terminal(e)));
    }
    for finding in &f.findings {
        s.push_str(&format!(
            "\n{file}: {} — {}\n",
            terminal(&finding.rule),
            terminal(&finding.why)
        ));
    }
    if let Some(fixed) = &f.fixed {
        s.push_str(&format!(
            "\nfixed   {file} → {} ({} lobes replaced)\n",
            terminal(&fixed.path),
            fixed.replaced
        ));
        if let Some(e) = &fixed.after_error {
            s.push_str(&format!(
                "        the fixed file could not be audited again: {}\n",
                terminal(e)
            ));
        }
    }
    s
}

/// A file's name, for a table line.
fn short(path: &str) -> &str {
    std::path::Path::new(path)
        .file_name()
        .and_then(|n| n.to_str())
        .unwrap_or(path)
}
