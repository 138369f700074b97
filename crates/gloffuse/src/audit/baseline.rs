//! `--baseline OLD.json`: the check fails only on what is new or worse than in an earlier
//! report. Each material is matched by file and name with the baseline's and is `new` (not
//! in it), `worse`, `better` or `unchanged`; a failing material fails the check only when
//! new or worse, and a file error only when the baseline had none for that file.
//!
//! Worse, in this order: it fails now and did not; its brightness moved further from 100 %
//! by more than the tolerance; or it has a finding that counts (rule at node, of error
//! severity and not waived) that the baseline had not. Better: it failed and does not; its
//! brightness came closer to 100 % by more than the tolerance; or a finding of the
//! baseline's that counted is gone. Anything else is unchanged.
//!
//! Only the fields compared are read from the baseline, so a report of another gloffuse
//! version serves as long as it has them.

use std::collections::{BTreeSet, HashMap, HashSet};
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::rules::Severity;
use super::verdict::{AuditReport, AuditedMaterial, Verdict};
use super::waivers::counts;
use crate::{Error, Field};

/// A material beside its baseline.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum BaselineState {
    New,
    Unchanged,
    Better,
    Worse,
}

impl BaselineState {
    pub const ALL: [BaselineState; 4] = [
        BaselineState::New,
        BaselineState::Worse,
        BaselineState::Better,
        BaselineState::Unchanged,
    ];

    pub fn key(self) -> &'static str {
        match self {
            BaselineState::New => "new",
            BaselineState::Unchanged => "unchanged",
            BaselineState::Better => "better",
            BaselineState::Worse => "worse",
        }
    }

    /// SARIF's `baselineState`: better and worse are both `updated`.
    pub fn sarif(self) -> &'static str {
        match self {
            BaselineState::New => "new",
            BaselineState::Unchanged => "unchanged",
            BaselineState::Better | BaselineState::Worse => "updated",
        }
    }

    /// Whether a failing material in this state fails the check.
    pub fn counts(self) -> bool {
        matches!(self, BaselineState::New | BaselineState::Worse)
    }
}

/// What the report says of its baseline.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct BaselineSummary {
    /// The baseline report, as given.
    pub path: String,
    pub new: usize,
    pub worse: usize,
    pub better: usize,
    pub unchanged: usize,
    /// Materials of the audited files that the baseline has and this audit does not
    /// (`FILE ▸ MATERIAL`).
    pub absent: Vec<String>,
}

#[derive(Deserialize)]
struct OldReport {
    files: Vec<OldFile>,
    materials: Vec<OldMaterial>,
}

#[derive(Deserialize)]
struct OldFile {
    file: String,
    #[serde(default)]
    error: Option<String>,
}

#[derive(Deserialize)]
struct OldMaterial {
    file: String,
    material: String,
    verdict: Verdict,
    #[serde(default)]
    mean: Option<f64>,
    /// Absent in reports older than waivers: then its verdict and `fail_on` decide.
    #[serde(default)]
    fails: Option<bool>,
    #[serde(default)]
    findings: Vec<OldFinding>,
}

#[derive(Deserialize)]
struct OldFinding {
    rule: String,
    node: String,
    #[serde(default)]
    severity: Severity,
    #[serde(default)]
    waived: Option<serde_json::Value>,
}

/// An earlier report, read for comparing.
pub struct Baseline {
    path: PathBuf,
    materials: HashMap<(String, String), OldMaterial>,
    file_errors: HashSet<String>,
}

impl Baseline {
    /// Reads the report at `path` (a report.json, or what `gloffuse audit` printed as JSON).
    pub fn read(path: &Path) -> Result<Baseline, Error> {
        let bytes = std::fs::read(path).map_err(|source| Error::Read {
            path: path.to_path_buf(),
            source,
        })?;
        let old: OldReport = serde_json::from_slice(&bytes).map_err(|e| {
            Error::input(
                Field::Baseline,
                path.display(),
                format!(
                    "an audit report (a report.json, or what `gloffuse audit` prints as JSON); \
                     it is not one: {e}"
                ),
            )
        })?;
        Ok(Baseline {
            path: path.to_path_buf(),
            file_errors: old
                .files
                .into_iter()
                .filter(|f| f.error.is_some())
                .map(|f| f.file)
                .collect(),
            materials: old
                .materials
                .into_iter()
                .map(|m| ((m.file.clone(), m.material.clone()), m))
                .collect(),
        })
    }

    /// Sets each material's state and the report's summary (its counts made by `finish`).
    pub fn apply(&self, report: &mut AuditReport) {
        let fail_on = report.settings.fail_on.clone();
        let tolerance = report.settings.tolerance;
        let mut present = HashSet::new();
        for m in &mut report.materials {
            present.insert((m.file.clone(), m.material.clone()));
            let old = self.materials.get(&(m.file.clone(), m.material.clone()));
            m.baseline = Some(match old {
                None => BaselineState::New,
                Some(old) => compare(m, old, &fail_on, tolerance),
            });
        }
        for f in &mut report.files {
            f.error_in_baseline = f.error.is_some() && self.file_errors.contains(&f.file);
        }
        let audited: HashSet<&String> = report.files.iter().map(|f| &f.file).collect();
        let mut absent: Vec<String> = self
            .materials
            .keys()
            .filter(|key| audited.contains(&key.0) && !present.contains(*key))
            .map(|(file, material)| format!("{file} ▸ {material}"))
            .collect();
        absent.sort();
        report.baseline = Some(BaselineSummary {
            path: self.path.display().to_string(),
            absent,
            ..BaselineSummary::default()
        });
    }
}

