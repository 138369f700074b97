//! Running a Python script in headless Blender (or in a Python that imports bpy): its own
//! process group, its output in a log file, a timeout that kills the whole group, and the
//! result read back from one marked line of its output.
//!
//! The script reports by printing one line `GLOFFUSE_RESULT {json}` to stdout; the last such
//! line wins. Write it in one call and flush, so Blender's own output cannot split it:
//! `sys.stdout.write("GLOFFUSE_RESULT " + json.dumps(result) + "\n"); sys.stdout.flush()`.
//!
//! A run succeeds when it exits 0 and printed a result line, and only then: the log is
//! never searched for words to decide (Blender prints tracebacks of drivers and handlers
//! that do not fail the job, and any path may hold any words). A traceback is looked for
//! only to quote it when a run has failed.

use super::probe::{Blender, BlenderKind};
use super::process::{Cancel, Exit, describe_status, format_seconds, run_logged, shell_join};
use crate::error::{Error, Field, Hint};
use std::ffi::OsString;
use std::fs::File;
use std::path::{Path, PathBuf};
use std::process::ExitStatus;
use std::time::{Duration, Instant};

/// The prefix of the stdout line that carries a script's result as JSON.
pub const RESULT_PREFIX: &str = "GLOFFUSE_RESULT ";

/// The line Python prints, alone, at the start of an exception's traceback.
const TRACEBACK: &str = "Traceback (most recent call last):";

/// How many lines of a traceback, or of the end of the log, an error quotes.
const TRACEBACK_LINES: usize = 8;
const TAIL_LINES: usize = 15;

/// One run of `script` in `blender`.
#[derive(Clone, Debug)]
pub struct Run<'a> {
    pub blender: &'a Blender,
    pub script: &'a Path,
    /// The script's own arguments (after `--` for a `blender` binary; `sys.argv[1:]` for bpy).
    pub args: Vec<OsString>,
    pub timeout: Duration,
    /// Stops the run when requested.
    pub cancel: Cancel,
    /// Where stdout and stderr go (created or truncated); it exists afterwards, whatever
    /// happened.
    pub log: PathBuf,
}

/// What a successful run gave back.
#[derive(Clone, Debug)]
pub struct RunOutput {
    /// Parsed from the last stdout line starting with [`RESULT_PREFIX`].
    pub result: serde_json::Value,
    pub log: PathBuf,
    /// Wall-clock time of the run.
    pub seconds: f64,
}

/// The full argument vector, program first.
///
/// Binary: `blender -b --factory-startup -noaudio --python-exit-code 1 --python SCRIPT -- ARGS`;
/// bpy module: `PYTHON SCRIPT ARGS`.
pub fn argv(run: &Run) -> Vec<OsString> {
    let mut v: Vec<OsString> = vec![run.blender.program.clone().into_os_string()];
    match run.blender.kind {
        BlenderKind::Binary => {
            for a in [
                "-b",
                "--factory-startup",
                "-noaudio",
                "--python-exit-code",
                "1",
                "--python",
            ] {
                v.push(a.into());
            }
            v.push(run.script.as_os_str().to_owned());
            v.push("--".into());
        }
        BlenderKind::PythonModule => v.push(run.script.as_os_str().to_owned()),
    }
    v.extend(run.args.iter().cloned());
    v
}

/// The command, shell-quoted so that a person can paste it to rerun the run.
pub fn command_line(run: &Run) -> String {
    shell_join(&argv(run))
}

/// Runs the script, waits at most `run.timeout`, and reads its result back.
///
/// Errors ([`Error::Blender`], naming the log and the command): Blender cannot be started,
/// it times out (its whole process group is killed), it exits non-zero, or it prints no
/// parseable `GLOFFUSE_RESULT` line.
pub fn run_script(run: &Run) -> Result<RunOutput, Error> {
    let argv = argv(run);
    let command = shell_join(&argv);
    let fail = |message: Hint| Error::Blender {
        message,
        log: Some(run.log.clone()),
        command: Some(command.clone()),
    };
    let log = File::create(&run.log).map_err(|e| Error::Write {
        path: run.log.clone(),
        message: e.to_string(),
    })?;
    let start = Instant::now();
    let exit = run_logged(&argv, &log, run.timeout, &run.cancel).map_err(|e| {
        fail(Hint::text(format!(
            "cannot start {}: {e}",
            run.blender.program.display()
        )))
    })?;
    let seconds = start.elapsed().as_secs_f64();
    drop(log);
    let status = match exit {
        Exit::Interrupted => {
            return Err(Error::Interrupted {
                log: Some(run.log.clone()),
                written: Vec::new(),
            });
        }
        Exit::TimedOut => {
            return Err(fail(Hint::new(
                format!(
                    "Blender timed out after {} s ({{}})",
                    format_seconds(run.timeout)
                ),
                [Field::Timeout],
            )));
        }
        Exit::Finished(status) => status,
    };
    let bytes = std::fs::read(&run.log).map_err(|e| Error::Read {
        path: run.log.clone(),
        source: e,
    })?;
    let text = String::from_utf8_lossy(&bytes);
    let result = check_output(&text, status).map_err(|m| fail(Hint::text(m)))?;
    Ok(RunOutput {
        result,
        log: run.log.clone(),
        seconds,
    })
}
/// Decides whether a finished run succeeded, from its exit status and its result line alone;
/// on failure the message quotes the lines that say why (its last traceback, else the end
/// of the log).
fn check_output(text: &str, status: ExitStatus) -> Result<serde_json::Value, String> {
    let lines: Vec<&str> = text.lines().collect();
    let quote = |what: &[&str]| -> String {
        what.iter()
            .map(|l| format!("\n    {}", clip(l, 300)))
            .collect()
    };
    let why = || match last_traceback(&lines) {
        Some(tb) => format!("its Python script raised:{}", quote(tb)),
        None => format!("the log ends:{}", quote(tail(&lines))),
    };
    if !status.success() {
        return Err(format!("Blender {}; {}", describe_status(status), why()));
    }
    let Some(line) = lines
        .iter()
        .rev()
        .find_map(|l| l.trim_end().strip_prefix(RESULT_PREFIX))
    else {
        return Err(format!(
            "Blender exited 0 but printed no result line ({RESULT_PREFIX}{{…}}); {}",
            why()
        ));
    };
    serde_json::from_str(line).map_err(|e| {
        format!(
            "Blender's result line is not valid JSON ({e}):{}",
            quote(&[line])
        )
    })
}

