//! Waivers and severities: which findings count. A material or node carries a waiver as its
//! custom property `gloffuse_ignore` (`RULE-ID: reason`, several separated by `;`, `*` for
//! every rule), which the job reads and reports as it is; a `gloffuse.toml` (config.rs)
//! waives by rule, file and material, and changes severities. A waived finding stays in the
//! report, with its reason and where the waiver came from; it never fails the check.
//!
//! What fails: a material whose verdict is in `--fail-on` and rests on a finding that counts
//! (an `error` finding, not waived), or on no finding at all (the job's error, a sphere
//! measured above 100 % with no rule to explain it, one black through a node the audit
//! does not know) unless `*` waives the material; and a
//! material or file with an `info` rule's finding raised to `error` that is not waived.

use std::path::{Path, PathBuf};

use super::config::{Config, ConfigWaiver, Rules, relative_to};
use super::job::JobWaiver;
use super::rules::{Effect, Severity, rule};
use super::verdict::{Finding, Verdict, Waived};

/// The custom property that carries a waiver.
pub const PROPERTY: &str = "gloffuse_ignore";

/// The longest waiver text read; a longer one waives nothing (it is an `invalid-waiver`).
pub const MAX_WAIVER: usize = 4096;

/// The waiver text of a `gloffuse_ignore` property: each entry's rules and reason, and what
/// could not be read (an entry that is wrong waives nothing; the rest still do).
pub fn parse_waiver(text: &str) -> (Vec<(Rules, String)>, Vec<String>) {
    let chars = text.chars().count();
    if chars > MAX_WAIVER {
        return (
            Vec::new(),
            vec![format!(
                "{chars} characters, over the {MAX_WAIVER} a waiver may hold"
            )],
        );
    }
    let mut entries = Vec::new();
    let mut problems = Vec::new();
    let pieces: Vec<&str> = text
        .split(';')
        .map(str::trim)
        .filter(|p| !p.is_empty())
        .collect();
    if pieces.is_empty() {
        problems.push("it holds no `RULE-ID: reason`".to_string());
    }
    for piece in pieces {
        let Some((id, reason)) = piece.split_once(':') else {
            problems.push(format!(
                "`{}` has no reason (`RULE-ID: reason`)",
                clip(piece)
            ));
            continue;
        };
        let (id, reason) = (id.trim(), reason.trim());
        if reason.is_empty() {
            problems.push(format!("`{}` has an empty reason", clip(id)));
            continue;
        }
        let rules = match id {
            "*" => Rules::All,
            _ => match rule(id) {
                Some(r) => Rules::Ids(vec![r.id]),
                None => {
                    problems.push(format!("unknown rule `{}`", clip(id)));
                    continue;
                }
            },
        };
        entries.push((rules, reason.to_string()));
    }
    (entries, problems)
}

/// A user's text shortened for a message (the whole is in the report's detail, clipped).
fn clip(text: &str) -> String {
    const SHOWN: usize = 80;
    if text.chars().count() <= SHOWN {
        text.to_string()
    } else {
        format!("{}…", text.chars().take(SHOWN).collect::<String>())
    }
}

/// What decides, for one file, which findings count.
pub struct Policy<'a> {
    /// The nearest `gloffuse.toml`, if one holds the file.
    pub config: Option<&'a Config>,
    /// The file's path below the configuration's folder.
    relative: PathBuf,
    /// Whether `invalid-waiver` runs (`--select`/`--ignore`).
    pub invalid_waiver_runs: bool,
    /// Whether the files' own `gloffuse_ignore` properties count (not with
    /// `--no-property-waivers`: a file's author cannot waive its own findings then).
    pub properties: bool,
}

impl<'a> Policy<'a> {
    pub fn new(config: Option<&'a Config>, file: &Path, invalid_waiver_runs: bool) -> Self {
        Policy {
            config,
            relative: config.map_or_else(|| file.to_path_buf(), |c| relative_to(c, file)),
            invalid_waiver_runs,
            properties: true,
        }
    }

    /// The same, with the files' own properties disregarded (or not).
    pub fn with_properties(self, properties: bool) -> Self {
        Policy { properties, ..self }
    }

    fn severity(&self, id: &str) -> Severity {
        self.config
            .and_then(|c| c.severity.get(id).copied())
            .or_else(|| rule(id).map(|r| r.severity))
            .unwrap_or(Severity::Error)
    }

