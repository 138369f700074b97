//! What the commands print as text: every rendering for a person, in one file. (The verify
//! table is a renderer of the verdict and lives with the others in `gloffuse::report::verify`.)

use std::fmt::Write as _;

use gloffuse::albedo::Albedo;
use gloffuse::fit::coefficients::Entry;
use gloffuse::fit::{ColorSpace, Curve, Shown, Target, Variable, Weighting};
use gloffuse::generate::Generated;
use gloffuse::lut::LutSummary;
use gloffuse::plural::count;
use gloffuse::refresh::Refreshed;
use gloffuse::report::escape::terminal;
use gloffuse::verify::VerifyReport;

/// The summary `generate` prints.
pub fn generated(out: &Generated) -> String {
    let mut s = String::new();
    if let Some(p) = &out.script {
        let _ = writeln!(s, "script: {}", p.display());
    }
    if let Some(p) = &out.blend {
        let _ = writeln!(
            s,
            "blend:  {} (Blender {})",
            p.display(),
            out.blender.as_deref().unwrap_or("?")
        );
    }
    if let Some(p) = &out.backup {
        let _ = writeln!(s, "backup: {}", p.display());
    }
    if let Some(p) = &out.catalogs {
        let _ = writeln!(s, "catalogs: {}", p.display());
    }
    if let Some(p) = &out.extension {
        let _ = writeln!(s, "extension: {}", p.display());
    }
    if let Some(p) = &out.addon {
        let _ = writeln!(s, "add-on: {}", p.display());
    }
    let _ = writeln!(s, "coefficients: {}", out.coefficients);
    if let Some(suits) = &out.suits {
        let _ = writeln!(s, "suits: {suits}");
    }
    let _ = writeln!(s, "groups: {}", out.groups.join(", "));
    for r in &out.renamed {
        let _ = writeln!(
            s,
            "renamed: your group '{}' (not made by gloffuse) is now '{}'; materials using it \
             still do",
            terminal(&r.group),
            terminal(&r.renamed_to)
        );
    }
    s
}

/// The verify table, then the flag for each preset a note suggests (the library's notes
/// name presets; only the command line knows its flags).
pub fn verify(report: &VerifyReport) -> String {
    let mut s = gloffuse::report::verify::table::render(report);
    let mut presets: Vec<&str> = report
        .notes
        .iter()
        .filter_map(|n| n.suggested_preset())
        .collect();
    presets.dedup();
    for p in presets {
        let _ = writeln!(s, "hint: rerun with --coefficients {p}");
    }
    s
}

/// The measured curve beside the prediction, the warnings, then the verify table.
pub fn refresh(r: &Refreshed) -> String {
    let mut s = format!(
        "Blender {}: measured furnace sphere means vs the integrator\n",
        r.blender_version
    );
    let _ = writeln!(
        s,
        "{:<18} {:>5} {:>9} {:>7} {:>10} {:>7}",
        "distribution", "r", "measured", "±SE", "predicted", "diff"
    );
    for m in &r.measurements {
        let _ = writeln!(
            s,
            "{:<18} {:>5} {:>8.2}% {:>6.2}% {:>9.2}% {:>+6.2}%",
            m.distribution.label(),
            m.roughness,
            100.0 * m.measured,
            100.0 * m.standard_error,
            100.0 * m.predicted,
            100.0 * (m.measured / m.predicted - 1.0)
        );
    }
    for w in &r.warnings {
        let _ = writeln!(s, "warning: {w}");
    }
    let _ = writeln!(s, "wrote {}", r.out);
    if let Some(v) = &r.verify {
        let _ = write!(s, "\n{}", verify(v));
    }
    s
}

