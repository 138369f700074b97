//! ⑤ Audit: the user's own materials. For every material of every .blend given, the rules
//! (nodes Cycles leaves uncompensated in that Blender, nodes that create energy), then a
//! white-furnace render of the material as authored beside its conserving twin, one Blender
//! process per file; optionally a fixed copy (or the file itself, through the one safe
//! path, `user_blend`), audited again. Files are streamed: each file's grid is handed to the
//! caller and dropped before the next file starts.

pub mod files;
pub mod fix_choice;
pub mod job;
pub mod judge;
pub mod merge;
pub mod rules;
pub mod verdict;

pub use verdict::{
    After, AuditJudging, AuditReport, AuditSettings, AuditedFile, AuditedMaterial, Counts, Finding,
    Fixed, ShardInput, ShardRun, Verdict,
};

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use crate::blend_file::{MATERIAL, count_blocks};
use crate::blender::{Blender, BlenderOptions, find_for_files};
use crate::file_lock::Wait;
use crate::fit::Coefficients;
use crate::generate::{ColorModel, Curves, GenerateParams, Mode};
use crate::measure::{BlenderVersion, Distribution, Engine};
use crate::output::{check_destination, temp_beside};
use crate::plural::count;
use crate::progress::Progress;
use crate::shard::Shard;
use crate::user_blend::{LockedBlend, UserBlend, read_header};
use crate::verify::RenderSettings;
use crate::verify::image::{Rgba, read_rgba};
use crate::{Error, Field, Hint};
use job::{FixItem, FixOutput, JobRun, JobSettings, run_job};
use judge::{Grid, judge_material};
use rules::Predictor;

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
        }
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
    // Bad input fails before Blender is looked for.
    let files = checked_files(o)?;
    let blender = find_for_files(&o.blender, &files, Field::AuditPath, None, progress)?;
    audit_files(&blender, o, &files, progress, on_file)
}

/// [`audit`] with a Blender already found.
pub fn audit_with(
    blender: &Blender,
    o: &AuditOptions,
    progress: &dyn Progress,
    on_file: &mut dyn FnMut(FileDone) -> Result<(), Error>,
) -> Result<AuditReport, Error> {
    audit_files(blender, o, &checked_files(o)?, progress, on_file)
}

/// The options checked, and the files they name.
fn checked_files(o: &AuditOptions) -> Result<Vec<PathBuf>, Error> {
    check(o)?;
    let files = files::blend_files(&o.paths)?;
    check_fix_inputs(o, &files)?;
    check_fix_dir_names(o, &files)?;
    check_fix_not_input(o, &files)?;
    Ok(files)
}

fn audit_files(
    blender: &Blender,
    o: &AuditOptions,
    files: &[PathBuf],
    progress: &dyn Progress,
    on_file: &mut dyn FnMut(FileDone) -> Result<(), Error>,
) -> Result<AuditReport, Error> {
    let mut report = empty_report(o, blender);
    let (files, counts) = files_to_audit(o, files, &mut report);
    let fix_targets = fix_targets(o, &files, blender);
    let mut twins = TwinGroups::new(blender);
    let mut predictor = Predictor::new(blender.version);
    let total: usize = counts.iter().sum();
    progress.begin(
        &format!(
            "auditing {} in {} with Blender {}",
            count(total, "material", "materials"),
            count(files.len(), "file", "files"),
            blender.version_string
        ),
        total as u64,
    );
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
    for ((file, materials), fix) in files.iter().zip(&counts).zip(fix_targets) {
        let settings = JobSettings {
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
    report.finish();
    Ok(report)
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
            report.shard = Some(shard_run(shard, files, &counts));
            shard_part(shard, files, counts)
        }
    }
}

