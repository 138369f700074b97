//! The binary's edge: parse the command line, call the library, print what it returns, and
//! map the outcome to an exit code. Nothing below this module parses flags or prints.
//!
//! Exit codes, one rule each:
//!
//! - 0: the command succeeded (for `verify` and `refresh`: every sphere passed; for `audit`:
//!   no material fails the check: a verdict in `--fail-on` that no waiver or severity
//!   suppresses, counted after the fix when one is asked, as ruff's `--fix`);
//! - 1: a check failed (`verify` or `refresh` found a sphere outside its tolerance, `audit`
//!   a material that fails);
//! - 2: an error (bad input, Blender failed, an output could not be written);
//! - 128 + the signal's number when stopped by a signal: 130 for Ctrl-C (SIGINT), 143 for
//!   SIGTERM (`timeout`, a CI cancel), 129 for SIGHUP. Blender is stopped and nothing is
//!   written: no output, no temporary file beside one.
//!
//! A closed stdout (`gloffuse … | head`, `| true`, `grep -q`) is not an outcome: what would
//! have been printed is dropped quietly and the exit code is the command's own, so a failing
//! verdict still exits 1 under `set -o pipefail`. The same holds for an output that is a pipe
//! (`--out -`, `--out /dev/stdout`). SIGPIPE stays ignored (Rust's default), so a write to a
//! closed pipe is an error we see (EPIPE), never a silent death.

mod args;
mod farm;
mod progress;
mod text;

use clap::Parser;
use std::io::{self, Write};
use std::path::Path;
use std::process::ExitCode;
use std::sync::OnceLock;
use std::sync::atomic::{AtomicI32, Ordering};

use args::{AlbedoArgs, Cli, CoefficientsCommand, Command, FarmCommand, FitArgs, ReportCommand};
use gloffuse::Error;
use gloffuse::albedo::AlbedoOutput;
use gloffuse::audit::AuditReport;
use gloffuse::blender::Cancel;
use gloffuse::fit::{FitSummary, Shown};
use gloffuse::output::{check_destination, is_stdout, write_output};
use gloffuse::progress::Progress;
use progress::{Terminal, eprintln_quietly};

/// How a command ended, when it did not fail.
enum Outcome {
    Success,
    /// A check (`verify`, `refresh`, `audit`) found a sphere or material outside its tolerance.
    CheckFailed,
}

/// Why a command did not end normally.
enum Failure {
    Library(Error),
    /// Writing to stdout failed (a closed pipe is not a failure; see [`Printed`]).
    Stdout(io::Error),
}

impl From<Error> for Failure {
    fn from(e: Error) -> Self {
        Failure::Library(e)
    }
}

impl From<io::Error> for Failure {
    fn from(e: io::Error) -> Self {
        Failure::Stdout(e)
    }
}

type Result<T> = std::result::Result<T, Failure>;

/// What Ctrl-C, SIGTERM and SIGHUP stop: every command's Blender options carry a clone of it.
static CANCEL: OnceLock<Cancel> = OnceLock::new();

/// The signal that stopped the command (0: none yet), for its exit code.
static SIGNAL: AtomicI32 = AtomicI32::new(0);

/// The signals that stop a command, each handled like Ctrl-C.
const STOP_SIGNALS: [libc::c_int; 3] = [libc::SIGINT, libc::SIGTERM, libc::SIGHUP];

fn cancel() -> &'static Cancel {
    CANCEL.get_or_init(Cancel::default)
}

/// The exit code of a command stopped by `signal`: 128 + its number, as shells report it.
fn stopped_code(signal: libc::c_int) -> u8 {
    u8::try_from(128 + signal).unwrap_or(130)
}

