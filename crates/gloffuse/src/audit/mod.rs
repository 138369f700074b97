//! ⑤ Audit: the user's own materials. For every material of every .blend given, the rules
//! (nodes Cycles leaves uncompensated in that Blender, nodes that create energy), then a
//! white-furnace render of the material as authored beside its conserving twin, one Blender
//! process per file; optionally a fixed copy (or the file itself, through the one safe
//! path, `user_blend`), audited again. Files are streamed: each file's grid is handed to the
//! caller and dropped before the next file starts.

pub mod baseline;
pub mod catalogue;
pub mod config;
pub mod files;
mod fix;
pub mod fix_choice;
pub mod job;
pub mod judge;
pub mod merge;
pub mod rules;
mod shard_cost;
mod twins;
pub mod verdict;
pub mod waivers;

pub use baseline::{Baseline, BaselineState, BaselineSummary};
pub use verdict::{
    After, AuditJudging, AuditReport, AuditSettings, AuditedFile, AuditedMaterial, Counts, Finding,
    Fixed, ShardInput, ShardRun, Verdict, Waived,
};

use std::path::{Path, PathBuf};

use crate::blend_file::read_header;
use crate::blend_file::{MATERIAL, count_blocks};
use crate::blender::{Blender, BlenderOptions, find_for_files};
use crate::file_lock::Wait;
use crate::measure::BlenderVersion;
use crate::output::check_destination;
use crate::plural::count;
use crate::progress::Progress;
use crate::shard::Shard;
use crate::verify::RenderSettings;
use crate::verify::image::{Rgba, read_rgba};
use crate::{Error, Field, Hint};
use config::Configs;
use fix::{Destination, FixPlan, check_fix_targets, fix_file, fix_targets};
use job::{JobRun, JobSettings};
use judge::{Grid, judge_material};
use rules::{Predictor, RULES, known_ids, rule};
use twins::{TwinGroups, run_twinned};
use waivers::Policy;

/// Where fixed files go.
#[derive(Clone, Debug, Default, PartialEq)]
pub enum FixTarget {
    #[default]
    None,
    /// One input's fixed copy.
    File(PathBuf),
    /// Every input's fixed copy, under its path relative to the folder it was found in.
    Dir(PathBuf),
    /// The inputs themselves (each keeps its previous version as `FILE.blend1`).
    InPlace,
}

#[derive(Clone, Debug, PartialEq)]
pub struct AuditOptions {
    pub paths: Vec<PathBuf>,
    /// Render the furnace (else rules only).
    pub render: bool,
    pub settings: RenderSettings,
    pub judging: AuditJudging,
    pub fix: FixTarget,
    pub allow_downgrade: bool,
    /// Audit only this part of the files (the same split on every machine).
    pub shard: Option<Shard>,
    pub blender: BlenderOptions,
    /// The only rules that run (empty: every rule), as ruff's `--select`.
    pub select: Vec<String>,
    /// Rules that do not run, as ruff's `--ignore`.
    pub ignore: Vec<String>,
    /// Whether the files' own `gloffuse_ignore` properties waive findings (as ruff's
    /// `--ignore-noqa` turned around: false disregards them; gloffuse.toml still counts).
    pub property_waivers: bool,
    /// An earlier report: the check then fails only on what is new or worse than in it.
    pub baseline: Option<PathBuf>,
}

impl Default for AuditOptions {
    fn default() -> Self {
        AuditOptions {
            paths: Vec::new(),
            render: true,
            settings: RenderSettings::default(),
            judging: AuditJudging::default(),
            fix: FixTarget::None,
            allow_downgrade: false,
            shard: None,
            blender: BlenderOptions::default(),
            baseline: None,
            select: Vec::new(),
            ignore: Vec::new(),
            property_waivers: true,
        }
    }
}