    fn config_waiver(
        &self,
        id: &str,
        material: Option<&str>,
    ) -> Option<(&'a Config, &'a ConfigWaiver)> {
        let config = self.config?;
        config
            .waivers
            .iter()
            .find(|w| w.applies(id, &self.relative, material))
            .map(|w| (config, w))
    }

    /// A `*` entry of the configuration that holds this material.
    fn config_star(&self, material: &str) -> Option<Waived> {
        let config = self.config?;
        config
            .waivers
            .iter()
            .find(|w| w.rules == Rules::All && w.covers_material(&self.relative, Some(material)))
            .map(|w| from_config(config, w))
    }

    /// The file's own findings (its scenes'): severities and the configuration's waivers.
    pub fn file_findings(&self, findings: &mut [Finding]) {
        for f in findings {
            f.severity = self.severity(&f.rule);
            f.waived = self
                .config_waiver(&f.rule, None)
                .map(|(c, w)| from_config(c, w));
        }
    }

    /// A material's findings: severities and waivers (the nearest property first, from the
    /// node itself up to the material, then the configuration), with an `invalid-waiver`
    /// finding for each property that cannot be read. Returns the material's `*` waiver.
    pub fn material_findings(
        &self,
        material: &str,
        findings: &mut Vec<Finding>,
        properties: &[JobWaiver],
    ) -> Option<Waived> {
        let mut read: Vec<(&JobWaiver, Vec<(Rules, String)>)> = Vec::new();
        let properties = if self.properties { properties } else { &[] };
        for p in properties {
            let (entries, problems) = match &p.value {
                Some(text) => parse_waiver(text),
                None => (
                    Vec::new(),
                    vec![format!(
                        "a property of type {} (it must be text)",
                        p.value_type
                    )],
                ),
            };
            if !problems.is_empty() && self.invalid_waiver_runs {
                findings.push(invalid_waiver(p, &problems));
            }
            read.push((p, entries));
        }
        // The nearest carrier first: the longest path.
        read.sort_by_key(|(p, _)| std::cmp::Reverse(p.node.len()));
        for f in findings.iter_mut() {
            f.severity = self.severity(&f.rule);
            let by_property = read.iter().find_map(|(p, entries)| {
                let holds = f.node_path.starts_with(&p.node);
                entries
                    .iter()
                    .find(|(rules, _)| holds && rules.covers(&f.rule))
                    .map(|(_, reason)| from_property(p, reason))
            });
            f.waived = by_property.or_else(|| {
                self.config_waiver(&f.rule, Some(material))
                    .map(|(c, w)| from_config(c, w))
            });
        }
        let material_star = read.iter().find_map(|(p, entries)| {
            (p.node.len() == 1)
                .then(|| entries.iter().find(|(rules, _)| *rules == Rules::All))
                .flatten()
                .map(|(_, reason)| from_property(p, reason))
        });
        material_star.or_else(|| self.config_star(material))
    }
}

fn from_property(p: &JobWaiver, reason: &str) -> Waived {
    Waived {
        reason: reason.to_string(),
        from: if p.node.len() == 1 {
            "material"
        } else {
            "node"
        }
        .to_string(),
        place: p.node.join(" ▸ "),
        line: None,
    }
}

fn from_config(c: &Config, w: &ConfigWaiver) -> Waived {
    Waived {
        reason: w.reason.clone(),
        from: "config".to_string(),
        place: c.path.display().to_string(),
        line: Some(w.line),
    }
}

fn invalid_waiver(p: &JobWaiver, problems: &[String]) -> Finding {
    let r = rule("invalid-waiver").expect("the catalogue has invalid-waiver");
    Finding {
        rule: r.id.to_string(),
        node: p.node.join(" ▸ "),
        node_path: p.node.clone(),
        node_type: p.node_type.clone(),
        kind: r.effect,
        versions: r.versions(),
        why: format!("{}: {}", r.why, problems.join("; ")),
        fix: r.fix.to_string(),
        predicted: None,
        twin: None,
        detail: serde_json::json!({
            "property": PROPERTY,
            "type": p.value_type,
            "value": p.value.as_deref().map(clip),
            "problems": problems,
        }),
        severity: r.severity,
        waived: None,
    }
}

/// Whether a finding counts toward failing: an `error` one, not waived.
pub fn counts(f: &Finding) -> bool {
    f.severity == Severity::Error && f.waived.is_none()
}

