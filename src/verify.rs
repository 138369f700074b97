//! `gloffuse verify`: render furnace spheres in one Blender process, read the EXR back and
//! compare every sphere's mean with 100 % and with the integrator's prediction.

use indicatif::{ProgressBar, ProgressStyle};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use crate::Error;
use crate::blender::script::{FURNACE_MAIN, GenerateParams, Mode, assemble};
use crate::blender::{Blender, Run, command_line, run_script};
use crate::cli::VerifyArgs;
use crate::coefficients::{Coefficients, ColorSpace};
use crate::furnace::image::{Rgba, read_rgba};
use crate::furnace::plan::{Plan, RenderSettings, Role};
use crate::furnace::report::{ReferenceSphere, RenderInfo, Row, VerifyReport};
use crate::furnace::stats::{SphereStats, sphere_stats};
use crate::generate::blender_from;
use crate::microfacet::{AlbedoIntegrator, Distribution, Glossy, Roughness};
use crate::output::write_atomic;

/// A rendered sweep: the image, per-cell statistics (in plan order) and how it was made.
pub struct Rendered {
    pub image: Rgba,
    pub stats: Vec<SphereStats>,
    pub info: RenderInfo,
    /// The EXR, in the run's directory beside its script and log.
    pub exr: PathBuf,
    pub plan: Plan,
}

/// Renders `plan` in one Blender process, with a progress bar fed by Blender's log.
pub fn render(
    blender: &Blender,
    plan: &Plan,
    groups: &GenerateParams,
    mode: Mode,
    timeout: u64,
    quiet: bool,
) -> Result<Rendered, Error> {
    let run_dir = crate::blender::runs::new_run_dir("verify")?;
    let exr = run_dir.join("sweep.exr");
    let params = plan.params(groups, mode, &exr);
    let script = run_dir.join("gloffuse-furnace.py");
    write_atomic(&script, assemble(&params, FURNACE_MAIN).as_bytes())?;
    let log = run_dir.join("blender.log");
    let run = Run {
        blender,
        script: &script,
        args: Vec::new(),
        timeout: Duration::from_secs(timeout),
        log: log.clone(),
    };
    let command = command_line(&run);

    let done = Arc::new(AtomicBool::new(false));
    let progress = (!quiet).then(|| {
        let bar = ProgressBar::new(plan.settings.samples as u64);
        bar.set_style(
            ProgressStyle::with_template(
                "{spinner} {msg} [{bar:30}] {pos}/{len} samples, {elapsed}",
            )
            .expect("valid template")
            .progress_chars("=> "),
        );
        bar.set_message(format!(
            "rendering {} spheres in Blender {}",
            plan.cells.len(),
            blender.version_string
        ));
        let (bar2, done2, log2) = (bar.clone(), done.clone(), log.clone());
        let watcher = std::thread::spawn(move || {
            while !done2.load(Ordering::Relaxed) {
                if let Some(s) = last_sample(&log2) {
                    bar2.set_position(s);
                }
                bar2.tick();
                std::thread::sleep(Duration::from_millis(200));
            }
        });
        (bar, watcher)
    });
    let outcome = run_script(&run);
    done.store(true, Ordering::Relaxed);
    if let Some((bar, watcher)) = progress {
        let _ = watcher.join();
        bar.finish_and_clear();
    }
    let out = outcome?;
    let image = read_rgba(&exr).map_err(|e| Error::Blender {
        message: e.to_string(),
        log: Some(log.clone()),
        command: Some(command.clone()),
    })?;
    let cell = plan.settings.cell as usize;
    let want = (plan.columns * cell, plan.rows() * cell);
    if (image.width, image.height) != want {
        return Err(Error::Blender {
            message: format!(
                "{} is {}×{} pixels; the plan needs {}×{}",
                exr.display(),
                image.width,
                image.height,
                want.0,
                want.1
            ),
            log: Some(log),
            command: Some(command),
        });
    }
    let stats = (0..plan.cells.len())
        .map(|i| sphere_stats(&image, i, plan.columns, cell, plan.settings.radius_fraction))
        .collect();
    let info = RenderInfo {
        blender_version: blender.version_string.clone(),
        blender_program: blender.program.display().to_string(),
        masking: blender.version.masking().to_string(),
        cell: plan.settings.cell,
        samples: plan.settings.samples,
        seed: plan.settings.seed,
        width: image.width,
        height: image.height,
        render_seconds: out.result["render_seconds"].as_f64().unwrap_or(out.seconds),
        log: log.display().to_string(),
        command,
    };
    Ok(Rendered {
        image,
        stats,
        info,
        exr,
        plan: plan.clone(),
    })
}

