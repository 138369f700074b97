//! Finding a Blender to run: a `blender` executable, or a Python interpreter that imports
//! `bpy` (Blender as a Python module), and, when there is none, installing bpy 4.5 LTS into
//! a per-user cache.
//!
//! Search order ([`find_blender`]): `--blender PATH`, then `$GLOFFUSE_BLENDER`, then
//! `blender` on `PATH`, then the bpy venv provisioned earlier in
//! `$XDG_CACHE_HOME/gloffuse/bpy-4.5` (else `~/.cache/gloffuse/bpy-4.5`), then — if allowed —
//! provisioning that venv. A path the user named (flag or variable) is used or refused,
//! never silently passed over.

use std::ffi::OsString;
use std::fs::File;
use std::os::fd::AsFd;
use std::os::unix::fs::PermissionsExt;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Duration;

use super::run::{Exit, run_logged, shell_join};
use super::version::BlenderVersion;
use crate::Error;

/// The environment variable that names a Blender (like `--blender`).
pub const ENV_VAR: &str = "GLOFFUSE_BLENDER";

/// The bpy series gloffuse provisions, and the pip requirement that selects it.
pub const BPY_SERIES: &str = "4.5";
pub const BPY_REQUIREMENT: &str = "bpy>=4.5,<4.6";

/// How long a version probe may take (a cold Blender start on a slow disk can take a while).
pub const PROBE_TIMEOUT: Duration = Duration::from_secs(60);

/// Printed by the bpy probe in front of `bpy.app.version_string`.
const BPY_MARKER: &str = "GLOFFUSE_BPY_VERSION ";

/// How a Blender is run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BlenderKind {
    /// A `blender` executable: `blender -b … --python SCRIPT -- ARGS`.
    Binary,
    /// A Python interpreter that imports `bpy`: `python SCRIPT ARGS`.
    PythonModule,
}

/// A working Blender, 3.0 or later.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Blender {
    pub kind: BlenderKind,
    pub program: PathBuf,
    pub version: BlenderVersion,
    /// As Blender reports it, e.g. `4.5.4 LTS` or `3.4.1`.
    pub version_string: String,
}

impl Blender {
    /// E.g. `Blender 4.5.4 LTS (bpy module, /opt/bpy45/bin/python)`.
    pub fn describe(&self) -> String {
        let kind = match self.kind {
            BlenderKind::Binary => "executable",
            BlenderKind::PythonModule => "bpy module",
        };
        format!(
            "Blender {} ({kind}, {})",
            self.version_string,
            self.program.display()
        )
    }
}

#[derive(Clone, Debug, Default)]
pub struct FindOptions {
    /// From `--blender PATH`: a blender executable, or a Python that imports bpy.
    pub explicit: Option<PathBuf>,
    /// Install bpy into the cache when nothing else is found (off with `--no-provision`).
    pub allow_provision: bool,
    /// No notice and no pip progress on stderr while provisioning.
    pub quiet: bool,
}

/// The parts of the process environment that discovery reads, so that the search can be
/// tested (and reasoned about) without touching the real environment.
#[derive(Clone, Debug, Default)]
pub struct Environment {
    /// `$GLOFFUSE_BLENDER`.
    pub gloffuse_blender: Option<OsString>,
    pub path: Option<OsString>,
    pub xdg_cache_home: Option<OsString>,
    pub home: Option<OsString>,
}

impl Environment {
    pub fn from_process() -> Self {
        Environment {
            gloffuse_blender: std::env::var_os(ENV_VAR),
            path: std::env::var_os("PATH"),
            xdg_cache_home: std::env::var_os("XDG_CACHE_HOME"),
            home: std::env::var_os("HOME"),
        }
    }
}

