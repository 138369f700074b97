//! The audit as a SARIF 2.1.0 log (OASIS's Static Analysis Results Interchange Format), the
//! form code-scanning services and editors read. One run: the driver lists every rule of
//! the catalogue and four of its own (the verdicts `loses`, `creates` and `error`, and a
//! file that could not be audited); each finding is a
//! result at its logical location (file ▸ material ▸ node path), a waived one carrying its
//! suppression, and each material whose verdict is not `ok` is one result of its verdict.
//! With a baseline, every result has its `baselineState`.

use serde_json::{Value, json};

use crate::audit::rules::{RULES, Rule, Severity};
use crate::audit::waivers::PROPERTY;
use crate::audit::{AuditReport, AuditedMaterial, BaselineState, Finding, Verdict, Waived};

/// The schema a SARIF 2.1.0 log names (the OASIS schema, as SchemaStore serves it).
pub const SCHEMA: &str = "https://json.schemastore.org/sarif-2.1.0.json";

/// A verdict reported without a rule of the catalogue: what the furnace measured, or why a
/// material or file could not be judged.
struct VerdictRule {
    id: &'static str,
    short: &'static str,
    full: &'static str,
    help: &'static str,
}

const VERDICT_RULES: [VerdictRule; 4] = [
    VerdictRule {
        id: "verdict-loses",
        short: "the material loses energy",
        full: "In the white furnace the material renders darker than its conserving twin \
               (every flagged lobe replaced by its energy-conserving equivalent), beyond the \
               tolerance and the render's noise; without a render, the integrator predicts a \
               loss.",
        help: "replace the flagged lobes by their conserving twins (the audit's fix does)",
    },
    VerdictRule {
        id: "verdict-creates",
        short: "the material creates energy",
        full: "In the white furnace the material renders brighter than 100 % (or one \
               view-cosine ring does), beyond the tolerance and the render's noise: it \
               reflects more light than arrives.",
        help: "fix the nodes the findings name; a material without findings needs checking by \
               hand",
    },
    VerdictRule {
        id: "verdict-error",
        short: "the material could not be judged",
        full: "The audit could not judge the material as authored (a missing texture, a \
               render that failed).",
        help: "see the finding or the message, fix the material, and audit again",
    },
    VerdictRule {
        id: "file-error",
        short: "the file could not be audited",
        full: "Blender could not open or audit the file, so its materials are missing from \
               the report.",
        help: "see the message; audit the file in the Blender that saved it or a newer one",
    },
];

/// The SARIF log of `report`; `command_line` is the command that reproduces it.
pub fn render(report: &AuditReport, command_line: &str) -> String {
    let mut results = Vec::new();
    for file in &report.files {
        if let Some(error) = &file.error {
            results.push(verdict_result(
                "file-error",
                "error",
                &format!("{}: {error}", file.file),
                &file.file,
                &[],
                None,
            ));
        }
        for f in &file.findings {
            results.push(finding_result(f, &file.file, &f.node_path, None));
        }
    }
    for m in &report.materials {
        let place = [m.material.clone()];
        for f in &m.findings {
            let path = if f.node_path.is_empty() {
                place.to_vec()
            } else {
                f.node_path.clone()
            };
            results.push(finding_result(f, &m.file, &path, m.baseline));
        }
        if let Some(result) = material_result(report, m) {
            results.push(result);
        }
    }
    let log = json!({
        "$schema": SCHEMA,
        "version": "2.1.0",
        "runs": [{
            "tool": {"driver": driver(report)},
            "invocations": [{
                "executionSuccessful": true,
                "commandLine": command_line,
                "properties": {
                    "blender": report.blender_version,
                    "passed": report.check_passed(),
                },
            }],
            "columnKind": "unicodeCodePoints",
            "results": results,
        }],
    });
    serde_json::to_string_pretty(&log).expect("a SARIF log serialises")
}

fn driver(report: &AuditReport) -> Value {
    let mut rules: Vec<Value> = RULES.iter().map(catalogue_rule).collect();
    rules.extend(VERDICT_RULES.iter().map(|r| {
        json!({
            "id": r.id,
            "shortDescription": {"text": r.short},
            "fullDescription": {"text": r.full},
            "help": {"text": r.help},
            "defaultConfiguration": {"level": "error"},
        })
    }));
    json!({
        "name": "gloffuse",
        "semanticVersion": report.gloffuse_version,
        "rules": rules,
    })
}

fn catalogue_rule(rule: &Rule) -> Value {
    json!({
        "id": rule.id,
        "shortDescription": {"text": first_clause(rule.why)},
        "fullDescription": {"text": format!("{} (Blender {}).", sentence(rule.why), rule.versions())},
        "help": {"text": sentence(rule.fix)},
        "defaultConfiguration": {"level": level(rule.severity)},
        "properties": {"effect": rule.effect.key(), "versions": rule.versions()},
    })
}

/// `error`, `warning` and `info` as SARIF's `error`, `warning` and `note`.
fn level(severity: Severity) -> &'static str {
    match severity {
        Severity::Error => "error",
        Severity::Warning => "warning",
        Severity::Info => "note",
    }
}

fn finding_result(
    f: &Finding,
    file: &str,
    path: &[String],
    baseline: Option<BaselineState>,
) -> Value {
    let mut result = json!({
        "ruleId": f.rule,
        "level": level(f.severity),
        "message": {"text": format!("{} at {}: {}. Fix: {}.", f.rule, f.node, f.why, f.fix)},
        "locations": [location(file, path, &f.node_type)],
        "properties": {
            "effect": f.kind.key(),
            "predicted": f.predicted,
            "twin": f.twin,
        },
    });
    if let Some(index) = rule_index(&f.rule) {
        result["ruleIndex"] = json!(index);
    }
    if let Some(w) = &f.waived {
        result["suppressions"] = json!([suppression(w)]);
    }
    if let Some(state) = baseline {
        result["baselineState"] = json!(state.sarif());
    }
    result
}

