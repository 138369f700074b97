//! The audit verdict as one HTML page: a banner in the verdict's colour (verify's) with the
//! counts; a summary (the rules that fired) and an index of the files (each file's counts,
//! its materials linked); the files' own cards (an error as one readable message, the
//! technical detail folded; a newer Blender; file findings; a fix); then one card per
//! material (failures first) with its picture (as authored | conserving twin |
//! difference), its numbers and its findings, each rule once with the nodes it flagged.

use std::collections::{BTreeMap, BTreeSet};

use super::table::{
    baseline_counts, baseline_words, counts, file_findings, older_blender, order, pct,
};
use crate::audit::waivers::said;
use crate::audit::{AuditReport, AuditedFile, AuditedMaterial, Finding, Verdict};
use crate::plural::count;
use crate::report::page::{banner, escape, page_css};

/// `pictures[i]` is material i's picture (report order), relative to the page.
pub fn render(report: &AuditReport, pictures: &[Option<String>], rerun: &str) -> String {
    let c = &report.counts;
    // With a fix, the banner is the exit code's: what is left after it.
    let verdict = if report.check_passed() {
        "PASS"
    } else {
        "FAIL"
    };
    let mut s = format!(
        "<!doctype html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\
         <title>gloffuse audit: {verdict}</title><style>\n{}\
         main{{max-width:70em}}\
         .card{{border:1px solid #ccc;border-radius:6px;padding:.8em;margin:.8em 0;background:white}}\
         .creates{{border-left:6px solid #b2182b}}.loses{{border-left:6px solid #2166ac}}\
         .error{{border-left:6px solid #777}}.ok{{border-left:6px solid #1a9850}}\
         img{{image-rendering:pixelated;width:384px;display:block;margin:.4em 0}}\
         .cap{{display:flex;width:384px;font-size:12px;color:#555}}.cap span{{flex:1;text-align:center}}\
         code{{background:#f4f4f4;padding:0 .2em}}\
         table.sum{{border-collapse:collapse;margin:.4em 0 1em}}\
         table.sum td,table.sum th{{border-bottom:1px solid #ddd;padding:.2em .6em;text-align:left}}\
         table.sum td.n{{text-align:right}}\
         details pre{{white-space:pre-wrap;font-size:12px;background:#f4f4f4;padding:.4em}}</style></head><body>\n",
        page_css(report.check_passed())
    );
    // On a failing page, the counts that fail it stand out; on a passing one, none does.
    let tally: Vec<String> = counts(report)
        .into_iter()
        .map(|(failing, words)| {
            if failing {
                format!("<b>{words}</b>")
            } else {
                words
            }
        })
        .collect();
    let detail = format!(
        "{} in {}, Blender {}, {} px, {} spp: {}. The check fails on: {}.",
        count(c.materials, "material", "materials"),
        count(c.files, "file", "files"),
        escape(&report.blender_version),
        report.settings.cell,
        report.settings.samples,
        tally.join(", "),
        report
            .settings
            .fail_on
            .iter()
            .map(|v| v.key())
            .collect::<Vec<_>>()
            .join(", "),
    );
    let detail = format!("{detail}{}", suppressed_words(report));
    s.push_str(&banner(&format!("gloffuse audit: {verdict}"), &detail));
    s.push_str(&format!(
        "<p>Each picture shows the material as authored in a white furnace (a uniformly lit \
         white world: a material that neither loses nor creates energy renders at 100 % of its \
         colour), its energy-conserving twin, and their difference (blue: darker than the \
         twin, red: brighter; ±5 % at full colour).</p>\n<p>Rerun: <code>{}</code></p>\n",
        escape(rerun)
    ));
    s.push_str(&summary(report));
    s.push_str(&index(report));
    s.push_str(&file_cards(report));
    for (index, m) in order(report) {
        s.push_str(&card(index, m, pictures.get(index).cloned().flatten()));
    }
    s.push_str("</main></body></html>\n");
    s
}

