//! `gloffuse generate`: the node groups as a script, a new .blend, or into an existing .blend.

use serde::Serialize;
use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::time::Duration;

use crate::Error;
use crate::blender::script::{GENERATE_MAIN, GenerateParams, assemble};
use crate::blender::{Blender, BlenderVersion, FindOptions, Run, find_blender, run_script};
use crate::cli::{BlenderArgs, GenerateArgs};
use crate::coefficients::Coefficients;
use crate::output::write_atomic;

#[derive(Debug, Serialize)]
pub struct Generated {
    pub blender: Option<String>,
    pub coefficients: String,
    pub script: Option<PathBuf>,
    pub blend: Option<PathBuf>,
    pub backup: Option<PathBuf>,
    pub groups: Vec<String>,
    pub log: Option<PathBuf>,
}

/// Finds Blender as the flags say, printing which one is used.
pub fn blender_from(args: &BlenderArgs, quiet: bool) -> Result<Blender, Error> {
    let b = find_blender(&FindOptions {
        explicit: args.blender.clone(),
        allow_provision: !args.no_provision,
        quiet,
    })?;
    eprintln!("gloffuse: using {}", b.describe());
    Ok(b)
}

/// A temporary file next to `dest`, removed on drop unless persisted.
fn temp_beside(dest: &Path, suffix: &str) -> Result<tempfile::TempPath, Error> {
    let dir = match dest.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    if !dir.is_dir() {
        return Err(Error::Write {
            path: dest.to_path_buf(),
            message: format!("the directory {} does not exist", dir.display()),
        });
    }
    tempfile::Builder::new()
        .prefix(".gloffuse-")
        .suffix(suffix)
        .tempfile_in(dir)
        .map(|f| f.into_temp_path())
        .map_err(|e| Error::Write {
            path: dest.to_path_buf(),
            message: e.to_string(),
        })
}

pub fn generate(g: &GenerateArgs) -> Result<Generated, Error> {
    if g.script.is_none() && g.blend.is_none() && g.into.is_none() {
        return Err(Error::input(
            "arguments",
            "(no output)",
            "--script OUT.py, --blend OUT.blend or --into EXISTING.blend",
        ));
    }
    if let Some(into) = &g.into
        && !into.is_file()
    {
        return Err(Error::input(
            "--into",
            &into.display().to_string(),
            "an existing .blend file",
        ));
    }
    for out in [&g.blend, &g.script].into_iter().flatten() {
        if out.is_dir() {
            return Err(Error::Write {
                path: out.clone(),
                message: "it is a directory; give a file name".into(),
            });
        }
    }
    let needs_blender = g.blend.is_some() || g.into.is_some();
    // Coefficients are checked before Blender is looked for: bad input fails fast.
    let explicit = g
        .coefficients
        .as_ref()
        .map(|c| Coefficients::load(c))
        .transpose()?;
    let blender = if needs_blender {
        Some(blender_from(&g.blender, false)?)
    } else {
        None
    };
    let version: BlenderVersion = blender
        .as_ref()
        .map(|b| b.version)
        .unwrap_or(g.blender_version);
    let (coefficients, source) = match (explicit, &g.coefficients) {
        (Some(c), Some(name)) => (c, name.clone()),
        _ => (
            Coefficients::load(version.preset_name())?,
            version.preset_name().to_string(),
        ),
    };
    let params = GenerateParams::new(&coefficients, &source);
    let script = assemble(&params, GENERATE_MAIN);
    let mut out = Generated {
        blender: blender.as_ref().map(|b| b.version_string.clone()),
        coefficients: source,
        script: None,
        blend: None,
        backup: None,
        groups: params
            .groups
            .iter()
            .flat_map(|s| [s.correction_group.clone(), s.shader_group.clone()])
            .collect(),
        log: None,
    };
    if let Some(path) = &g.script {
        write_atomic(path, script.as_bytes())?;
        out.script = Some(path.clone());
    }
    let Some(blender) = blender else {
        return Ok(out);
    };

    let run_dir = crate::blender::runs::new_run_dir("generate")?;
    let script_path = run_dir.join("gloffuse-generate.py");
    write_atomic(&script_path, script.as_bytes())?;
    let dest = g
        .blend
        .clone()
        .or_else(|| g.into.clone())
        .expect("needs_blender");
    let tmp = temp_beside(&dest, ".blend")?;
    let mut args: Vec<OsString> = Vec::new();
    if let Some(into) = &g.into {
        args.extend([OsString::from("--open"), into.clone().into_os_string()]);
    }
    args.extend([OsString::from("--save"), tmp.to_path_buf().into_os_string()]);
    let log = run_dir.join("blender.log");
    run_script(&Run {
        blender: &blender,
        script: &script_path,
        args,
        timeout: Duration::from_secs(g.blender.timeout),
        log: log.clone(),
    })?;
    if std::fs::metadata(&tmp).map(|m| m.len()).unwrap_or(0) == 0 {
        return Err(Error::Blender {
            message: "Blender reported success but wrote no .blend".into(),
            log: Some(log),
            command: None,
        });
    }
    if g.into.is_some() {
        // Blender's own convention: the previous version stays beside the file as .blend1.
        let mut backup = dest.clone().into_os_string();
        backup.push("1");
        let backup = PathBuf::from(backup);
        std::fs::copy(&dest, &backup).map_err(|e| Error::Write {
            path: backup.clone(),
            message: e.to_string(),
        })?;
        out.backup = Some(backup);
    }
    tmp.persist(&dest).map_err(|e| Error::Write {
        path: dest.clone(),
        message: e.error.to_string(),
    })?;
    out.blend = Some(dest);
    out.log = Some(log);
    Ok(out)
}