/// gloffuse's per-user cache: `$XDG_CACHE_HOME/gloffuse`, else `$HOME/.cache/gloffuse`
/// (a relative `XDG_CACHE_HOME` is ignored, as the XDG spec says).
pub fn cache_dir(env: &Environment) -> Option<PathBuf> {
    let set = |v: &Option<OsString>| {
        v.as_ref()
            .filter(|v| Path::new(v).is_absolute())
            .map(PathBuf::from)
    };
    set(&env.xdg_cache_home)
        .or_else(|| set(&env.home).map(|h| h.join(".cache")))
        .map(|c| c.join("gloffuse"))
}

/// Where the bpy venv lives (or would be provisioned): `cache_dir/bpy-4.5`.
pub fn bpy_venv_dir(env: &Environment) -> Option<PathBuf> {
    cache_dir(env).map(|c| c.join(format!("bpy-{BPY_SERIES}")))
}

/// A venv's interpreter.
pub fn venv_python(venv: &Path) -> PathBuf {
    venv.join("bin").join("python")
}

/// Where a candidate came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Source {
    /// `--blender PATH`.
    Explicit,
    /// `$GLOFFUSE_BLENDER`.
    EnvVar,
    /// `blender` on `PATH`.
    SystemPath,
    /// The provisioned bpy venv.
    Cache,
}

impl std::fmt::Display for Source {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Source::Explicit => "--blender",
            Source::EnvVar => ENV_VAR,
            Source::SystemPath => "`blender` on PATH",
            Source::Cache => "the bpy cache",
        })
    }
}

/// One step of the search.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Step {
    /// Probe this program; `required`: if it does not work, fail (the user named it)
    /// rather than go on.
    Probe {
        source: Source,
        program: PathBuf,
        kind: Option<BlenderKind>,
        required: bool,
    },
    /// Nothing there: say so in the not-found message.
    Absent { place: String },
    /// Install bpy into this venv directory (if provisioning is allowed).
    Provision { venv: PathBuf },
}

/// The search, in order, as far as it can be decided without running anything.
///
/// `--blender` and `$GLOFFUSE_BLENDER` each end the search: what the user named is used or
/// refused. Otherwise: `blender` on PATH, the cached venv if it exists, else provisioning.
pub fn search_plan(opts: &FindOptions, env: &Environment) -> Vec<Step> {
    if let Some(p) = &opts.explicit {
        return vec![Step::Probe {
            source: Source::Explicit,
            program: p.clone(),
            kind: None,
            required: true,
        }];
    }
    if let Some(p) = env.gloffuse_blender.as_ref().filter(|p| !p.is_empty()) {
        return vec![Step::Probe {
            source: Source::EnvVar,
            program: PathBuf::from(p),
            kind: None,
            required: true,
        }];
    }
    let mut plan = vec![Step::Absent {
        place: format!("{ENV_VAR}: not set"),
    }];
    plan.push(match which("blender", env.path.as_deref()) {
        Some(program) => Step::Probe {
            source: Source::SystemPath,
            program,
            kind: Some(BlenderKind::Binary),
            required: false,
        },
        None => Step::Absent {
            place: "`blender` on PATH: not found".into(),
        },
    });
    match bpy_venv_dir(env) {
        Some(venv) if venv.exists() => plan.push(Step::Probe {
            source: Source::Cache,
            program: venv_python(&venv),
            kind: Some(BlenderKind::PythonModule),
            // A venv there was complete when it was renamed into place; if it no longer
            // works, say so rather than install a second copy over it.
            required: true,
        }),
        Some(venv) => {
            plan.push(Step::Absent {
                place: format!("bpy cache {}: not provisioned", venv.display()),
            });
            plan.push(Step::Provision { venv });
        }
        None => plan.push(Step::Absent {
            place: "bpy cache: none (neither XDG_CACHE_HOME nor HOME is set)".into(),
        }),
    }
    plan
}

/// Finds a Blender, as described in the module docs, in the process's own environment.
pub fn find_blender(opts: &FindOptions) -> Result<Blender, Error> {
    find_blender_in(opts, &Environment::from_process())
}