/// The files' own cards: errors, a file newer than the Blender that audited it, and the
/// file findings (one per rule, naming the files).
fn file_cards(report: &AuditReport) -> String {
    let mut s = String::new();
    for (i, f) in report.files.iter().enumerate() {
        let Some(error) = &f.error else { continue };
        let (message, detail) = readable_error(error, &f.file);
        s.push_str(&format!(
            "<div class=\"card error\" id=\"file-{i}\"><b>{}</b> could not be audited: {}\
             <details><summary>technical detail</summary><pre>{}</pre></details></div>\n",
            escape(&f.file),
            escape(&message),
            escape(&detail)
        ));
    }
    for (f, words) in report
        .files
        .iter()
        .filter_map(|f| Some((f, older_blender(f, &report.blender_version)?)))
    {
        s.push_str(&format!(
            "<div class=\"card\"><b>{}</b>: {}</div>\n",
            escape(&f.file),
            escape(&words)
        ));
    }
    for f in report.files.iter().filter(|f| f.fixed.is_some()) {
        s.push_str(&fixed_card(f));
    }
    for (rule, (why, files)) in file_findings(report) {
        let names: Vec<String> = files.iter().map(|f| escape(f)).collect();
        s.push_str(&format!(
            "<div class=\"card\"><code>{}</code> in {}: {}.<br><small>{}</small></div>\n",
            escape(rule),
            count(files.len(), "file", "files"),
            escape(why),
            names.join(", ")
        ));
    }
    s
}

fn card(index: usize, m: &AuditedMaterial, picture: Option<String>) -> String {
    let mut s = format!(
        "<div class=\"card {v}\" id=\"m-{index}\"><h3>{v}: {} <small>({})</small></h3>\n<p>{}</p>\n",
        escape(&m.material),
        escape(&m.file),
        escape(&m.reason),
        v = m.verdict.key()
    );
    if let Some(p) = picture {
        s.push_str(&format!(
            "<img src=\"{}\" alt=\"{} as authored, its twin, their difference\">\
             <div class=\"cap\"><span>as authored</span><span>twin</span><span>difference</span></div>\n",
            escape(&p),
            escape(&m.material)
        ));
    }
    s.push_str(&format!(
        "<p>mean {}, centre {}, rim {}; twin {} (centre {}, rim {})</p>\n",
        pct(m.mean),
        pct(m.center),
        pct(m.rim),
        pct(m.twin_mean),
        pct(m.twin_center),
        pct(m.twin_rim)
    ));
    if let Some(opacity) = m.opacity.filter(|o| *o < 0.99) {
        s.push_str(&format!(
            "<p>It covers {} of its sphere: the white world seen through it counts.</p>\n",
            pct(Some(opacity))
        ));
    }
    if let Some(why) = &m.suppressed {
        s.push_str(&format!(
            "<p class=\"suppressed\">Suppressed: {}</p>\n",
            escape(why)
        ));
    }
    if let Some(state) = m.baseline {
        s.push_str(&format!(
            "<p class=\"baseline\">{}.</p>\n",
            escape(&capitalised(&baseline_words(m, state)))
        ));
    }
    if let Some(why) = &m.no_fix {
        s.push_str(&format!("<p>{}</p>\n", escape(why)));
    }
    match &m.after {
        Some(after) if after.rewritten => s.push_str(&format!(
            "<p>After the fix: {} at {}</p>\n",
            after.verdict.key(),
            pct(after.mean)
        )),
        Some(_) => s.push_str("<p>Left as it was by the fix.</p>\n"),
        None => {}
    }
    if !m.findings.is_empty() {
        s.push_str("<ul>\n");
        for (f, nodes) in once_each(&m.findings) {
            let nodes: Vec<String> = nodes.iter().map(|n| escape(n)).collect();
            s.push_str(&format!(
                "<li><code>{}</code> at {} ({}): {}. <i>Fix:</i> {}.{}</li>\n",
                escape(&f.rule),
                nodes.join(", "),
                escape(&f.versions),
                escape(&f.why),
                escape(&f.fix),
                f.twin
                    .as_ref()
                    .map(|t| format!(" In the twin: {}.", escape(t)))
                    .unwrap_or_default()
                    + &waived_words(f)
            ));
        }
        s.push_str("</ul>\n");
    }
    s.push_str("</div>\n");
    s
}