fn compare(
    m: &AuditedMaterial,
    old: &OldMaterial,
    fail_on: &[Verdict],
    tolerance: f64,
) -> BaselineState {
    let failed = old.fails.unwrap_or(fail_on.contains(&old.verdict));
    let distance = |mean: Option<f64>| mean.map(|v| (v - 1.0).abs());
    let moved = match (distance(m.mean), distance(old.mean)) {
        (Some(now), Some(then)) => now - then,
        _ => 0.0,
    };
    // The findings that count (error severity, not waived): a new warning is no worse.
    let now: BTreeSet<(&str, &str)> = m
        .findings
        .iter()
        .filter(|f| counts(f))
        .map(|f| (f.rule.as_str(), f.node.as_str()))
        .collect();
    let then: BTreeSet<(&str, &str)> = old
        .findings
        .iter()
        .filter(|f| f.severity == Severity::Error && f.waived.is_none())
        .map(|f| (f.rule.as_str(), f.node.as_str()))
        .collect();
    let fails = m.fails == Some(true);
    if (fails && !failed) || moved > tolerance || !now.is_subset(&then) {
        BaselineState::Worse
    } else if (failed && !fails) || moved < -tolerance || now != then {
        BaselineState::Better
    } else {
        BaselineState::Unchanged
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    /// A material as a report holds it: `fails`, its mean and its findings (rule, severity).
    fn material(fails: bool, mean: f64, findings: &[(&str, &str)]) -> AuditedMaterial {
        let findings: Vec<_> = findings
            .iter()
            .map(|(rule, severity)| {
                json!({"rule": rule, "node": "m ▸ Glossy", "node_path": ["m", "Glossy"],
                       "node_type": "ShaderNodeBsdfGlossy", "kind": "loses", "versions": "",
                       "why": "", "fix": "", "predicted": null, "twin": null, "detail": null,
                       "severity": severity})
            })
            .collect();
        serde_json::from_value(json!({
            "file": "a.blend", "material": "m", "verdict": if fails { "loses" } else { "ok" },
            "reason": "", "fails": fails, "mean": mean, "center": null, "rim": null,
            "twin_mean": null, "twin_center": null, "twin_rim": null, "replaced": 0,
            "findings": findings, "library": null, "after": null,
        }))
        .unwrap()
    }

    fn old(m: &AuditedMaterial) -> OldMaterial {
        serde_json::from_value(serde_json::to_value(m).unwrap()).unwrap()
    }

    fn state(now: &AuditedMaterial, then: &AuditedMaterial) -> BaselineState {
        compare(now, &old(then), &[Verdict::Loses], 0.01)
    }

    #[test]
    fn a_material_is_worse_better_or_unchanged_beside_its_baseline() {
        let glossy = [("glossy-single-scatter", "error")];
        let losing = material(true, 0.80, &glossy);
        assert_eq!(state(&losing, &losing), BaselineState::Unchanged);
        // Within the tolerance of the same brightness: unchanged (render noise).
        assert_eq!(
            state(&material(true, 0.795, &glossy), &losing),
            BaselineState::Unchanged
        );
        // Further from 100 % by more than the tolerance: worse; closer: better.
        assert_eq!(
            state(&material(true, 0.70, &glossy), &losing),
            BaselineState::Worse
        );
        assert_eq!(
            state(&material(true, 0.90, &glossy), &losing),
            BaselineState::Better
        );
        // Fails now and did not: worse, whatever its brightness; the other way: better.
        let fine = material(false, 1.0, &[]);
        assert_eq!(state(&losing, &fine), BaselineState::Worse);
        assert_eq!(state(&fine, &losing), BaselineState::Better);
        // A new finding that counts is worse; a new warning is not.
        let two = [("glossy-single-scatter", "error"), ("toon-smooth", "error")];
        assert_eq!(
            state(&material(true, 0.80, &two), &losing),
            BaselineState::Worse
        );
        let warned = [
            ("glossy-single-scatter", "error"),
            ("unknown-node", "warning"),
        ];
        assert_eq!(
            state(&material(true, 0.80, &warned), &losing),
            BaselineState::Unchanged
        );
        assert_eq!(
            state(&losing, &material(true, 0.80, &two)),
            BaselineState::Better
        );
    }

    #[test]
    fn only_a_new_or_worse_failure_counts() {
        assert!(BaselineState::New.counts() && BaselineState::Worse.counts());
        assert!(!BaselineState::Better.counts() && !BaselineState::Unchanged.counts());
        assert_eq!(
            BaselineState::ALL.map(BaselineState::sarif),
            ["new", "updated", "updated", "unchanged"]
        );
    }
}
