//! Probing a program: is it a Blender executable or a Python that imports bpy, and which
//! version? A version probe is one short run with a timeout.

use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use super::environment::{ENV_VAR, venv_python, which};
use super::process::{Cancel, Exit, format_seconds, run_captured, shell_join};
use crate::error::{Error, Field, Hint};
use crate::measure::BlenderVersion;

/// How long a version probe may take at most (a cold Blender start on a slow disk can take
/// a while); a shorter `--timeout` bounds it further.
pub const PROBE_TIMEOUT: Duration = Duration::from_secs(60);

/// The newest Cycles whose source was read for everything gloffuse depends on
/// (`docs/BLENDER-VERSIONS.md`): read, not run, as its bpy wheel does not install here.
pub const SOURCE_READ_UP_TO: BlenderVersion = BlenderVersion { major: 5, minor: 2 };

/// What a Blender newer than [`BlenderVersion::NEWEST_KNOWN`] is assumed to share with it:
/// each is something a group's correction or a verdict's prediction rests on, and each is
/// unchanged in Cycles up to [`SOURCE_READ_UP_TO`] (`docs/BLENDER-VERSIONS.md` says where).
pub const ASSUMED: [&str; 5] = [
    "the height-correlated masking of GGX and Beckmann",
    "the 3.6+ shading-normal rule (ensure_valid_specular_reflection)",
    "the Glossy BSDF's distributions, its defaults and roughness squared",
    "the GGX albedo tables behind Multiscatter GGX",
    "Principled BSDF's specular set by IOR, with Thin Wall off",
];

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

/// The notice for a Blender newer than gloffuse knows: which rules it assumes, whether the
/// Cycles source read confirms them for `version`, and how to get a known version. `None`
/// for a known version.
pub fn newer_than_known(version: BlenderVersion) -> Option<Hint> {
    if !version.is_newer_than_known() {
        return None;
    }
    let known = BlenderVersion::NEWEST_KNOWN;
    let checked = if version <= SOURCE_READ_UP_TO {
        format!(
            "Cycles {version}'s source confirms each (read, not run), and the Python side \
             uses feature tests, not version numbers"
        )
    } else {
        format!(
            "nothing confirms them for {version}: Cycles' source was read up to \
             {SOURCE_READ_UP_TO}"
        )
    };
    let message = format!(
        "Blender {version} is newer than the newest version gloffuse knows ({known}): \
         assuming {known}'s rules: {}; {checked} (docs/BLENDER-VERSIONS.md). For measured results \
         give {{}} a Blender {} to {known}",
        ASSUMED.join(", "),
        BlenderVersion::OLDEST,
    );
    Some(Hint::new(message, [Field::Blender]))
}

impl Blender {
    /// [`newer_than_known`] for this Blender.
    pub fn newer_than_known(&self) -> Option<Hint> {
        newer_than_known(self.version)
    }
}

/// Where a candidate came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Source {
    /// Given explicitly (the CLI's `--blender PATH`).
    Explicit,
    /// `$GLOFFUSE_BLENDER`.
    EnvVar,
    /// `blender` on `PATH`.
    SystemPath,
    /// The provisioned bpy venv.
    Cache,
}

impl Source {
    /// The source as a message names it (the explicit one by its field).
    pub fn hint(self) -> Hint {
        match self {
            Source::Explicit => Hint::new("{}", [Field::Blender]),
            Source::EnvVar => Hint::text(ENV_VAR),
            Source::SystemPath => Hint::text("`blender` on PATH"),
            Source::Cache => Hint::text("the bpy cache"),
        }
    }
}

impl std::fmt::Display for Source {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        self.hint().fmt(f)
    }
}

/// Probes `program` and says what Blender it is, whichever kind it is.
///
/// Tries it as a `blender` executable (`-b --factory-startup -noaudio --version`), then as a
/// Python that imports bpy (a name starting with `python` is tried that way first). A
/// directory is looked into for `blender` or a venv's `bin/python`.
pub fn probe(program: &Path) -> Result<Blender, Error> {
    probe_as(
        program,
        None,
        Source::Explicit,
        Instant::now() + PROBE_TIMEOUT,
        &Cancel::default(),
    )
}

