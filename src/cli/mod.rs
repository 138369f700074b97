//! The binary's edge: parse the command line, call the library, print what it returns, and
//! map the outcome to an exit code. Nothing below this module parses flags or prints.
//!
//! Exit codes: 0 success, 1 a check failed, 2 an error, 130 interrupted (Ctrl-C). A closed
//! stdout (`gloffuse … | head`) ends the program quietly with 0, as ripgrep does.

mod args;
mod progress;
mod text;

use clap::Parser;
use serde_json::json;
use std::io::{self, Write};
use std::path::Path;
use std::process::ExitCode;

use args::{AlbedoArgs, Cli, CoefficientsCommand, Command, FitArgs};
use gloffuse::Error;
use gloffuse::fit::coefficients::{INTEGRATOR_DEGREE, PRESETS, today};
use gloffuse::fit::{Coefficients, POINTS_DEGREE, fit_points};
use gloffuse::measure::brdf::{Model, model_albedo, model_average_albedo};
use gloffuse::measure::{AlbedoIntegrator, Glossy, Roughness};
use gloffuse::output::{check_destination, is_stdout, write_output};
use gloffuse::progress::Quiet;
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

/// Ctrl-C: while a Blender run is waited for, ask the library to stop it (the run then
/// fails with `Error::Interrupted`, nothing is written, and `main` exits 130); otherwise end
/// at once. Only async-signal-safe calls here.
extern "C" fn on_interrupt(_: libc::c_int) {
    use gloffuse::blender::process::{CHILD_RUNNING, INTERRUPTED};
    use std::sync::atomic::Ordering;
    if CHILD_RUNNING.load(Ordering::SeqCst) {
        INTERRUPTED.store(true, Ordering::SeqCst);
    } else {
        let message = b"\ngloffuse: interrupted; nothing was written\n";
        // SAFETY: write and _exit are async-signal-safe.
        unsafe {
            libc::write(2, message.as_ptr().cast(), message.len());
            libc::_exit(130);
        }
    }
}

