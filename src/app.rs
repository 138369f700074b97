//! Runs a parsed command: calls the library for data, then prints it (text or JSON).

use serde_json::json;
use std::fmt::Write as _;

use crate::Error;
use crate::cli::{AlbedoArgs, Cli, CoefficientsCommand, Command, FitArgs};
use crate::coefficients::{
    self, Coefficients, ColorSpace, Entry, FORMAT, FORMAT_VERSION, PRESETS, Provenance, Target,
};
use crate::fit::{Curve, Fit, Variable, fit_polynomial};
use crate::microfacet::{AlbedoIntegrator, Glossy};
use crate::output::write_atomic;

/// Degree of `fit --from integrator`: the lowest that keeps every distribution's gain
/// within 0.1 % of 1/E_avg (measured; see README).
pub const INTEGRATOR_DEGREE: usize = 6;

/// What a command produced: the process exit code (0, or 1 when a check failed).
pub fn run(cli: Cli) -> Result<i32, Error> {
    match cli.command {
        Command::Albedo(a) => albedo(a),
        Command::Fit(f) => fit(f),
        Command::Generate(g) => {
            let out = crate::generate::generate(&g)?;
            if g.json {
                print_json(&out);
            } else {
                if let Some(p) = &out.script {
                    println!("script: {}", p.display());
                }
                if let Some(p) = &out.blend {
                    println!(
                        "blend:  {} (Blender {})",
                        p.display(),
                        out.blender.as_deref().unwrap_or("?")
                    );
                }
                if let Some(p) = &out.backup {
                    println!("backup: {}", p.display());
                }
                println!("coefficients: {}", out.coefficients);
                println!("groups: {}", out.groups.join(", "));
            }
            Ok(0)
        }
        Command::Verify(v) => {
            let (report, rendered) = crate::verify::verify(&v)?;
            if let Some(dir) = &v.report {
                let written = crate::verify::write_report_files(dir, &report, &rendered)?;
                for p in written {
                    eprintln!("wrote {}", p.display());
                }
            }
            if v.json {
                print_json(&report);
            } else {
                print!("{}", crate::verify::table(&report));
            }
            Ok(if report.pass { 0 } else { 1 })
        }
        Command::Refresh(a) => {
            let r = crate::refresh::refresh(&a)?;
            if a.json {
                print_json(&r);
            } else {
                print!("{}", crate::refresh::table(&r));
                if let Some(v) = &r.verify {
                    print!("\n{}", crate::verify::table(v));
                }
            }
            Ok(match &r.verify {
                Some(v) if !v.pass => 1,
                _ => 0,
            })
        }
        Command::Lut(l) => {
            let summary = crate::lut::lut(&l)?;
            if l.json {
                print_json(&summary);
            } else {
                print!("{}", crate::lut::describe(&summary));
            }
            Ok(0)
        }
        Command::Bench(b) => {
            let r = crate::refresh::bench(&b)?;
            println!(
                "{} spheres: one Blender process {:.1} s, one process per sphere {:.1} s: {:.1}× faster",
                r.spheres, r.one_process_seconds, r.per_sphere_seconds, r.ratio
            );
            Ok(0)
        }
        Command::Coefficients {
            action: CoefficientsCommand::Show { source, json },
        } => show(source, json),
    }
}

/// Prints `value` as pretty JSON on stdout (`--json`). Our reports are plain data, so
/// serialising them cannot fail.
fn print_json(value: &impl serde::Serialize) {
    println!(
        "{}",
        serde_json::to_string_pretty(value).expect("reports serialise to JSON")
    );
}

fn albedo(a: AlbedoArgs) -> Result<i32, Error> {
    if let Some(model) = a.model {
        return model_albedo(&a, model);
    }
    let distribution = a
        .distribution
        .expect("clap requires --distribution without --model");
    let masking = a.blender_version.masking();
    let integrator = AlbedoIntegrator::default();
    if let Some(path) = &a.table {
        // A bad destination fails before minutes of integration, not after.
        crate::output::check_destination(path)?;
        let n = a.grid as usize;
        let rs: Vec<f64> = (0..n).map(|j| j as f64 / (n - 1) as f64).collect();
        let mus: Vec<f64> = (0..n).map(|i| (i as f64 + 0.5) / n as f64).collect();
        let make = |r: f64| Glossy {
            distribution,
            masking,
            alpha: r * r,
        };
        let e = integrator.table(make, &mus, &rs);
        let avg = integrator.average_table(make, &rs);
        let mut csv = String::from("roughness,mu,albedo,average_albedo\n");
        for (i, mu) in mus.iter().enumerate() {
            for (j, r) in rs.iter().enumerate() {
                let _ = writeln!(csv, "{r},{mu},{},{}", e[i * n + j], avg[j]);
            }
        }
        write_atomic(path, csv.as_bytes())?;
        eprintln!(
            "wrote {} ({n}×{n} grid, {} masking, Blender {})",
            path.display(),
            masking,
            a.blender_version
        );
        return Ok(0);
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
        print_json(&v);
    } else {
        println!(
            "{} roughness {} (alpha {}), Blender {} ({} masking)",
            distribution.label(),
            roughness.get(),
            roughness.alpha(),
            a.blender_version,
            masking
        );
        println!(
            "E(mu = {}) = {e:.6}   brightness at view cosine {} ({:.2} %)",
            a.mu,
            a.mu,
            100.0 * e
        );
        println!(
            "E_avg      = {avg:.6}   mean brightness of a furnace sphere ({:.2} %)",
            100.0 * avg
        );
    }
    Ok(0)
}