/// [`find_blender`] in the given environment.
pub fn find_blender_in(opts: &FindOptions, env: &Environment) -> Result<Blender, Error> {
    // Every place looked at, for the not-found message; the candidates that were there but
    // could not be used, for the provisioning notice.
    let mut looked: Vec<String> = Vec::new();
    let mut skipped: Vec<String> = Vec::new();
    for step in search_plan(opts, env) {
        match step {
            Step::Absent { place } => looked.push(place),
            Step::Probe {
                source,
                program,
                kind,
                required,
            } => match probe_as(&program, kind, source) {
                Ok(b) => return Ok(b),
                Err(e) if required => return Err(e),
                Err(e) => {
                    let why = format!("{source} ({}): {e}", program.display());
                    looked.push(why.clone());
                    skipped.push(why);
                }
            },
            Step::Provision { venv } if opts.allow_provision => {
                return provision(&venv, env, opts.quiet, &skipped);
            }
            Step::Provision { .. } => {}
        }
    }
    Err(not_found(&looked))
}

fn not_found(looked: &[String]) -> Error {
    let mut m = String::from("no Blender found. gloffuse looked at:");
    for l in looked {
        m.push_str("\n  - ");
        m.push_str(l);
    }
    m.push_str(&format!(
        "\nPoint it at one with --blender PATH or {ENV_VAR}=PATH (a blender executable, or a \
         Python that imports bpy), install one (apt-get install blender), or drop \
         --no-provision to let gloffuse install bpy {BPY_SERIES} LTS (~370 MB) into its cache."
    ));
    Error::BlenderNotFound(m)
}

/// Probes `program` and says what Blender it is, whichever kind it is.
///
/// Tries it as a `blender` executable (`-b --factory-startup -noaudio --version`), then as a
/// Python that imports bpy (a name starting with `python` is tried that way first). A
/// directory is looked into for `blender` or a venv's `bin/python`.
pub fn probe(program: &Path) -> Result<Blender, Error> {
    probe_as(program, None, Source::Explicit)
}

fn probe_as(program: &Path, kind: Option<BlenderKind>, source: Source) -> Result<Blender, Error> {
    let named =
        |what: &str| Error::BlenderNotFound(format!("{source} {}: {what}", program.display()));
    let program = if program.is_dir() {
        [program.join("blender"), venv_python(program)]
            .into_iter()
            .find(|p| p.is_file())
            .ok_or_else(|| {
                named("is a directory without `blender` or `bin/python` in it; give the blender executable or the Python that imports bpy")
            })?
    } else if program.is_file() {
        program.to_path_buf()
    } else if program.exists() || program.symlink_metadata().is_ok() {
        return Err(named("is not a file (a broken link?)"));
    } else if let Some(found) = program
        .to_str()
        .filter(|s| !s.contains('/'))
        .and_then(|name| which(name, std::env::var_os("PATH").as_deref()))
    {
        // A bare command name (`--blender blender`, `--blender python3`) is looked up on PATH.
        found
    } else {
        return Err(named("no such file (nor a command of that name on PATH)"));
    };
    // Absolute (but with symlinks kept: a venv's python must stay in its venv), so the
    // rerun command printed for a failure works from any directory.
    let program = std::path::absolute(&program).unwrap_or(program);
    let looks_like_python = program
        .file_name()
        .is_some_and(|n| n.to_string_lossy().starts_with("python"));
    let order: &[BlenderKind] = match kind {
        Some(BlenderKind::Binary) => &[BlenderKind::Binary],
        Some(BlenderKind::PythonModule) => &[BlenderKind::PythonModule],
        None if looks_like_python => &[BlenderKind::PythonModule, BlenderKind::Binary],
        None => &[BlenderKind::Binary, BlenderKind::PythonModule],
    };
    let mut tried = Vec::new();
    for &k in order {
        match probe_kind(&program, k)? {
            Probed::Found(b) => return Ok(b),
            Probed::Not(attempt) => {
                // Something that answered like Blender must not then be fed Python code:
                // an old Blender would take `-c CODE` for a file and open its window.
                let blenderish = k == BlenderKind::Binary && attempt.output.contains("Blender");
                tried.push(attempt);
                if blenderish {
                    break;
                }
            }
        }
    }
    let mut m = format!(
        "{source} {} is neither a working Blender ({} or later) nor a Python that imports bpy",
        program.display(),
        BlenderVersion::OLDEST
    );
    for t in &tried {
        m.push_str(&format!("\n  `{}` {}", t.command, t.outcome));
        for line in last_lines(&t.output, 6) {
            m.push_str("\n      ");
            m.push_str(line);
        }
    }
    Err(Error::Blender {
        message: m,
        log: None,
        command: None,
    })
}

