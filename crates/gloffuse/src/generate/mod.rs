//! ③ Generate: the node groups as a Python script, a new .blend, or into an existing .blend.
//! `vocabulary` holds the modes and colour models, `tables` the packed tables the groups
//! read, `names` the groups' public names, `document` the parameter document; `bundle`
//! turns the Blender-side Python package into single-file scripts, `script` assembles a
//! job's script, `blend` checks what Blender wrote.

pub mod blend;
pub mod bundle;
pub mod catalogs;
pub mod document;
pub mod extension;
pub mod names;
pub mod script;
pub mod suits;
pub mod tables;
pub mod vocabulary;

pub use document::{Curves, GenerateParams, GroupSpec};
pub use names::{
    correction_group_name, layered_group_name, multiscatter_group_name, shader_group_name,
};
pub use script::{Job, assemble, assemble_with_main};
pub use vocabulary::{ColorModel, Mode};

use serde::Serialize;
use std::ffi::OsString;
use std::path::{Path, PathBuf};

use crate::blend_file::read_header;
use crate::blender::{
    Blender, BlenderOptions, Run, RunOutput, command_line, find_for_files, run_following_steps,
};
use crate::error::{Error, Field, Hint};
use crate::file_lock::{FileLock, Wait};
use crate::fit::{Coefficients, preset_for};
use crate::measure::{BlenderVersion, Engine, Masking};
use crate::output::{Destination, check_destination, keep_beside, temp_beside, write_output};
use crate::progress::Progress;
use crate::user_blend::{LockedBlend, UserBlend};
use blend::incomplete_blend;
use extension::Packaging;

/// What `generate` writes, and from what.
#[derive(Clone, Debug, PartialEq)]
pub struct GenerateOptions {
    /// A preset or coefficients file (else the preset of the Blender used).
    pub coefficients: Option<String>,
    /// Write the Python script here (needs no Blender).
    pub script: Option<PathBuf>,
    /// Write a new .blend library holding the groups.
    pub blend: Option<PathBuf>,
    /// Add or replace the groups in this existing .blend, in place (keeping a .blend1).
    pub into: Option<PathBuf>,
    /// Let `into` be a file saved by a newer Blender than the one that runs (its newer
    /// data is lost).
    pub allow_downgrade: bool,
    /// Let `blend` replace an existing file that is not a gloffuse library.
    pub force: bool,
    /// Write a Blender extension (.zip) that installs the library as an asset library.
    pub extension: Option<PathBuf>,
    /// Write the same add-on as a classic add-on (.zip) for Blender 3.4 to 4.1.
    pub addon: Option<PathBuf>,
    /// The audit's data the add-on's panel reads (the audit is a later stage: the
    /// caller hands in `gloffuse::audit::catalogue::EXTENSION`); none: its panel has none.
    pub audit_catalogue: Option<extension::AuditCatalogue>,
    /// Which groups to build besides the roughness-only pair.
    pub modes: Vec<Mode>,
    /// The engines to build groups for (empty: Cycles, or the engine of `coefficients`).
    pub engines: Vec<Engine>,
    pub color_model: ColorModel,
    pub blender: BlenderOptions,
}

impl Default for GenerateOptions {
    fn default() -> Self {
        GenerateOptions {
            coefficients: None,
            script: None,
            blend: None,
            into: None,
            allow_downgrade: false,
            force: false,
            extension: None,
            addon: None,
            audit_catalogue: None,
            modes: vec![Mode::Roughness],
            engines: Vec::new(),
            color_model: ColorModel::Exact,
            blender: BlenderOptions::default(),
        }
    }
}

impl GenerateOptions {
    /// The .zip files asked for: how each is packed, where it goes, and its flag.
    fn zips(&self) -> Vec<(Packaging, &PathBuf, Field)> {
        [
            (Packaging::Extension, &self.extension, Field::Extension),
            (Packaging::Addon, &self.addon, Field::Addon),
        ]
        .into_iter()
        .filter_map(|(packaging, zip, field)| Some((packaging, zip.as_ref()?, field)))
        .collect()
    }