fn fit(f: FitArgs) -> Result<i32, Error> {
    if let Some(path) = &f.out {
        crate::output::check_destination(path)?;
    }
    let coefficients = if f.from.is_some() {
        if f.distribution.is_some() {
            return Err(Error::input(
                "--distribution",
                &f.distribution.map(|d| d.to_string()).unwrap_or_default(),
                "nothing with --from integrator (it fits all three distributions)",
            ));
        }
        let degree = f.degree.unwrap_or(INTEGRATOR_DEGREE);
        Coefficients::from_integrator(
            f.blender_version,
            degree,
            f.target,
            f.weighting,
            Some(coefficients::today()),
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
            ));
        }
        let degree = f.degree.unwrap_or(3);
        let Fit { curve, residuals } =
            fit_polynomial(&f.points, Variable::Roughness, degree, f.weighting)?;
        let entry = Entry {
            degree,
            curve,
            target: f.target,
            color_space: ColorSpace::Linear,
            masking: f.blender_version.masking(),
            weighting: f.weighting,
            residuals,
            provenance: Provenance {
                source: "points".into(),
                blender_version: None,
                samples: None,
                resolution: None,
                points: f.points.len(),
                date: Some(coefficients::today()),
                note: Some(
                    f.points
                        .iter()
                        .map(|p| format!("{}:{}", p.roughness, p.percent))
                        .collect::<Vec<_>>()
                        .join(" "),
                ),
            },
        };
        Coefficients {
            format: FORMAT.into(),
            format_version: FORMAT_VERSION,
            name: format!("{d} fit"),
            description: format!("Fitted by hand to {} points.", f.points.len()),
            distributions: [(d, entry)].into_iter().collect(),
        }
    };
    if let Some(path) = &f.out {
        // Re-validate exactly what is written: a curve reaching 0 on [0, 1] is refused.
        let text = coefficients.to_json();
        Coefficients::parse(&text, &path.display().to_string())?;
        write_atomic(path, text.as_bytes())?;
        eprintln!("wrote {}", path.display());
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
        print_json(&json!({ "fits": list }));
    } else {
        for (d, e) in &coefficients.distributions {
            print!("{}", describe_entry(d.label(), e));
        }
    }
    Ok(0)
}

/// `f(r) = −34 r³ + 5 r² + 100` style text for a polynomial curve.
pub fn formula(curve: &Curve) -> String {
    let var = match curve.variable {
        Variable::Roughness => "r",
        Variable::Alpha => "α",
    };
    let poly = |c: &[f64]| {
        let mut terms = Vec::new();
        for (k, &v) in c.iter().enumerate().rev() {
            if v == 0.0 && k != 0 {
                continue;
            }
            let t = match k {
                0 => fmt_num(v.abs()),
                1 => format!("{} {var}", fmt_num(v.abs())),
                _ => format!("{} {var}^{k}", fmt_num(v.abs())),
            };
            let sign = if v < 0.0 { "−" } else { "+" };
            terms.push((sign, t));
        }
        let mut s = String::new();
        for (i, (sign, t)) in terms.iter().enumerate() {
            if i == 0 {
                if *sign == "−" {
                    s.push('−');
                }
            } else {
                let _ = write!(s, " {sign} ");
            }
            s.push_str(t);
        }
        s
    };
    if curve.denominator == [1.0] {
        poly(&curve.numerator)
    } else {
        format!(
            "({}) / ({})",
            poly(&curve.numerator),
            poly(&curve.denominator)
        )
    }
}

