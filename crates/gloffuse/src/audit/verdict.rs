//! The audit's verdict as data: one [`AuditedMaterial`] per material, its [`Finding`]s,
//! the files, the counts and whether the check passed.

use serde::{Deserialize, Serialize};

use super::baseline::{BaselineState, BaselineSummary};
use super::fix_choice::MaterialFix;
use super::rules::{Effect, Severity};
use crate::shard::Shard;

/// What the furnace and the rules say about one material.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize, PartialOrd, Ord)]
#[serde(rename_all = "kebab-case")]
pub enum Verdict {
    /// It creates energy: brighter than the light it receives.
    Creates,
    /// It loses energy its conserving twin keeps.
    Loses,
    /// It could not be audited as authored.
    Error,
    Ok,
}

impl Verdict {
    pub const ALL: [Verdict; 4] = [
        Verdict::Ok,
        Verdict::Loses,
        Verdict::Creates,
        Verdict::Error,
    ];

    pub fn key(self) -> &'static str {
        match self {
            Verdict::Ok => "ok",
            Verdict::Loses => "loses",
            Verdict::Creates => "creates",
            Verdict::Error => "error",
        }
    }
}

/// Thresholds of the furnace verdict.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AuditJudging {
    /// Allowed excess of the mean over 1, and of the twin's mean over the material's (0.01 = 1 %).
    pub tolerance: f64,
    /// Allowed excess of a ring's mean over 1.
    pub ring_tolerance: f64,
    /// The verdicts that fail the check.
    pub fail_on: Vec<Verdict>,
}

impl Default for AuditJudging {
    fn default() -> Self {
        AuditJudging {
            tolerance: 0.01,
            ring_tolerance: 0.03,
            fail_on: vec![Verdict::Loses, Verdict::Creates, Verdict::Error],
        }
    }
}

/// One flagged node.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Finding {
    pub rule: String,
    /// `Material ▸ Group node ▸ Node`.
    pub node: String,
    pub node_path: Vec<String>,
    pub node_type: String,
    pub kind: Effect,
    /// The Blender versions the rule applies to.
    pub versions: String,
    pub why: String,
    pub fix: String,
    /// The lobe's brightness the integrator predicts (1.0 = 100 %), where it is known.
    pub predicted: Option<f64>,
    /// What the conserving twin put in the node's place; none: nothing conserving exists.
    pub twin: Option<String>,
    /// What the job read off the node (distribution, roughness, …).
    pub detail: serde_json::Value,
    /// How much it counts: only an `error` finding fails the check (the catalogue's
    /// default, or the configuration's `[severity]`).
    #[serde(default)]
    pub severity: Severity,
    /// The waiver that suppresses it, if any: it stays in the report and fails nothing.
    #[serde(default)]
    pub waived: Option<Waived>,
}

/// Why a finding, or a material's verdict, is suppressed: the waiver's reason and where it
/// came from.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Waived {
    pub reason: String,
    /// `material` or `node` (its `gloffuse_ignore` property), or `config` (a gloffuse.toml).
    pub from: String,
    /// The material or node (`A ▸ B`) that carries the property, or the configuration file.
    #[serde(rename = "where")]
    pub place: String,
    /// The configuration's line where the `[[waiver]]` entry starts.
    #[serde(default)]
    pub line: Option<usize>,
}

/// Furnace brightness of one sphere (1.0 = 100 %), as the furnace shows it: where the
/// material is transparent, the white world seen through it counts.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Brightness {
    pub mean: f64,
    pub center: f64,
    /// The grazing views: view cosine below 0.3.
    pub rim: f64,
    /// The brightest ring.
    pub max_ring: f64,
    /// The highest of the rings' means less their noise (three standard errors each): a
    /// ring of a few grazing pixels can read above 100 % by noise alone at the audit's
    /// samples, and must not count as creating energy.
    #[serde(default)]
    pub ring_floor: f64,
    pub standard_error: f64,
    /// How much of the disc the material covers (1: opaque).
    pub opacity: f64,
}

