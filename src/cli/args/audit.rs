//! `gloffuse audit`.

use clap::Args;
use std::path::PathBuf;

use super::blender::BlenderArgs;
use super::parse::{parse_shard, parse_tolerance, parse_verdict};
use gloffuse::audit::{AuditJudging, AuditOptions, FixTarget, Verdict};
use gloffuse::shard::Shard;
use gloffuse::verify::RenderSettings;

fn audit_defaults() -> AuditOptions {
    AuditOptions::default()
}

pub(super) const AUDIT_EXAMPLES: &str = "Examples:
  gloffuse audit assets/                         every .blend below assets/, a table
  gloffuse audit lib.blend --report audit-report an HTML page with each material beside its twin
  gloffuse audit assets/ --junit audit.xml --fail-on creates,error
                                                 a CI check that fails only on energy creation
  gloffuse audit lib.blend --fix lib-fixed.blend a fixed copy, audited again (before and after)
  gloffuse audit assets/ --fix-dir fixed/        fixed copies of every file, same layout
  gloffuse audit lib.blend --in-place            fix the file itself (the old one kept as lib.blend1)
  gloffuse audit assets/ --no-render             the rules alone, no Blender render
  gloffuse audit assets/ --ignore toon-smooth,filter-glossy
                                                 every rule but these two
  gloffuse audit assets/ --select glossy-single-scatter --no-render
                                                 only that rule
  gloffuse audit assets/ --json > accepted.json  a baseline: what the studio accepts today
  gloffuse audit assets/ --baseline accepted.json --sarif audit.sarif
                                                 fail only on what is new or worse, and a
                                                 SARIF log for a code-scanning service

