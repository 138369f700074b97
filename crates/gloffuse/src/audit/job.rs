//! One audit job: the parameter document for one .blend, one Blender run, and its result
//! line read back as data. The job (`blender/gloffuse_blender/audit_job.py`) opens the file
//! (never saving it), applies the rules, renders each material and then its conserving
//! twin on the same sphere in the white furnace; asked to fix, it applies the replacements
//! of the materials it is given, saves the copy and audits the copy instead.

use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::time::Duration;

use serde::{Deserialize, Serialize};

use super::rules::{RuleRange, ranges};
use super::twins::TwinNames;
use crate::Error;
use crate::blender::{Blender, BlenderOptions, Run, run_following_render, runs};
use crate::generate::{GenerateParams, Job, assemble};
use crate::measure::BlenderVersion;
use crate::output::write_output;
use crate::verify::RenderSettings;

/// The `audit` section of the job's parameter document.
#[derive(Clone, Debug, Serialize)]
struct AuditSection {
    output: String,
    /// Where the twins' render goes, when any material has a twin.
    twin_output: String,
    render: bool,
    cell: u32,
    samples: u32,
    seed: u32,
    threads: u32,
    radius_fraction: f64,
    rules: Vec<RuleRange>,
    /// The gloffuse groups a twin may use, by mode and Blender distribution enum; the job
    /// asks for the ones it needs (`needs`) when the document holds no groups.
    twin_names: TwinNames,
    /// With a fixed copy to save: the materials to fix.
    fix: Vec<FixItem>,
}

/// One material a fix rewrites: its index in the job's materials, and the scale of an Add
/// Shader that creates energy (1 over its measured brightness), if it has one.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct FixItem {
    pub material: usize,
    pub scale: Option<f64>,
}

/// The job's parameter document: the generate fields (the groups twins may need), flattened,
/// plus `audit`.
#[derive(Serialize)]
pub struct AuditParams<'a> {
    #[serde(flatten)]
    generate: Option<&'a GenerateParams>,
    audit: AuditSection,
}

/// A finding as the job reports it.
#[derive(Clone, Debug, Deserialize)]
pub struct JobFinding {
    pub rule: String,
    pub node: Vec<String>,
    #[serde(default)]
    pub node_type: String,
    #[serde(default)]
    pub detail: serde_json::Value,
    #[serde(default)]
    pub twin: Option<String>,
}

/// A `gloffuse_ignore` property as the job read it, on a material or on a node it uses.
/// Its text is parsed here (waivers.rs), never in the job.
#[derive(Clone, Debug, Deserialize)]
pub struct JobWaiver {
    /// The material's name, or the path from it down to the node (by node names).
    pub node: Vec<String>,
    /// `Material`, or the node's type.
    pub node_type: String,
    /// The property's text; none when it is not text (`type` says what it is).
    pub value: Option<String>,
    /// The property's Python type (`str`, `int`, `IDPropertyGroup`, …).
    #[serde(rename = "type")]
    pub value_type: String,
}

/// A material as the job reports it.
#[derive(Clone, Debug, Deserialize)]
pub struct JobMaterial {
    pub name: String,
    #[serde(default)]
    pub library: Option<String>,
    #[serde(default)]
    pub cell: Option<usize>,
    #[serde(default)]
    pub twin_cell: Option<usize>,
    #[serde(default)]
    pub replaced: usize,
    #[serde(default)]
    pub findings: Vec<JobFinding>,
    #[serde(default)]
    pub error: Option<String>,
    /// Its `gloffuse_ignore` properties and its nodes'.
    #[serde(default)]
    pub waivers: Vec<JobWaiver>,
}

#[derive(Clone, Debug, Deserialize)]
pub struct JobFixed {
    pub path: String,
    pub replaced: usize,
}

/// The job's result line.
#[derive(Clone, Debug, Deserialize)]
pub struct JobResult {
    #[serde(default)]
    pub output: Option<String>,
    /// The twins' render, when any material has a twin: its cells follow the materials'.
    #[serde(default)]
    pub twin_output: Option<String>,
    #[serde(default)]
    pub columns: Option<usize>,
    #[serde(default)]
    pub render_seconds: Option<f64>,
    #[serde(default)]
    pub scan_seconds: Option<f64>,
    #[serde(default)]
    pub file_findings: Vec<JobFinding>,
    pub materials: Vec<JobMaterial>,
    #[serde(default)]
    pub fixed: Option<JobFixed>,
    /// The gloffuse groups the twins need, as (mode, distribution enum), when the document
    /// held none: the job then stopped after its scan.
    #[serde(default)]
    pub needs: Vec<(String, String)>,
}

/// What one job run needs besides the file.
#[derive(Clone, Copy)]
pub struct JobSettings<'a> {
    pub blender: &'a Blender,
    pub options: &'a BlenderOptions,
    /// The twins' gloffuse groups, once a job has asked for them.
    pub groups: Option<&'a GenerateParams>,
    pub render: Option<RenderSettings>,
    /// About how many materials the file holds (for the timeout).
    pub materials: usize,
    /// Told the fraction of the render done (by Cycles' estimate) while it runs.
    pub on_fraction: &'a (dyn Fn(f64) + Sync),
    /// Rules that do not run (`--select`, `--ignore`): left out of the document.
    pub skip: &'a [String],
}