    /// Whether a new library is made (a .blend, or one packed into a .zip).
    fn makes_a_library(&self) -> bool {
        self.blend.is_some() || !self.zips().is_empty()
    }
}

/// What `generate` wrote.
#[derive(Debug, Serialize)]
pub struct Generated {
    pub blender: Option<String>,
    pub coefficients: String,
    pub script: Option<PathBuf>,
    pub blend: Option<PathBuf>,
    pub backup: Option<PathBuf>,
    /// The catalog definition file written (merged) beside a new .blend.
    pub catalogs: Option<PathBuf>,
    pub extension: Option<PathBuf>,
    pub addon: Option<PathBuf>,
    /// The Blenders the groups built suit (by the Blender that saved them and the masking
    /// their Cycles corrections fit), when a Blender ran.
    pub suits: Option<String>,
    /// The groups built, as the job reports them when a Blender ran; else every group the
    /// script builds (in Blender 3.0–3.4 it leaves out anisotropic Beckmann).
    pub groups: Vec<String>,
    /// The user's own groups (no gloffuse tag) that had a name gloffuse builds: renamed out
    /// of the way, every material using them still does.
    pub renamed: Vec<RenamedGroup>,
    pub log: Option<PathBuf>,
}

/// A node group of the user's that was in the way, and its new name.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct RenamedGroup {
    pub group: String,
    pub renamed_to: String,
}

/// Refuses what cannot work before anything is looked for or written.
fn check_inputs(g: &GenerateOptions) -> Result<(), Error> {
    if [&g.script, &g.blend, &g.into, &g.extension, &g.addon]
        .iter()
        .all(|o| o.is_none())
    {
        return Err(Error::input(
            Field::Arguments,
            "(no output)",
            Hint::new(
                "{} OUT.py, {} OUT.blend, {} EXISTING.blend, {} OUT.zip or {} OUT.zip",
                [
                    Field::Script,
                    Field::Blend,
                    Field::Into,
                    Field::Extension,
                    Field::Addon,
                ],
            ),
        ));
    }
    if let Some(into) = &g.into {
        let expected = if !into.is_file() {
            Some("an existing .blend file".to_string())
        } else {
            read_header(into)
                .err()
                .map(|why| format!("an existing .blend file (this file {why})"))
        };
        if let Some(expected) = expected {
            return Err(Error::input(
                Field::Into,
                into.display(),
                Hint::text(expected),
            ));
        }
        if g.makes_a_library() {
            return Err(Error::input(
                Field::Into,
                into.display(),
                Hint::new(
                    "{} alone (with {} at most): {}, {} and {} make a new library, {} \
                     changes your file in place",
                    [
                        Field::Into,
                        Field::Script,
                        Field::Blend,
                        Field::Extension,
                        Field::Addon,
                        Field::Into,
                    ],
                ),
            ));
        }
    }
    check_zips(g)?;
    for out in [&g.blend, &g.script, &g.extension, &g.addon]
        .into_iter()
        .flatten()
    {
        check_destination(out)?;
    }
    Ok(())
}

/// Each .zip asked for is named .zip (or is a stream), and the two are not one file.
fn check_zips(g: &GenerateOptions) -> Result<(), Error> {
    for (_, zip, field) in g.zips() {
        let named_zip = zip
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("zip"));
        if !named_zip
            && !matches!(
                check_destination(zip)?,
                Destination::Stream(_) | Destination::Stdout
            )
        {
            return Err(Error::input(
                field,
                zip.display(),
                "a file name ending in .zip (Blender installs add-ons from a .zip)",
            ));
        }
    }
    if g.extension.is_some() && g.extension == g.addon {
        return Err(Error::input(
            Field::Addon,
            g.addon.as_ref().unwrap().display(),
            Hint::new("a file other than the {}", [Field::Extension]),
        ));
    }
    Ok(())
}