/// Rings with fewer fully covered pixels than this are too noisy to judge flatness by (at
/// 64 px per sphere, the outermost ring, μ ∈ [0.3, 0.4), holds 72 pixels: at 32 spp its
/// mean scatters by ±2 % in multiscatter mode, while at 512 spp every ring is within 0.3 %).
pub const MIN_RING_PIXELS: usize = 150;

/// The largest |ring mean − 100 %| over the view-cosine rings of a sphere.
fn worst_ring(s: &crate::furnace::stats::SphereStats) -> f64 {
    s.rings
        .iter()
        .filter(|r| r.pixels >= MIN_RING_PIXELS)
        .map(|r| (r.mean - 1.0).abs())
        .fold(0.0, f64::max)
}

/// The highest "Sample N/M" Cycles has logged so far.
fn last_sample(log: &Path) -> Option<u64> {
    let text = std::fs::read(log).ok()?;
    let text = String::from_utf8_lossy(&text);
    let at = text.rfind("Sample ")?;
    let rest = &text[at + 7..];
    let n: String = rest.chars().take_while(|c| c.is_ascii_digit()).collect();
    n.parse().ok()
}

/// Checks the arguments, finds Blender, then [`verify_with`].
pub fn verify(v: &VerifyArgs) -> Result<(VerifyReport, Rendered), Error> {
    check_args(v)?;
    // Coefficients are loaded (and --distribution checked against them) before Blender is
    // looked for: bad input fails fast.
    if let Some(c) = &v.coefficients {
        distributions_of(v, &Coefficients::load(c)?, c)?;
    }
    let blender = blender_from(&v.blender, v.json)?;
    verify_with(&blender, v)
}

fn check_args(v: &VerifyArgs) -> Result<(), Error> {
    let mut seen = Vec::new();
    for r in &v.roughness {
        if seen.contains(&r.get()) {
            return Err(Error::input(
                "--roughness",
                &r.get().to_string(),
                "each roughness once",
            ));
        }
        seen.push(r.get());
    }
    // The report directory is made if needed, so the nearest part of it that exists must
    // be a directory.
    if let Some(dir) = &v.report
        && let Some(file) = dir.ancestors().find(|a| a.exists() && !a.is_dir())
    {
        return Err(Error::Write {
            path: dir.clone(),
            message: if file == dir.as_path() {
                "--report needs a directory, and this is a file".into()
            } else {
                format!(
                    "--report needs a directory, but {} is a file",
                    file.display()
                )
            },
        });
    }
    Ok(())
}

/// The distributions to check (all in the coefficients unless --distribution names some),
/// each of which the coefficients must hold.
fn distributions_of(
    v: &VerifyArgs,
    coefficients: &Coefficients,
    source: &str,
) -> Result<Vec<Distribution>, Error> {
    if v.distribution.is_empty() {
        return Ok(coefficients.distributions.keys().copied().collect());
    }
    for d in &v.distribution {
        if !coefficients.distributions.contains_key(d) {
            let have: Vec<_> = coefficients.distributions.keys().map(|d| d.key()).collect();
            return Err(Error::input(
                "--distribution",
                d.key(),
                &format!("one the coefficients '{source}' hold: {}", have.join(", ")),
            ));
        }
    }
    Ok(v.distribution.clone())
}

