//! `gloffuse generate`: the node groups as a script, a new .blend, or into an existing .blend.

use serde::Serialize;
use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::time::Duration;

use crate::Error;
use crate::blender::script::{GENERATE_MAIN, GenerateParams, Mode, assemble};
use crate::blender::{
    Blender, BlenderVersion, FindOptions, Run, command_line, find_blender, run_script,
};
use crate::cli::{BlenderArgs, GenerateArgs};
use crate::coefficients::Coefficients;
use crate::output::{check_destination, write_atomic};

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

/// Whether `path` opens like a .blend: `BLENDER` (uncompressed), or the gzip (before 3.0)
/// or zstd (3.0 and later) magic of a compressed one.
fn starts_like_blend(path: &Path) -> bool {
    use std::io::Read;
    let mut head = [0u8; 7];
    std::fs::File::open(path)
        .and_then(|mut f| f.read_exact(&mut head))
        .is_ok_and(|()| {
            head.starts_with(b"BLENDER")
                || head.starts_with(&[0x1f, 0x8b])
                || head.starts_with(&[0x28, 0xb5, 0x2f, 0xfd])
        })
}

/// Why the .blend Blender saved at `path` is unusable, if it is: missing or empty, not a
/// .blend, or (saved uncompressed, as `save_blend` does) without the `ENDB` block that
/// closes every complete .blend in its last 24 or 32 bytes.
fn incomplete_blend(path: &Path) -> Option<String> {
    use std::io::{Read, Seek, SeekFrom};
    let shown = path.display();
    let len = std::fs::metadata(path).map(|m| m.len()).unwrap_or(0);
    if len == 0 {
        return Some(format!("wrote no .blend ({shown} is empty)"));
    }
    if !starts_like_blend(path) {
        return Some(format!(
            "the .blend it wrote is truncated or corrupt ({shown} does not start with a .blend header)"
        ));
    }
    let mut tail = vec![0u8; len.min(64) as usize];
    let compressed = std::fs::File::open(path)
        .and_then(|mut f| {
            let mut head = [0u8; 7];
            f.read_exact(&mut head)?;
            f.seek(SeekFrom::End(-(tail.len() as i64)))?;
            f.read_exact(&mut tail)?;
            Ok(&head != b"BLENDER")
        })
        .unwrap_or(false);
    if !compressed && !tail.windows(4).any(|w| w == b"ENDB") {
        return Some(format!(
            "the .blend it wrote is truncated or corrupt ({shown} lacks the ENDB block that ends a .blend)"
        ));
    }
    None
}

pub fn generate(g: &GenerateArgs) -> Result<Generated, Error> {
    if g.script.is_none() && g.blend.is_none() && g.into.is_none() {
        return Err(Error::input(
            "arguments",
            "(no output)",
            "--script OUT.py, --blend OUT.blend or --into EXISTING.blend",
        ));
    }
    if let Some(into) = &g.into {
        let expected = if !into.is_file() {
            Some("an existing .blend file")
        } else if !starts_like_blend(into) {
            Some("an existing .blend file (this file does not start with a .blend header)")
        } else {
            None
        };
        if let Some(expected) = expected {
            return Err(Error::input(
                "--into",
                &into.display().to_string(),
                expected,
            ));
        }
    }
    // Outputs are checked before Blender is looked for: bad input fails fast.
    for out in [&g.blend, &g.script].into_iter().flatten() {
        check_destination(out)?;
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
    let mut params = GenerateParams::new(&coefficients, &source);
    if g.mode.iter().any(|m| *m != Mode::Roughness) {
        params = params.with_view(version.masking());
    }
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
            .flat_map(|s| {
                let mut names = vec![s.correction_group.clone(), s.shader_group.clone()];
                if let Some(v) = &s.view {
                    names.extend([
                        v.correction_group.clone(),
                        v.shader_group.clone(),
                        v.multiscatter_group.clone(),
                    ]);
                }
                names
            })
            .collect(),
        log: None,
    };
    let Some(blender) = blender else {
        if let Some(path) = &g.script {
            write_atomic(path, script.as_bytes())?;
            out.script = Some(path.clone());
        }
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
    let run = Run {
        blender: &blender,
        script: &script_path,
        args,
        timeout: Duration::from_secs(g.blender.timeout),
        log: log.clone(),
    };
    run_script(&run)?;
    if let Some(why) = incomplete_blend(&tmp) {
        return Err(Error::Blender {
            message: format!("Blender reported success but {why}"),
            log: Some(log),
            command: Some(command_line(&run)),
        });
    }
    // Only now, with the .blend made, the script: a failed run leaves no output at all.
    if let Some(path) = &g.script {
        write_atomic(path, script.as_bytes())?;
        out.script = Some(path.clone());
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