impl AuditOptions {
    /// The catalogue's rules that do not run: those not selected, and those ignored.
    pub fn skipped_rules(&self) -> Vec<String> {
        RULES
            .iter()
            .map(|r| r.id)
            .filter(|id| {
                (!self.select.is_empty() && !self.select.iter().any(|s| s == id))
                    || self.ignore.iter().any(|s| s == id)
            })
            .map(String::from)
            .collect()
    }
}

/// One audited file, as handed to the caller while the audit goes on: its grid is only
/// alive for the call.
pub struct FileDone<'a> {
    pub file: &'a AuditedFile,
    pub materials: &'a [AuditedMaterial],
    pub image: Option<&'a Rgba>,
}

/// Audits every material of the .blend files under `o.paths`; `on_file` sees each file as it
/// is done (the report's pictures are made there, so grids never pile up in memory).
pub fn audit(
    o: &AuditOptions,
    progress: &dyn Progress,
    on_file: &mut dyn FnMut(FileDone) -> Result<(), Error>,
) -> Result<AuditReport, Error> {
    // Bad input (a bad gloffuse.toml or baseline too) fails before Blender is looked for.
    let mut inputs = checked_inputs(o)?;
    let blender = find_for_files(&o.blender, &inputs.files, Field::AuditPath, None, progress)?;
    audit_files(&blender, o, &mut inputs, progress, on_file)
}

/// [`audit`] with a Blender already found.
pub fn audit_with(
    blender: &Blender,
    o: &AuditOptions,
    progress: &dyn Progress,
    on_file: &mut dyn FnMut(FileDone) -> Result<(), Error>,
) -> Result<AuditReport, Error> {
    let mut inputs = checked_inputs(o)?;
    audit_files(blender, o, &mut inputs, progress, on_file)
}

/// What the options name, each read and checked before any Blender runs.
struct Inputs {
    files: Vec<PathBuf>,
    /// The configurations that hold the files.
    configs: Configs,
    baseline: Option<Baseline>,
}

fn checked_inputs(o: &AuditOptions) -> Result<Inputs, Error> {
    check(o)?;
    let files = files::blend_files(&o.paths)?;
    check_fix_targets(o, &files)?;
    let mut configs = Configs::default();
    for file in &files {
        configs.for_file(file)?;
    }
    let baseline = o.baseline.as_deref().map(Baseline::read).transpose()?;
    Ok(Inputs {
        files,
        configs,
        baseline,
    })
}

fn audit_files(
    blender: &Blender,
    o: &AuditOptions,
    inputs: &mut Inputs,
    progress: &dyn Progress,
    on_file: &mut dyn FnMut(FileDone) -> Result<(), Error>,
) -> Result<AuditReport, Error> {
    let mut report = empty_report(o, blender);
    let (files, counts) = files_to_audit(o, &inputs.files, &mut report);
    let configs = &mut inputs.configs;
    let fix_targets = fix_targets(o, &files, blender);
    let mut twins = TwinGroups::new(blender);
    let mut predictor = Predictor::new(blender.version);
    begin(progress, &counts, blender);
    // Fixes make files beside the user's and replace them: a stop waits for the next check
    // (between files, before a replacement), and then says what was written.
    let _hold = o.blender.cancel.hold();
    let mut written: Vec<PathBuf> = Vec::new();
    let stopped = |e: Error, before: &[PathBuf]| match e {
        Error::Interrupted { log, written } => Error::Interrupted {
            log,
            written: [before, &written].concat(),
        },
        other => other,
    };
    let mut done = 0u64;
    let skip = o.skipped_rules();
    let invalid_waiver_runs = !skip.iter().any(|id| id == "invalid-waiver");
    for ((file, materials), fix) in files.iter().zip(&counts).zip(fix_targets) {
        let policy = Policy::new(configs.for_file(file)?, file, invalid_waiver_runs)
            .with_properties(o.property_waivers);
        let settings = JobSettings {
            skip: &skip,
            blender,
            options: &o.blender,
            groups: None,
            render: o.render.then_some(o.settings),
            materials: *materials,
            on_fraction: &|f: f64| progress.set(done + (f.min(1.0) * *materials as f64) as u64),
        };
        let step = o.blender.cancel.check().and_then(|()| {
            let audited = audit_one(
                &settings,
                &mut twins,
                file,
                fix,
                o,
                &policy,
                &mut predictor,
                progress,
            )?;
            written.extend(audited.3.clone());
            on_file(FileDone {
                file: &audited.0,
                materials: &audited.1,
                image: audited.2.as_ref(),
            })?;
            Ok(audited)
        });
        let (audited_file, materials_done, _, _) = match step {
            Ok(audited) => audited,
            Err(e) => {
                progress.end();
                return Err(stopped(e, &written));
            }
        };
        report.files.push(audited_file);
        report.materials.extend(materials_done);
        done += *materials as u64;
        progress.set(done);
    }
    progress.end();
    if let Some(baseline) = &inputs.baseline {
        baseline.apply(&mut report);
    }
    report.finish();
    Ok(report)
}