/// [`probe`] as `kind` (or either), for a candidate from `source`; every probe it runs ends
/// by `deadline`.
pub(super) fn probe_as(
    program: &Path,
    kind: Option<BlenderKind>,
    source: Source,
    deadline: Instant,
    cancel: &Cancel,
) -> Result<Blender, Error> {
    let program = resolve_program(program, source)?;
    let mut tried = Vec::new();
    for &k in probe_order(kind, &program) {
        match probe_kind(&program, k, deadline, cancel)? {
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
    Err(neither(&program, source, &tried))
}

/// The file to run for `program`: itself, the `blender` or venv Python in a directory, or
/// a bare command name found on PATH; made absolute.
fn resolve_program(program: &Path, source: Source) -> Result<PathBuf, Error> {
    let named = |what: &str| {
        Error::BlenderNotFound(
            source
                .hint()
                .then(Hint::text(format!(" {}: {what}", program.display()))),
        )
    };
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
    Ok(std::path::absolute(&program).unwrap_or(program))
}

/// The kinds to try `program` as, in order: `kind` alone if given, else a Python first
/// when its name says so.
fn probe_order(kind: Option<BlenderKind>, program: &Path) -> &'static [BlenderKind] {
    let looks_like_python = program
        .file_name()
        .is_some_and(|n| n.to_string_lossy().starts_with("python"));
    match kind {
        Some(BlenderKind::Binary) => &[BlenderKind::Binary],
        Some(BlenderKind::PythonModule) => &[BlenderKind::PythonModule],
        None if looks_like_python => &[BlenderKind::PythonModule, BlenderKind::Binary],
        None => &[BlenderKind::Binary, BlenderKind::PythonModule],
    }
}

/// The error for a program that answered no probe: each command tried, how it ended and
/// the last lines it printed.
fn neither(program: &Path, source: Source, tried: &[Attempt]) -> Error {
    let mut m = Hint::text(format!(
        " {} is neither a working Blender ({} or later) nor a Python that imports bpy",
        program.display(),
        BlenderVersion::OLDEST
    ));
    for t in tried {
        m = m
            .then(Hint::text(format!("\n  `{}` ", t.command)))
            .then(t.outcome.clone());
        for line in last_lines(&t.output, 6) {
            m = m.then(Hint::text(format!("\n      {line}")));
        }
    }
    Error::Blender {
        message: source.hint().then(m),
        log: None,
        command: None,
    }
}

struct Attempt {
    command: String,
    outcome: Hint,
    output: String,
}

enum Probed {
    Found(Blender),
    Not(Attempt),
}

/// Runs one version probe, for at most [`PROBE_TIMEOUT`] and not past `deadline`.
/// `Ok(Not)`: it did not answer as this kind. `Err`: it did, but as a Blender older than 3.0.
fn probe_kind(
    program: &Path,
    kind: BlenderKind,
    deadline: Instant,
    cancel: &Cancel,
) -> Result<Probed, Error> {
    let argv = probe_argv(program, kind);
    let command = shell_join(&argv);
    let not = |outcome: Hint, output: String| {
        Ok(Probed::Not(Attempt {
            command: command.clone(),
            outcome,
            output,
        }))
    };
    let output = match run_probe(&argv, deadline, cancel)? {
        Ran::Answered(output) => output,
        Ran::Failed(outcome, output) => return not(outcome, output),
    };
    let Some(version_string) = reported_version(&output, kind) else {
        return not("did not report a Blender version".into(), output);
    };
    let token = version_string.split_whitespace().next().unwrap_or("");
    let version = match token.parse::<BlenderVersion>() {
        Ok(v) => v,
        Err(_) if is_old_version(token) => {
            return Err(too_old(program, version_string, command));
        }
        Err(_) => {
            return not(
                format!("reported an unrecognised version '{version_string}'").into(),
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

/// The version probe's command line for `kind`.
fn probe_argv(program: &Path, kind: BlenderKind) -> Vec<OsString> {
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
    argv
}

/// How a probe run ended.
enum Ran {
    /// It exited successfully, printing this.
    Answered(String),
    /// It did not: how it ended, and what it printed.
    Failed(Hint, String),
}

/// Runs `argv` for at most [`PROBE_TIMEOUT`] and not past `deadline`; `Err` only when
/// cancelled.
fn run_probe(argv: &[OsString], deadline: Instant, cancel: &Cancel) -> Result<Ran, Error> {
    let timeout = deadline
        .saturating_duration_since(Instant::now())
        .min(PROBE_TIMEOUT);
    if timeout.is_zero() {
        let outcome = Hint::new("was not probed: {} ran out", [Field::Timeout]);
        return Ok(Ran::Failed(outcome, String::new()));
    }
    let (exit, output) = match run_captured(argv, timeout, cancel) {
        Ok(r) => r,
        Err(e) => {
            return Ok(Ran::Failed(
                format!("could not be run: {e}").into(),
                String::new(),
            ));
        }
    };
    match exit {
        Exit::Interrupted => Err(Error::Interrupted {
            log: None,
            written: Vec::new(),
        }),
        Exit::TimedOut => {
            // To a tenth of a second: the milliseconds a loaded machine spends before the
            // probe starts are not what the user set.
            let shown = Duration::from_millis((timeout.as_millis() as u64 + 50) / 100 * 100);
            let within = format!("did not answer within {} s", format_seconds(shown));
            let outcome = if timeout < PROBE_TIMEOUT {
                Hint::text(within).then(Hint::new(" ({})", [Field::Timeout]))
            } else {
                Hint::text(within)
            };
            Ok(Ran::Failed(outcome, output))
        }
        Exit::Finished(s) if !s.success() => {
            Ok(Ran::Failed(format!("failed ({s})").into(), output))
        }
        Exit::Finished(_) => Ok(Ran::Answered(output)),
    }
}

/// The version a probe's output reports: after `Blender ` (an executable) or the bpy
/// probe's marker, trimmed.
fn reported_version(output: &str, kind: BlenderKind) -> Option<&str> {
    let prefix = match kind {
        BlenderKind::Binary => "Blender ",
        BlenderKind::PythonModule => BPY_MARKER,
    };
    output
        .lines()
        .find_map(|l| l.trim().strip_prefix(prefix))
        .map(str::trim)
}

/// The error for a Blender older than gloffuse supports.
fn too_old(program: &Path, version_string: &str, command: String) -> Error {
    Error::Blender {
        message: format!(
            "{} is Blender {version_string}; gloffuse needs Blender {} or later \
             (older Glossy BSDFs are not modelled)",
            program.display(),
            BlenderVersion::OLDEST
        )
        .into(),
        log: None,
        command: Some(command),
    }
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

pub(super) fn last_lines(text: &str, n: usize) -> Vec<&str> {
    let lines: Vec<&str> = text.lines().filter(|l| !l.trim().is_empty()).collect();
    lines[lines.len().saturating_sub(n)..].to_vec()
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

    fn version(s: &str) -> BlenderVersion {
        s.parse().unwrap()
    }

    #[test]
    fn known_versions_need_no_notice() {
        for v in ["3.0", "3.4.1", "4.5.4", "5.0", "5.0.1"] {
            assert!(newer_than_known(version(v)).is_none(), "{v}");
        }
    }

    #[test]
    fn a_probed_5_2_names_every_assumption_and_what_confirms_it() {
        let blender = Blender {
            kind: BlenderKind::PythonModule,
            program: PathBuf::from("/opt/bpy52/bin/python"),
            version: version("5.2.0"),
            version_string: "5.2.0".into(),
        };
        let hint = blender.newer_than_known().expect("5.2 is newer than 5.0");
        let text = hint.render(|f| format!("--{}", f.name()));
        assert!(
            text.starts_with(
                "Blender 5.2 is newer than the newest version gloffuse knows (5.0): assuming 5.0's rules: "
            ),
            "{text}"
        );
        for assumption in ASSUMED {
            assert!(text.contains(assumption), "{assumption} missing: {text}");
        }
        assert!(
            text.contains("Cycles 5.2's source confirms each (read, not run)"),
            "{text}"
        );
        assert!(text.contains("docs/BLENDER-VERSIONS.md"), "{text}");
        // The way out is named as an input, never as a flag.
        assert_eq!(hint.to_string(), text.replace("--blender", "blender"));
        assert!(
            text.contains("give --blender a Blender 3.0 to 5.0"),
            "{text}"
        );
    }

    #[test]
    fn a_version_past_the_source_read_is_not_claimed_confirmed() {
        for v in ["5.3", "6.0"] {
            let text = newer_than_known(version(v)).unwrap().to_string();
            assert!(
                text.contains(&format!(
                    "nothing confirms them for {v}: Cycles' source was read up to 5.2"
                )),
                "{text}"
            );
            assert!(!text.contains("confirms each"), "{text}");
        }
        let text = newer_than_known(version("5.1")).unwrap().to_string();
        assert!(text.contains("Cycles 5.1's source confirms each"), "{text}");
    }
}
