//! The audit verdict for a terminal: one line per material (failures first), then its
//! findings, the file findings, and the counts. Every name and message in it comes from
//! users' files (or a shard's report.json) and is shown through [`terminal`], so none can
//! drive the terminal or start a line of its own.

use crate::audit::rules::Severity;
use crate::audit::waivers::said;
use crate::audit::{
    AuditReport, AuditedFile, AuditedMaterial, BaselineState, BaselineSummary, Verdict,
};
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
        s.push_str(&material_lines(m));
    }
    for f in &report.files {
        s.push_str(&file_lines(f));
        if let Some(words) = older_blender(f, &report.blender_version) {
            s.push_str(&format!(
                "\nnote    {}: {}\n",
                terminal(&f.file),
                terminal(&words)
            ));
        }
    }
    for (rule, (why, files)) in file_findings(report) {
        s.push_str(&format!(
            "\n{} in {}: {}\n",
            terminal(rule),
            files_named(&files),
            terminal(why)
        ));
    }
    s.push_str(&last_line(report));
    s
}

/// The verdict, the counts, what does not fail and why, beside a baseline and before a fix.
fn last_line(report: &AuditReport) -> String {
    let failing: Vec<&str> = report.settings.fail_on.iter().map(|v| v.key()).collect();
    let unread = match report.counts.files_failed {
        0 => String::new(),
        n => format!(", {} could not be audited", count(n, "file", "files")),
    };
    let mut notes = String::new();
    if report.counts.suppressed > 0 {
        notes.push_str(&format!(
            ", {} not failing (waived, or below error severity)",
            count(report.counts.suppressed, "material", "materials")
        ));
    }
    if report.counts.waived_findings > 0 {
        notes.push_str(&format!(
            ", {} waived",
            count(report.counts.waived_findings, "finding", "findings")
        ));
    }
    if let Some(b) = &report.baseline {
        notes.push_str(&format!("; {}", baseline_counts(b, &terminal(&b.path))));
    }
    // With a fix, the verdict is the exit code's: what is left after the fix.
    let fix = match report.passed_after_fix {
        Some(after) if after != report.passed => format!(
            "; before the fix: {}",
            if report.passed { "PASS" } else { "FAIL" }
        ),
        _ => String::new(),
    };
    format!(
        "\n{}: {}{unread}{notes} (failing on: {}){fix}\n",
        if report.check_passed() {
            "PASS"
        } else {
            "FAIL"
        },
        counts(report).map(|(_, words)| words).join(", "),
        failing.join(", ")
    )
}