/// The progress begun: the materials of every file to audit.
fn begin(progress: &dyn Progress, counts: &[usize], blender: &Blender) {
    let total: usize = counts.iter().sum();
    progress.begin(
        &format!(
            "auditing {} in {} with Blender {}",
            count(total, "material", "materials"),
            count(counts.len(), "file", "files"),
            blender.version_string
        ),
        total as u64,
    );
}

/// The files this run audits (its shard's, when sharded) and their material counts; a
/// shard's place in the whole run goes into `report`.
fn files_to_audit(
    o: &AuditOptions,
    files: &[PathBuf],
    report: &mut AuditReport,
) -> (Vec<PathBuf>, Vec<usize>) {
    let counts: Vec<usize> = files
        .iter()
        .map(|f| count_blocks(f, MATERIAL).unwrap_or(1))
        .collect();
    match o.shard {
        None => (files.to_vec(), counts),
        Some(shard) => {
            report.shard = Some(shard_cost::shard_run(shard, files, &counts));
            shard_cost::shard_part(shard, files, counts)
        }
    }
}

/// One file audited, and when asked its fix made, audited and installed. An error of the
/// file's own becomes its entry; a stop (`Error::Interrupted`) is returned.
#[allow(clippy::too_many_arguments)]
fn audit_one(
    settings: &JobSettings,
    twins: &mut TwinGroups,
    file: &Path,
    fix: Result<Option<FixPlan>, Error>,
    o: &AuditOptions,
    policy: &Policy,
    predictor: &mut Predictor,
    progress: &dyn Progress,
) -> Result<FileAudit, Error> {
    let audited = fix.and_then(|fix| {
        let fix = fix.as_ref();
        audit_file(settings, twins, file, fix, o, policy, predictor, progress)
    });
    match audited {
        Err(e @ Error::Interrupted { .. }) => Err(e),
        Err(e) => Ok((
            failed_file(file, &e, settings.blender.version),
            Vec::new(),
            None,
            None,
        )),
        Ok(ok) => Ok(ok),
    }
}

/// The report before any file: how the audit runs and judges.
fn empty_report(o: &AuditOptions, blender: &Blender) -> AuditReport {
    AuditReport {
        gloffuse_version: env!("CARGO_PKG_VERSION").to_string(),
        blender_version: blender.version_string.clone(),
        blender_program: blender.program.display().to_string(),
        baseline: None,
        settings: AuditSettings {
            cell: o.settings.cell,
            samples: o.settings.samples,
            seed: o.settings.seed,
            render: o.render,
            tolerance: o.judging.tolerance,
            ring_tolerance: o.judging.ring_tolerance,
            fail_on: o.judging.fail_on.clone(),
            skipped_rules: o.skipped_rules(),
            property_waivers: o.property_waivers,
            fix: o.fix != FixTarget::None,
        },
        shard: None,
        passed: false,
        passed_after_fix: None,
        counts: Counts::default(),
        files: Vec::new(),
        materials: Vec::new(),
    }
}

