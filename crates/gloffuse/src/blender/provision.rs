//! Installing bpy (Blender as a Python module) into the per-user cache when no Blender is
//! found: a venv made under a temporary name, `pip install`, a probe, and only then a rename
//! into place.

use std::ffi::OsString;
use std::fs::File;
use std::os::fd::AsFd;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Instant;

use super::environment::{
    BPY_REQUIREMENT, BPY_SERIES, BPY_SIZE, ENV_VAR, Environment, broken_venv, venv_python, which,
};
use super::probe::{Blender, BlenderKind, PROBE_TIMEOUT, Source, last_lines, probe_as};
use super::process::{Cancel, Exit, run_captured};
use crate::error::{Error, Field, Hint};
use crate::progress::Progress;

/// Where the installer's (venv's and pip's) output goes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum InstallerOutput {
    /// To `bpy-4.5-install.log` beside the venv, quoted in the error if the install fails.
    #[default]
    Log,
    /// To this process's stderr (never stdout, which may carry JSON), so a person sees
    /// pip's own progress.
    Stderr,
}

/// Installs bpy into `venv`: a venv made in a temporary sibling directory, `pip install`,
/// a probe, and only then a rename into place — an interrupted install leaves only a
/// `.bpy-4.5.partial-*` directory, never a `bpy-4.5` that looks valid. `skipped` names
/// the Blenders that were found but could not be used; they are announced through
/// `progress` with the install. `broken` says why the venv already there cannot run: it is
/// moved aside and removed (under the install lock), and the install announced as a repair.
pub(super) fn provision(
    venv: &Path,
    env: &Environment,
    output: InstallerOutput,
    skipped: &[Hint],
    broken: Option<&str>,
    progress: &dyn Progress,
    cancel: &Cancel,
) -> Result<Blender, Error> {
    let parent = venv.parent().unwrap_or(Path::new("."));
    // Fail before announcing or creating anything if the install cannot work.
    let python = base_python(env, cancel)?;
    std::fs::create_dir_all(parent).map_err(|e| write_error(parent, &e))?;
    // One install at a time: a second gloffuse (a parallel CI job sharing the cache)
    // waits for the first, then uses what it installed.
    let _lock = InstallLock::take(&parent.join(format!(".bpy-{BPY_SERIES}.lock")), progress)?;
    // Judged again under the lock: another gloffuse may have repaired it meanwhile.
    let broken = broken.and_then(|_| broken_venv(venv));
    if broken.is_none() && venv_python(venv).exists() {
        return probe_cached(&venv_python(venv), cancel);
    }
    remove_stale_partials(parent);
    if let Some(why) = &broken {
        progress.advise(&Hint::text(format!(
            "the cached bpy {BPY_SERIES} at {} is broken ({why}); reinstalling it",
            venv.display()
        )));
        remove_broken(venv)?;
    }
    announce_install(venv, skipped, progress);
    let tmp = tempfile::Builder::new()
        .prefix(&format!(".bpy-{BPY_SERIES}.partial-"))
        .tempdir_in(parent)
        .map_err(|e| write_error(parent, &e))?;
    let installer = Installer {
        venv,
        log: (output == InstallerOutput::Log)
            .then(|| parent.join(format!("bpy-{BPY_SERIES}-install.log"))),
    };
    installer.run(venv_command(python, tmp.path()))?;
    let tmp_python = venv_python(tmp.path());
    installer.run(pip_command(&tmp_python, installer.log.is_some()))?;
    // Check the install before it is given the name that makes it look valid.
    probe_cached(&tmp_python, cancel)?;
    move_into_place(tmp, venv, cancel)
}

fn write_error(path: &Path, e: &dyn std::fmt::Display) -> Error {
    Error::Write {
        path: path.to_path_buf(),
        message: e.to_string(),
    }
}

/// Probes the bpy of a venv in the cache.
fn probe_cached(python: &Path, cancel: &Cancel) -> Result<Blender, Error> {
    probe_as(
        python,
        Some(BlenderKind::PythonModule),
        Source::Cache,
        Instant::now() + PROBE_TIMEOUT,
        cancel,
    )
}