/// A finished job: its result, its log, and the EXRs when it rendered (the materials', and
/// the twins' when any has one).
pub struct JobRun {
    pub result: JobResult,
    pub log: PathBuf,
    pub exr: Option<PathBuf>,
    pub twin_exr: Option<PathBuf>,
}

/// Each material's share of an audit job's time limit: five times what bpy 4.5 took at
/// the default settings on two shared cores (2,000 materials, scan, twins and furnace, in
/// 13 minutes: 0.4 s each).
const SECONDS_PER_MATERIAL: u64 = 2;

/// The time limit of an audit job on a file of `materials` materials: the Blender options'
/// timeout (what a start and a few materials need) plus [`SECONDS_PER_MATERIAL`] each, so
/// a file of thousands of materials gets the time its materials take.
fn job_timeout(timeout: Duration, materials: usize) -> Duration {
    let materials = u64::try_from(materials).unwrap_or(u64::MAX);
    timeout.saturating_add(Duration::from_secs(
        SECONDS_PER_MATERIAL.saturating_mul(materials),
    ))
}

/// Where a job saves its fixed copy, and what it fixes.
#[derive(Clone, Copy)]
pub struct FixOutput<'a> {
    pub path: &'a Path,
    /// Saved compressed (as the input was).
    pub compress: bool,
    pub materials: &'a [FixItem],
}

/// Runs the audit job on `file` (its real path); with `fix`, the job applies the fixes,
/// saves the copy there and audits the copy. The two paths are the job's arguments, not in
/// the document: they reach Blender byte for byte, UTF-8 or not.
pub fn run_job(s: &JobSettings, file: &Path, fix: Option<FixOutput>) -> Result<JobRun, Error> {
    let run_dir = runs::new_run_dir("audit")?;
    let exr = run_dir.join("audit.exr");
    let twin_exr = run_dir.join("audit-twins.exr");
    let materials = fix.as_ref().map_or(&[][..], |f| f.materials);
    let mut params = document(
        s.blender.version,
        s.groups,
        s.render,
        &exr,
        &twin_exr,
        materials,
    );
    params
        .audit
        .rules
        .retain(|r| !s.skip.iter().any(|id| id == r.id));
    let script = run_dir.join("gloffuse-audit.py");
    write_output(&script, assemble(&params, Job::Audit).as_bytes())?;
    let log = run_dir.join("blender.log");
    let run = Run {
        blender: s.blender,
        script: &script,
        args: job_args(file, fix),
        timeout: job_timeout(s.options.timeout, s.materials),
        cancel: s.options.cancel.clone(),
        log: log.clone(),
    };
    let out = run_following_render(&run, &|e| (s.on_fraction)(e.done))?;
    let result: JobResult = serde_json::from_value(out.result).map_err(|e| Error::Blender {
        message: format!("the audit job's result line is not what gloffuse expects ({e})").into(),
        log: Some(log.clone()),
        command: None,
    })?;
    let exr = (s.render.is_some() && result.output.is_some()).then_some(exr);
    let twin_exr = exr
        .as_ref()
        .and(result.twin_output.as_ref())
        .map(|_| twin_exr);
    Ok(JobRun {
        result,
        log,
        exr,
        twin_exr,
    })
}

/// The job's parameter document: the groups twins may use (when they were asked for), the
/// render settings (none: scan only), where the two renders go, and the materials to fix.
pub fn document<'a>(
    version: BlenderVersion,
    groups: Option<&'a GenerateParams>,
    render: Option<RenderSettings>,
    exr: &Path,
    twin_exr: &Path,
    fix: &[FixItem],
) -> AuditParams<'a> {
    let settings = render.unwrap_or_default();
    let section = AuditSection {
        output: exr.to_string_lossy().into_owned(),
        twin_output: twin_exr.to_string_lossy().into_owned(),
        render: render.is_some(),
        cell: settings.cell,
        samples: settings.samples,
        seed: settings.seed,
        threads: 0,
        radius_fraction: settings.radius_fraction,
        rules: ranges(),
        twin_names: TwinNames::new(version),
        fix: fix.to_vec(),
    };
    AuditParams {
        generate: groups,
        audit: section,
    }
}

/// The job's arguments: the file, and where its fixed copy goes.
fn job_args(file: &Path, fix: Option<FixOutput>) -> Vec<OsString> {
    let mut args = vec![OsString::from("--open"), file.as_os_str().to_owned()];
    if let Some(fix) = fix {
        args.extend([OsString::from("--save"), fix.path.as_os_str().to_owned()]);
        if fix.compress {
            args.push(OsString::from("--compress"));
        }
    }
    args
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_time_limit_grows_with_the_materials() {
        let base = Duration::from_secs(600);
        assert_eq!(job_timeout(base, 0), base);
        assert_eq!(
            job_timeout(base, 2000),
            base + Duration::from_secs(2000 * SECONDS_PER_MATERIAL)
        );
        assert!(job_timeout(base, 2000) > job_timeout(base, 10));
        assert_eq!(job_timeout(Duration::MAX, usize::MAX), Duration::MAX);
    }
}