/// The engines to build groups for: as asked, else Cycles, or the engine the pinned
/// coefficients were fitted for (which must be the only one asked for).
fn engines_of(
    g: &GenerateOptions,
    pinned: Option<(&Coefficients, &str)>,
) -> Result<Vec<Engine>, Error> {
    let Some((coefficients, name)) = pinned else {
        return Ok(if g.engines.is_empty() {
            vec![Engine::Cycles]
        } else {
            g.engines.clone()
        });
    };
    let engine = coefficients.engine();
    if g.engines.is_empty() || g.engines == [engine] {
        return Ok(vec![engine]);
    }
    let asked: Vec<&str> = g.engines.iter().map(|e| e.key()).collect();
    Err(Error::input(
        Field::Engine,
        asked.join(","),
        Hint::new(
            format!(
                "{} alone: the coefficients '{name}' correct {}'s Glossy (leave out {{}} to \
                 build every engine's groups from the presets)",
                engine.key(),
                engine.label()
            ),
            [Field::Coefficients],
        ),
    ))
}

/// Writes what `g` asks for; nothing is written if anything fails.
pub fn generate(g: &GenerateOptions, progress: &dyn Progress) -> Result<Generated, Error> {
    let began = std::time::SystemTime::now();
    // Inputs and coefficients are checked before Blender is looked for: bad input fails fast.
    check_inputs(g)?;
    check_library(g)?;
    let pinned = pinned_coefficients(g)?;
    let engines = engines_of(g, pinned.as_ref().map(|(c, name)| (c, *name)))?;
    let blender = blender_for(g, progress)?;
    if g.modes.contains(&Mode::Anisotropic) {
        progress.notice(
            "computing E(μ, φ, αx, αy) for the anisotropic groups, 65,536 albedos per distribution \
             and masking family",
        );
    }
    let mut params = script_params(g, pinned.as_ref(), &engines)?;
    let catalogs = merge_catalogs(g, &mut params)?;
    let script = assemble(&params, Job::Generate);
    let mut out = Generated {
        blender: blender.as_ref().map(|b| b.version_string.clone()),
        coefficients: coefficients_label(pinned.as_ref(), &engines, blender.as_ref()),
        script: None,
        blend: None,
        backup: None,
        catalogs: None,
        extension: None,
        addon: None,
        suits: (blender.as_ref())
            .map(|b| suits::library(pinned.as_ref().map(|p| p.1), &engines, b.version)),
        groups: params.group_names(),
        renamed: Vec::new(),
        log: None,
    };
    let Some(blender) = blender else {
        write_script(g, &script, &mut out)?;
        return Ok(out);
    };
    // The user's file is checked against the Blender found before that Blender starts.
    let user_blend = g
        .into
        .as_deref()
        .map(|into| UserBlend::open(into, Field::Into, blender.version, g.allow_downgrade))
        .transpose()?;
    // From here files are made beside the user's: a stop waits for the next check, which
    // removes them (see `Cancel::hold`).
    let _hold = g.blender.cancel.hold();
    let (locked, _library_lock) = writers_locks(g, user_blend, began, progress)?;
    let built = run_blender(g, &blender, &script, locked.as_ref(), progress)?;
    out.log = Some(built.log.clone());
    out.renamed = built.renamed.clone();
    if let Some(groups) = &built.groups {
        out.groups = groups.clone();
    }
    // Everything is made before anything is written: a failed run leaves no output at all,
    // and the catalog file is staged (under its lock) before the library is replaced.
    let packages = package_zips(g, &built, &params, &blender)?;
    let catalogs = catalogs
        .map(|file| catalogs::stage(&file, &params.catalogs))
        .transpose()?;
    write_script(g, &script, &mut out)?;
    write_zips(&packages, &mut out)?;
    g.blender.cancel.check()?;
    // The library and its catalogs change together or not at all: the library's previous
    // version is kept until the catalog file is in place, and put back if it cannot be.
    let previous = install_blend(built, locked, &mut out)?;
    if let Some(staged) = catalogs {
        match staged.commit() {
            Ok(file) => out.catalogs = Some(file),
            Err(e) => {
                return Err(match previous.map(Previous::restore).transpose() {
                    Ok(_) => e,
                    Err(restore) => restore,
                });
            }
        }
    }
    Ok(out)
}