/// The rules that fired, each with its effect and how many materials and files it fired in
/// (a file's own findings count for the file), most materials first.
fn summary(report: &AuditReport) -> String {
    // rule -> (effect, materials by index, files)
    let mut rules: BTreeMap<&str, (&str, Vec<usize>, BTreeSet<&str>)> = BTreeMap::new();
    let of_materials = report.materials.iter().enumerate().flat_map(|(i, m)| {
        m.findings
            .iter()
            .map(move |f| (f, Some(i), m.file.as_str()))
    });
    let of_files = report
        .files
        .iter()
        .flat_map(|file| file.findings.iter().map(|f| (f, None, file.file.as_str())));
    for (f, material, file) in of_materials.chain(of_files) {
        let entry =
            rules
                .entry(f.rule.as_str())
                .or_insert((f.kind.key(), Vec::new(), BTreeSet::new()));
        // A material's findings come together, so a repeat is the last one counted.
        if let Some(m) = material.filter(|m| entry.1.last() != Some(m)) {
            entry.1.push(m);
        }
        entry.2.insert(file);
    }
    let mut s = String::from("<h2>Summary</h2>\n");
    if rules.is_empty() {
        s.push_str("<p>No rule fired.</p>\n");
        return s;
    }
    let mut rows: Vec<_> = rules.into_iter().collect();
    rows.sort_by_key(|(rule, (_, materials, files))| {
        (
            std::cmp::Reverse(materials.len()),
            std::cmp::Reverse(files.len()),
            *rule,
        )
    });
    s.push_str(
        "<table class=\"sum\"><tr><th>rule</th><th>effect</th><th>materials</th>\
         <th>files</th></tr>\n",
    );
    for (rule, (effect, materials, files)) in rows {
        s.push_str(&format!(
            "<tr><td><code>{}</code></td><td>{}</td><td class=\"n\">{}</td>\
             <td class=\"n\">{}</td></tr>\n",
            escape(rule),
            effect,
            materials.len(),
            files.len()
        ));
    }
    s.push_str("</table>\n");
    s
}

/// One row per file: its materials by verdict, what became of it, and its materials
/// (failures first) linked to their cards.
fn index(report: &AuditReport) -> String {
    let mut s = format!(
        "<h2>Files</h2>\n<table class=\"sum\"><tr><th>file</th><th>materials</th>{}\
         <th>notes</th></tr>\n",
        Verdict::ALL
            .iter()
            .map(|v| format!("<th>{}</th>", v.key()))
            .collect::<String>()
    );
    let ordered = order(report);
    for (i, f) in report.files.iter().enumerate() {
        let mine: Vec<&(usize, &AuditedMaterial)> =
            ordered.iter().filter(|(_, m)| m.file == f.file).collect();
        let by_verdict: String = Verdict::ALL
            .iter()
            .map(|v| {
                let n = mine.iter().filter(|(_, m)| m.verdict == *v).count();
                format!("<td class=\"n\">{n}</td>")
            })
            .collect();
        let links: Vec<String> = mine
            .iter()
            .map(|(index, m)| {
                format!(
                    "<a href=\"#m-{index}\">{}</a> ({})",
                    escape(&m.material),
                    m.verdict.key()
                )
            })
            .collect();
        let materials = if links.is_empty() {
            "0".to_string()
        } else {
            format!(
                "<details><summary>{}</summary>{}</details>",
                count(links.len(), "material", "materials"),
                links.join("<br>")
            )
        };
        s.push_str(&format!(
            "<tr><td>{}</td><td>{materials}</td>{by_verdict}<td>{}</td></tr>\n",
            escape(&f.file),
            file_notes(i, f, &report.blender_version)
        ));
    }
    s.push_str("</table>\n");
    s
}