fn check(o: &AuditOptions) -> Result<(), Error> {
    for (value, what) in [
        (o.judging.tolerance, "tolerance"),
        (o.judging.ring_tolerance, "ring tolerance"),
    ] {
        if !(0.0..1.0).contains(&value) {
            return Err(Error::input(
                Field::Arguments,
                value,
                format!("a {what} from 0 to 100 %"),
            ));
        }
    }
    for (ids, field) in [(&o.select, Field::Select), (&o.ignore, Field::Ignore)] {
        if let Some(id) = ids.iter().find(|id| rule(id).is_none()) {
            return Err(Error::input(
                field,
                id,
                Hint::text(format!("rule ids, comma-separated, from: {}", known_ids())),
            ));
        }
    }
    match &o.fix {
        FixTarget::File(out) => {
            check_destination(out)?;
        }
        FixTarget::Dir(dir) if dir.exists() && !dir.is_dir() => {
            return Err(Error::input(
                Field::FixDir,
                dir.display(),
                "a folder for the fixed copies (it is a file)",
            ));
        }
        _ => {}
    }
    Ok(())
}

/// A file's entry, its materials, its grid, and the path its fix was installed at.
type FileAudit = (
    AuditedFile,
    Vec<AuditedMaterial>,
    Option<Rgba>,
    Option<PathBuf>,
);

#[allow(clippy::too_many_arguments)]
fn audit_file(
    s: &JobSettings,
    twins: &mut TwinGroups,
    file: &Path,
    fix: Option<&FixPlan>,
    o: &AuditOptions,
    policy: &Policy,
    predictor: &mut Predictor,
    progress: &dyn Progress,
) -> Result<FileAudit, Error> {
    let real = blend_to_open(file)?;
    // The file itself is replaced: its writers' lock is held from before Blender reads it
    // until it is replaced.
    let wait = Wait {
        limit: None,
        cancel: &o.blender.cancel,
        progress: Some(progress),
    };
    let destination = fix
        .map(|plan| Destination::prepare(plan, &wait))
        .transpose()?;
    let job = run_twinned(s, twins, &real, None)?;
    let image = read_grids(&job)?;
    judge::check_grid(&job, image.as_ref(), o.settings.cell)?;
    let mut audited = judged(file, &job, image.as_ref(), o, policy, predictor);
    let installed = match destination {
        None => None,
        Some(destination) => fix_file(
            s,
            twins,
            &real,
            destination,
            o,
            policy,
            predictor,
            &mut audited,
        )?,
    };
    let (file_entry, materials) = audited;
    Ok((file_entry, materials, image, installed))
}

/// The file Blender opens for `file` (every link followed). A file that is no .blend (a
/// text file so named) is said so here, not by a Python traceback from Blender.
fn blend_to_open(file: &Path) -> Result<PathBuf, Error> {
    let real = std::fs::canonicalize(file).map_err(|source| Error::Read {
        path: file.to_path_buf(),
        source,
    })?;
    match read_header(&real) {
        Ok(_) => Ok(real),
        Err(why) => Err(Error::input(
            Field::AuditPath,
            file.display(),
            Hint::text(format!("a .blend file (this file {why})")),
        )),
    }
}

/// The job's grid: the materials' render, with the twins' stacked below it when there is
/// one (the job numbers the twins' cells so).
fn read_grids(job: &JobRun) -> Result<Option<Rgba>, Error> {
    let Some(exr) = &job.exr else {
        return Ok(None);
    };
    let mut image = read_grid(exr)?;
    if let Some(twins) = &job.twin_exr {
        let below = read_grid(twins)?;
        if below.width != image.width || below.height != image.height {
            return Err(Error::Blender {
                message: format!(
                    "the twins' render ({} x {} px) is not the size of the materials' ({} x {} \
                     px)",
                    below.width, below.height, image.width, image.height
                )
                .into(),
                log: Some(job.log.clone()),
                command: None,
            });
        }
        image.height += below.height;
        image.pixels.extend(below.pixels);
    }
    Ok(Some(image))
}