/// The lock of every file `g` replaces, taken before Blender reads it (waiting, and saying
/// so, while another gloffuse writes it): the user's file (`into`, checked again under the
/// lock), or the library `blend` replaces.
fn writers_locks(
    g: &GenerateOptions,
    user_blend: Option<UserBlend>,
    began: std::time::SystemTime,
    progress: &dyn Progress,
) -> Result<(Option<LockedBlend>, Option<FileLock>), Error> {
    let wait = Wait {
        limit: None,
        cancel: &g.blender.cancel,
        progress: Some(progress),
    };
    if let Some(user_blend) = user_blend {
        return Ok((Some(user_blend.lock(&wait, began)?), None));
    }
    let library = match g.blend.as_deref().map(check_destination).transpose()? {
        Some(Destination::File(real)) => Some(FileLock::take(&real, &wait)?),
        _ => None,
    };
    Ok((None, library))
}

/// The coefficients `g` pins, with the name they were given by.
fn pinned_coefficients(g: &GenerateOptions) -> Result<Option<(Coefficients, &str)>, Error> {
    g.coefficients
        .as_deref()
        .map(|name| Coefficients::load(name).map(|c| (c, name)))
        .transpose()
}

/// The Blender to run when a .blend or an extension is asked for (a script needs none);
/// it must be able to build an extension if one is asked for, and should be as new as the
/// file to update (else saving it would lose what that Blender does not know).
fn blender_for(g: &GenerateOptions, progress: &dyn Progress) -> Result<Option<Blender>, Error> {
    let needs_blender = g.into.is_some() || g.makes_a_library();
    if !needs_blender {
        return Ok(None);
    }
    // An extension needs 4.2+: an older Blender on PATH is passed over, not refused.
    let need = g.extension.is_some().then_some(extension::NEED);
    let into: Vec<PathBuf> = g.into.iter().cloned().collect();
    Ok(Some(find_for_files(
        &g.blender,
        &into,
        Field::Into,
        need,
        progress,
    )?))
}

/// The script's parameters: the pinned coefficients' curves or every engine's presets;
/// previews only for a new library (.blend or extension).
fn script_params(
    g: &GenerateOptions,
    pinned: Option<&(Coefficients, &str)>,
    engines: &[Engine],
) -> Result<GenerateParams, Error> {
    // The script carries both masking families and picks the one of the Blender it runs
    // in, so one script serves every version.
    let curves = match pinned {
        Some((coefficients, name)) => Curves::Pinned { coefficients, name },
        None => Curves::Presets(engines),
    };
    let mut params = GenerateParams::new(curves, &Masking::ALL, &g.modes, g.color_model)?;
    params.previews = g.makes_a_library();
    Ok(params)
}

/// A new .blend gets the catalogs of the definition file beside it (the user's own catalog
/// for one of our paths wins): checks the file and its destination, merges its catalogs
/// into `params` and returns the file, to re-read, merge and write once the .blend is made
/// ([`catalogs::stage`]). `--into` keeps the user's file as it is apart from the groups, and
/// a script leaves both to the Blender it runs in.
fn merge_catalogs(
    g: &GenerateOptions,
    params: &mut GenerateParams,
) -> Result<Option<PathBuf>, Error> {
    let Some(file) = (match &g.blend {
        Some(blend) => catalogs_beside(blend)?,
        None => None,
    }) else {
        return Ok(None);
    };
    if let Destination::Stream(_) | Destination::Stdout = check_destination(&file)? {
        return Err(Error::Write {
            path: file,
            message: "the asset catalog definition file must be a regular file".to_string(),
        });
    }
    let existing = catalogs::read(&file)?;
    params.catalogs = params.catalogs.merge(existing.as_deref()).0;
    Ok(Some(file))
}