struct Attempt {
    command: String,
    outcome: String,
    output: String,
}

enum Probed {
    Found(Blender),
    Not(Attempt),
}

/// Runs one version probe. `Ok(Not)`: it did not answer as this kind. `Err`: it did, but
/// as a Blender older than 3.0.
fn probe_kind(program: &Path, kind: BlenderKind) -> Result<Probed, Error> {
    let mut argv: Vec<OsString> = vec![program.as_os_str().to_owned()];
    match kind {
        BlenderKind::Binary => {
            argv.extend(["-b", "--factory-startup", "-noaudio", "--version"].map(OsString::from))
        }
        BlenderKind::PythonModule => argv.extend(
            [
                "-c",
                &format!("import bpy, sys; print({BPY_MARKER:?} + bpy.app.version_string)"),
            ]
            .map(OsString::from),
        ),
    }
    let command = shell_join(&argv);
    let not = |outcome: String, output: String| {
        Ok(Probed::Not(Attempt {
            command: command.clone(),
            outcome,
            output,
        }))
    };
    let (exit, output) = match run_captured(&argv, PROBE_TIMEOUT) {
        Ok(r) => r,
        Err(e) => return not(format!("could not be run: {e}"), String::new()),
    };
    match exit {
        Exit::TimedOut => {
            return not(
                format!("did not answer within {} s", PROBE_TIMEOUT.as_secs()),
                output,
            );
        }
        Exit::Finished(s) if !s.success() => return not(format!("failed ({s})"), output),
        Exit::Finished(_) => {}
    }
    let reported = match kind {
        BlenderKind::Binary => output
            .lines()
            .find_map(|l| l.trim().strip_prefix("Blender ")),
        BlenderKind::PythonModule => output
            .lines()
            .find_map(|l| l.trim().strip_prefix(BPY_MARKER)),
    };
    let Some(version_string) = reported.map(str::trim) else {
        return not("did not report a Blender version".into(), output);
    };
    let token = version_string.split_whitespace().next().unwrap_or("");
    let version = match token.parse::<BlenderVersion>() {
        Ok(v) => v,
        Err(_) if is_old_version(token) => {
            return Err(Error::Blender {
                message: format!(
                    "{} is Blender {version_string}; gloffuse needs Blender {} or later \
                     (older Glossy BSDFs are not modelled)",
                    program.display(),
                    BlenderVersion::OLDEST
                ),
                log: None,
                command: Some(command),
            });
        }
        Err(_) => {
            return not(
                format!("reported an unrecognised version '{version_string}'"),
                output,
            );
        }
    };
    Ok(Probed::Found(Blender {
        kind,
        program: program.to_path_buf(),
        version,
        version_string: version_string.to_string(),
    }))
}

/// `2.79`, `2.93.1`: a well-formed version below 3.0.
fn is_old_version(token: &str) -> bool {
    let mut parts = token.split('.');
    let major = parts.next().and_then(|p| p.parse::<u32>().ok());
    let minor_ok = parts
        .next()
        .is_some_and(|p| !p.is_empty() && p.chars().take_while(char::is_ascii_digit).count() > 0);
    matches!(major, Some(m) if m < BlenderVersion::OLDEST.major) && minor_ok
}