/// The human-readable summary `gloffuse lut` prints.
pub fn lut(s: &LutSummary) -> String {
    let mut out = format!(
        "wrote {} ({} bytes): {} {}×{} {}, {} {}-bit\n",
        s.path.display(),
        s.bytes,
        s.kind.key(),
        s.width,
        s.height,
        s.format.key(),
        s.pixel_format,
        s.bits.count(),
    );
    let mut how = vec![match s.samples {
        Some(n) => format!("{n} samples per texel"),
        None => "deterministic quadrature".to_string(),
    }];
    if let Some(g) = s.g_model {
        how.push(format!("{} masking", g.key()));
    }
    if s.method == Some(gloffuse::lut::Method::Classic) {
        how.push("classic (UE4) estimator".to_string());
    }
    if let Some(d) = s.distribution {
        how.push(format!("{d}"));
    }
    if let Some(v) = &s.blender_version {
        how.push(format!("Blender {v}"));
    }
    out += &format!("  {}\n", how.join(", "));
    for c in &s.channels {
        out += &format!("  {c}\n");
    }
    match (&s.azimuths, &s.ior) {
        (Some(azimuths), _) => {
            let n = s.width / azimuths.len().max(1);
            let list: Vec<String> = azimuths
                .iter()
                .map(|v| format!("{:.1}°", v.to_degrees()))
                .collect();
            out += &format!(
                "  {} columns × {n} rows of {n}×{n} slices; column k at view azimuth {} from the tangent\n",
                azimuths.len(),
                list.join(", ")
            );
            out += &format!(
                "  row l at ry = l/{m}; in a slice, texel (x, y) at rx = (x − {n}k)/{m}, N·V = (y − {n}l)/{m} (grid points: sample at u = (rx·{m} + ½)/{n}); αx = rx², αy = ry²; first row first\n",
                m = n - 1
            );
        }
        (None, Some(ior)) => {
            let n = s.width / ior.len().max(1);
            let list: Vec<String> = ior.iter().map(|v| format!("{v:.3}")).collect();
            out += &format!(
                "  {} slices of {n}×{n} side by side, slice k at IOR {}\n",
                ior.len(),
                list.join(", ")
            );
            out += &format!(
                "  in slice k, texel (x, y) at roughness (x − {n}k + ½)/{n}, N·V (y + ½)/{n}, first row first\n"
            );
            if s.height == 2 * n {
                out += &glass_rows(n);
            }
        }
        (None, None) => {
            out += &format!(
                "  uv = (roughness, N·V); texel (x, y) at ((x + ½)/{}, (y + ½)/{}), first row first\n",
                s.width, s.height
            );
        }
    }
    out += &format!(
        "  computed in {:.2} s ({:.2} s in all)\n",
        s.compute_seconds, s.seconds
    );
    out
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

/// One distribution's curve, its fit and where it came from, as `fit` and
/// `coefficients show` print it.
pub fn entry(label: &str, e: &Entry) -> String {
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
            Weighting::Absolute => "absolute",
            Weighting::Relative => "relative",
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
    let mut prov = format!("  from {} ({} points", p.source.key(), p.points);
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

/// What `albedo` prints for one surface.
pub fn albedo(a: &Albedo) -> String {
    let mut s = String::new();
    match a {
        Albedo::Glossy {
            alpha,
            average_albedo,
            blender_version,
            directional_albedo: e,
            distribution,
            masking,
            mu,
            roughness,
        } => {
            let _ = writeln!(
                s,
                "{} roughness {roughness} (alpha {alpha}), Blender {blender_version} ({masking} masking)",
                distribution.label()
            );
            let _ = writeln!(
                s,
                "E(mu = {mu}) = {e:.6}   brightness at view cosine {mu} ({:.2} %)",
                100.0 * e
            );
            let _ = writeln!(
                s,
                "E_avg      = {average_albedo:.6}   mean brightness of a furnace sphere ({:.2} %)",
                100.0 * average_albedo
            );
        }
        Albedo::Model {
            average_albedo,
            directional_albedo: e,
            model,
            mu,
            parameters: p,
        } => {
            let _ = writeln!(
                s,
                "{model:?} (rho {}, rs {}, exponent {}, alpha {} × {})",
                p.rho, p.rs, p.exponent, p.alpha_x, p.alpha_y
            );
            let _ = writeln!(s, "E(mu = {mu}) = {e:.6}");
            let _ = writeln!(s, "E_avg      = {average_albedo:.6}");
        }
    }
    s
}

/// What `coefficients show` prints: the presets, or one set of coefficients.
pub fn shown(shown: &Shown) -> String {
    let mut s = String::new();
    match shown {
        Shown::Presets(presets) => {
            s.push_str("Built-in presets (gloffuse coefficients show NAME):\n");
            for (name, summary) in presets {
                let _ = writeln!(s, "  {name:<10} {summary}");
            }
        }
        Shown::Coefficients(c) => {
            let _ = writeln!(s, "{} — {}", c.name, c.description);
            for (d, e) in &c.distributions {
                s.push_str(&entry(d.label(), e));
            }
        }
    }
    s
}

/// The audit benchmark: materials per second per library size, one process per file beside
/// one process per material.
pub fn bench_audit(r: &gloffuse::bench::audit::AuditBenchResult) -> String {
    let mut s = format!(
        "audit in Blender {} ({} px, {} spp), wall time with Blender's start:\n\n\
         {:>9}  {:>14}  {:>12}  {:>14}  {:>16}\n",
        r.blender_version,
        r.cell,
        r.samples,
        "materials",
        "one process",
        "materials/s",
        "rules alone",
        "scan per 1,000"
    );
    for t in &r.sizes {
        s.push_str(&format!(
            "{:>9}  {:>12.1} s  {:>12.2}  {:>12.1} s  {:>14.2} s\n",
            t.materials,
            t.seconds,
            t.materials_per_second,
            t.rules_seconds,
            t.scan_seconds_per_1000
        ));
    }
    let p = &r.per_material;
    let best = r
        .sizes
        .iter()
        .map(|t| t.materials_per_second)
        .fold(f64::NAN, f64::max);
    s.push_str(&format!(
        "\none process per material ({}): {:.1} s, {:.2} materials/s \
         (one process per file is {:.1}× faster at its best)\n",
        count(p.materials, "material", "materials"),
        p.seconds,
        p.materials_per_second,
        best / p.materials_per_second
    ));
    s
}

pub fn bench_shards(r: &gloffuse::bench::shards::ShardBenchResult) -> String {
    format!(
        "sharded audit in Blender {} ({} px, {} spp): {} of {}\n\
         \n  one run:            {:>7.1} s\n  {} at once:   {:>7.1} s   {:.2}× faster\n\
         \ncost model: a file takes {:.2} s to start (Blender and the twins' tables) plus \
         {:.3} s per material\n",
        r.blender_version,
        r.cell,
        r.samples,
        count(r.files, "file", "files"),
        count(r.materials_per_file, "material", "materials"),
        r.one_run_seconds,
        count(r.shards, "shard", "shards"),
        r.sharded_seconds,
        r.speedup,
        r.start_seconds,
        r.per_material_seconds
    )
}

/// The glass atlas's two rows of slices, entering and leaving.
fn glass_rows(n: usize) -> String {
    format!(
        "  two rows of slices: rows 0–{} light entering (η = IOR), rows {n}–{} leaving (η = 1/IOR, N·V (y − {n} + ½)/{n})\n",
        n - 1,
        2 * n - 1
    )
}