/// Refuses, before Blender runs, a `blend` destination that exists but is no .blend at all
/// (unless `force`); whether a .blend is a gloffuse library is checked in the Blender run.
fn check_library(g: &GenerateOptions) -> Result<(), Error> {
    let Some(blend) = &g.blend else {
        return Ok(());
    };
    if g.force || !blend.is_file() || read_header(blend).is_ok() {
        return Ok(());
    }
    Err(not_a_library(blend, "it is not a .blend file"))
}

/// The refusal of a `blend` destination that is not a gloffuse library.
fn not_a_library(blend: &std::path::Path, why: &str) -> Error {
    Error::input(
        Field::Blend,
        blend.display(),
        Hint::new(
            format!(
                "a new file or a gloffuse library to replace ({why}); to replace it anyway, \
                 add {{}}"
            ),
            [Field::Force],
        ),
    )
}

/// The coefficients the groups use, as [`Generated`] names them: the pinned ones, else
/// each engine's preset (for Cycles without a Blender, both it may pick).
fn coefficients_label(
    pinned: Option<&(Coefficients, &str)>,
    engines: &[Engine],
    blender: Option<&Blender>,
) -> String {
    if let Some((_, name)) = pinned {
        return name.to_string();
    }
    engines
        .iter()
        .map(|&engine| match (engine, blender) {
            (Engine::Eevee, _) => preset_for(engine, BlenderVersion::OLDEST).to_string(),
            (Engine::Cycles, Some(b)) => preset_for(engine, b.version).to_string(),
            (Engine::Cycles, None) => format!(
                "{} or {}, for the Blender the script runs in",
                preset_for(engine, BlenderVersion::OLDEST),
                preset_for(engine, BlenderVersion::HEIGHT_CORRELATED_FROM)
            ),
        })
        .collect::<Vec<_>>()
        .join("; ")
}

/// Writes the script if one is asked for.
fn write_script(g: &GenerateOptions, script: &str, out: &mut Generated) -> Result<(), Error> {
    if let Some(path) = &g.script {
        write_output(path, script.as_bytes())?;
        out.script = Some(path.clone());
    }
    Ok(())
}

/// What a Blender run made: the saved .blend under a temporary name, and where it goes.
struct Built {
    /// The .blend Blender saved, beside its destination or in the run folder.
    tmp: tempfile::TempPath,
    /// The new library or the file changed in place, if any (an extension alone has none).
    dest: Option<PathBuf>,
    target: Destination,
    log: PathBuf,
    renamed: Vec<RenamedGroup>,
    /// The groups the job built, as it says (a script builds some groups only in some
    /// Blenders: anisotropic Beckmann from 3.5).
    groups: Option<Vec<String>>,
}