/// Runs a short command with a timeout and returns its stdout and stderr (together, lossy).
fn run_captured(argv: &[OsString], timeout: Duration) -> std::io::Result<(Exit, String)> {
    let out = tempfile::tempfile()?;
    let exit = run_logged(argv, &out, timeout)?;
    let mut out = out;
    let mut bytes = Vec::new();
    use std::io::{Read, Seek};
    out.rewind()?;
    out.read_to_end(&mut bytes)?;
    Ok((exit, String::from_utf8_lossy(&bytes).into_owned()))
}

fn last_lines(text: &str, n: usize) -> Vec<&str> {
    let lines: Vec<&str> = text.lines().filter(|l| !l.trim().is_empty()).collect();
    lines[lines.len().saturating_sub(n)..].to_vec()
}

/// The first executable file called `name` in the directories of `path`.
pub fn which(name: &str, path: Option<&std::ffi::OsStr>) -> Option<PathBuf> {
    std::env::split_paths(path?)
        .filter(|d| !d.as_os_str().is_empty())
        .map(|d| d.join(name))
        .find(|p| {
            std::fs::metadata(p).is_ok_and(|m| m.is_file() && m.permissions().mode() & 0o111 != 0)
        })
}

/// Installs bpy into `venv`: a venv made in a temporary sibling directory, `pip install`,
/// a probe, and only then a rename into place — an interrupted install leaves only a
/// `.bpy-4.5.partial-*` directory, never a `bpy-4.5` that looks valid.
fn provision(
    venv: &Path,
    env: &Environment,
    quiet: bool,
    skipped: &[String],
) -> Result<Blender, Error> {
    let parent = venv.parent().unwrap_or(Path::new("."));
    let write_err = |path: &Path, e: &dyn std::fmt::Display| Error::Write {
        path: path.to_path_buf(),
        message: e.to_string(),
    };
    // Fail before announcing or creating anything if the install cannot work.
    let python = base_python(env)?;
    std::fs::create_dir_all(parent).map_err(|e| write_err(parent, &e))?;
    if !quiet {
        for s in skipped {
            eprintln!("gloffuse: not using {s}");
        }
        eprintln!(
            "gloffuse: no Blender found; installing bpy {BPY_SERIES} LTS (Blender as a Python \
             module, ~370 MB) into {} — point --blender or {ENV_VAR} at a Blender to skip this",
            venv.display()
        );
    }
    let tmp = tempfile::Builder::new()
        .prefix(&format!(".bpy-{BPY_SERIES}.partial-"))
        .tempdir_in(parent)
        .map_err(|e| write_err(parent, &e))?;
    let log_path = parent.join(format!("bpy-{BPY_SERIES}-install.log"));
    let step = |argv: Vec<OsString>| -> Result<(), Error> {
        let command = shell_join(&argv);
        let mut cmd = Command::new(&argv[0]);
        cmd.args(&argv[1..]).stdin(Stdio::null());
        // pip's progress goes to our stderr, never our stdout (which may carry JSON).
        let (out, log) = if quiet {
            let f = File::create(&log_path).map_err(|e| write_err(&log_path, &e))?;
            (f, Some(log_path.clone()))
        } else {
            let fd = std::io::stderr()
                .as_fd()
                .try_clone_to_owned()
                .map_err(|e| write_err(Path::new("<stderr>"), &e))?;
            (File::from(fd), None)
        };
        let status = cmd
            .stdout(
                out.try_clone()
                    .map_err(|e| write_err(Path::new("<stderr>"), &e))?,
            )
            .stderr(out)
            .status();
        let fail = |what: String| {
            let mut message = format!(
                "installing bpy {BPY_SERIES} into {} failed: {what}",
                venv.display()
            );
            if let Some(l) = &log {
                let text = std::fs::read(l)
                    .map(|b| String::from_utf8_lossy(&b).into_owned())
                    .unwrap_or_default();
                for line in last_lines(&text, 8) {
                    message.push_str("\n    ");
                    message.push_str(line);
                }
            }
            message.push_str(&format!(
                "\n  (bpy {BPY_SERIES} needs CPython 3.11 and network access to PyPI; or point \
                 --blender or {ENV_VAR} at a Blender)"
            ));
            Error::Blender {
                message,
                log: log.clone(),
                command: Some(command.clone()),
            }
        };
        match status {
            Ok(s) if s.success() => Ok(()),
            Ok(s) => Err(fail(format!("{s}"))),
            Err(e) => Err(fail(e.to_string())),
        }
    };
    let mut make_venv: Vec<OsString> = vec![python.into_os_string()];
    make_venv.extend(["-m", "venv"].map(OsString::from));
    make_venv.push(tmp.path().as_os_str().to_owned());
    step(make_venv)?;
    let tmp_python = venv_python(tmp.path());
    let mut pip: Vec<OsString> = vec![tmp_python.clone().into_os_string()];
    pip.extend(
        [
            "-m",
            "pip",
            "install",
            "--disable-pip-version-check",
            "--no-input",
        ]
        .map(OsString::from),
    );
    if quiet {
        pip.push("-q".into());
    }
    pip.push(BPY_REQUIREMENT.into());
    step(pip)?;
    // Check the install before it is given the name that makes it look valid.
    probe_as(&tmp_python, Some(BlenderKind::PythonModule), Source::Cache)?;
    if let Err(e) = std::fs::rename(tmp.path(), venv) {
        // Another gloffuse may have finished first; use its venv (ours is removed on drop).
        if !venv_python(venv).exists() {
            return Err(write_err(venv, &e));
        }
    } else {
        let _ = tmp.keep();
    }
    match probe_as(
        &venv_python(venv),
        Some(BlenderKind::PythonModule),
        Source::Cache,
    ) {
        Ok(b) => Ok(b),
        Err(e) => {
            let _ = std::fs::remove_dir_all(venv);
            Err(e)
        }
    }
}