/// One file audited, and when asked its fix made, audited and installed. An error of the
/// file's own becomes its entry; a stop (`Error::Interrupted`) is returned.
fn audit_one(
    settings: &JobSettings,
    twins: &mut TwinGroups,
    file: &Path,
    fix: Result<Option<FixPlan>, Error>,
    o: &AuditOptions,
    predictor: &mut Predictor,
    progress: &dyn Progress,
) -> Result<FileAudit, Error> {
    let audited =
        fix.and_then(|fix| audit_file(settings, twins, file, fix.as_ref(), o, predictor, progress));
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

/// What a Blender start costs, in materials' audit time: the split balances each file's
/// materials plus one start. Measured (docs/FARM.md): 19 materials in Blender 3.4, 7 in
/// bpy 4.5; one constant for every Blender, between the two.
const START_COST: u64 = 12;

/// Each file's cost to the split: its materials and a Blender start.
fn file_costs(materials: &[usize]) -> Vec<u64> {
    materials.iter().map(|&m| m as u64 + START_COST).collect()
}

/// A shard's place in the run: every file of the run, with its material count.
fn shard_run(shard: Shard, files: &[PathBuf], counts: &[usize]) -> ShardRun {
    ShardRun {
        shard,
        inputs: files
            .iter()
            .zip(counts)
            .map(|(f, &materials)| ShardInput {
                file: f.display().to_string(),
                materials,
            })
            .collect(),
    }
}

/// The files (and their material counts) `shard` audits.
fn shard_part(shard: Shard, files: &[PathBuf], counts: Vec<usize>) -> (Vec<PathBuf>, Vec<usize>) {
    let costs = file_costs(&counts);
    files
        .iter()
        .cloned()
        .zip(counts)
        .zip(shard.takes(&costs))
        .filter_map(|(kept, takes)| takes.then_some(kept))
        .unzip()
}

/// The report before any file: how the audit runs and judges.
fn empty_report(o: &AuditOptions, blender: &Blender) -> AuditReport {
    AuditReport {
        gloffuse_version: env!("CARGO_PKG_VERSION").to_string(),
        blender_version: blender.version_string.clone(),
        blender_program: blender.program.display().to_string(),
        settings: AuditSettings {
            cell: o.settings.cell,
            samples: o.settings.samples,
            seed: o.settings.seed,
            render: o.render,
            tolerance: o.judging.tolerance,
            ring_tolerance: o.judging.ring_tolerance,
            fail_on: o.judging.fail_on.clone(),
        },
        shard: None,
        passed: false,
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

/// `--fix OUT` takes one input file.
fn check_fix_inputs(o: &AuditOptions, files: &[PathBuf]) -> Result<(), Error> {
    match &o.fix {
        FixTarget::File(out) if files.len() != 1 => Err(Error::input(
            Field::Fix,
            out.display(),
            Hint::new(
                format!(
                    "one input .blend ({} were found): for several, use {{}}",
                    files.len()
                ),
                [Field::FixDir],
            ),
        )),
        _ => Ok(()),
    }
}

/// `--fix-dir` writes each input under its path relative to the folder it was found in:
/// two inputs that would land on one path (`a/x.blend b/x.blend`) are refused, naming both,
/// rather than one fixed copy silently replacing the other.
fn check_fix_dir_names(o: &AuditOptions, files: &[PathBuf]) -> Result<(), Error> {
    let FixTarget::Dir(dir) = &o.fix else {
        return Ok(());
    };
    let mut seen: std::collections::BTreeMap<PathBuf, &PathBuf> = Default::default();
    for file in files {
        let relative = relative_to_root(file, &o.paths);
        if let Some(first) = seen.insert(relative.clone(), file) {
            return Err(Error::input(
                Field::FixDir,
                dir.display(),
                Hint::text(format!(
                    "a folder where each input's fixed copy has a path of its own: {} and {} \
                     would both be written to {} (audit them in two runs, or name the folders \
                     that hold them so that their paths below those folders differ)",
                    first.display(),
                    file.display(),
                    dir.join(&relative).display()
                )),
            ));
        }
    }
    Ok(())
}

/// A fixed copy never replaces its input (`--fix x.blend` of x.blend, `--fix-dir` of the
/// folder audited): that is `--in-place`, which keeps a backup and takes the file's lock.
fn check_fix_not_input(o: &AuditOptions, files: &[PathBuf]) -> Result<(), Error> {
    let real = |p: &Path| std::fs::canonicalize(p).ok();
    for file in files {
        let (field, given, dest) = match &o.fix {
            FixTarget::File(out) => (Field::Fix, out, out.clone()),
            FixTarget::Dir(dir) => (
                Field::FixDir,
                dir,
                dir.join(relative_to_root(file, &o.paths)),
            ),
            FixTarget::None | FixTarget::InPlace => return Ok(()),
        };
        if real(&dest).is_some_and(|d| real(file) == Some(d)) {
            let expected = match &o.fix {
                // The path goes in as text: a `{}` in a file name is no template.
                FixTarget::Dir(_) => Hint::text(format!(
                    "a folder where no fixed copy is written over its input ({} would be; to \
                     fix the files themselves, use ",
                    file.display()
                ))
                .then(Hint::new("{})", [Field::InPlace])),
                _ => Hint::new(
                    "a path other than the audited file (to fix the file itself, use {})",
                    [Field::InPlace],
                ),
            };
            return Err(Error::input(field, given.display(), expected));
        }
    }
    Ok(())
}

/// How one file's fix is written.
struct FixPlan {
    /// The input, checked (its header: version and compression).
    input: UserBlend,
    /// Where the fixed file goes; `None`: the input itself.
    dest: Option<PathBuf>,
    /// When the audit began: a `.blend1` made since then is another gloffuse's, kept.
    began: std::time::SystemTime,
}

/// Each file's fix plan, checked before any render: no file saved by a newer Blender unless
/// a downgrade is allowed. A file that cannot be fixed is that file's error: the others are
/// audited and fixed all the same.
fn fix_targets(
    o: &AuditOptions,
    files: &[PathBuf],
    blender: &Blender,
) -> Vec<Result<Option<FixPlan>, Error>> {
    let began = std::time::SystemTime::now();
    let field = match &o.fix {
        FixTarget::None => return files.iter().map(|_| Ok(None)).collect(),
        FixTarget::File(_) => Field::Fix,
        FixTarget::Dir(_) => Field::FixDir,
        FixTarget::InPlace => Field::InPlace,
    };
    files
        .iter()
        .map(|file| {
            let input = UserBlend::open(file, field, blender.version, o.allow_downgrade)?;
            let dest = match &o.fix {
                FixTarget::File(out) => Some(out.clone()),
                FixTarget::Dir(dir) => Some(dir.join(relative_to_root(file, &o.paths))),
                _ => None,
            };
            Ok(Some(FixPlan { input, dest, began }))
        })
        .collect()
}

/// `file`'s path below the folder it was found in (its name, when it was named itself).
fn relative_to_root(file: &Path, roots: &[PathBuf]) -> PathBuf {
    roots
        .iter()
        .filter(|r| r.is_dir())
        .find_map(|r| file.strip_prefix(r).ok())
        .map(Path::to_path_buf)
        .unwrap_or_else(|| file.file_name().map(PathBuf::from).unwrap_or_default())
}

/// The gloffuse groups twins use, built on a job's first request and grown to cover every
/// later one: their tables take seconds to compute, so an audit whose materials need none
/// never computes them, and one that does computes only the distributions and modes asked.
struct TwinGroups<'a> {
    blender: &'a Blender,
    needs: BTreeSet<(Mode, Distribution)>,
    params: Option<GenerateParams>,
}

impl<'a> TwinGroups<'a> {
    fn new(blender: &'a Blender) -> Self {
        TwinGroups {
            blender,
            needs: BTreeSet::new(),
            params: None,
        }
    }

    /// Groups covering `needs` (the job's (mode, distribution enum) pairs) and every earlier need.
    fn cover(&mut self, needs: &[(String, String)], log: &Path) -> Result<&GenerateParams, Error> {
        let mut grew = self.params.is_none();
        for (mode, distribution) in needs {
            let need = Mode::ALL
                .into_iter()
                .find(|m| m.key() == mode)
                .zip(distribution.parse::<Distribution>().ok())
                .filter(|(m, _)| matches!(m, Mode::Multiscatter | Mode::Layered))
                .ok_or_else(|| Error::Blender {
                    message: format!("the audit job asked for groups gloffuse does not build ({mode}, {distribution})").into(),
                    log: Some(log.to_path_buf()),
                    command: None,
                })?;
            grew |= self.needs.insert(need);
        }
        if grew {
            let (mut coefficients, source) =
                Coefficients::load_or_preset(None, Engine::Cycles, self.blender.version)?;
            coefficients
                .distributions
                .retain(|d, _| self.needs.iter().any(|(_, n)| n == d));
            let modes: Vec<Mode> = Mode::ALL
                .into_iter()
                .filter(|m| self.needs.iter().any(|(n, _)| n == m))
                .collect();
            self.params = Some(GenerateParams::new(
                Curves::Pinned {
                    coefficients: &coefficients,
                    name: &source,
                },
                &[self.blender.version.masking()],
                &modes,
                ColorModel::Exact,
            )?);
        }
        Ok(self.params.as_ref().expect("built above"))
    }
}

/// Runs the job on `file`, and again with the gloffuse groups its twins asked for.
fn run_twinned(
    s: &JobSettings,
    twins: &mut TwinGroups,
    file: &Path,
    fix: Option<FixOutput>,
) -> Result<JobRun, Error> {
    let first = run_job(
        &JobSettings {
            groups: twins.params.as_ref(),
            ..*s
        },
        file,
        fix,
    )?;
    if first.result.needs.is_empty() {
        return Ok(first);
    }
    let groups = twins.cover(&first.result.needs, &first.log)?;
    let second = run_job(
        &JobSettings {
            groups: Some(groups),
            ..*s
        },
        file,
        fix,
    )?;
    if second.result.needs.is_empty() {
        Ok(second)
    } else {
        Err(Error::Blender {
            message: "the audit job asked again for the groups it was given".into(),
            log: Some(second.log),
            command: None,
        })
    }
}

/// A file's entry, its materials, its grid, and the path its fix was installed at.
type FileAudit = (
    AuditedFile,
    Vec<AuditedMaterial>,
    Option<Rgba>,
    Option<PathBuf>,
);

fn audit_file(
    s: &JobSettings,
    twins: &mut TwinGroups,
    file: &Path,
    fix: Option<&FixPlan>,
    o: &AuditOptions,
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
    let (target, temp) = match fix {
        None => (None, None),
        Some(FixPlan {
            input,
            dest: None,
            began,
        }) => {
            let locked = input.lock(&wait, *began)?;
            let temp = locked.temp()?;
            (Some(Installing::InPlace(locked)), Some(temp))
        }
        Some(FixPlan {
            dest: Some(dest), ..
        }) => {
            if let Some(dir) = dest.parent() {
                std::fs::create_dir_all(dir).map_err(|e| Error::Write {
                    path: dir.to_path_buf(),
                    message: e.to_string(),
                })?;
            }
            (
                Some(Installing::Copy(dest)),
                Some(temp_beside(dest, ".blend")?),
            )
        }
    };
    let job = run_twinned(s, twins, &real, None)?;
    let image = read_grids(&job)?;
    judge::check_grid(&job, image.as_ref(), o.settings.cell)?;
    let (mut file_entry, mut materials) = judged(file, &job, image.as_ref(), o, predictor);
    if matches!(target, Some(Installing::InPlace(_))) {
        keep_a_partly_read_file(&file_entry, &mut materials);
    }
    let mut installed = None;
    if let (Some(target), Some(temp), Some(plan)) = (target, temp, fix) {
        let chosen = chosen_fixes(&materials);
        if chosen.is_empty() && matches!(target, Installing::InPlace(_)) {
            return Ok((file_entry, materials, image, None));
        }
        o.blender.cancel.check()?;
        let fixed = FixOutput {
            path: &temp,
            compress: plan.input.compressed(),
            materials: &chosen,
        };
        let (replaced, after) = fix_and_audit(s, twins, &real, fixed, o, predictor)?;
        o.blender.cancel.check()?;
        if let Some((mut entry, path)) = install_fix(target, temp, replaced)? {
            match after {
                Ok(after) => attach_after(&mut materials, after),
                Err(e) => entry.after_error = Some(e),
            }
            file_entry.fixed = Some(entry);
            installed = Some(path);
        }
    }
    Ok((file_entry, materials, image, installed))
}

/// A file Blender loaded only in part (a `load-warning`) is never saved over: what Blender
/// could not read would be gone from it. Its fixes become reasons.
fn keep_a_partly_read_file(file: &AuditedFile, materials: &mut [AuditedMaterial]) {
    if !file.findings.iter().any(|f| f.rule == "load-warning") {
        return;
    }
    for m in materials.iter_mut().filter(|m| m.fix.is_some()) {
        m.fix = None;
        m.no_fix = Some(
            "not fixed in place: Blender could not read all of this file (load-warning), so \
             saving over it would drop what it could not read; fix it into a copy instead"
                .to_string(),
        );
    }
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

/// The fixes the judged materials call for, in the job's material order.
fn chosen_fixes(materials: &[AuditedMaterial]) -> Vec<FixItem> {
    materials
        .iter()
        .enumerate()
        .filter_map(|(material, m)| {
            m.fix.map(|f| FixItem {
                material,
                scale: f.scale,
            })
        })
        .collect()
}

/// Fixes `file` into `fixed.path` and audits the copy: the lobes replaced, and the copy's
/// materials judged (or why they could not be).
fn fix_and_audit(
    s: &JobSettings,
    twins: &mut TwinGroups,
    file: &Path,
    fixed: FixOutput,
    o: &AuditOptions,
    predictor: &mut Predictor,
) -> Result<(usize, Result<Vec<AuditedMaterial>, String>), Error> {
    let job = run_twinned(s, twins, file, Some(fixed))?;
    let replaced = job.result.fixed.as_ref().map_or(0, |f| f.replaced);
    let after = read_grids(&job).and_then(|image| {
        judge::check_grid(&job, image.as_ref(), o.settings.cell)?;
        Ok(judged(fixed.path, &job, image.as_ref(), o, predictor).1)
    });
    Ok((replaced, after.map_err(|e| e.to_string())))
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

/// The file's entry and its materials' verdicts.
fn judged(
    file: &Path,
    job: &JobRun,
    image: Option<&Rgba>,
    o: &AuditOptions,
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
        .map(|m| judge_material(&name, m, grid.as_ref(), &o.judging, predictor))
        .collect();
    let entry = AuditedFile {
        file: name,
        saved_by: read_header(file)
            .ok()
            .and_then(|h| h.version)
            .map(|v| v.to_string()),
        error: None,
        findings: job
            .result
            .file_findings
            .iter()
            .map(|f| judge::word(f, predictor))
            .collect(),
        materials: job.result.materials.len(),
        log: Some(job.log.display().to_string()),
        render_seconds: job.result.render_seconds,
        scan_seconds: job.result.scan_seconds,
        grid: image.map(|_| (columns, cell)),
        fixed: None,
    };
    (entry, materials)
}

/// Where a fixed file goes.
enum Installing<'a> {
    /// Over the input itself, under its writers' lock.
    InPlace(LockedBlend),
    /// A copy at this path.
    Copy(&'a Path),
}

/// Puts a fixed file in place: a copy renamed to its destination, or the input replaced
/// through `LockedBlend::install` (its previous version kept as `.blend1`). An in-place fix
/// that replaced nothing leaves the file alone. Returns the entry and the path installed.
fn install_fix(
    target: Installing,
    temp: tempfile::TempPath,
    replaced: usize,
) -> Result<Option<(Fixed, PathBuf)>, Error> {
    let (path, backup) = match target {
        Installing::InPlace(_) if replaced == 0 => return Ok(None),
        Installing::InPlace(locked) => {
            let real = locked.blend.real.clone();
            let backup = locked.install(temp)?;
            (real, Some(backup.display().to_string()))
        }
        Installing::Copy(dest) => {
            temp.persist(dest).map_err(|e| Error::Write {
                path: dest.to_path_buf(),
                message: e.error.to_string(),
            })?;
            (dest.to_path_buf(), None)
        }
    };
    let fixed = Fixed {
        path: path.display().to_string(),
        replaced,
        backup,
        after_error: None,
    };
    Ok(Some((fixed, path)))
}

fn attach_after(materials: &mut [AuditedMaterial], after: Vec<AuditedMaterial>) {
    for m in materials {
        m.after = after
            .iter()
            .find(|a| a.material == m.material)
            .map(|a| After {
                rewritten: m.fix.is_some(),
                verdict: a.verdict,
                mean: a.mean,
                findings: a.findings.len(),
            });
    }
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