/// What the index says of a file beside its counts: an error (linked to its card), a
/// newer Blender, its own findings, a fix.
fn file_notes(i: usize, f: &AuditedFile, blender_version: &str) -> String {
    let mut notes = Vec::new();
    if f.error.is_some() {
        notes.push(format!("<a href=\"#file-{i}\">could not be audited</a>"));
    }
    if let Some(saved) = f
        .saved_by
        .as_deref()
        .filter(|_| older_blender(f, blender_version).is_some())
    {
        notes.push(format!("saved by Blender {}", escape(saved)));
    }
    if !f.findings.is_empty() {
        let mut rules: Vec<String> = f.findings.iter().map(|x| escape(&x.rule)).collect();
        rules.dedup();
        notes.push(format!("<code>{}</code>", rules.join("</code>, <code>")));
    }
    if let Some(fixed) = &f.fixed {
        notes.push(format!(
            "fixed ({} replaced)",
            count(fixed.replaced, "lobe", "lobes")
        ));
    }
    notes.join("; ")
}

/// A fixed file's card, as the table's line: where the fix went, the lobes it replaced, the
/// backup of an in-place fix, and why the fixed file could not be audited again.
fn fixed_card(f: &AuditedFile) -> String {
    let Some(fixed) = &f.fixed else {
        return String::new();
    };
    let mut s = format!(
        "<div class=\"card\"><b>{}</b> fixed as {} ({} replaced)",
        escape(&f.file),
        escape(&fixed.path),
        count(fixed.replaced, "lobe", "lobes")
    );
    if let Some(backup) = &fixed.backup {
        s.push_str(&format!(
            "; the previous version is kept as {}",
            escape(backup)
        ));
    }
    s.push('.');
    if let Some(e) = &fixed.after_error {
        s.push_str(&format!(
            "<br>The fixed file could not be audited again: {}",
            escape(e)
        ));
    }
    s.push_str("</div>\n");
    s
}

/// A material's findings, each once: findings that differ only by their node (a rule that
/// fired on several nodes, or several inputs of one node) are one, with its nodes in order;
/// a waived and an unwaived finding of one rule stay two.
fn once_each(findings: &[Finding]) -> Vec<(&Finding, Vec<&str>)> {
    let mut kept: Vec<(&Finding, Vec<&str>)> = Vec::new();
    for f in findings {
        let same = |k: &Finding| {
            (
                &k.rule,
                &k.why,
                &k.fix,
                &k.twin,
                &k.versions,
                &k.waived,
                k.severity,
            ) == (
                &f.rule,
                &f.why,
                &f.fix,
                &f.twin,
                &f.versions,
                &f.waived,
                f.severity,
            )
        };
        match kept.iter_mut().find(|(k, _)| same(k)) {
            Some((_, nodes)) if nodes.contains(&f.node.as_str()) => {}
            Some((_, nodes)) => nodes.push(&f.node),
            None => kept.push((f, vec![&f.node])),
        }
    }
    kept
}

/// A file's error as one readable message and the whole text: a Blender run's Python
/// exception, not its traceback (Blender's own words, "Error: " dropped), or the error's
/// first line; without the log's path, and the file's own path shortened to its name.
fn readable_error(error: &str, file: &str) -> (String, String) {
    let body = error
        .split("\n  log:")
        .next()
        .unwrap_or(error)
        .split("; log: ")
        .next()
        .unwrap_or(error);
    let raised = body.split_once("raised:").and_then(|(_, traceback)| {
        traceback.lines().rev().find_map(|line| {
            let (name, message) = line.trim().split_once(": ")?;
            let is_exception = !name.is_empty()
                && name
                    .chars()
                    .all(|c| c.is_alphanumeric() || c == '_' || c == '.')
                && (name.ends_with("Error") || name.ends_with("Exception"));
            is_exception.then_some(message)
        })
    });
    let mut message = raised.unwrap_or_else(|| body.lines().next().unwrap_or(body));
    while let Some(rest) = message.strip_prefix("Error: ") {
        message = rest;
    }
    (shorten_path(message.trim(), file), error.to_string())
}