/// A stop signal: while a Blender run is waited for, ask the library to stop it (the run then
/// fails with `Error::Interrupted`, its temporary files are dropped, nothing is written, and
/// `main` exits 128 + the signal); otherwise end at once, as nothing is half-written outside
/// a run. Only async-signal-safe calls here (`main` made the handle before installing this).
extern "C" fn on_signal(signal: libc::c_int) {
    // The first signal names the exit code.
    let _ = SIGNAL.compare_exchange(0, signal, Ordering::SeqCst, Ordering::SeqCst);
    if !CANCEL.get().is_some_and(Cancel::request) {
        let message = b"\ngloffuse: stopped; nothing was written\n";
        // SAFETY: write and _exit are async-signal-safe.
        unsafe {
            libc::write(2, message.as_ptr().cast(), message.len());
            libc::_exit(i32::from(stopped_code(SIGNAL.load(Ordering::SeqCst))));
        }
    }
}

/// Standard output or error, where a reader that has gone away (EPIPE) ends the printing
/// and not the command: later writes are dropped, and the command's outcome stands.
struct Printed<W: Write> {
    inner: W,
    closed: bool,
}

impl<W: Write> Printed<W> {
    fn new(inner: W) -> Self {
        Printed {
            inner,
            closed: false,
        }
    }

    fn guard<T>(&mut self, done: T, write: impl FnOnce(&mut W) -> io::Result<T>) -> io::Result<T> {
        if self.closed {
            return Ok(done);
        }
        match write(&mut self.inner) {
            Err(e) if e.kind() == io::ErrorKind::BrokenPipe => {
                self.closed = true;
                Ok(done)
            }
            other => other,
        }
    }
}

impl<W: Write> Write for Printed<W> {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        self.guard(buf.len(), |w| w.write(buf))
    }

    fn flush(&mut self) -> io::Result<()> {
        self.guard((), Write::flush)
    }
}

pub fn main() -> ExitCode {
    cancel();
    for signal in STOP_SIGNALS {
        // SAFETY: installs a handler that only touches atomics and calls write/_exit.
        unsafe {
            libc::signal(signal, on_signal as *const () as libc::sighandler_t);
        }
    }
    let cli = Cli::parse();
    let mut out = Printed::new(io::stdout().lock());
    let outcome = run(cli, &mut out).and_then(|o| {
        out.flush()?;
        Ok(o)
    });
    // A stop that came while held work was finishing (after its last check): the work is
    // whole, but the exit code still says the command was stopped.
    let signal = SIGNAL.load(Ordering::SeqCst);
    if signal != 0 && outcome.is_ok() {
        eprintln_quietly(
            "gloffuse: stopped as it finished; what it wrote is complete and reported above",
        );
        return ExitCode::from(stopped_code(signal));
    }
    match outcome {
        Ok(Outcome::Success) => ExitCode::SUCCESS,
        Ok(Outcome::CheckFailed) => ExitCode::from(1),
        Err(Failure::Stdout(e)) => {
            eprintln_quietly(&format!("error: cannot write to standard output: {e}"));
            ExitCode::from(2)
        }
        Err(Failure::Library(e @ Error::Interrupted { .. })) => {
            eprintln_quietly(&format!("gloffuse: {e}"));
            let signal = SIGNAL.load(Ordering::SeqCst);
            ExitCode::from(stopped_code(if signal == 0 {
                libc::SIGINT
            } else {
                signal
            }))
        }
        Err(Failure::Library(e)) => {
            eprintln_quietly(&format!("error: {}", chain(&e)));
            ExitCode::from(2)
        }
    }
}

/// An error, its fields named by their flags, and every error that caused it, joined by
/// `: ` (the chain in full).
fn chain(e: &Error) -> String {
    let mut text = e.render(args::flag);
    let mut cause = std::error::Error::source(e);
    while let Some(c) = cause {
        text.push_str(&format!(": {c}"));
        cause = c.source();
    }
    text
}

/// Where a command's summary goes: stdout, unless one of its outputs is stdout itself
/// (`-`, `/dev/stdout`), then stderr.
fn summary<'a>(
    out: &'a mut dyn Write,
    err: &'a mut dyn Write,
    outputs: &[Option<&Path>],
) -> &'a mut dyn Write {
    if outputs.iter().flatten().any(|p| is_stdout(p)) {
        err
    } else {
        out
    }
}