/// Runs the script in `blender`, saving the .blend under a temporary name, and checks that
/// Blender wrote a whole .blend. The user's file (`--into`) is opened where it really is and
/// saved beside it, compressed as it was.
fn run_blender(
    g: &GenerateOptions,
    blender: &Blender,
    script: &str,
    user_blend: Option<&LockedBlend>,
    progress: &dyn Progress,
) -> Result<Built, Error> {
    let run_dir = crate::blender::runs::new_run_dir("generate")?;
    let script_path = run_dir.join("gloffuse-generate.py");
    write_output(&script_path, script.as_bytes())?;
    // Blender saves beside the file it replaces (relative paths in the .blend stay
    // right), or, for a stream or an extension alone, in the run folder.
    let dest = g.blend.clone().or_else(|| g.into.clone());
    let target = match &dest {
        Some(dest) => check_destination(dest)?,
        None => Destination::Stream(run_dir.join(extension::LIBRARY_FILE)),
    };
    let tmp = match (&target, user_blend) {
        (_, Some(user_blend)) => user_blend.temp()?,
        (Destination::File(real), None) => temp_beside(real, ".blend")?,
        (Destination::Stream(_) | Destination::Stdout, None) => {
            temp_beside(&run_dir.join("out"), ".blend")?
        }
    };
    let mut args: Vec<OsString> = Vec::new();
    if let Some(user_blend) = user_blend {
        args.extend([
            OsString::from("--open"),
            user_blend.blend.real.clone().into_os_string(),
        ]);
        if user_blend.blend.compressed() {
            args.push(OsString::from("--compress"));
        }
    }
    args.extend(library_args(g, &target));
    args.extend([OsString::from("--save"), tmp.to_path_buf().into_os_string()]);
    let log = run_dir.join("blender.log");
    let run = Run {
        blender,
        script: &script_path,
        args,
        timeout: g.blender.timeout,
        cancel: g.blender.cancel.clone(),
        log: log.clone(),
    };
    // A run stopped while Blender saved leaves its partial `NAME@` beside the temp name.
    let output = run_following(&run, progress).inspect_err(|_| remove_partial_save(&tmp))?;
    let renamed = job_report(g, &output.result)?;
    let groups = output.result["groups"].as_array().map(|names| {
        names
            .iter()
            .filter_map(|n| n.as_str().map(str::to_string))
            .collect()
    });
    if let Some(why) = incomplete_blend(&tmp) {
        return Err(Error::Blender {
            message: format!("Blender reported success but {why}").into(),
            log: Some(log),
            command: Some(command_line(&run)),
        });
    }
    Ok(Built {
        tmp,
        dest,
        target,
        log,
        renamed,
        groups,
    })
}

/// Runs the generate job while `progress` follows the steps it says it begins (each
/// distribution's groups, each preview, the save).
fn run_following(run: &Run, progress: &dyn Progress) -> Result<RunOutput, Error> {
    let version = &run.blender.version_string;
    let mut begun = false;
    let outcome = run_following_steps(run, &mut |step| {
        if !begun {
            progress.begin(&format!("Blender {version}"), step.total);
            begun = true;
        }
        progress.set(step.done);
        progress.doing(&format!("Blender {version}: {}", step.what));
    });
    progress.end();
    outcome
}

/// Removes what Blender writes before renaming it to `saved` (`saved@`), if it is there.
fn remove_partial_save(saved: &Path) {
    let mut partial = saved.as_os_str().to_owned();
    partial.push("@");
    let _ = std::fs::remove_file(partial);
}

/// The job's check of the library a `blend` replaces: the existing file, unless `force`.
fn library_args(g: &GenerateOptions, target: &Destination) -> Vec<OsString> {
    match (&g.blend, target) {
        (Some(_), Destination::File(real)) if real.is_file() && !g.force => {
            vec![OsString::from("--replace-library"), real.clone().into()]
        }
        _ => Vec::new(),
    }
}

/// What the job's result says beyond success: a refused library (an input error), and the
/// user's groups it renamed.
fn job_report(g: &GenerateOptions, result: &serde_json::Value) -> Result<Vec<RenamedGroup>, Error> {
    if let (Some(why), Some(blend)) = (result["refused"].as_str(), &g.blend) {
        return Err(not_a_library(blend, why));
    }
    let renamed = result["renamed"]
        .as_array()
        .map(Vec::as_slice)
        .unwrap_or(&[]);
    Ok(renamed
        .iter()
        .filter_map(|pair| {
            Some(RenamedGroup {
                group: pair[0].as_str()?.to_string(),
                renamed_to: pair[1].as_str()?.to_string(),
            })
        })
        .collect())
}

/// The .zip files asked for, in memory, with where each goes: the saved .blend and its
/// catalogs packed as an extension or a classic add-on.
fn package_zips(
    g: &GenerateOptions,
    built: &Built,
    params: &GenerateParams,
    blender: &Blender,
) -> Result<Vec<(Packaging, PathBuf, Vec<u8>)>, Error> {
    let zips = g.zips();
    if zips.is_empty() {
        return Ok(Vec::new());
    }
    let blend = std::fs::read(&built.tmp).map_err(|source| Error::Read {
        path: built.tmp.to_path_buf(),
        source,
    })?;
    let catalogs = params.catalogs.definition_file();
    zips.into_iter()
        .map(|(packaging, zip, _)| {
            let bytes = extension::package(
                packaging,
                &blend,
                &catalogs,
                blender.version,
                g.audit_catalogue,
            )?;
            Ok((packaging, zip.clone(), bytes))
        })
        .collect()
}