What fails (exit 1): a material whose verdict is in --fail-on, unless every finding that
verdict rests on is waived or below error severity; a verdict no finding explains (a sphere
measured above 100 % with no creating rule, a black render through a node the audit does
not know, a job's error) is waived only by `*` on the material. An info rule raised to
error by gloffuse.toml fails by itself. Waived findings stay in every report, with their
reason and where the waiver came from.

Waivers: a material's or node's custom property gloffuse_ignore = \"RULE-ID: reason\"
(several separated by ;, * for every rule), and gloffuse.toml, the nearest one in the
file's folder or above (ruff's way; none are merged):
  [severity]
  toon-smooth = \"warning\"           # error | warning | info
  [[waiver]]
  rules = [\"glossy-single-scatter\"] # or [\"*\"]
  reason = \"the brushed look is signed off\"
  files = [\"props/**/*.blend\"]      # optional: globs relative to the file's folder
  materials = [\"Chrome\"]            # optional: exact material names
docs/AUDIT.md (Waivers and severities) has the whole story.

With --baseline OLD.json, each material is new, worse, better or unchanged beside the
material of its file and name in that report, and a failing material fails the check only
when new or worse (a file error only when the baseline had none for that file).

With a fix (--fix, --fix-dir, --in-place) the exit code counts what is left after the fix,
as ruff's --fix does: a file whose only failure the fix removes exits 0. The reports keep
the verdicts before the fix (and each material's after).";

#[derive(Args, Debug)]
pub struct AuditArgs {
    /// .blend files, or folders searched recursively for them (hidden folders and linked
    /// folders skipped; .blend1 backups ignored).
    #[arg(value_name = "PATH", required = true)]
    pub paths: Vec<PathBuf>,

    /// Allowed brightness above 100 %, and allowed loss against the twin, in percent (plus
    /// three standard errors of render noise).
    #[arg(long, value_parser = parse_tolerance, default_value_t = 100.0 * AuditJudging::default().tolerance)]
    pub tolerance: f64,

    /// Allowed brightness above 100 % of any view-cosine ring, in percent (plus three
    /// standard errors of that ring's render noise).
    #[arg(long, value_parser = parse_tolerance, default_value_t = 100.0 * AuditJudging::default().ring_tolerance)]
    pub ring_tolerance: f64,

    /// The verdicts that fail the check (exit 1), comma-separated: loses, creates, error,
    /// ok [default: loses,creates,error]. A verdict fails only when a finding it rests on
    /// counts (error severity, not waived): see below.
    #[arg(long, value_name = "VERDICT,...", value_delimiter = ',', value_parser = parse_verdict)]
    pub fail_on: Vec<Verdict>,

    /// Run only these rules (comma-separated ids, as ruff's --select): the others are not
    /// looked for, and the conserving twin leaves their nodes as they are [default: all].
    #[arg(long, value_name = "RULE-ID,...", value_delimiter = ',')]
    pub select: Vec<String>,

    /// Do not run these rules (comma-separated ids, as ruff's --ignore): their findings are
    /// not reported and their nodes are left alone by the twin and the fix.
    #[arg(long, value_name = "RULE-ID,...", value_delimiter = ',')]
    pub ignore: Vec<String>,

    /// Disregard the files' own gloffuse_ignore properties (a file's author then cannot
    /// waive its findings; gloffuse.toml still does), as ruff's --ignore-noqa.
    #[arg(long)]
    pub no_property_waivers: bool,

    /// The rules alone: no furnace render (each material judged by its findings and the
    /// integrator's predictions).
    #[arg(long)]
    pub no_render: bool,

    /// Pixels across each sphere's cell.
    #[arg(long, default_value_t = audit_defaults().settings.cell, value_parser = clap::value_parser!(u32).range(8..=1024))]
    pub resolution: u32,

    /// Samples per pixel (the default keeps a sphere's standard error near 0.2 %).
    #[arg(long, default_value_t = audit_defaults().settings.samples, value_parser = clap::value_parser!(u32).range(1..=65_536))]
    pub spp: u32,

    /// Cycles' random seed (another seed gives the same means with fresh noise).
    #[arg(long, default_value_t = audit_defaults().settings.seed)]
    pub seed: u32,

    /// Write a fixed copy of the one audited file here (flagged lobes replaced by their
    /// conserving twins), then audit the copy: the report shows before and after, and the
    /// exit code what is left after the fix.
    #[arg(long, value_name = "OUT.blend", conflicts_with_all = ["fix_dir", "in_place"])]
    pub fix: Option<PathBuf>,

    /// Write a fixed copy of every audited file into this folder, under its path below the
    /// folder it was found in, then audit the copies.
    #[arg(long, value_name = "DIR", conflicts_with = "in_place")]
    pub fix_dir: Option<PathBuf>,

    /// Fix the audited files themselves (only those with something to replace), each saved
    /// atomically with its previous version kept as FILE.blend1, then audit them again.
    #[arg(long)]
    pub in_place: bool,

    /// Let a fix save a file that a newer Blender wrote (what this Blender does not know is
    /// lost in the saved file).
    #[arg(long)]
    pub allow_downgrade: bool,

    /// Also write report.html (each material as authored, its twin and their difference,
    /// failures first) and report.json into this folder (made if missing; its parent must
    /// exist).
    #[arg(long, value_name = "DIR")]
    pub report: Option<PathBuf>,

    /// Also write the verdict as JUnit XML (one test case per material) for a CI server.
    #[arg(long, value_name = "FILE.xml")]
    pub junit: Option<PathBuf>,

    /// Also write a SARIF 2.1.0 log (every rule, each finding at file ▸ material ▸ node,
    /// waivers as suppressions, each material's baseline state) for a code-scanning service.
    #[arg(long, value_name = "FILE.sarif")]
    pub sarif: Option<PathBuf>,

    /// An earlier report (a report.json, or the JSON this command prints with --json):
    /// fail only on materials that are new or worse than in it.
    #[arg(long, value_name = "OLD.json")]
    pub baseline: Option<PathBuf>,

    /// Audit only part K of N of the files (K from 1 to N), for a farm: every machine
    /// computes the same split, balanced by each file's material count, and `gloffuse report
    /// merge` joins the shards' reports into the one a single run gives.
    #[arg(long, value_name = "K/N", value_parser = parse_shard)]
    pub shard: Option<Shard>,

    /// Exit 0 even when materials fail the check (the verdict stays in the reports): for a
    /// farm task whose failure would keep the merge from running. Bad input and a Blender
    /// that cannot run still exit 2.
    #[arg(long)]
    pub exit_zero: bool,

    #[command(flatten)]
    pub blender: BlenderArgs,

    /// Print the JSON report instead of the table.
    #[arg(long)]
    pub json: bool,
}

impl AuditArgs {
    pub fn options(&self) -> AuditOptions {
        AuditOptions {
            paths: self.paths.clone(),
            render: !self.no_render,
            settings: RenderSettings {
                cell: self.resolution,
                samples: self.spp,
                seed: self.seed,
                ..RenderSettings::default()
            },
            judging: AuditJudging {
                tolerance: self.tolerance / 100.0,
                ring_tolerance: self.ring_tolerance / 100.0,
                fail_on: if self.fail_on.is_empty() {
                    AuditJudging::default().fail_on
                } else {
                    self.fail_on.clone()
                },
            },
            fix: match (&self.fix, &self.fix_dir, self.in_place) {
                (Some(out), _, _) => FixTarget::File(out.clone()),
                (_, Some(dir), _) => FixTarget::Dir(dir.clone()),
                (_, _, true) => FixTarget::InPlace,
                _ => FixTarget::None,
            },
            allow_downgrade: self.allow_downgrade,
            shard: self.shard,
            blender: self.blender.options(self.json),
            select: self.select.clone(),
            ignore: self.ignore.clone(),
            property_waivers: !self.no_property_waivers,
            baseline: self.baseline.clone(),
        }
    }
}