/// The after-fix audit of a material.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct After {
    /// Whether the fix rewrote this material (a material it needed no fix for, or had no
    /// safe fix for, is the same in the fixed file).
    pub rewritten: bool,
    pub verdict: Verdict,
    pub mean: Option<f64>,
    pub findings: usize,
    /// Whether it fails the check after the fix (what the exit code of a fix counts). Always
    /// set by gloffuse; a report without it (hand-made, older) is read as its verdict in
    /// `fail_on`.
    #[serde(default)]
    pub fails: Option<bool>,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct AuditedMaterial {
    pub file: String,
    pub material: String,
    pub verdict: Verdict,
    /// Why, in words.
    pub reason: String,
    /// Whether it fails the check: its verdict is in `fail_on` and rests on a finding that
    /// counts (or on none, unwaived), or an `info` rule's finding raised to `error` counts.
    /// Always set by gloffuse; a report without it (hand-made, older) is read as its verdict
    /// in `fail_on` ([`AuditReport::finish`]).
    #[serde(default)]
    pub fails: Option<bool>,
    /// Why a verdict in `fail_on` does not fail: its findings waived or below `error`.
    #[serde(default)]
    pub suppressed: Option<String>,
    /// With `--baseline`: new, worse, better or unchanged beside the baseline's material of
    /// that file and name (a failing material fails the check only when new or worse).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub baseline: Option<BaselineState>,
    pub mean: Option<f64>,
    pub center: Option<f64>,
    pub rim: Option<f64>,
    pub twin_mean: Option<f64>,
    pub twin_center: Option<f64>,
    pub twin_rim: Option<f64>,
    /// How many lobes the twin replaced.
    pub replaced: usize,
    /// Why a fix leaves this material alone although its verdict fails (no safe twin).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub no_fix: Option<String>,
    /// How much of its sphere's disc it covers, where rendered (below 1: partly transparent,
    /// and the world seen through it counts to its mean).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub opacity: Option<f64>,
    pub findings: Vec<Finding>,
    /// The library it is linked from, as the file writes it.
    pub library: Option<String>,
    /// Its cell and its twin's in the file's rendered grid.
    #[serde(skip)]
    pub cells: Option<(usize, usize)>,
    /// What a fix would do to it (none: it needs none, or `no_fix` says why not).
    #[serde(skip)]
    pub fix: Option<MaterialFix>,
    pub after: Option<After>,
}

impl AuditedMaterial {
    /// Whether it fails the check: it fails, and is new or worse beside a baseline.
    pub fn failing(&self) -> bool {
        self.fails == Some(true) && self.beyond_baseline()
    }

    /// Whether a failure of it counts beside the baseline (without one, always).
    pub fn beyond_baseline(&self) -> bool {
        self.baseline.is_none_or(BaselineState::counts)
    }
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Fixed {
    pub path: String,
    pub replaced: usize,
    /// With `--in-place`: where the previous version was kept.
    pub backup: Option<String>,
    /// Why the fixed file could not be audited again (its materials then have no `after`).
    pub after_error: Option<String>,
}

/// One audited .blend.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct AuditedFile {
    pub file: String,
    /// The Blender version that saved it, from its header.
    pub saved_by: Option<String>,
    /// Why the file could not be audited (its materials are then missing from the report).
    pub error: Option<String>,
    /// With `--baseline`: the baseline has an error for this file too, so its error does
    /// not fail the check.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub error_in_baseline: bool,
    /// Findings of the file as a whole (its scenes' settings).
    pub findings: Vec<Finding>,
    pub materials: usize,
    pub log: Option<String>,
    pub render_seconds: Option<f64>,
    /// How long the rules took in Blender.
    pub scan_seconds: Option<f64>,
    /// The rendered grid's columns and cell size, for pictures.
    #[serde(skip)]
    pub grid: Option<(usize, usize)>,
    pub fixed: Option<Fixed>,
}