/// Renders the verify sweep in `blender` and judges it.
pub fn verify_with(blender: &Blender, v: &VerifyArgs) -> Result<(VerifyReport, Rendered), Error> {
    check_args(v)?;
    let seen: Vec<f64> = v.roughness.iter().map(|r| r.get()).collect();
    let explicit = v
        .coefficients
        .as_ref()
        .map(|c| Coefficients::load(c))
        .transpose()?;
    let (coefficients, source) = match (explicit, &v.coefficients) {
        (Some(c), Some(name)) => (c, name.clone()),
        _ => {
            let name = blender.version.preset_name();
            (Coefficients::load(name)?, name.to_string())
        }
    };
    let distributions = distributions_of(v, &coefficients, &source)?;
    let settings = RenderSettings {
        cell: v.resolution,
        samples: v.spp,
        seed: v.seed,
        ..RenderSettings::default()
    };
    let plan = Plan::verify(&distributions, &seen, settings, true);
    let masking = blender.version.masking();
    let mut groups = GenerateParams::new(&coefficients, &source);
    if v.mode != Mode::Roughness {
        groups = groups.with_view(masking);
    }
    let rendered = render(blender, &plan, &groups, v.mode, v.blender.timeout, v.json)?;

    let integrator = AlbedoIntegrator::default();
    let tolerance = v.tolerance / 100.0;
    let find = |role: Role, r: f64| {
        plan.cells
            .iter()
            .position(|c| c.role == role && c.roughness == r)
            .map(|i| rendered.stats[i].clone())
            .expect("the plan holds every role at every roughness")
    };
    let mut rows = Vec::new();
    for &d in &distributions {
        let curve = &coefficients.distributions[&d].curve;
        for &r in &seen {
            let e_avg = integrator.average_albedo(&Glossy::new(d, masking, Roughness::new(r)?));
            let corrected = find(Role::Corrected(d), r);
            let worst_ring = worst_ring(&corrected);
            let rings_flat = v.mode == Mode::Roughness || worst_ring <= v.ring_tolerance / 100.0;
            rows.push(Row {
                distribution: d,
                roughness: r,
                uncorrected: find(Role::Uncorrected(d), r),
                pass: (corrected.mean - 1.0).abs() <= tolerance && rings_flat,
                worst_ring,
                corrected,
                predicted_uncorrected: e_avg,
                predicted_corrected: match v.mode {
                    Mode::Roughness => curve.gain(r) * e_avg,
                    Mode::View | Mode::Multiscatter => 1.0,
                },
            });
        }
    }
    let reference = seen
        .iter()
        .map(|&r| ReferenceSphere {
            roughness: r,
            stats: find(Role::Reference, r),
        })
        .collect();
    let pass = rows.iter().all(|r| r.pass);
    let mut notes = Vec::new();
    for (d, e) in &coefficients.distributions {
        if e.masking != masking && e.color_space == ColorSpace::Linear && distributions.contains(d)
        {
            notes.push(format!(
                "{}: the coefficients were fitted for {} masking, but Blender {} uses {} masking; use --coefficients {}.",
                d.label(), e.masking, blender.version, masking, blender.version.preset_name()
            ));
        }
    }
    if coefficients
        .distributions
        .values()
        .any(|e| e.color_space == ColorSpace::Display)
    {
        let worst = rows.iter().filter(|r| !r.pass).max_by(|a, b| {
            (a.corrected.mean - 1.0)
                .abs()
                .total_cmp(&(b.corrected.mean - 1.0).abs())
        });
        let mut note = format!(
            "The coefficients '{source}' are display-referred: their percentages are sRGB-encoded brightness read off a screen (sRGB(0.305) ≈ 0.59 is GGX's centre at r = 1), but a shader gain acts on linear light, so 100/f(r) under-corrects rough spheres."
        );
        if let Some(w) = worst {
            note.push_str(&format!(
                " Worst: {} r = {} comes out at {:.1} % (gain {:.3}; 1/E_avg = {:.3} is needed).",
                w.distribution.label(),
                w.roughness,
                100.0 * w.corrected.mean,
                coefficients.distributions[&w.distribution]
                    .curve
                    .gain(w.roughness),
                1.0 / w.predicted_uncorrected
            ));
        }
        notes.push(note);
    }
    let report = VerifyReport {
        coefficients: source,
        mode: v.mode,
        ring_tolerance_percent: v.ring_tolerance,
        render: rendered.info.clone(),
        tolerance_percent: v.tolerance,
        rows,
        reference,
        notes,
        pass,
    };
    Ok((report, rendered))
}