/// The findings a verdict rests on: every finding of its kind (a `loses` verdict also on a
/// creating lobe the twin changed, as a Toon BSDF's Smooth measures darker).
fn rests_on(verdict: Verdict, f: &Finding) -> bool {
    match verdict {
        Verdict::Loses => {
            f.kind == Effect::Loses || (f.kind == Effect::Creates && f.twin.is_some())
        }
        Verdict::Creates => f.kind == Effect::Creates,
        // A material that renders black through a node the audit does not know rests on no
        // rule: `unknown-node` is a warning wherever the node renders.
        Verdict::Error => f.kind == Effect::Error,
        Verdict::Ok => false,
    }
}

/// Whether a material fails the check, and, where its verdict is in `fail_on` but does not
/// fail, why (its findings waived, or below `error` severity).
pub fn fails(
    verdict: Verdict,
    findings: &[Finding],
    star: Option<&Waived>,
    fail_on: &[Verdict],
) -> (bool, Option<String>) {
    let raised = findings.iter().any(|f| f.kind == Effect::Info && counts(f));
    if !fail_on.contains(&verdict) {
        return (raised, None);
    }
    let resting: Vec<&Finding> = findings.iter().filter(|f| rests_on(verdict, f)).collect();
    if resting.is_empty() {
        return match star {
            Some(w) => (
                raised,
                Some(format!("{} waived: {}", verdict.key(), said(w))),
            ),
            None => (true, None),
        };
    }
    if resting.iter().any(|f| counts(f)) {
        return (true, None);
    }
    let why: Vec<String> = resting
        .iter()
        .map(|f| match &f.waived {
            Some(w) => format!("{} at {} waived: {}", f.rule, f.node, said(w)),
            None => format!("{} at {} is a {}", f.rule, f.node, f.severity.key()),
        })
        .collect();
    (
        raised,
        Some(format!("{} not failing: {}", verdict.key(), why.join("; "))),
    )
}