/// Moves a broken venv aside (so no half-removed venv ever has the valid name) and removes
/// it; a removal cut short leaves a `.bpy-4.5.partial-*` that the next install removes.
fn remove_broken(venv: &Path) -> Result<(), Error> {
    let parent = venv.parent().unwrap_or(Path::new("."));
    let aside = parent.join(format!(
        ".bpy-{BPY_SERIES}.partial-broken-{}",
        std::process::id()
    ));
    std::fs::rename(venv, &aside).map_err(|e| write_error(venv, &e))?;
    // A symlinked venv is only unlinked: what it points at is not gloffuse's to delete.
    let removed = if aside.is_symlink() {
        std::fs::remove_file(&aside)
    } else {
        std::fs::remove_dir_all(&aside)
    };
    removed.map_err(|e| write_error(&aside, &e))
}

/// Says, through `progress`, which Blenders are not used and that bpy is being installed.
fn announce_install(venv: &Path, skipped: &[Hint], progress: &dyn Progress) {
    for s in skipped {
        progress.advise(&Hint::text("not using ").then(s.clone()));
    }
    progress.advise(&Hint::new(
        format!(
            "no Blender found; installing bpy {BPY_SERIES} LTS (Blender as a Python \
             module; {BPY_SIZE}) into {} — point {{}} or {ENV_VAR} at a Blender to skip this",
            venv.display()
        ),
        [Field::Blender],
    ));
}

/// `python -m venv DIR`.
fn venv_command(python: PathBuf, dir: &Path) -> Vec<OsString> {
    let mut argv: Vec<OsString> = vec![python.into_os_string()];
    argv.extend(["-m", "venv"].map(OsString::from));
    argv.push(dir.as_os_str().to_owned());
    argv
}

/// `python -m pip install … [-q] REQUIREMENT` (`-q` when the output goes to the log).
fn pip_command(python: &Path, quiet: bool) -> Vec<OsString> {
    let mut argv: Vec<OsString> = vec![python.as_os_str().to_owned()];
    argv.extend(
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
        argv.push("-q".into());
    }
    argv.push(BPY_REQUIREMENT.into());
    argv
}

/// Renames the checked install in `tmp` to `venv` and probes it there; a venv that does
/// not work under its final name is removed.
fn move_into_place(tmp: tempfile::TempDir, venv: &Path, cancel: &Cancel) -> Result<Blender, Error> {
    if let Err(e) = std::fs::rename(tmp.path(), venv) {
        // Another gloffuse may have finished first; use its venv (ours is removed on drop).
        if !venv_python(venv).exists() {
            return Err(write_error(venv, &e));
        }
    } else {
        let _ = tmp.keep();
    }
    match probe_cached(&venv_python(venv), cancel) {
        Ok(b) => Ok(b),
        Err(e) => {
            let _ = std::fs::remove_dir_all(venv);
            Err(e)
        }
    }
}

/// Runs the install's steps (making the venv, pip) for `venv`.
struct Installer<'a> {
    venv: &'a Path,
    /// The install log the steps write to, quoted in an error; none when their output
    /// goes to stderr ([`InstallerOutput::Stderr`]).
    log: Option<PathBuf>,
}

