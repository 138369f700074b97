//! The audit's fixes (`--fix`, `--fix-dir`, `--in-place`): their destinations checked
//! before any render, the chosen materials rewritten into a copy that is audited again, and
//! the copy installed (the input itself replaced through `user_blend`).

use std::path::{Path, PathBuf};

use super::job::{FixItem, FixOutput, JobSettings};
use super::rules::Predictor;
use super::twins::{TwinGroups, run_twinned};
use super::waivers::Policy;
use super::{
    After, AuditOptions, AuditedFile, AuditedMaterial, FixTarget, Fixed, judge, judged, read_grids,
};
use crate::blender::Blender;
use crate::file_lock::Wait;
use crate::output::temp_beside;
use crate::user_blend::{LockedBlend, UserBlend};
use crate::{Error, Field, Hint};

/// The fix's destinations, checked against the files found before any render.
pub(super) fn check_fix_targets(o: &AuditOptions, files: &[PathBuf]) -> Result<(), Error> {
    check_fix_inputs(o, files)?;
    check_fix_dir_names(o, files)?;
    check_fix_not_input(o, files)
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
pub(super) struct FixPlan {
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
pub(super) fn fix_targets(
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

/// Where one file's fix goes, made ready before Blender reads the file: the input locked
/// (in place) or the copy's folder made, and the temporary file Blender saves into.
pub(super) struct Destination<'a> {
    plan: &'a FixPlan,
    target: Installing<'a>,
    temp: tempfile::TempPath,
}

impl<'a> Destination<'a> {
    pub(super) fn prepare(plan: &'a FixPlan, wait: &Wait) -> Result<Destination<'a>, Error> {
        let (target, temp) = match plan {
            FixPlan {
                input,
                dest: None,
                began,
            } => {
                let locked = input.lock(wait, *began)?;
                let temp = locked.temp()?;
                (Installing::InPlace(locked), temp)
            }
            FixPlan {
                dest: Some(dest), ..
            } => {
                if let Some(dir) = dest.parent() {
                    std::fs::create_dir_all(dir).map_err(|e| Error::Write {
                        path: dir.to_path_buf(),
                        message: e.to_string(),
                    })?;
                }
                (Installing::Copy(dest), temp_beside(dest, ".blend")?)
            }
        };
        Ok(Destination { plan, target, temp })
    }
}

/// The judged file (`audited`: its entry and materials) fixed into `destination`, the fix
/// audited again and installed; returns the path installed, if any.
#[allow(clippy::too_many_arguments)]
pub(super) fn fix_file(
    s: &JobSettings,
    twins: &mut TwinGroups,
    real: &Path,
    destination: Destination,
    o: &AuditOptions,
    policy: &Policy,
    predictor: &mut Predictor,
    audited: &mut (AuditedFile, Vec<AuditedMaterial>),
) -> Result<Option<PathBuf>, Error> {
    let Destination { plan, target, temp } = destination;
    let (file_entry, materials) = audited;
    let in_place = matches!(target, Installing::InPlace(_));
    if in_place {
        keep_a_partly_read_file(file_entry, materials);
    }
    let chosen = chosen_fixes(materials);
    if chosen.is_empty() && in_place {
        return Ok(None);
    }
    o.blender.cancel.check()?;
    let fixed = FixOutput {
        path: &temp,
        compress: plan.input.compressed(),
        materials: &chosen,
    };
    let (replaced, after) = fix_and_audit(s, twins, real, fixed, o, policy, predictor)?;
    o.blender.cancel.check()?;
    let Some((mut entry, path)) = install_fix(target, temp, replaced)? else {
        return Ok(None);
    };
    match after {
        Ok(after) => attach_after(materials, after),
        Err(e) => entry.after_error = Some(e),
    }
    file_entry.fixed = Some(entry);
    Ok(Some(path))
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
    policy: &Policy,
    predictor: &mut Predictor,
) -> Result<(usize, Result<Vec<AuditedMaterial>, String>), Error> {
    let job = run_twinned(s, twins, file, Some(fixed))?;
    let replaced = job.result.fixed.as_ref().map_or(0, |f| f.replaced);
    let after = read_grids(&job).and_then(|image| {
        judge::check_grid(&job, image.as_ref(), o.settings.cell)?;
        Ok(judged(fixed.path, &job, image.as_ref(), o, policy, predictor).1)
    });
    Ok((replaced, after.map_err(|e| e.to_string())))
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
                fails: a.fails,
            });
    }
}