/// A waiver in words: its reason and where it came from.
pub fn said(w: &Waived) -> String {
    let place = match (w.from.as_str(), w.line) {
        ("config", Some(line)) => format!("{}, line {line}", w.place),
        ("material", _) => format!("{PROPERTY} on material {}", w.place),
        _ => format!("{PROPERTY} on node {}", w.place),
    };
    format!("“{}” ({place})", w.reason)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::audit::config::parse_config;

    fn ids(entries: &[(Rules, String)]) -> Vec<(Rules, &str)> {
        entries
            .iter()
            .map(|(r, s)| (r.clone(), s.as_str()))
            .collect()
    }

    #[test]
    fn a_waiver_reads_rule_ids_and_reasons() {
        let (entries, problems) =
            parse_waiver(" glossy-single-scatter: the look ; *: legacy asset;;");
        assert!(problems.is_empty(), "{problems:?}");
        assert_eq!(
            ids(&entries),
            [
                (Rules::Ids(vec!["glossy-single-scatter"]), "the look"),
                (Rules::All, "legacy asset")
            ]
        );
        // A reason may hold colons.
        let (entries, _) = parse_waiver("toon-smooth: see https://x.example: ok");
        assert_eq!(entries[0].1, "see https://x.example: ok");
    }

    #[test]
    fn hostile_waivers_waive_nothing_and_say_why() {
        for (text, words) in [
            ("", "holds no"),
            (";;; ;", "holds no"),
            ("glossy-single-scatter", "has no reason"),
            ("glossy-single-scatter:   ", "empty reason"),
            ("glossy: typo", "unknown rule `glossy`"),
            ("\u{202e}evil\n: x", "unknown rule"),
        ] {
            let (entries, problems) = parse_waiver(text);
            assert!(entries.is_empty(), "{text:?}");
            assert!(
                problems.iter().any(|p| p.contains(words)),
                "{text:?}: {problems:?}"
            );
        }
        let huge = format!("*: {}", "x".repeat(1 << 20));
        let (entries, problems) = parse_waiver(&huge);
        assert!(entries.is_empty());
        assert!(problems[0].contains("over the 4096"), "{problems:?}");
        // A long unknown id is clipped in the message.
        let (_, problems) = parse_waiver(&format!("{}: x", "y".repeat(500)));
        assert!(problems[0].chars().count() < 120, "{problems:?}");
        // One wrong entry leaves the others.
        let (entries, problems) = parse_waiver("nope: x; toon-smooth: y");
        assert_eq!(entries.len(), 1);
        assert_eq!(problems.len(), 1);
    }

    fn finding(rule_id: &str, node: &[&str], twin: Option<&str>) -> Finding {
        let r = rule(rule_id).unwrap();
        Finding {
            rule: rule_id.into(),
            node: node.join(" ▸ "),
            node_path: node.iter().map(|s| s.to_string()).collect(),
            node_type: "ShaderNodeBsdfGlossy".into(),
            kind: r.effect,
            versions: r.versions(),
            why: String::new(),
            fix: String::new(),
            predicted: None,
            twin: twin.map(String::from),
            detail: serde_json::Value::Null,
            severity: Severity::Info,
            waived: None,
        }
    }

    fn property(node: &[&str], value: Option<&str>, kind: &str) -> JobWaiver {
        JobWaiver {
            node: node.iter().map(|s| s.to_string()).collect(),
            node_type: "Material".into(),
            value: value.map(String::from),
            value_type: kind.into(),
        }
    }

    const FAIL_ON: [Verdict; 3] = [Verdict::Loses, Verdict::Creates, Verdict::Error];

    #[test]
    fn the_nearest_property_waives_and_the_verdict_follows() {
        let policy = Policy::new(None, Path::new("a.blend"), true);
        let mut findings = vec![
            finding(
                "glossy-single-scatter",
                &["M", "Group", "Glossy"],
                Some("x"),
            ),
            finding("glossy-single-scatter", &["M", "Glossy 2"], Some("x")),
        ];
        let star = policy.material_findings(
            "M",
            &mut findings,
            &[
                property(
                    &["M", "Group"],
                    Some("glossy-single-scatter: the group's look"),
                    "str",
                ),
                property(&["M", "Group", "Glossy"], Some("*: this node"), "str"),
            ],
        );
        assert_eq!(star, None);
        assert_eq!(findings[0].waived.as_ref().unwrap().reason, "this node");
        assert_eq!(findings[0].waived.as_ref().unwrap().from, "node");
        assert_eq!(findings[0].severity, Severity::Error);
        assert!(findings[1].waived.is_none());
        // One losing finding still counts: the measured loss fails.
        assert_eq!(
            fails(Verdict::Loses, &findings, None, &FAIL_ON),
            (true, None)
        );
        findings.truncate(1);
        let (fail, why) = fails(Verdict::Loses, &findings, None, &FAIL_ON);
        assert!(!fail);
        assert!(
            why.unwrap()
                .contains("“this node” (gloffuse_ignore on node M ▸ Group ▸ Glossy)")
        );
    }

    /// A verdict no finding explains (a sphere above 100 % with no creating rule, the job's
    /// error) is waived only by `*` on the material.
    #[test]
    fn a_verdict_without_a_rule_needs_a_star() {
        let policy = Policy::new(None, Path::new("a.blend"), true);
        let mut findings = vec![finding("glossy-single-scatter", &["M", "G"], Some("x"))];
        let star = policy.material_findings(
            "M",
            &mut findings,
            &[property(&["M"], Some("glossy-single-scatter: fine"), "str")],
        );
        assert!(star.is_none());
        assert!(!fails(Verdict::Loses, &findings, None, &FAIL_ON).0);
        assert!(fails(Verdict::Creates, &findings, None, &FAIL_ON).0);
        let star = policy.material_findings(
            "M",
            &mut findings,
            &[property(&["M"], Some("*: all"), "str")],
        );
        let star = star.expect("a star on the material");
        assert_eq!(star.from, "material");
        let (fail, why) = fails(Verdict::Creates, &findings, Some(&star), &FAIL_ON);
        assert!(!fail && why.unwrap().starts_with("creates waived"));
        // Black through an unknown node (a warning): the error rests on no rule.
        let mut unknown = vec![finding("unknown-node", &["M", "Script"], None)];
        policy.material_findings("M", &mut unknown, &[]);
        assert_eq!(unknown[0].severity, Severity::Warning);
        assert_eq!(
            fails(Verdict::Error, &unknown, None, &FAIL_ON),
            (true, None)
        );
        assert!(!fails(Verdict::Error, &unknown, Some(&star), &FAIL_ON).0);
        // Not in --fail-on: nothing to say.
        assert_eq!(
            fails(Verdict::Creates, &findings, None, &[Verdict::Error]),
            (false, None)
        );
    }

    #[test]
    fn a_property_that_is_not_text_is_an_invalid_waiver_finding() {
        let policy = Policy::new(None, Path::new("a.blend"), true);
        let mut findings = Vec::new();
        for (value, kind) in [(None, "int"), (None, "IDPropertyGroup"), (Some(";"), "str")] {
            policy.material_findings("M", &mut findings, &[property(&["M", "N"], value, kind)]);
        }
        assert_eq!(findings.len(), 3);
        assert!(
            findings[0].why.contains("type int (it must be text)"),
            "{}",
            findings[0].why
        );
        assert!(findings[1].why.contains("IDPropertyGroup"));
        assert_eq!(findings[2].severity, Severity::Warning);
        // A warning fails nothing; raised to error by a configuration, it fails alone.
        assert!(!fails(Verdict::Ok, &findings, None, &FAIL_ON).0);
        let config = parse_config(
            Path::new("/s/gloffuse.toml"),
            "[severity]\ninvalid-waiver = \"error\"\n",
        )
        .unwrap();
        let strict = Policy::new(Some(&config), Path::new("/s/a.blend"), true);
        let mut findings = Vec::new();
        strict.material_findings("M", &mut findings, &[property(&["M"], None, "float")]);
        assert_eq!(findings[0].severity, Severity::Error);
        assert!(fails(Verdict::Ok, &findings, None, &FAIL_ON).0);
        // Disregarded, a property waives nothing and is not read.
        let strict = Policy::new(None, Path::new("a.blend"), true).with_properties(false);
        let mut findings = vec![finding("toon-smooth", &["M", "T"], Some("x"))];
        let star =
            strict.material_findings("M", &mut findings, &[property(&["M"], Some("*: x"), "str")]);
        assert!(star.is_none() && findings[0].waived.is_none() && findings.len() == 1);
        // Ignored, it is not reported.
        let quiet = Policy::new(None, Path::new("a.blend"), false);
        let mut findings = Vec::new();
        quiet.material_findings("M", &mut findings, &[property(&["M"], None, "int")]);
        assert!(findings.is_empty());
    }

    #[test]
    fn a_configuration_waives_by_file_and_material_and_sets_severities() {
        let config = parse_config(
            Path::new("/s/gloffuse.toml"),
            "[severity]\ncolor-above-one = \"warning\"\n\n[[waiver]]\nrules = \
             [\"glossy-single-scatter\"]\nreason = \"approved\"\nfiles = [\"props/*.blend\"]\n\n\
             [[waiver]]\nrules = [\"*\"]\nreason = \"legacy\"\nmaterials = [\"Old\"]\n",
        )
        .unwrap();
        let policy = Policy::new(Some(&config), Path::new("/s/props/a.blend"), true);
        let mut findings = vec![
            finding("glossy-single-scatter", &["M", "G"], Some("x")),
            finding("color-above-one", &["M", "D"], Some("x")),
        ];
        assert!(policy.material_findings("M", &mut findings, &[]).is_none());
        let w = findings[0].waived.as_ref().unwrap();
        assert_eq!((w.from.as_str(), w.line), ("config", Some(4)));
        assert_eq!(said(w), "“approved” (/s/gloffuse.toml, line 4)");
        assert_eq!(findings[1].severity, Severity::Warning);
        let (fail, why) = fails(Verdict::Creates, &findings, None, &FAIL_ON);
        assert!(
            !fail
                && why
                    .unwrap()
                    .contains("color-above-one at M ▸ D is a warning")
        );
        let star = policy.material_findings("Old", &mut findings, &[]).unwrap();
        assert_eq!(star.line, Some(9));
        let elsewhere = Policy::new(Some(&config), Path::new("/s/other/a.blend"), true);
        let mut findings = vec![finding("glossy-single-scatter", &["M", "G"], Some("x"))];
        elsewhere.material_findings("M", &mut findings, &[]);
        assert!(findings[0].waived.is_none());
        // A file finding is waived by an entry that names no material.
        let mut file = vec![finding("filter-glossy", &["Scene"], None)];
        Policy::new(Some(&config), Path::new("/s/props/a.blend"), true).file_findings(&mut file);
        assert_eq!(file[0].severity, Severity::Warning);
        assert!(file[0].waived.is_none());
    }
}
