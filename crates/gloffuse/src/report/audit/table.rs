//! The audit verdict for a terminal: one line per material (failures first), then its
//! findings, the file findings, and the counts. Every name and message in it comes from
//! users' files (or a shard's report.json) and is shown through [`terminal`], so none can
//! drive the terminal or start a line of its own.

use crate::audit::{AuditReport, AuditedFile, AuditedMaterial, Verdict};
use crate::plural::count;
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
        "Audit of {} in {}, Blender {} ({} px, {} spp)\n\n",
        count(report.counts.materials, "material", "materials"),
        count(report.counts.files, "file", "files"),
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
        if let Some(why) = &m.no_fix {
            s.push_str(&format!("{:<36}{}\n", "", terminal(why)));
        }
        if let Some(after) = m.after.as_ref().filter(|a| a.rewritten) {
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
    for (rule, (why, files)) in file_findings(report) {
        s.push_str(&format!(
            "\n{} in {}: {}\n",
            terminal(rule),
            files_named(&files),
            terminal(why)
        ));
    }
    let failing: Vec<&str> = report.settings.fail_on.iter().map(|v| v.key()).collect();
    let unread = match report.counts.files_failed {
        0 => String::new(),
        n => format!(", {} could not be audited", count(n, "file", "files")),
    };
    s.push_str(&format!(
        "\n{}: {}{unread} (failing on: {})\n",
        if report.passed { "PASS" } else { "FAIL" },
        counts(report).map(|(_, words)| words).join(", "),
        failing.join(", ")
    ));
    s
}

/// The materials' counts by verdict, in words (`0 ok`, `1 loses energy`, `2 errors`), each
/// with whether it fails the check: a verdict in `--fail-on` that some material has.
pub(super) fn counts(report: &AuditReport) -> [(bool, String); 4] {
    let c = &report.counts;
    [
        (Verdict::Ok, c.ok, "ok", "ok"),
        (Verdict::Loses, c.loses, "loses energy", "lose energy"),
        (
            Verdict::Creates,
            c.creates,
            "creates energy",
            "create energy",
        ),
        (Verdict::Error, c.error, "error", "errors"),
    ]
    .map(|(verdict, n, one, many)| {
        let failing = n > 0 && report.settings.fail_on.contains(&verdict);
        (failing, count(n, one, many))
    })
}

/// A file's error, its own findings and its fix, each on a line of its own.
fn file_lines(f: &AuditedFile) -> String {
    let mut s = String::new();
    let file = terminal(&f.file);
    if let Some(e) = &f.error {
        s.push_str(&format!("\nerror   {file}: {}\n", terminal(e)));
    }
    if let Some(fixed) = &f.fixed {
        s.push_str(&format!(
            "\nfixed   {file} → {} ({} replaced)\n",
            terminal(&fixed.path),
            count(fixed.replaced, "lobe", "lobes")
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

/// The files' own findings (a scene's Filter Glossy, say), one entry per rule with its
/// reason and the files it fired in: most files share Blender's defaults, so a rule is one
/// line, not one paragraph per file.
pub(super) fn file_findings(
    report: &AuditReport,
) -> std::collections::BTreeMap<&str, (&str, Vec<&str>)> {
    let mut rules = std::collections::BTreeMap::new();
    for f in &report.files {
        for finding in &f.findings {
            let entry = rules
                .entry(finding.rule.as_str())
                .or_insert((finding.why.as_str(), Vec::new()));
            if entry.1.last() != Some(&f.file.as_str()) {
                entry.1.push(f.file.as_str());
            }
        }
    }
    rules
}

/// "a.blend", "a.blend and b.blend", or "12 files (a.blend, b.blend, …)".
fn files_named(files: &[&str]) -> String {
    let names: Vec<String> = files.iter().map(|f| terminal(short(f)).into_owned()).collect();
    match names.as_slice() {
        [one] => one.clone(),
        [a, b] => format!("{a} and {b}"),
        [a, b, ..] => format!("{} ({a}, {b}, …)", count(names.len(), "file", "files")),
        [] => String::new(),
    }
}

/// A file's name, for a table line.
fn short(path: &str) -> &str {
    std::path::Path::new(path)
        .file_name()
        .and_then(|n| n.to_str())
        .unwrap_or(path)
}