/// The last traceback in the log, from its `Traceback` line to the exception line (the
/// first unindented line after it), cut to its last [`TRACEBACK_LINES`] lines.
fn last_traceback<'t>(lines: &'t [&'t str]) -> Option<&'t [&'t str]> {
    let start = lines.iter().rposition(|l| l.trim_end() == TRACEBACK)?;
    let end = lines[start + 1..]
        .iter()
        .position(|l| !l.is_empty() && !l.starts_with([' ', '\t']))
        .map_or(lines.len(), |i| start + 1 + i + 1);
    let block = &lines[start..end];
    Some(&block[block.len().saturating_sub(TRACEBACK_LINES)..])
}

/// The last [`TAIL_LINES`] non-blank lines.
fn tail<'t>(lines: &'t [&'t str]) -> &'t [&'t str] {
    let end = lines
        .iter()
        .rposition(|l| !l.trim().is_empty())
        .map_or(0, |i| i + 1);
    if end == 0 {
        return &["(the log is empty)"];
    }
    &lines[end.saturating_sub(TAIL_LINES)..end]
}

fn clip(line: &str, max: usize) -> String {
    match line.char_indices().nth(max) {
        Some((i, _)) => format!("{}…", &line[..i]),
        None => line.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::os::unix::process::ExitStatusExt;

    fn ok() -> ExitStatus {
        ExitStatus::from_raw(0)
    }

    #[test]
    fn result_is_the_last_marked_line() {
        let log = "Blender 4.5\nGLOFFUSE_RESULT {\"a\": 1}\nnoise\nGLOFFUSE_RESULT {\"a\": 2}\n\nBlender quit\n";
        assert_eq!(check_output(log, ok()).unwrap()["a"], 2);
    }

    #[test]
    fn failures_quote_the_right_lines() {
        let log = "start\nTraceback (most recent call last):\n  File \"x.py\", line 3, in <module>\n    1/0\nZeroDivisionError: division by zero\nBlender quit\n";
        let e = check_output(log, ExitStatus::from_raw(1 << 8)).unwrap_err();
        assert!(e.contains("exited with status 1"), "{e}");
        assert!(e.contains("ZeroDivisionError"), "{e}");
        assert!(!e.contains("Blender quit"), "{e}");
        // Exit 0 with a result line succeeds whatever the log says (a driver's traceback,
        // a folder named like one); without a result line the traceback is quoted.
        let with_result = format!("{log}GLOFFUSE_RESULT {{\"a\": 3}}\n");
        assert_eq!(check_output(&with_result, ok()).unwrap()["a"], 3);
        let e = check_output(log, ok()).unwrap_err();
        assert!(
            e.contains("no result line") && e.contains("ZeroDivisionError"),
            "{e}"
        );
        let odd = "Read blend: \"/tmp/Traceback (most recent call last)/Error: x.blend\"\n";
        assert!(check_output(&format!("{odd}GLOFFUSE_RESULT {{}}\n"), ok()).is_ok());
        let e = check_output(odd, ExitStatus::from_raw(1 << 8)).unwrap_err();
        assert!(
            e.contains("the log ends:") && e.contains("Read blend"),
            "{e}"
        );
        let e = check_output("a\nb\n", ok()).unwrap_err();
        assert!(e.contains("no result line") && e.contains("\n    b"), "{e}");
        let e = check_output("GLOFFUSE_RESULT {oops\n", ok()).unwrap_err();
        assert!(e.contains("not valid JSON"), "{e}");
        assert!(check_output("", ok()).unwrap_err().contains("log is empty"));
    }

    #[test]
    fn long_tracebacks_are_cut_to_their_end() {
        let mut log = String::from("Traceback (most recent call last):\n");
        for i in 0..20 {
            log.push_str(&format!("  File \"f{i}.py\", line {i}\n"));
        }
        log.push_str("KeyError: 'x'\nafter\n");
        let e = check_output(&log, ExitStatus::from_raw(1 << 8)).unwrap_err();
        assert_eq!(e.matches("\n    ").count(), TRACEBACK_LINES);
        assert!(e.contains("KeyError") && !e.contains("f0.py") && !e.contains("after"));
    }
}