/// A material's line, then its reason, what suppresses it, its waived findings and its fix.
fn material_lines(m: &AuditedMaterial) -> String {
    let mut s = String::new();
    let rules: Vec<String> = m.findings.iter().map(finding_label).collect();
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
    if let Some(why) = &m.suppressed {
        s.push_str(&format!("{:<36}suppressed: {}\n", "", terminal(why)));
    }
    if let Some(state) = m.baseline {
        s.push_str(&format!("{:<36}{}\n", "", baseline_words(m, state)));
    }
    // Each waiver once: those the suppression already names are not repeated.
    let named = m.suppressed.as_deref().unwrap_or_default();
    for f in &m.findings {
        if let Some(w) = f.waived.as_ref().filter(|w| !named.contains(&said(w))) {
            s.push_str(&format!(
                "{:<36}waived {} at {}: {}\n",
                "",
                terminal(&f.rule),
                terminal(&f.node),
                terminal(&said(w))
            ));
        }
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
    s
}

/// The materials beside the baseline (`path` as the renderer shows it), in words.
pub(super) fn baseline_counts(b: &BaselineSummary, path: &str) -> String {
    let gone = match b.absent.len() {
        0 => String::new(),
        n => format!(", {} gone", count(n, "material", "materials")),
    };
    format!(
        "beside the baseline {path}: {} new, {} worse, {} better, {} unchanged{gone}",
        b.new, b.worse, b.better, b.unchanged
    )
}

/// A material beside the baseline, in words: its state, and whether its failure counts.
pub(super) fn baseline_words(m: &AuditedMaterial, state: BaselineState) -> String {
    let counted = if m.fails != Some(true) {
        ""
    } else if state.counts() {
        " (it fails the check)"
    } else {
        " (its failure is in the baseline: it does not fail the check)"
    };
    format!("{} beside the baseline{counted}", state.key())
}

/// A finding's rule as the table lists it: marked when it is waived or not an error.
fn finding_label(f: &crate::audit::Finding) -> String {
    match (&f.waived, f.severity) {
        (Some(_), _) => format!("{} (waived)", f.rule),
        (None, Severity::Error) => f.rule.clone(),
        (None, severity) => format!("{} ({})", f.rule, severity.key()),
    }
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
        let failing = report
            .materials
            .iter()
            .any(|m| m.verdict == verdict && m.failing());
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

/// The files' own findings (a scene's Filter Glossy, say), one entry per rule and reason
/// with the files it fired in: most files share Blender's defaults, so a rule is one line,
/// not one paragraph per file (a reason that quotes the file's own message is its own).
pub(super) fn file_findings(report: &AuditReport) -> Vec<(&str, (&str, Vec<&str>))> {
    let mut rules = std::collections::BTreeMap::new();
    for f in &report.files {
        for finding in &f.findings {
            let files: &mut Vec<&str> = rules
                .entry((finding.rule.as_str(), finding.why.as_str()))
                .or_default();
            if files.last() != Some(&f.file.as_str()) {
                files.push(f.file.as_str());
            }
        }
    }
    rules
        .into_iter()
        .map(|((rule, why), files)| (rule, (why, files)))
        .collect()
}

/// "a.blend", "a.blend and b.blend", or "12 files (a.blend, b.blend, …)".
fn files_named(files: &[&str]) -> String {
    let names: Vec<String> = files
        .iter()
        .map(|f| terminal(short(f)).into_owned())
        .collect();
    match names.as_slice() {
        [one] => one.clone(),
        [a, b] => format!("{a} and {b}"),
        [a, b, ..] => format!("{} ({a}, {b}, …)", count(names.len(), "file", "files")),
        [] => String::new(),
    }
}

/// "saved by X, audited in Y" when the Blender that audited `f` is older (by major.minor)
/// than the one that saved it: its rules and its renders then describe the file as that
/// older Blender reads it (or explain why that Blender crashed on it).
pub(super) fn older_blender(f: &AuditedFile, blender_version: &str) -> Option<String> {
    fn major_minor(v: &str) -> Option<(u32, u32)> {
        let mut parts = v.split(|c: char| !c.is_ascii_digit());
        Some((parts.next()?.parse().ok()?, parts.next()?.parse().ok()?))
    }
    let saved = f.saved_by.as_deref()?;
    if major_minor(saved)? <= major_minor(blender_version)? {
        return None;
    }
    Some(format!(
        "saved by Blender {saved}, audited in {blender_version}: an older Blender reads newer \
         nodes and settings as it knows them (a 4.x Principled BSDF as 3.x's), so audit it in \
         Blender {saved} or later"
    ))
}

/// A file's name, for a table line.
fn short(path: &str) -> &str {
    std::path::Path::new(path)
        .file_name()
        .and_then(|n| n.to_str())
        .unwrap_or(path)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn file(name: &str, saved_by: &str, findings: serde_json::Value) -> AuditedFile {
        serde_json::from_value(serde_json::json!({
            "file": name, "saved_by": saved_by, "error": null, "findings": findings,
            "materials": 0, "log": null, "render_seconds": null, "scan_seconds": null,
            "fixed": null
        }))
        .unwrap()
    }

    /// A file saved by a newer Blender than the one auditing says so; the same or an older
    /// one does not (by major.minor: 3.4.1 audits 3.4 files).
    #[test]
    fn a_file_from_a_newer_blender_is_named() {
        let f = file("a.blend", "4.5", serde_json::json!([]));
        let words = older_blender(&f, "3.4.1").unwrap();
        assert!(
            words.starts_with("saved by Blender 4.5, audited in 3.4.1"),
            "{words}"
        );
        assert!(older_blender(&f, "4.5.15 LTS").is_none());
        assert!(older_blender(&f, "5.0.1").is_none());
        assert!(older_blender(&file("b.blend", "3.4", serde_json::json!([])), "3.4.1").is_none());
        assert!(older_blender(&file("c.blend", "4.10", serde_json::json!([])), "4.5").is_some());
    }

    /// A rule that fired in several files is one entry naming them all, in order.
    #[test]
    fn a_file_finding_is_one_entry_for_every_file() {
        let finding = |rule: &str| {
            serde_json::json!([{"rule": rule, "node": "scene ▸ Scene", "node_path": [],
                "node_type": "Scene", "kind": "info", "versions": "", "why": "because",
                "fix": "", "predicted": null, "twin": null, "detail": {}}])
        };
        let report: AuditReport = serde_json::from_value(serde_json::json!({
            "gloffuse_version": "0", "blender_version": "4.5.15", "blender_program": "b",
            "settings": {"cell": 64, "samples": 32, "seed": 0, "render": true,
                "tolerance": 0.01, "ring_tolerance": 0.03, "fail_on": ["loses"]},
            "passed": true, "counts": {"files": 3, "files_failed": 0, "materials": 0,
                "ok": 0, "loses": 0, "creates": 0, "error": 0},
            "files": [file("x/a.blend", "4.5", finding("filter-glossy")),
                      file("x/b.blend", "4.5", serde_json::json!([])),
                      file("y/c.blend", "4.5", finding("filter-glossy"))],
            "materials": []
        }))
        .unwrap();
        let rules = file_findings(&report);
        assert_eq!(rules.len(), 1);
        assert_eq!(
            rules[0],
            ("filter-glossy", ("because", vec!["x/a.blend", "y/c.blend"]))
        );
        let table = render(&report);
        assert!(
            table.contains("\nfilter-glossy in a.blend and c.blend: because\n"),
            "{table}"
        );
        assert_eq!(table.matches("because").count(), 1, "{table}");
    }

    /// A suppressed material and its waived finding show, with the reason and where the
    /// waiver came from, in the table, the JUnit file (a skipped case) and the page.
    #[test]
    fn every_report_shows_a_waiver_with_its_reason() {
        let finding = serde_json::json!({"rule": "glossy-single-scatter", "node": "M ▸ G",
            "node_path": ["M", "G"], "node_type": "ShaderNodeBsdfGlossy", "kind": "loses",
            "versions": "3.0 and later", "why": "w", "fix": "f", "predicted": null,
            "twin": "Multiscatter GGX", "detail": {}, "severity": "error",
            "waived": {"reason": "signed <off>", "from": "node", "where": "M ▸ G", "line": null}});
        let report: AuditReport = serde_json::from_value(serde_json::json!({
            "gloffuse_version": "0", "blender_version": "4.5.15", "blender_program": "b",
            "settings": {"cell": 64, "samples": 32, "seed": 0, "render": false,
                "tolerance": 0.01, "ring_tolerance": 0.03, "fail_on": ["loses"]},
            "passed": true, "counts": {"files": 1, "files_failed": 0, "materials": 1,
                "ok": 0, "loses": 1, "creates": 0, "error": 0},
            "files": [file("a.blend", "4.5", serde_json::json!([]))],
            "materials": [{"file": "a.blend", "material": "M", "verdict": "loses",
                "reason": "r", "fails": false,
                "suppressed": "loses not failing: glossy-single-scatter at M ▸ G waived: \
                               “signed <off>” (gloffuse_ignore on node M ▸ G)",
                "mean": null, "center": null, "rim": null, "twin_mean": null,
                "twin_center": null, "twin_rim": null, "replaced": 1, "findings": [finding],
                "library": null, "after": null}]
        }))
        .unwrap();
        let mut report = report;
        report.finish();
        assert!(report.passed && report.check_passed());
        assert_eq!(
            (report.counts.suppressed, report.counts.waived_findings),
            (1, 1)
        );
        let table = render(&report);
        assert!(table.contains("glossy-single-scatter (waived)"), "{table}");
        assert!(table.contains("suppressed: loses not failing"), "{table}");
        assert!(
            table.contains("“signed <off>” (gloffuse_ignore on node M ▸ G)"),
            "{table}"
        );
        assert!(
            table.starts_with("Audit") && table.contains("\nPASS: "),
            "{table}"
        );
        let junit = super::super::junit::render(&report, "rerun");
        assert!(
            junit.contains("<skipped message=\"loses not failing"),
            "{junit}"
        );
        assert!(junit.contains("name=\"waived\""), "{junit}");
        assert!(junit.contains("signed &lt;off&gt;"), "{junit}");
        let page = super::super::html::render(&report, &[None], "rerun");
        assert!(page.contains("Waived:</b> “signed &lt;off&gt;”"), "{page}");
        assert!(page.contains("Suppressed: loses not failing"), "{page}");
        // The same material failing: FAIL everywhere, no skipped case.
        report.materials[0].fails = Some(true);
        report.materials[0].suppressed = None;
        report.materials[0].findings[0].waived = None;
        report.finish();
        assert!(!report.passed);
        assert!(render(&report).contains("\nFAIL: "));
        assert!(!super::super::junit::render(&report, "r").contains("<skipped"));
    }
}