/// Writes the packed .zip files and says where.
fn write_zips(
    packages: &[(Packaging, PathBuf, Vec<u8>)],
    out: &mut Generated,
) -> Result<(), Error> {
    for (packaging, zip, bytes) in packages {
        write_output(zip, bytes)?;
        match packaging {
            Packaging::Extension => out.extension = Some(zip.clone()),
            Packaging::Addon => out.addon = Some(zip.clone()),
        }
    }
    Ok(())
}

/// Puts the saved .blend in its destination, if it has one: the user's file replaced the
/// safe way (its previous version kept as .blend1), a new file renamed into place, or the
/// bytes copied to a stream. A file replaced in place returns what it replaced, so that
/// the caller can put it back (until dropped).
fn install_blend(
    built: Built,
    user_blend: Option<LockedBlend>,
    out: &mut Generated,
) -> Result<Option<Previous>, Error> {
    let Built {
        tmp, dest, target, ..
    } = built;
    let Some(dest) = dest else {
        return Ok(None);
    };
    if let Some(user_blend) = user_blend {
        out.backup = Some(user_blend.install(tmp)?);
        out.blend = Some(dest);
        return Ok(None);
    }
    let previous = match &target {
        Destination::File(real) => {
            let previous = Previous::keep(real)?;
            tmp.persist(real).map_err(|e| Error::Write {
                path: dest.clone(),
                message: e.error.to_string(),
            })?;
            Some(previous)
        }
        Destination::Stream(_) | Destination::Stdout => {
            let bytes = std::fs::read(&tmp).map_err(|source| Error::Read {
                path: tmp.to_path_buf(),
                source,
            })?;
            write_output(&dest, &bytes)?;
            None
        }
    };
    out.blend = Some(dest);
    Ok(previous)
}

/// A file about to be replaced, kept under a temporary name beside it (a hard link: the
/// very bytes) until dropped, so that [`Previous::restore`] can undo the replacement.
struct Previous {
    real: PathBuf,
    /// `None`: there was no file.
    link: Option<tempfile::TempPath>,
}

impl Previous {
    fn keep(real: &Path) -> Result<Previous, Error> {
        if !real.exists() {
            return Ok(Previous {
                real: real.to_path_buf(),
                link: None,
            });
        }
        let link = keep_beside(real, ".blend").map_err(|e| Error::Write {
            path: real.to_path_buf(),
            message: format!("cannot keep the previous version while it is replaced: {e}"),
        })?;
        Ok(Previous {
            real: real.to_path_buf(),
            link: Some(link),
        })
    }

    /// Puts the previous version back (or removes the new file, where there was none).
    fn restore(self) -> Result<(), Error> {
        let fail = |e: std::io::Error| Error::Write {
            path: self.real.clone(),
            message: format!("cannot put the previous version back: {e}"),
        };
        match self.link {
            Some(link) => link
                .persist(&self.real)
                .map(drop)
                .map_err(|e| fail(e.error)),
            None => std::fs::remove_file(&self.real).map_err(fail),
        }
    }
}

/// Where the catalog definition file of the library `blend` lives: beside the file it
/// really is (through a symlink); none for a stream, which has no folder.
fn catalogs_beside(blend: &std::path::Path) -> Result<Option<PathBuf>, Error> {
    Ok(match check_destination(blend)? {
        Destination::File(real) => {
            let folder = real.parent().unwrap_or(std::path::Path::new("."));
            Some(folder.join(catalogs::FILE_NAME))
        }
        Destination::Stream(_) | Destination::Stdout => None,
    })
}