/// A Python 3.11 to make the venv with (bpy 4.5 wheels are for CPython 3.11 only):
/// `python3.11`, else `python3` if it is 3.11.
fn base_python(env: &Environment) -> Result<PathBuf, Error> {
    let mut seen = Vec::new();
    for name in ["python3.11", "python3"] {
        let Some(p) = which(name, env.path.as_deref()) else {
            continue;
        };
        let argv: Vec<OsString> = vec![
            p.clone().into_os_string(),
            "-c".into(),
            "import sys; print('%d.%d' % sys.version_info[:2])".into(),
        ];
        if let Ok((Exit::Finished(s), out)) = run_captured(&argv, PROBE_TIMEOUT) {
            let v = out
                .lines()
                .map(str::trim)
                .rfind(|l| {
                    l.split('.')
                        .all(|p| !p.is_empty() && p.bytes().all(|b| b.is_ascii_digit()))
                })
                .unwrap_or("?");
            if s.success() && v == "3.11" {
                return Ok(p);
            }
            seen.push(format!("{} is Python {v}", p.display()));
        }
    }
    Err(Error::BlenderNotFound(format!(
        "no Blender found, and bpy {BPY_SERIES} cannot be installed: it needs CPython 3.11 \
         (python3.11 or python3 on PATH){}. Install python3.11, or point --blender or \
         {ENV_VAR} at a Blender (apt-get install blender).",
        if seen.is_empty() {
            String::new()
        } else {
            format!("; found {}", seen.join(", "))
        }
    )))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn old_versions_are_recognised() {
        assert!(is_old_version("2.79"));
        assert!(is_old_version("2.93.1"));
        assert!(!is_old_version("3.4.1"));
        assert!(!is_old_version("2"));
        assert!(!is_old_version("two.79"));
    }
}