/// `text` with every quoted path of `file` (as given, or as Blender spells it: any path
/// ending in its name) replaced by the file's name: the card already names the file.
fn shorten_path(text: &str, file: &str) -> String {
    let Some(name) = std::path::Path::new(file)
        .file_name()
        .and_then(|n| n.to_str())
    else {
        return text.to_string();
    };
    let mut out = text.to_string();
    for quote in ['"', '\''] {
        out = out
            .split(quote)
            .enumerate()
            .map(|(i, part)| {
                let quoted = i % 2 == 1;
                if quoted && part.contains('/') && part.ends_with(&format!("/{name}")) {
                    name
                } else {
                    part
                }
            })
            .collect::<Vec<_>>()
            .join(&quote.to_string());
    }
    out
}

/// A finding's waiver (or its severity below error), in words for the page.
fn waived_words(f: &Finding) -> String {
    match &f.waived {
        Some(w) => format!(" <b>Waived:</b> {}.", escape(&said(w))),
        None if f.severity != crate::audit::rules::Severity::Error => {
            format!(" <b>Severity:</b> {}.", f.severity.key())
        }
        None => String::new(),
    }
}

/// The banner's words on what does not fail: suppressed materials, waived findings, and the
/// files as they were when a fix changed the verdict.
fn suppressed_words(report: &AuditReport) -> String {
    let c = &report.counts;
    let mut s = String::new();
    if c.suppressed > 0 {
        s.push_str(&format!(
            " {} not failing (waived, or below error severity).",
            count(c.suppressed, "material", "materials")
        ));
    }
    if c.waived_findings > 0 {
        s.push_str(&format!(
            " {} waived.",
            count(c.waived_findings, "finding", "findings")
        ));
    }
    if let Some(b) = &report.baseline {
        s.push_str(&format!(
            " {}.",
            escape(&capitalised(&baseline_counts(b, &b.path)))
        ));
    }
    if report
        .passed_after_fix
        .is_some_and(|after| after != report.passed)
    {
        s.push_str(&format!(
            " Before the fix: {}.",
            if report.passed { "PASS" } else { "FAIL" }
        ));
    }
    s
}