/// The terminal table.
pub fn table(report: &VerifyReport) -> String {
    use std::fmt::Write as _;
    let i = &report.render;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "Blender {} ({} masking) · coefficients {} · {} px per sphere, {} spp, seed {} · rendered in {:.1} s",
        i.blender_version,
        i.masking,
        report.coefficients,
        i.cell,
        i.samples,
        i.seed,
        i.render_seconds
    );
    let _ = writeln!(
        s,
        "{:<18} {:>5} {:>12} {:>11} {:>7} {:>10} {:>7} {:>8}  status",
        "distribution", "r", "uncorrected", "corrected", "±SE", "predicted", "centre", "ring Δ"
    );
    for r in &report.rows {
        let _ = writeln!(
            s,
            "{:<18} {:>5} {:>11.2}% {:>10.2}% {:>6.2}% {:>9.2}% {:>6.1}% {:>7.2}%  {}",
            r.distribution.label(),
            r.roughness,
            100.0 * r.uncorrected.mean,
            100.0 * r.corrected.mean,
            100.0 * r.corrected.standard_error,
            100.0 * r.predicted_corrected,
            100.0 * r.corrected.center,
            100.0 * r.worst_ring,
            if r.pass { "ok" } else { "FAIL" }
        );
    }
    for r in &report.reference {
        let _ = writeln!(
            s,
            "{:<18} {:>5} {:>11.2}% {:>10} {:>6.2}% {:>10} {:>6.1}%  reference",
            "Multiscatter GGX",
            r.roughness,
            100.0 * r.stats.mean,
            "",
            100.0 * r.stats.standard_error,
            "",
            100.0 * r.stats.center
        );
    }
    let failed = report.rows.iter().filter(|r| !r.pass).count();
    let rings = match report.mode {
        Mode::Roughness => String::new(),
        _ => format!(
            ", every view-cosine ring within ±{} %",
            report.ring_tolerance_percent
        ),
    };
    let _ = writeln!(
        s,
        "{}: {} of {} corrected spheres ({:?} mode) within ±{} % of 100 %{rings}",
        if report.pass { "PASS" } else { "FAIL" },
        report.rows.len() - failed,
        report.rows.len(),
        report.mode,
        report.tolerance_percent
    );
    for n in &report.notes {
        let _ = writeln!(s, "note: {n}");
    }
    if !report.pass {
        let _ = writeln!(s, "log: {}\nrerun: {}", i.log, i.command);
    }
    s
}

/// Writes report.json, sweep.exr, contact-sheet.png and brightness.png into `dir`
/// (created if needed).
pub fn write_report_files(
    dir: &Path,
    report: &VerifyReport,
    rendered: &Rendered,
) -> Result<Vec<PathBuf>, Error> {
    std::fs::create_dir_all(dir).map_err(|e| Error::Write {
        path: dir.to_path_buf(),
        message: e.to_string(),
    })?;
    let json_path = dir.join("report.json");
    write_atomic(
        &json_path,
        (serde_json::to_string_pretty(report).expect("json") + "\n").as_bytes(),
    )?;
    let exr_path = dir.join("sweep.exr");
    let bytes = std::fs::read(&rendered.exr).map_err(|source| Error::Read {
        path: rendered.exr.clone(),
        source,
    })?;
    write_atomic(&exr_path, &bytes)?;
    let sheet = dir.join("contact-sheet.png");
    let (rows, columns) = crate::furnace::png::sheet_labels(&rendered.plan);
    crate::furnace::png::contact_sheet(
        &rendered.image,
        rendered.plan.settings.cell as usize,
        &rows,
        &columns,
        &sheet,
    )?;
    let plot = dir.join("brightness.png");
    crate::furnace::png::brightness_plot(report, &plot)?;
    Ok(vec![json_path, exr_path, sheet, plot])
}