#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct Counts {
    pub files: usize,
    /// Files Blender could not audit (their materials are missing from the counts).
    pub files_failed: usize,
    pub materials: usize,
    pub ok: usize,
    pub loses: usize,
    pub creates: usize,
    pub error: usize,
    /// Materials that fail the check.
    #[serde(default)]
    pub failing: usize,
    /// Materials whose verdict is in `fail_on` but does not fail (waived, or a warning).
    #[serde(default)]
    pub suppressed: usize,
    /// Findings waived, of materials and files.
    #[serde(default)]
    pub waived_findings: usize,
}

/// How the materials were rendered.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AuditSettings {
    pub cell: u32,
    pub samples: u32,
    pub seed: u32,
    pub render: bool,
    pub tolerance: f64,
    pub ring_tolerance: f64,
    pub fail_on: Vec<Verdict>,
    /// The rules that did not run (`--select`, `--ignore`).
    #[serde(default)]
    pub skipped_rules: Vec<String>,
    /// Whether a fix was asked: the check then counts what is left after it.
    #[serde(default)]
    pub fix: bool,
    /// Whether the files' own `gloffuse_ignore` properties waived findings.
    #[serde(default = "yes")]
    pub property_waivers: bool,
}

fn yes() -> bool {
    true
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct AuditReport {
    pub gloffuse_version: String,
    pub blender_version: String,
    pub blender_program: String,
    pub settings: AuditSettings,
    /// Set in a shard's report (`--shard K/N`): which part it is, and the whole run's inputs.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shard: Option<ShardRun>,
    /// With `--baseline`: the baseline, and how many materials are new, worse, better and
    /// unchanged beside it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub baseline: Option<BaselineSummary>,
    /// Whether the files as they were pass the check.
    pub passed: bool,
    /// With a fix: whether what is left after it passes (the exit code's verdict).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub passed_after_fix: Option<bool>,
    pub counts: Counts,
    pub files: Vec<AuditedFile>,
    pub materials: Vec<AuditedMaterial>,
}

/// A shard's place in its run. The inputs are the same in every shard of a run: a merge
/// checks them and puts the files back in their order.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ShardRun {
    pub shard: Shard,
    /// Every file of the run, in order, with its materials as counted from its blocks (the
    /// cost the split balances).
    pub inputs: Vec<ShardInput>,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ShardInput {
    pub file: String,
    pub materials: usize,
}

impl AuditReport {
    /// Counts the verdicts and decides `passed`: no file error (none the baseline has
    /// too), no failing material (new or worse beside a baseline).
    pub fn finish(&mut self) {
        let mut counts = Counts {
            files: self.files.len(),
            files_failed: self.files.iter().filter(|f| f.error.is_some()).count(),
            materials: self.materials.len(),
            ..Counts::default()
        };
        for m in &self.materials {
            *match m.verdict {
                Verdict::Ok => &mut counts.ok,
                Verdict::Loses => &mut counts.loses,
                Verdict::Creates => &mut counts.creates,
                Verdict::Error => &mut counts.error,
            } += 1;
        }
        // A report read back without `fails` (hand-made, or older): its verdicts decide.
        let fail_on = self.settings.fail_on.clone();
        for m in &mut self.materials {
            m.fails.get_or_insert(fail_on.contains(&m.verdict));
            if let Some(a) = &mut m.after {
                a.fails.get_or_insert(fail_on.contains(&a.verdict));
            }
        }
        counts.failing = self.materials.iter().filter(|m| m.failing()).count();
        counts.suppressed = self
            .materials
            .iter()
            .filter(|m| m.suppressed.is_some())
            .count();
        counts.waived_findings = self
            .materials
            .iter()
            .flat_map(|m| &m.findings)
            .chain(self.files.iter().flat_map(|f| &f.findings))
            .filter(|f| f.waived.is_some())
            .count();
        let new_file_error = self
            .files
            .iter()
            .any(|f| f.error.is_some() && !f.error_in_baseline);
        let file_failed = (new_file_error && self.settings.fail_on.contains(&Verdict::Error))
            || self
                .files
                .iter()
                .flat_map(|f| &f.findings)
                .any(super::waivers::counts);
        self.passed = !file_failed && counts.failing == 0;
        // What a fix leaves: a rewritten (or re-audited) material's state after it, any
        // other's as it was.
        self.passed_after_fix = self.settings.fix.then(|| {
            !file_failed
                && !self.materials.iter().any(|m| {
                    m.after.as_ref().map_or(m.failing(), |a| {
                        a.fails == Some(true) && m.beyond_baseline()
                    })
                })
        });
        if let Some(summary) = &mut self.baseline {
            let n = |state| {
                self.materials
                    .iter()
                    .filter(|m| m.baseline == Some(state))
                    .count()
            };
            summary.new = n(BaselineState::New);
            summary.worse = n(BaselineState::Worse);
            summary.better = n(BaselineState::Better);
            summary.unchanged = n(BaselineState::Unchanged);
        }
        self.counts = counts;
    }

    /// Whether the check passes: with a fix, on what is left after it (as ruff's `--fix`).
    pub fn check_passed(&self) -> bool {
        self.passed_after_fix.unwrap_or(self.passed)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn report(fix: bool, materials: serde_json::Value) -> AuditReport {
        serde_json::from_value(serde_json::json!({
            "gloffuse_version": "0", "blender_version": "4.5.15", "blender_program": "b",
            "settings": {"cell": 64, "samples": 32, "seed": 0, "render": false,
                "tolerance": 0.01, "ring_tolerance": 0.03, "fail_on": ["loses"], "fix": fix},
            "passed": true, "counts": {"files": 0, "files_failed": 0, "materials": 0,
                "ok": 0, "loses": 0, "creates": 0, "error": 0},
            "files": [], "materials": materials
        }))
        .unwrap()
    }

    fn material(fails: bool, after: Option<bool>) -> serde_json::Value {
        serde_json::json!({"file": "a.blend", "material": "m", "verdict": "loses",
            "reason": "", "fails": fails, "mean": null, "center": null, "rim": null,
            "twin_mean": null, "twin_center": null, "twin_rim": null, "replaced": 1,
            "findings": [], "library": null,
            "after": after.map(|fails| serde_json::json!({"rewritten": true,
                "verdict": "ok", "mean": null, "findings": 0, "fails": fails}))})
    }

    /// With a fix, the check counts what is left after it: a material the fix repaired
    /// passes, one it could not fix (no `after`) still fails; `passed` keeps the before.
    #[test]
    fn a_fix_is_judged_by_what_it_leaves() {
        let mut r = report(true, serde_json::json!([material(true, Some(false))]));
        r.finish();
        assert_eq!((r.passed, r.passed_after_fix), (false, Some(true)));
        assert!(r.check_passed());
        let mut r = report(
            true,
            serde_json::json!([material(true, Some(false)), material(true, None)]),
        );
        r.finish();
        assert!(!r.check_passed());
        let mut r = report(true, serde_json::json!([material(false, Some(true))]));
        r.finish();
        assert!(
            r.passed && !r.check_passed(),
            "a fix that made it worse fails"
        );
        let mut r = report(false, serde_json::json!([material(true, Some(false))]));
        r.finish();
        assert_eq!(r.passed_after_fix, None);
        assert!(!r.check_passed());
        // Without `fails` (a hand-made or older report), the verdict in fail_on decides.
        let mut bare = material(false, Some(false));
        bare.as_object_mut().unwrap().remove("fails");
        bare["after"].as_object_mut().unwrap().remove("fails");
        let mut r = report(true, serde_json::json!([bare]));
        r.finish();
        assert_eq!(r.materials[0].fails, Some(true));
        assert_eq!(r.materials[0].after.as_ref().unwrap().fails, Some(false));
        assert_eq!((r.passed, r.check_passed()), (false, true));
    }
}