fn run(cli: Cli, out: &mut dyn Write) -> Result<Outcome> {
    let terminal = Terminal::default();
    let mut stderr = Printed::new(io::stderr());
    match cli.command {
        Command::Albedo(a) => albedo(&a, out, &terminal),
        Command::Fit(f) => {
            let out = summary(out, &mut stderr, &[f.out.as_deref()]);
            fit(&f, out)
        }
        Command::Generate(g) => {
            let generated = gloffuse::generate::generate(&g.options(), &terminal)?;
            let outputs = [g.script.as_deref(), g.blend.as_deref()];
            emit(
                summary(out, &mut stderr, &outputs),
                g.json,
                &generated,
                text::generated,
            )?;
            Ok(Outcome::Success)
        }
        Command::Verify(v) => {
            // Report outputs are checked before any slow work: bad input fails fast.
            if let Some(dir) = &v.report {
                gloffuse::report::check_dir(dir)?;
            }
            if let Some(path) = &v.junit {
                check_destination(path)?;
            }
            let verification = gloffuse::verify::verify(&v.options(), &terminal)?;
            let rerun = this_command();
            if let Some(dir) = &v.report {
                for p in gloffuse::report::verify::write_files(dir, &verification, &rerun)? {
                    eprintln_quietly(&format!("wrote {}", p.display()));
                }
            }
            let report = &verification.report;
            if let Some(path) = &v.junit {
                let xml = gloffuse::report::verify::junit::render(report, &rerun);
                write_output(path, xml.as_bytes())?;
                eprintln_quietly(&format!("wrote {}", path.display()));
            }
            let out = summary(out, &mut stderr, &[v.junit.as_deref()]);
            emit(out, v.json, report, text::verify)?;
            // Last, below the table, where a person looks: the page to open.
            if let Some(dir) = &v.report {
                eprintln_quietly(&format!(
                    "report: {} (open it in a browser)",
                    dir.join("report.html").display()
                ));
            }
            Ok(verdict(report.pass))
        }
        Command::Audit(a) => audit(&a, out, &mut stderr, &terminal),
        Command::Refresh(a) => {
            let r = gloffuse::refresh::refresh(&a.options(), &terminal)?;
            let out = summary(out, &mut stderr, &[Some(a.out.as_path())]);
            emit(out, a.json, &r, text::refresh)?;
            Ok(verdict(r.verify.as_ref().is_none_or(|v| v.pass)))
        }
        Command::Lut(l) => {
            let written = gloffuse::lut::lut(&l.options(), &terminal)?;
            let out = summary(out, &mut stderr, &[Some(l.out.as_path())]);
            emit(out, l.json, &written, text::lut)?;
            Ok(Outcome::Success)
        }
        Command::Bench(b) => bench(&b, out, &terminal),
        Command::Farm {
            action: FarmCommand::Slurm(a),
        } => farm::slurm_job(&a, out),
        Command::Farm {
            action: FarmCommand::Openjd(a),
        } => farm::openjd_template(&a, out),
        Command::Report {
            action: ReportCommand::Merge(m),
        } => merge(&m, out, &mut stderr),
        Command::Coefficients {
            action: CoefficientsCommand::Show { source, json },
        } => show(source.as_deref(), json, out),
    }
}

/// `bench`: the verify sweep, the audit (`--audit`) or sharding (`--shards`), timed.
fn bench(b: &args::BenchArgs, out: &mut dyn Write, progress: &dyn Progress) -> Result<Outcome> {
    if let Some(n) = b.shards {
        let r = gloffuse::bench::shards::bench_shards(&b.audit_options(), n as usize, progress)?;
        out.write_all(text::bench_shards(&r).as_bytes())?;
    } else if !b.audit.is_empty() {
        let r = gloffuse::bench::audit::bench_audit(&b.audit_options(), progress)?;
        out.write_all(text::bench_audit(&r).as_bytes())?;
    } else {
        let r = gloffuse::bench::bench(&b.options(), progress)?;
        writeln!(
            out,
            "{}: one Blender process {:.1} s, one process per sphere {:.1} s: {:.1}× faster",
            gloffuse::plural::count(r.spheres, "sphere", "spheres"),
            r.one_process_seconds,
            r.per_sphere_seconds,
            r.ratio
        )?;
    }
    Ok(Outcome::Success)
}