fn read_grid(exr: &Path) -> Result<Rgba, Error> {
    read_rgba(exr).map_err(|e| Error::Blender {
        message: format!("{}: {e}", exr.display()).into(),
        log: None,
        command: None,
    })
}

/// The file's entry and its materials' verdicts, their findings counted under `policy`.
fn judged(
    file: &Path,
    job: &JobRun,
    image: Option<&Rgba>,
    o: &AuditOptions,
    policy: &Policy,
    predictor: &mut Predictor,
) -> (AuditedFile, Vec<AuditedMaterial>) {
    let cell = o.settings.cell as usize;
    let columns = job.result.columns.unwrap_or(1).max(1);
    let grid = image.map(|image| Grid {
        image,
        columns,
        cell,
        radius_fraction: o.settings.radius_fraction,
    });
    let name = file.display().to_string();
    let materials = job
        .result
        .materials
        .iter()
        .map(|m| judge_material(&name, m, grid.as_ref(), &o.judging, policy, predictor))
        .collect();
    let mut findings: Vec<_> = job
        .result
        .file_findings
        .iter()
        .map(|f| judge::word(f, predictor))
        .collect();
    policy.file_findings(&mut findings);
    let entry = AuditedFile {
        file: name,
        error_in_baseline: false,
        saved_by: read_header(file)
            .ok()
            .and_then(|h| h.version)
            .map(|v| v.to_string()),
        error: None,
        findings,
        materials: job.result.materials.len(),
        log: Some(job.log.display().to_string()),
        render_seconds: job.result.render_seconds,
        scan_seconds: job.result.scan_seconds,
        grid: image.map(|_| (columns, cell)),
        fixed: None,
    };
    (entry, materials)
}

/// A file that could not be audited, with why. Where a Blender older than the file failed
/// on it (3.4 crashes on 4.x meshes, and reads no 5.x file at all), that is the reason,
/// with the last words Blender said and its log, not its whole output.
fn failed_file(file: &Path, e: &Error, blender: BlenderVersion) -> AuditedFile {
    let saved_by = read_header(file).ok().and_then(|h| h.version);
    let error = match saved_by {
        Some(saved) if saved > blender => too_new(e, saved, blender),
        _ => e.to_string(),
    };
    AuditedFile {
        file: file.display().to_string(),
        saved_by: saved_by.map(|v| v.to_string()),
        error: Some(error),
        error_in_baseline: false,
        findings: Vec::new(),
        materials: 0,
        log: None,
        render_seconds: None,
        scan_seconds: None,
        grid: None,
        fixed: None,
    }
}

/// Why a Blender older than a file failed on it, in a sentence: what to run instead, then
/// Blender's last error line (or how it ended: a crash has none) and its log's path.
fn too_new(e: &Error, saved: BlenderVersion, blender: BlenderVersion) -> String {
    let (message, log) = match e {
        Error::Blender { message, log, .. } => (message.to_string(), log.as_deref()),
        other => (other.to_string(), None),
    };
    let lines: Vec<&str> = message.lines().map(str::trim).collect();
    let ended = lines
        .first()
        .map_or("", |l| l.split(';').next().unwrap_or(l));
    let said = lines
        .iter()
        .rev()
        .find(|l| l.contains("Error"))
        .copied()
        .unwrap_or(ended);
    let mut words = format!(
        "Blender {blender} could not audit this file, saved by the newer Blender {saved}: \
         audit it in Blender {saved} or later ({said})"
    );
    if let Some(log) = log {
        words.push_str(&format!("; log: {}", log.display()));
    }
    words
}