/// The result of a material's verdict, unless it is `ok`.
fn material_result(report: &AuditReport, m: &AuditedMaterial) -> Option<Value> {
    let id = match m.verdict {
        Verdict::Ok => return None,
        Verdict::Loses => "verdict-loses",
        Verdict::Creates => "verdict-creates",
        Verdict::Error => "verdict-error",
    };
    // A verdict the check fails on is an error; one it does not fail on (not in
    // `--fail-on`, or resting on waived or lesser findings) a warning.
    let level = if report.settings.fail_on.contains(&m.verdict) && m.suppressed.is_none() {
        "error"
    } else {
        "warning"
    };
    let mut result = verdict_result(
        id,
        level,
        &format!("{}: {}", m.verdict.key(), m.reason),
        &m.file,
        std::slice::from_ref(&m.material),
        m.baseline,
    );
    result["properties"] = json!({
        "mean": m.mean,
        "twinMean": m.twin_mean,
        "fails": m.failing(),
    });
    if let Some(suppression) = material_suppression(m) {
        result["suppressions"] = json!([suppression]);
    }
    Some(result)
}

/// A material verdict's suppression, where waivers suppress it (not where its findings are
/// only below error severity): in the asset when a waiver is a custom property of it.
fn material_suppression(m: &AuditedMaterial) -> Option<Value> {
    let why = m.suppressed.as_ref()?;
    let waivers: Vec<&Waived> = m
        .findings
        .iter()
        .filter_map(|f| f.waived.as_ref())
        .collect();
    // A `*` on the material waives a verdict no finding explains: its words name the property.
    let star = waivers.is_empty() && why.contains(PROPERTY);
    if waivers.is_empty() && !star {
        return None;
    }
    let in_source = star || waivers.iter().any(|w| w.from != "config");
    Some(json!({
        "kind": if in_source { "inSource" } else { "external" },
        "status": "accepted",
        "justification": why,
    }))
}

fn verdict_result(
    id: &str,
    level: &str,
    message: &str,
    file: &str,
    path: &[String],
    baseline: Option<BaselineState>,
) -> Value {
    let index = RULES.len()
        + VERDICT_RULES
            .iter()
            .position(|r| r.id == id)
            .expect("a verdict rule");
    let mut result = json!({
        "ruleId": id,
        "ruleIndex": index,
        "level": level,
        "message": {"text": message},
        "locations": [location(file, path, "")],
    });
    if let Some(state) = baseline {
        result["baselineState"] = json!(state.sarif());
    }
    result
}

fn rule_index(id: &str) -> Option<usize> {
    RULES.iter().position(|r| r.id == id)
}

/// The file as an artifact, and the material and node path in it as one logical location.
fn location(file: &str, path: &[String], node_type: &str) -> Value {
    let mut names = vec![file.to_string()];
    names.extend(path.iter().cloned());
    let mut logical = json!({
        "fullyQualifiedName": names.join(" ▸ "),
        "name": names.last().expect("the file at least"),
        "kind": if path.len() > 1 { "element" } else { "resource" },
    });
    if !node_type.is_empty() {
        logical["properties"] = json!({"nodeType": node_type});
    }
    json!({
        "physicalLocation": {"artifactLocation": {"uri": uri_reference(file)}},
        "logicalLocations": [logical],
    })
}

/// A waiver as SARIF says it: in the asset (`inSource`, a custom property on the material
/// or node) or beside it (`external`, a gloffuse.toml), accepted, with its reason.
fn suppression(w: &Waived) -> Value {
    let kind = if w.from == "config" {
        "external"
    } else {
        "inSource"
    };
    json!({
        "kind": kind,
        "status": "accepted",
        "justification": w.reason,
        "properties": {"from": w.from, "where": w.place, "line": w.line},
    })
}

/// A path as a URI reference: every byte but the unreserved ones and `/` percent-encoded
/// (a Windows `\` becomes `/`).
fn uri_reference(path: &str) -> String {
    let mut out = String::new();
    for byte in path.replace('\\', "/").bytes() {
        match byte {
            b'A'..=b'Z' | b'a'..=b'z' | b'0'..=b'9' | b'-' | b'.' | b'_' | b'~' | b'/' => {
                out.push(byte as char)
            }
            _ => out.push_str(&format!("%{byte:02X}")),
        }
    }
    out
}

/// The text up to the first colon or parenthesis: a rule's `why` in a few words.
fn first_clause(text: &str) -> String {
    let end = text.find([':', '(']).unwrap_or(text.len());
    text[..end].trim_end().trim_end_matches(',').to_string()
}

/// `text` with a capital letter and no full stop (the caller adds its own).
fn sentence(text: &str) -> String {
    let mut chars = text.chars();
    let first: String = chars
        .next()
        .map(|c| c.to_uppercase().collect())
        .unwrap_or_default();
    format!("{first}{}", chars.as_str().trim_end_matches('.'))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_path_becomes_a_uri_reference() {
        assert_eq!(uri_reference("assets/lib.blend"), "assets/lib.blend");
        assert_eq!(uri_reference("my lib/é.blend"), "my%20lib/%C3%A9.blend");
        assert_eq!(uri_reference("a\\b#1.blend"), "a/b%231.blend");
    }

    #[test]
    fn a_rule_reads_as_a_short_and_a_full_description() {
        assert_eq!(
            first_clause("a single-scatter glossy lobe (GGX) loses light: much"),
            "a single-scatter glossy lobe"
        );
        assert_eq!(sentence("replace it."), "Replace it");
    }
}