/// `audit`: outputs checked first, then the audit, whose report folder takes each file's
/// pictures as it is done.
fn audit(
    a: &args::AuditArgs,
    out: &mut dyn Write,
    err: &mut dyn Write,
    progress: &dyn Progress,
) -> Result<Outcome> {
    if let Some(dir) = &a.report {
        gloffuse::report::check_dir(dir)?;
    }
    for path in [&a.junit, &a.sarif].into_iter().flatten() {
        check_destination(path)?;
    }
    // The report is staged in a folder beside its destination: a stop waits for the next
    // check (the library's between files, this one's before the report is written), so that
    // the staging folder is removed and the message says what was written.
    let _hold = cancel().hold();
    let mut folder = None;
    let report = gloffuse::audit::audit(&a.options(), progress, &mut |done| {
        if let Some(dir) = &a.report {
            if folder.is_none() {
                folder = Some(gloffuse::report::audit::ReportDir::create(dir)?);
            }
            folder.as_mut().expect("made above").add(&done)?;
        }
        Ok(())
    })?;
    let rerun = this_command();
    cancel().check()?;
    if let Some(dir) = &a.report {
        let folder = match folder {
            Some(f) => f,
            None => gloffuse::report::audit::ReportDir::create(dir)?,
        };
        for p in folder.finish(&report, &rerun)? {
            eprintln_quietly(&format!("wrote {}", p.display()));
        }
    }
    write_audit_junit(a.junit.as_deref(), &report, &rerun)?;
    write_audit_sarif(a.sarif.as_deref(), &report, &rerun)?;
    let out = summary(out, err, &[a.junit.as_deref(), a.sarif.as_deref()]);
    emit(out, a.json, &report, gloffuse::report::audit::table::render)?;
    Ok(verdict(report.check_passed() || a.exit_zero))
}

fn write_audit_junit(path: Option<&Path>, report: &AuditReport, rerun: &str) -> Result<()> {
    if let Some(path) = path {
        let xml = gloffuse::report::audit::junit::render(report, rerun);
        write_output(path, xml.as_bytes())?;
        eprintln_quietly(&format!("wrote {}", path.display()));
    }
    Ok(())
}

fn write_audit_sarif(path: Option<&Path>, report: &AuditReport, rerun: &str) -> Result<()> {
    if let Some(path) = path {
        let log = gloffuse::report::audit::sarif::render(report, rerun);
        write_output(path, format!("{log}\n").as_bytes())?;
        eprintln_quietly(&format!("wrote {}", path.display()));
    }
    Ok(())
}

