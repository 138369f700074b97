//! The binary's edge: parse the command line, call the library, print what it returns, and
//! map the outcome to an exit code. Nothing below this module parses flags or prints.
//!
//! Exit codes: 0 success, 1 a check failed, 2 an error, 130 interrupted (Ctrl-C). A closed
//! stdout (`gloffuse … | head`) ends the program quietly with 0, as ripgrep does.

mod args;
mod progress;
mod text;

use clap::Parser;
use std::io::{self, Write};
use std::path::Path;
use std::process::ExitCode;
use std::sync::OnceLock;

use args::{AlbedoArgs, Cli, CoefficientsCommand, Command, FitArgs};
use gloffuse::Error;
use gloffuse::albedo::AlbedoOutput;
use gloffuse::blender::Cancel;
use gloffuse::fit::{FitSummary, Shown};
use gloffuse::output::{check_destination, is_stdout, write_output};
use gloffuse::progress::Progress;
use progress::{Terminal, eprintln_quietly};

/// How a command ended, when it did not fail.
enum Outcome {
    Success,
    /// A check (`verify`, `refresh`) found a sphere outside its tolerance.
    CheckFailed,
}

/// Why a command did not end normally.
enum Failure {
    Library(Error),
    /// Writing to stdout failed (a closed pipe is not a failure; see [`main`]).
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

/// What Ctrl-C stops: every command's Blender options carry a clone of it.
static CANCEL: OnceLock<Cancel> = OnceLock::new();

fn cancel() -> &'static Cancel {
    CANCEL.get_or_init(Cancel::default)
}

/// Ctrl-C: while a Blender run is waited for, ask the library to stop it (the run then
/// fails with `Error::Interrupted`, nothing is written, and `main` exits 130); otherwise end
/// at once. Only async-signal-safe calls here (`main` made the handle before installing this).
extern "C" fn on_interrupt(_: libc::c_int) {
    // With a child waited for, its wait loop stops it and the command ends with 130.
    if !CANCEL.get().is_some_and(Cancel::request) {
        let message = b"\ngloffuse: interrupted; nothing was written\n";
        // SAFETY: write and _exit are async-signal-safe.
        unsafe {
            libc::write(2, message.as_ptr().cast(), message.len());
            libc::_exit(130);
        }
    }
}

pub fn main() -> ExitCode {
    cancel();
    // SAFETY: installs a handler that only touches atomics and calls write/_exit.
    unsafe {
        libc::signal(
            libc::SIGINT,
            on_interrupt as *const () as libc::sighandler_t,
        );
    }
    let cli = Cli::parse();
    let mut out = io::stdout().lock();
    let outcome = run(cli, &mut out).and_then(|o| {
        out.flush()?;
        Ok(o)
    });
    match outcome {
        Ok(Outcome::Success) => ExitCode::SUCCESS,
        Ok(Outcome::CheckFailed) => ExitCode::from(1),
        Err(Failure::Stdout(e)) if e.kind() == io::ErrorKind::BrokenPipe => ExitCode::SUCCESS,
        Err(Failure::Stdout(e)) => {
            eprintln_quietly(&format!("error: cannot write to standard output: {e}"));
            ExitCode::from(2)
        }
        Err(Failure::Library(e @ Error::Interrupted { .. })) => {
            eprintln_quietly(&format!("gloffuse: {e}"));
            ExitCode::from(130)
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
    let mut stderr = io::stderr();
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
                for p in gloffuse::report::write_files(dir, &verification, &rerun)? {
                    eprintln_quietly(&format!("wrote {}", p.display()));
                }
            }
            let report = &verification.report;
            if let Some(path) = &v.junit {
                let xml = gloffuse::report::junit::render(report, &rerun);
                write_output(path, xml.as_bytes())?;
                eprintln_quietly(&format!("wrote {}", path.display()));
            }
            let out = summary(out, &mut stderr, &[v.junit.as_deref()]);
            emit(out, v.json, report, text::verify)?;
            Ok(verdict(report.pass))
        }
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
        Command::Bench(b) => {
            let r = gloffuse::bench::bench(&b.options(), &terminal)?;
            writeln!(
                out,
                "{} spheres: one Blender process {:.1} s, one process per sphere {:.1} s: {:.1}× faster",
                r.spheres, r.one_process_seconds, r.per_sphere_seconds, r.ratio
            )?;
            Ok(Outcome::Success)
        }
        Command::Coefficients {
            action: CoefficientsCommand::Show { source, json },
        } => show(source.as_deref(), json, out),
    }
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