/// `text` with its first letter in capitals.
fn capitalised(text: &str) -> String {
    let mut chars = text.chars();
    match chars.next() {
        Some(first) => first.to_uppercase().chain(chars).collect(),
        None => String::new(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A file error as the audit words a Blender run that raised (bpy 4.5 opening a
    /// truncated .blend): the traceback flattened into the message, the run's paths after it.
    const RAISED: &str = "Blender exited with status 1; its Python script raised:\n        \
        path, said = open_user_file(args.open)\n      File \"/root/.cache/gloffuse/runs/\
        audit-1/gloffuse-audit.py\", line 5034, in open_user_file\n        \
        bpy.ops.wm.open_mainfile(filepath=path, load_ui=False)\n    RuntimeError: Error: \
        Loading \"/tmp/x/in/broken.blend\" failed: Failed to read blend file \
        '/tmp/x/in/broken.blend': Missing DNA block\n  log: /root/.cache/gloffuse/runs/\
        audit-1/blender.log\n  command: /usr/bin/python /root/.cache/gloffuse/runs/audit-1/\
        gloffuse-audit.py --open /tmp/x/in/broken.blend";

    fn finding(rule: &str, node: &str, why: &str) -> serde_json::Value {
        serde_json::json!({"rule": rule, "node": node, "node_path": [], "node_type": "N",
            "kind": "loses", "versions": "3.0 and later", "why": why, "fix": "fix it",
            "predicted": null, "twin": null, "detail": {}})
    }

    fn file(name: &str, error: Option<&str>, findings: serde_json::Value) -> serde_json::Value {
        serde_json::json!({"file": name, "saved_by": "4.5", "error": error,
            "findings": findings, "materials": 0, "log": null, "render_seconds": null,
            "scan_seconds": null,
            "fixed": if error.is_none() { serde_json::json!({"path": "out/a.blend",
                "replaced": 1, "backup": null, "after_error": null}) }
                else { serde_json::Value::Null }})
    }

    fn material(
        name: &str,
        file: &str,
        verdict: &str,
        findings: serde_json::Value,
    ) -> serde_json::Value {
        serde_json::json!({"file": file, "material": name, "verdict": verdict,
            "reason": "because", "mean": null, "center": null, "rim": null,
            "twin_mean": null, "twin_center": null, "twin_rim": null, "replaced": 0,
            "findings": findings, "library": null, "after": null})
    }

    fn report() -> AuditReport {
        let twice = serde_json::json!([
            finding("glossy-single-scatter", "m ▸ Left ▸ Glossy", "single"),
            finding("glossy-single-scatter", "m ▸ Right ▸ Glossy", "single"),
            finding("color-above-one", "m ▸ Diffuse", "above"),
            finding("color-above-one", "m ▸ Diffuse", "above"),
        ]);
        serde_json::from_value(serde_json::json!({
            "gloffuse_version": "0", "blender_version": "4.5.15", "blender_program": "b",
            "settings": {"cell": 64, "samples": 32, "seed": 0, "render": false,
                "tolerance": 0.01, "ring_tolerance": 0.03, "fail_on": ["loses"]},
            "passed": false, "counts": {"files": 2, "files_failed": 1, "materials": 2,
                "ok": 1, "loses": 1, "creates": 0, "error": 0},
            "files": [file("in/a.blend", None,
                           serde_json::json!([finding("filter-glossy", "scene ▸ S", "fg")])),
                      file("in/broken.blend", Some(RAISED), serde_json::json!([]))],
            "materials": [material("m", "in/a.blend", "loses", twice),
                          material("plain <b>", "in/a.blend", "ok", serde_json::json!([]))]
        }))
        .unwrap()
    }

    /// The elements of `html` that must close, in order: every one opened is closed, none
    /// closed twice (a small parser: tags by name, void elements skipped).
    fn balanced(html: &str) -> Result<(), String> {
        const VOID: [&str; 5] = ["meta", "br", "img", "!doctype", "hr"];
        let mut open: Vec<String> = Vec::new();
        for tag in html.split('<').skip(1) {
            let inside = tag.split('>').next().unwrap_or_default();
            let (closing, name) = match inside.strip_prefix('/') {
                Some(rest) => (true, rest),
                None => (false, inside),
            };
            let name = name
                .split(|c: char| c.is_whitespace())
                .next()
                .unwrap_or_default()
                .to_ascii_lowercase();
            if VOID.contains(&name.as_str()) {
                continue;
            }
            if closing {
                match open.pop() {
                    Some(o) if o == name => {}
                    other => return Err(format!("</{name}> closes {other:?}")),
                }
            } else {
                open.push(name);
            }
        }
        if open.is_empty() {
            Ok(())
        } else {
            Err(format!("left open: {open:?}"))
        }
    }

    /// The text of the first element that starts with `start`, up to its `end`.
    fn between<'a>(html: &'a str, start: &str, end: &str) -> &'a str {
        let from = html
            .find(start)
            .unwrap_or_else(|| panic!("no {start} in {html}"));
        let rest = &html[from..];
        &rest[..rest.find(end).unwrap_or(rest.len())]
    }

    #[test]
    fn a_python_traceback_becomes_one_message_with_the_detail_folded() {
        let (message, detail) = readable_error(RAISED, "in/broken.blend");
        assert_eq!(
            message,
            "Loading \"broken.blend\" failed: Failed to read blend file 'broken.blend': \
             Missing DNA block"
        );
        assert_eq!(detail, RAISED);
        let (message, _) = readable_error(
            "invalid path 'in/empty.blend': expected a .blend file\nmore",
            "in/empty.blend",
        );
        assert_eq!(
            message,
            "invalid path 'empty.blend': expected a .blend file"
        );
        let (message, _) = readable_error(
            "Blender 3.4 could not audit this file, saved by the newer Blender 4.5: audit it \
             in Blender 4.5 or later (Blender was killed by signal 11); log: /tmp/r/b.log",
            "x.blend",
        );
        assert!(
            message.ends_with("(Blender was killed by signal 11)"),
            "{message}"
        );

        let page = render(&report(), &[None, None], "gloffuse audit in");
        balanced(&page).unwrap();
        let card = between(&page, "<div class=\"card error\"", "</div>");
        let (shown, folded) = card.split_once("<details>").unwrap();
        assert!(shown.contains("could not be audited: Loading &quot;broken.blend&quot; failed"));
        for hidden in ["Traceback", "File &quot;", "/root/", "/tmp/", "raised"] {
            assert!(!shown.contains(hidden), "{hidden} in {shown}");
        }
        assert!(folded.contains("gloffuse-audit.py") && folded.contains("log: /root/"));
    }

    #[test]
    fn a_finding_is_shown_once_per_material_with_its_nodes() {
        let page = render(&report(), &[None, None], "r");
        balanced(&page).unwrap();
        let card = between(&page, "<div class=\"card loses\" id=\"m-0\"", "</div>");
        assert_eq!(
            card.matches("<code>glossy-single-scatter</code>").count(),
            1,
            "{card}"
        );
        assert_eq!(
            card.matches("<code>color-above-one</code>").count(),
            1,
            "{card}"
        );
        assert!(
            card.contains("at m ▸ Left ▸ Glossy, m ▸ Right ▸ Glossy ("),
            "{card}"
        );
        assert!(card.contains("at m ▸ Diffuse ("), "{card}");
    }

    #[test]
    fn the_summary_and_the_index_come_first_and_agree_with_the_report() {
        let r = report();
        let page = render(&r, &[None, None], "r");
        balanced(&page).unwrap();
        let (summary, index, first_card) = (
            page.find("<h2>Summary</h2>").unwrap(),
            page.find("<h2>Files</h2>").unwrap(),
            page.find("<div class=\"card").unwrap(),
        );
        assert!(summary < index && index < first_card);
        // Each rule once, counted by materials (not findings) and files.
        let rows = between(&page, "<h2>Summary</h2>", "</table>");
        let row = |rule: &str| between(rows, &format!("<code>{rule}</code>"), "</tr>").to_string();
        assert!(
            row("glossy-single-scatter").contains("<td class=\"n\">1</td><td class=\"n\">1</td>")
        );
        assert!(row("filter-glossy").contains("<td class=\"n\">0</td><td class=\"n\">1</td>"));
        assert_eq!(rows.matches("<tr>").count(), 1 + 3);
        // A row per file; its materials linked to their cards, which exist.
        let files = between(&page, "<h2>Files</h2>", "</table>");
        assert_eq!(files.matches("<tr>").count(), 1 + r.files.len());
        let a = between(files, "<td>in/a.blend</td>", "</tr>");
        assert!(a.contains("<summary>2 materials</summary>"), "{a}");
        assert!(a.contains("fixed (1 lobe replaced)"), "{a}");
        assert!(
            a.contains("<a href=\"#m-1\">plain &lt;b&gt;</a> (ok)"),
            "{a}"
        );
        for target in ["m-0", "m-1", "file-1"] {
            assert!(files.contains(&format!("href=\"#{target}\"")), "{target}");
            assert_eq!(
                page.matches(&format!("id=\"{target}\"")).count(),
                1,
                "{target}"
            );
        }
        // The fix and the file finding, as the table shows them, with plurals that agree.
        assert!(page.contains("<b>in/a.blend</b> fixed as out/a.blend (1 lobe replaced)."));
        assert!(page.contains("<code>filter-glossy</code> in 1 file: fg."));
    }
}