pub fn main() -> ExitCode {
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

/// An error and every error that caused it, joined by `: ` (the chain in full).
fn chain(e: &dyn std::error::Error) -> String {
    let mut text = e.to_string();
    let mut cause = e.source();
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
        Command::Albedo(a) => albedo(&a, out),
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

fn albedo(a: &AlbedoArgs, out: &mut dyn Write) -> Result<Outcome> {
    if let Some(model) = a.model {
        return albedo_of_model(a, model, out);
    }
    let distribution = a
        .distribution
        .expect("clap requires --distribution without --model");
    let masking = a.blender_version.masking();
    let integrator = AlbedoIntegrator::default();
    if let Some(path) = &a.table {
        // A bad destination fails before minutes of integration, not after.
        check_destination(path)?;
        let n = a.grid as usize;
        let mus: Vec<f64> = (0..n).map(|i| (i as f64 + 0.5) / n as f64).collect();
        let grid = integrator.grid(distribution, masking, &Roughness::grid(n), &mus, &Quiet);
        write_output(path, grid.csv().as_bytes())?;
        eprintln_quietly(&format!(
            "wrote {} ({n}×{n} grid, {} masking, Blender {})",
            path.display(),
            masking,
            a.blender_version
        ));
        return Ok(Outcome::Success);
    }
    let roughness = a.roughness.ok_or_else(|| {
        Error::input(
            "arguments",
            "(none)",
            "--roughness R (0 to 1), or --table FILE for a grid",
        )
    })?;
    let g = Glossy::new(distribution, masking, roughness);
    let e = integrator.directional_albedo(&g, a.mu);
    let avg = integrator.average_albedo(&g);
    if a.json {
        let v = json!({
            "distribution": distribution,
            "roughness": roughness.get(),
            "alpha": roughness.alpha(),
            "mu": a.mu,
            "blender_version": a.blender_version.to_string(),
            "masking": masking,
            "directional_albedo": e,
            "average_albedo": avg,
        });
        print_json(out, &v)?;
    } else {
        writeln!(
            out,
            "{} roughness {} (alpha {}), Blender {} ({} masking)",
            distribution.label(),
            roughness.get(),
            roughness.alpha(),
            a.blender_version,
            masking
        )?;
        writeln!(
            out,
            "E(mu = {}) = {e:.6}   brightness at view cosine {} ({:.2} %)",
            a.mu,
            a.mu,
            100.0 * e
        )?;
        writeln!(
            out,
            "E_avg      = {avg:.6}   mean brightness of a furnace sphere ({:.2} %)",
            100.0 * avg
        )?;
    }
    Ok(Outcome::Success)
}

/// `albedo --model`: directional albedo of a classic BRDF, and its hemispherical average.
fn albedo_of_model(a: &AlbedoArgs, model: Model, out: &mut dyn Write) -> Result<Outcome> {
    let params = a.model_params();
    let e = model_albedo(model, &params, a.mu)?;
    let avg = model_average_albedo(model, &params)?;
    if a.json {
        let v = json!({
            "model": format!("{model:?}"),
            "parameters": { "rho": a.rho, "rs": a.rs, "exponent": a.exponent, "alpha_x": a.alpha_x, "alpha_y": a.alpha_y },
            "mu": a.mu,
            "directional_albedo": e,
            "average_albedo": avg,
        });
        print_json(out, &v)?;
    } else {
        writeln!(
            out,
            "{model:?} (rho {}, rs {}, exponent {}, alpha {} × {})",
            a.rho, a.rs, a.exponent, a.alpha_x, a.alpha_y
        )?;
        writeln!(out, "E(mu = {}) = {e:.6}", a.mu)?;
        writeln!(out, "E_avg      = {avg:.6}")?;
    }
    Ok(Outcome::Success)
}

fn fit(f: &FitArgs, out: &mut dyn Write) -> Result<Outcome> {
    if let Some(path) = &f.out {
        check_destination(path)?;
    }
    let coefficients = if f.from.is_some() {
        if let Some(d) = f.distribution {
            return Err(Error::input(
                "--distribution",
                &d.to_string(),
                "nothing with --from integrator (it fits all three distributions)",
            )
            .into());
        }
        Coefficients::from_integrator(
            f.engine,
            f.blender_version,
            f.degree.unwrap_or(INTEGRATOR_DEGREE),
            f.target,
            f.weighting,
            Some(today()),
        )?
    } else {
        let d = f.distribution.ok_or_else(|| {
            Error::input(
                "arguments",
                "(no --distribution)",
                "--distribution D with --point R:PERCENT values, or --from integrator",
            )
        })?;
        if f.points.is_empty() {
            return Err(Error::input(
                "arguments",
                "(no --point)",
                "at least one --point ROUGHNESS:PERCENT (e.g. --point 0.5:97 --point 1:71), or --from integrator",
            )
            .into());
        }
        fit_points(
            d,
            &f.points,
            f.degree.unwrap_or(POINTS_DEGREE),
            f.weighting,
            f.target,
            f.engine,
            f.blender_version,
        )?
    };
    if let Some(path) = &f.out {
        coefficients.write(path)?;
        eprintln_quietly(&format!("wrote {}", path.display()));
    }
    if f.json {
        let list: Vec<_> = coefficients
            .distributions
            .iter()
            .map(|(d, e)| {
                let n = &e.curve.numerator;
                let c = |k: usize| n.get(k).copied().unwrap_or(0.0);
                json!({
                    "distribution": d,
                    "degree": e.degree,
                    "a": c(3), "b": c(2), "c": c(1), "d": c(0),
                    "coefficients_ascending": n,
                    "curve": e.curve,
                    "weighting": e.weighting,
                    "residuals": e.residuals,
                })
            })
            .collect();
        print_json(out, &json!({ "fits": list }))?;
    } else {
        for (d, e) in &coefficients.distributions {
            out.write_all(text::entry(d.label(), e).as_bytes())?;
        }
    }
    Ok(Outcome::Success)
}

fn show(source: Option<&str>, json: bool, out: &mut dyn Write) -> Result<Outcome> {
    let Some(source) = source else {
        writeln!(out, "Built-in presets (gloffuse coefficients show NAME):")?;
        for (name, _, summary) in PRESETS {
            writeln!(out, "  {name:<10} {summary}")?;
        }
        return Ok(Outcome::Success);
    };
    let c = Coefficients::load(source)?;
    if json {
        out.write_all(c.to_json().as_bytes())?;
        return Ok(Outcome::Success);
    }
    writeln!(out, "{} — {}", c.name, c.description)?;
    for (d, e) in &c.distributions {
        out.write_all(text::entry(d.label(), e).as_bytes())?;
    }
    Ok(Outcome::Success)
}
