//! The audit verdict as one HTML page: a banner in the verdict's colour (verify's) with the
//! counts, then one card per material (failures first) with its picture (as authored |
//! conserving twin | difference), its numbers and its findings with their fixes.

use super::table::{counts, file_findings, older_blender, order, pct};
use crate::audit::waivers::said;
use crate::audit::{AuditReport, AuditedMaterial};
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
         code{{background:#f4f4f4;padding:0 .2em}}</style></head><body>\n",
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
    s.push_str(&file_cards(report));
    for (index, m) in order(report) {
        s.push_str(&card(m, pictures.get(index).cloned().flatten()));
    }
    s.push_str("</main></body></html>\n");
    s
}

/// The files' own cards: errors, a file newer than the Blender that audited it, and the
/// file findings (one per rule, naming the files).
fn file_cards(report: &AuditReport) -> String {
    let mut s = String::new();
    for f in report.files.iter().filter(|f| f.error.is_some()) {
        s.push_str(&format!(
            "<div class=\"card error\"><b>{}</b>: {}</div>\n",
            escape(&f.file),
            escape(f.error.as_deref().unwrap_or_default())
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

fn card(m: &AuditedMaterial, picture: Option<String>) -> String {
    let mut s = format!(
        "<div class=\"card {v}\"><h3>{v}: {} <small>({})</small></h3>\n<p>{}</p>\n",
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
        for f in &m.findings {
            s.push_str(&format!(
                "<li><code>{}</code> at {} ({}): {}. <i>Fix:</i> {}.{}</li>\n",
                escape(&f.rule),
                escape(&f.node),
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

/// A finding's waiver (or its severity below error), in words for the page.
fn waived_words(f: &crate::audit::Finding) -> String {
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