/// `report merge`: the shards read and checked, then the outputs of one unsharded audit.
fn merge(m: &args::MergeArgs, out: &mut dyn Write, err: &mut dyn Write) -> Result<Outcome> {
    use gloffuse::report::audit::merge::{Skipped, copy_pictures};
    if let Some(dir) = &m.report {
        gloffuse::report::check_dir(dir)?;
    }
    for path in [&m.junit, &m.sarif, &m.json].into_iter().flatten() {
        check_destination(path)?;
    }
    // As in `audit`: a stop removes the staging folder instead of ending the process in it.
    let _hold = cancel().hold();
    let merged = gloffuse::audit::merge::merge(&m.shards)?;
    let report = &merged.report;
    let rerun = this_command();
    if let Some(dir) = &m.report {
        let (folder, skipped) = copy_pictures(dir, &merged, cancel())?;
        for s in skipped {
            eprintln_quietly(&match s {
                Skipped::NotRegular(path) => format!(
                    "note: skipped {}: a symbolic link or not a regular file (a merge copies \
                     only a shard's own pictures, never what a link points to)",
                    path.display()
                ),
                Skipped::NoPictures(k) => format!(
                    "note: shard {k} has no pictures beside its report.json (run the shards \
                     with --report DIR to have them in the merged report)"
                ),
            });
        }
        cancel().check()?;
        for p in folder.finish(report, &rerun)? {
            eprintln_quietly(&format!("wrote {}", p.display()));
        }
    }
    write_audit_junit(m.junit.as_deref(), report, &rerun)?;
    write_audit_sarif(m.sarif.as_deref(), report, &rerun)?;
    if let Some(path) = &m.json {
        let text = serde_json::to_string_pretty(report).expect("reports serialise to JSON");
        write_output(path, format!("{text}\n").as_bytes())?;
        if !is_stdout(path) {
            eprintln_quietly(&format!("wrote {}", path.display()));
        }
    }
    let out = summary(
        out,
        err,
        &[m.junit.as_deref(), m.sarif.as_deref(), m.json.as_deref()],
    );
    if !m.json.as_deref().is_some_and(is_stdout) {
        out.write_all(gloffuse::report::audit::table::render(report).as_bytes())?;
    }
    Ok(verdict(report.check_passed() || m.exit_zero))
}

/// The command line this process was started with, quoted for a shell: how to rerun it.
fn this_command() -> String {
    let argv: Vec<std::ffi::OsString> = std::env::args_os().collect();
    gloffuse::blender::process::shell_join(&argv)
}

fn verdict(pass: bool) -> Outcome {
    if pass {
        Outcome::Success
    } else {
        Outcome::CheckFailed
    }
}

/// A command's result: pretty JSON with `--json`, else the text `render` makes of it.
fn emit<T: serde::Serialize>(
    out: &mut dyn Write,
    json: bool,
    value: &T,
    render: fn(&T) -> String,
) -> Result<()> {
    if json {
        print_json(out, value)
    } else {
        out.write_all(render(value).as_bytes())?;
        Ok(())
    }
}

/// Pretty JSON of a report (plain data, so serialising it cannot fail).
fn print_json(out: &mut dyn Write, value: &impl serde::Serialize) -> Result<()> {
    let text = serde_json::to_string_pretty(value).expect("reports serialise to JSON");
    writeln!(out, "{text}")?;
    Ok(())
}

fn albedo(a: &AlbedoArgs, out: &mut dyn Write, progress: &dyn Progress) -> Result<Outcome> {
    match gloffuse::albedo::albedo(&a.options(), progress)? {
        AlbedoOutput::Table {
            path,
            grid,
            masking,
            blender_version,
        } => eprintln_quietly(&format!(
            "wrote {} ({grid}×{grid} grid, {masking} masking, Blender {blender_version})",
            path.display()
        )),
        // Keys sorted, as albedo's JSON has always been.
        AlbedoOutput::Point(albedo) => emit(out, a.json, &albedo, text::albedo)?,
    }
    Ok(Outcome::Success)
}

fn fit(f: &FitArgs, out: &mut dyn Write) -> Result<Outcome> {
    let fitted = gloffuse::fit::fit(&f.options())?;
    if let Some(path) = &fitted.wrote {
        eprintln_quietly(&format!("wrote {}", path.display()));
    }
    if f.json {
        // Through a JSON value, so the keys are sorted as fit's JSON has always been.
        let summary = serde_json::to_value(FitSummary::of(&fitted.coefficients))
            .expect("a fit serialises to JSON");
        print_json(out, &summary)?;
    } else {
        for (d, e) in &fitted.coefficients.distributions {
            out.write_all(text::entry(d.label(), e).as_bytes())?;
        }
    }
    Ok(Outcome::Success)
}

fn show(source: Option<&str>, json: bool, out: &mut dyn Write) -> Result<Outcome> {
    match gloffuse::fit::show(source)? {
        Shown::Coefficients(c) if json => out.write_all(c.to_json().as_bytes())?,
        shown => out.write_all(text::shown(&shown).as_bytes())?,
    }
    Ok(Outcome::Success)
}