impl Installer<'_> {
    /// Runs one step, its output to the log (made afresh) or to stderr.
    fn run(&self, argv: Vec<OsString>) -> Result<(), Error> {
        let mut cmd = Command::new(&argv[0]);
        cmd.args(&argv[1..]).stdin(Stdio::null());
        let out = self.output()?;
        let status = cmd
            .stdout(
                out.try_clone()
                    .map_err(|e| write_error(Path::new("<stderr>"), &e))?,
            )
            .stderr(out)
            .status();
        match status {
            Ok(s) if s.success() => Ok(()),
            Ok(s) => Err(self.failure(format!("{s}"))),
            Err(e) => Err(self.failure(e.to_string())),
        }
    }

    /// Where a step's output goes: the log, truncated, or a duplicate of stderr.
    fn output(&self) -> Result<File, Error> {
        match &self.log {
            Some(log) => File::create(log).map_err(|e| write_error(log, &e)),
            None => {
                let fd = std::io::stderr()
                    .as_fd()
                    .try_clone_to_owned()
                    .map_err(|e| write_error(Path::new("<stderr>"), &e))?;
                Ok(File::from(fd))
            }
        }
    }

    /// The error of a step that failed with `what`: the log's last lines, and advice. The
    /// step ran in a temporary venv that is removed as the error returns, so no command of
    /// it is offered to rerun: gloffuse itself is.
    fn failure(&self, what: String) -> Error {
        let mut message = format!(
            "installing bpy {BPY_SERIES} into {} failed: {what}",
            self.venv.display()
        );
        if let Some(l) = &self.log {
            let text = std::fs::read(l)
                .map(|b| String::from_utf8_lossy(&b).into_owned())
                .unwrap_or_default();
            for line in last_lines(&text, 8) {
                message.push_str("\n    ");
                message.push_str(line);
            }
        }
        let advice = Hint::new(
            format!(
                "\n  (the partial install was removed; run this gloffuse command again to \
                 retry. bpy {BPY_SERIES} needs CPython 3.11 and network access to PyPI; or \
                 point {{}} or {ENV_VAR} at a Blender)"
            ),
            [Field::Blender],
        );
        Error::Blender {
            message: Hint::text(message).then(advice),
            log: self.log.clone(),
            command: None,
        }
    }
}

/// An exclusive `flock` on a lock file in the cache, held while this process installs bpy;
/// the kernel releases it when the process ends, however it ends.
struct InstallLock {
    /// Closing it (on drop) releases the lock.
    _file: File,
}

impl InstallLock {
    fn take(path: &Path, progress: &dyn Progress) -> Result<Self, Error> {
        use std::os::fd::AsRawFd;
        let file = File::create(path).map_err(|e| Error::Write {
            path: path.to_path_buf(),
            message: e.to_string(),
        })?;
        let fd = file.as_raw_fd();
        // SAFETY: flock only locks the open file `fd` refers to.
        if unsafe { libc::flock(fd, libc::LOCK_EX | libc::LOCK_NB) } != 0 {
            progress.notice(&format!(
                "another gloffuse is installing bpy {BPY_SERIES} into the cache; waiting for it ({})",
                path.display()
            ));
            // SAFETY: as above; this call blocks until the other process is done.
            if unsafe { libc::flock(fd, libc::LOCK_EX) } != 0 {
                return Err(Error::Write {
                    path: path.to_path_buf(),
                    message: std::io::Error::last_os_error().to_string(),
                });
            }
        }
        Ok(InstallLock { _file: file })
    }
}

/// Removes `.bpy-4.5.partial-*` folders an install left when it was killed: with the
/// install lock held, nobody else is writing one.
fn remove_stale_partials(parent: &Path) {
    let prefix = format!(".bpy-{BPY_SERIES}.partial-");
    let Ok(entries) = std::fs::read_dir(parent) else {
        return;
    };
    for entry in entries.flatten() {
        if entry.file_name().to_string_lossy().starts_with(&prefix) {
            let _ = std::fs::remove_dir_all(entry.path());
        }
    }
}

/// A Python 3.11 to make the venv with (bpy 4.5 wheels are for CPython 3.11 only):
/// `python3.11`, else `python3` if it is 3.11.
fn base_python(env: &Environment, cancel: &Cancel) -> Result<PathBuf, Error> {
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
        if let Ok((Exit::Finished(s), out)) = run_captured(&argv, PROBE_TIMEOUT, cancel) {
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
    let found = if seen.is_empty() {
        String::new()
    } else {
        format!("; found {}", seen.join(", "))
    };
    Err(Error::BlenderNotFound(
        Hint::text(format!(
            "no Blender found, and bpy {BPY_SERIES} cannot be installed: it needs CPython 3.11 \
             (python3.11 or python3 on PATH){found}. "
        ))
        .then(Hint::new(
            format!("Install python3.11, or point {{}} or {ENV_VAR} at a Blender (apt-get install blender)."),
            [Field::Blender],
        )),
    ))
}