fn fmt_num(v: f64) -> String {
    let s = format!("{v:.6}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    s.to_string()
}

fn describe_entry(label: &str, e: &Entry) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "{label}: f(r) = {}", formula(&e.curve));
    if e.curve.variable == Variable::Roughness && e.curve.denominator == [1.0] {
        let n = &e.curve.numerator;
        let c = |k: usize| n.get(k).copied().unwrap_or(0.0);
        let mut line = format!(
            "  a = {}, b = {}, c = {}, d = {}",
            fmt_num_signed(c(3)),
            fmt_num_signed(c(2)),
            fmt_num_signed(c(1)),
            fmt_num_signed(c(0))
        );
        for k in 4..n.len() {
            let _ = write!(line, ", r^{k}: {}", fmt_num_signed(c(k)));
        }
        let _ = writeln!(s, "{line}");
    }
    let _ = writeln!(
        s,
        "  degree {}, target {}, {} colour, {} masking, {} weighting",
        e.degree,
        match e.target {
            Target::Mean => "mean (E_avg)",
            Target::Center => "centre (E(1, r))",
        },
        match e.color_space {
            ColorSpace::Linear => "linear",
            ColorSpace::Display => "display-referred (sRGB)",
        },
        e.masking,
        match e.weighting {
            crate::fit::Weighting::Absolute => "absolute",
            crate::fit::Weighting::Relative => "relative",
        }
    );
    let r = &e.residuals;
    let _ = writeln!(
        s,
        "  residuals: max {:.4} points (rms {:.4}); gain error max {:.4} % (rms {:.4} %)",
        r.max_points,
        r.rms_points,
        100.0 * r.max_gain_error,
        100.0 * r.rms_gain_error
    );
    let p = &e.provenance;
    let mut prov = format!("  from {} ({} points", p.source, p.points);
    if let Some(v) = &p.blender_version {
        let _ = write!(prov, ", Blender {v}");
    }
    if let Some(v) = &p.samples {
        let _ = write!(prov, ", {v}");
    }
    if let Some(v) = p.resolution {
        let _ = write!(prov, ", {v} px");
    }
    if let Some(v) = &p.date {
        let _ = write!(prov, ", {v}");
    }
    prov.push(')');
    if let Some(n) = &p.note {
        let _ = write!(prov, ": {n}");
    }
    let _ = writeln!(s, "{prov}");
    let gains: Vec<String> = [0.25, 0.5, 0.75, 1.0]
        .iter()
        .map(|&r| format!("r={r}: {:.4}", e.curve.gain(r)))
        .collect();
    let _ = writeln!(s, "  gain 100/f: {}", gains.join(", "));
    s
}

fn fmt_num_signed(v: f64) -> String {
    if v < 0.0 {
        format!("-{}", fmt_num(-v))
    } else {
        fmt_num(v)
    }
}

fn show(source: Option<String>, json: bool) -> Result<i32, Error> {
    let Some(source) = source else {
        println!("Built-in presets (gloffuse coefficients show NAME):");
        for (name, _, summary) in PRESETS {
            println!("  {name:<10} {summary}");
        }
        return Ok(0);
    };
    let c = Coefficients::load(&source)?;
    if json {
        print!("{}", c.to_json());
        return Ok(0);
    }
    println!("{} — {}", c.name, c.description);
    for (d, e) in &c.distributions {
        print!("{}", describe_entry(d.label(), e));
    }
    Ok(0)
}

/// `albedo --model`: directional albedo of a classic BRDF, and its hemispherical average.
fn model_albedo(a: &AlbedoArgs, model: crate::brdf::Model) -> Result<i32, Error> {
    let params = crate::brdf::ModelParams {
        rho: a.rho,
        rs: a.rs,
        exponent: a.exponent,
        alpha_x: a.alpha_x,
        alpha_y: a.alpha_y,
    };
    let e = crate::brdf::model_albedo(model, &params, a.mu)?;
    // E_avg = 2∫E(μ)μdμ by a 16-point midpoint rule in μ².
    let n = 16;
    let avg = (0..n)
        .map(|i| {
            let mu = ((i as f64 + 0.5) / n as f64).sqrt();
            crate::brdf::model_albedo(model, &params, mu).map(|e| e / n as f64)
        })
        .sum::<Result<f64, Error>>()?;
    if a.json {
        let v = json!({
            "model": format!("{model:?}"),
            "parameters": { "rho": a.rho, "rs": a.rs, "exponent": a.exponent, "alpha_x": a.alpha_x, "alpha_y": a.alpha_y },
            "mu": a.mu,
            "directional_albedo": e,
            "average_albedo": avg,
        });
        print_json(&v);
    } else {
        println!(
            "{model:?} (rho {}, rs {}, exponent {}, alpha {} × {})",
            a.rho, a.rs, a.exponent, a.alpha_x, a.alpha_y
        );
        println!("E(mu = {}) = {e:.6}", a.mu);
        println!("E_avg      = {avg:.6}");
    }
    Ok(0)
}
