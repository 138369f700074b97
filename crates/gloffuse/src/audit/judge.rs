//! From a job's result and its rendered grid to verdicts: each material's brightness and its
//! twin's, its findings worded from the catalogue, and `ok`, `loses`, `creates` or `error`.

use super::fix_choice;
use super::job::{JobFinding, JobMaterial, JobRun};
use super::rules::{Effect, Predictor, rule};
use super::verdict::{AuditJudging, AuditedMaterial, Brightness, Finding, Verdict};
use super::waivers::{self, Policy};
use crate::Error;
use crate::verify::image::Rgba;
use crate::verify::stats::{SphereStats, sphere_stats};

/// Standard errors a difference may be off by noise alone before it counts.
const NOISE_SIGMAS: f64 = 3.0;

/// A sphere less opaque than this over its disc is invisible: the world is seen through it
/// everywhere (Alpha 0, a Transparent BSDF, a holdout), and there is nothing to judge.
const MIN_OPACITY: f64 = 0.02;

/// A mean below this, with a node the audit does not know, is that node failing to render.
const BLACK: f64 = 0.01;

/// The rendered grid of one file.
pub struct Grid<'a> {
    pub image: &'a Rgba,
    pub columns: usize,
    pub cell: usize,
    pub radius_fraction: f64,
}

/// Checks that the job's grid (its columns, every material's cells) is the image's: as
/// wide as its columns of `cell` pixels, every cell inside. A job whose result and image
/// disagree is the file's error, never judged (a cell outside the image would read as a
/// sphere that rendered nothing).
pub fn check_grid(job: &JobRun, image: Option<&Rgba>, cell: u32) -> Result<(), Error> {
    let Some(image) = image else {
        return Ok(());
    };
    let columns = job.result.columns.unwrap_or(0);
    let outside = job
        .result
        .materials
        .iter()
        .flat_map(|m| [m.cell, m.twin_cell])
        .flatten()
        .find(|&i| image.cell_origin(columns, cell as usize, i).is_none());
    let what = match outside {
        Some(index) => format!("cell {index}"),
        None if columns.checked_mul(cell as usize) != Some(image.width) => "the width".into(),
        None => return Ok(()),
    };
    Err(Error::Blender {
        message: format!(
            "the furnace image ({} x {} px) does not hold {what} of the job's grid ({columns} \
             columns of {cell} px)",
            image.width, image.height
        )
        .into(),
        log: Some(job.log.clone()),
        command: None,
    })
}

impl Grid<'_> {
    /// The sphere in cell `index` as the furnace shows it (a partly transparent one with
    /// the world seen through it); `None` when it is invisible.
    fn brightness(&self, index: usize) -> Option<Brightness> {
        let s: SphereStats = sphere_stats(
            self.image,
            index,
            self.columns,
            self.cell,
            self.radius_fraction,
        );
        if s.opacity.is_nan() || s.opacity < MIN_OPACITY || !s.mean.is_finite() {
            return None;
        }
        let rings = s.rings.iter().filter(|r| r.mean.is_finite());
        let floors = rings
            .clone()
            .filter(|r| r.standard_error.is_finite())
            .map(|r| r.mean - NOISE_SIGMAS * r.standard_error);
        Some(Brightness {
            mean: s.seen(),
            center: s.center,
            rim: s.rim,
            max_ring: rings.map(|r| r.mean).fold(f64::NEG_INFINITY, f64::max),
            ring_floor: floors.fold(f64::NEG_INFINITY, f64::max),
            standard_error: s.standard_error,
            opacity: s.opacity,
        })
    }
}

/// A job's finding in words: the catalogue's why and fix, the rule's versions, and the
/// integrator's prediction where it knows the lobe.
pub fn word(f: &JobFinding, predictor: &mut Predictor) -> Finding {
    let known = rule(&f.rule);
    let predicted = predictor.predict(&f.rule, &f.detail);
    let mut why = known.map_or_else(
        || "a rule this gloffuse does not know".to_string(),
        |r| r.why.to_string(),
    );
    if let Some(said) = f.detail["blender_said"].as_str() {
        why = format!("{why} (Blender said “{said}”)");
    }
    if let Some(read) = pbr_values(&f.detail) {
        why = format!("{why}: {read}");
    }
    if let Some(p) = predicted {
        why.push_str(&format!(
            "; the integrator predicts {:.1} % for this lobe",
            100.0 * p
        ));
    }
    Finding {
        rule: f.rule.clone(),
        node: f.node.join(" ▸ "),
        node_path: f.node.clone(),
        node_type: f.node_type.clone(),
        kind: known.map_or(Effect::Info, |r| r.effect),
        versions: known.map_or_else(String::new, |r| r.versions()),
        why,
        fix: known.map_or_else(String::new, |r| r.fix.to_string()),
        predicted,
        twin: f.twin.clone(),
        detail: f.detail.clone(),
        severity: known.map_or_else(Default::default, |r| r.severity),
        waived: None,
    }
}

/// What a PBR range rule read off the node, in the charts' sRGB units: "Base Color sRGB
/// 29.0, 29.0, 29.0 (luminance 29.0), Metallic 0, below the strict floor (30)".
fn pbr_values(detail: &serde_json::Value) -> Option<String> {
    let srgb: Vec<String> = detail["srgb"]
        .as_array()?
        .iter()
        .map(|c| format!("{:.1}", c.as_f64().unwrap_or(f64::NAN)))
        .collect();
    let mut words = format!(
        "{} sRGB {} (luminance {:.1})",
        detail["input"].as_str().unwrap_or("colour"),
        srgb.join(", "),
        detail["luminance"].as_f64().unwrap_or(f64::NAN)
    );
    if let Some(m) = detail["metallic"].as_f64() {
        words.push_str(&format!(", Metallic {m}"));
    }
    if detail["strict"] == true {
        words.push_str(", below the strict floor (30)");
    }
    Some(words)
}

fn pct(x: f64) -> String {
    format!("{:.1} %", 100.0 * x)
}

/// The verdict on one material of `file`, and whether it fails the check under `policy`
/// (its waivers and severities).
pub fn judge_material(
    file: &str,
    m: &JobMaterial,
    grid: Option<&Grid>,
    judging: &AuditJudging,
    policy: &Policy,
    predictor: &mut Predictor,
) -> AuditedMaterial {
    let mut findings: Vec<Finding> = m.findings.iter().map(|f| word(f, predictor)).collect();
    let star = policy.material_findings(&m.name, &mut findings, &m.waivers);
    let cells = m.cell.map(|c| (c, m.twin_cell.unwrap_or(c)));
    let measured = grid
        .zip(cells)
        .map(|(g, (c, t))| (g.brightness(c), g.brightness(t)));
    // A verdict names a finding that counts where one does (not a waived one beside it).
    let mut counting_first: Vec<&Finding> = findings.iter().collect();
    counting_first.sort_by_key(|f| !waivers::counts(f));
    let counting_first: Vec<Finding> = counting_first.into_iter().cloned().collect();
    let (verdict, reason) = verdict(m, &counting_first, measured, judging);
    let own = measured.and_then(|(b, _)| b);
    let twin = measured.and_then(|(_, t)| t);
    let fix = fix_choice::choose(verdict, &findings, m.replaced, own.zip(twin), judging);
    let (fails, suppressed) = waivers::fails(verdict, &findings, star.as_ref(), &judging.fail_on);
    // A material whose failing verdict is waived (or only a warning) is left as it is.
    let fix = if suppressed.is_some() { Ok(None) } else { fix };
    AuditedMaterial {
        file: file.to_string(),
        material: m.name.clone(),
        verdict,
        reason,
        baseline: None,
        fails: Some(fails),
        suppressed,
        mean: own.map(|b| b.mean),
        center: own.map(|b| b.center),
        rim: own.map(|b| b.rim),
        twin_mean: twin.map(|b| b.mean),
        twin_center: twin.map(|b| b.center),
        twin_rim: twin.map(|b| b.rim),
        replaced: m.replaced,
        no_fix: fix.clone().err(),
        opacity: own.map(|b| b.opacity),
        fix: fix.ok().flatten(),
        findings,
        library: m.library.clone(),
        cells,
        after: None,
    }
}

type Measured = Option<(Option<Brightness>, Option<Brightness>)>;

fn verdict(
    m: &JobMaterial,
    findings: &[Finding],
    measured: Measured,
    judging: &AuditJudging,
) -> (Verdict, String) {
    if let Some(error) = &m.error {
        return (Verdict::Error, error.clone());
    }
    if let Some(f) = findings.iter().find(|f| f.kind == Effect::Error) {
        return (Verdict::Error, format!("{} ({})", f.rule, f.node));
    }
    match measured {
        None => by_rules(findings, judging),
        Some((None, _)) | Some((_, None)) => unmeasured(findings),
        Some((Some(own), Some(twin))) => by_furnace(findings, own, twin, judging),
    }
}

/// A sphere the furnace saw nothing of: the world shows through it everywhere. Reported,
/// never judged (nor failed).
fn unmeasured(findings: &[Finding]) -> (Verdict, String) {
    let what = findings.iter().find(|f| f.rule == "holdout").map_or_else(
        || "the material is transparent everywhere (Alpha 0, or a Transparent BSDF)".into(),
        |f| format!("{} at {} cuts it out", f.rule, f.node),
    );
    (
        Verdict::Ok,
        format!("not judged: the furnace sees nothing of its sphere ({what})"),
    )
}

/// Without a render: a creating finding creates; a losing one loses unless the integrator
/// predicts the loss within the tolerance.
fn by_rules(findings: &[Finding], judging: &AuditJudging) -> (Verdict, String) {
    if let Some(f) = findings.iter().find(|f| f.kind == Effect::Creates) {
        return (Verdict::Creates, format!("{} at {}", f.rule, f.node));
    }
    let losing = findings.iter().find(|f| {
        f.kind == Effect::Loses && f.predicted.is_none_or(|p| 1.0 - p > judging.tolerance)
    });
    match losing {
        Some(f) => (Verdict::Loses, format!("{} at {}", f.rule, f.node)),
        None => (
            Verdict::Ok,
            "no rule fired beyond the tolerance (not rendered)".to_string(),
        ),
    }
}

/// Whether a sphere renders above 100 % by more than the tolerance and its noise, or has a
/// ring above 100 % by more than the ring tolerance and that ring's noise.
pub fn creates(b: &Brightness, j: &AuditJudging) -> bool {
    b.mean > 1.0 + j.tolerance + NOISE_SIGMAS * b.standard_error
        || b.ring_floor > 1.0 + j.ring_tolerance
}

fn by_furnace(
    findings: &[Finding],
    own: Brightness,
    twin: Brightness,
    j: &AuditJudging,
) -> (Verdict, String) {
    let emits = findings.iter().any(|f| f.rule == "emission");
    if !emits && creates(&own, j) {
        return (
            Verdict::Creates,
            format!(
                "renders at {} (brightest ring {}): above 100 % in a white furnace",
                pct(own.mean),
                pct(own.max_ring)
            ),
        );
    }
    let noise = NOISE_SIGMAS * own.standard_error.hypot(twin.standard_error);
    // A twin that creates energy itself is no conserving reference.
    let reference = !creates(&twin, j);
    if reference && twin.mean - own.mean > j.tolerance + noise {
        return (
            Verdict::Loses,
            format!(
                "renders at {}; its conserving twin at {}",
                pct(own.mean),
                pct(twin.mean)
            ),
        );
    }
    if own.mean < BLACK
        && let Some(f) = findings.iter().find(|f| f.rule == "unknown-node")
    {
        return (
            Verdict::Error,
            format!(
                "renders black: {} at {} did not render in this Blender ({})",
                f.rule,
                f.node,
                why_unknown(f)
            ),
        );
    }
    // A loss with no conserving node to compare with is judged by the integrator alone.
    let untwinned = findings.iter().find(|f| {
        f.kind == Effect::Loses
            && (f.twin.is_none() || !reference)
            && f.predicted.is_none_or(|p| 1.0 - p > j.tolerance)
    });
    if let Some(f) = untwinned {
        let why = if f.twin.is_none() {
            "has no conserving equivalent in this Blender".to_string()
        } else {
            format!(
                "loses, and its twin is no reference (it renders at {}, above 100 %)",
                pct(twin.mean)
            )
        };
        return (
            Verdict::Loses,
            format!(
                "renders at {}; {} at {} {why}",
                pct(own.mean),
                f.rule,
                f.node
            ),
        );
    }
    (
        Verdict::Ok,
        format!(
            "renders at {}; its conserving twin at {}",
            pct(own.mean),
            pct(twin.mean)
        ),
    )
}

/// Why a node the audit does not know may render black.
fn why_unknown(f: &Finding) -> &'static str {
    if f.node_type == "ShaderNodeScript" {
        "an OSL script needs Cycles' Open Shading Language, which a headless Blender cannot \
         compile"
    } else {
        "a node this Blender does not know: an add-on's node needs its add-on, a newer \
         Blender's node that Blender"
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 64 px cell holding a white sphere whose pixels with view cosine in [0.4, 0.5)
    /// (the audit's outermost ring of fully covered pixels at this size) read `rim(x, y)`;
    /// the world around it is 1 too.
    fn sphere(rim: impl Fn(usize, usize) -> f32) -> Rgba {
        let (cell, radius) = (64usize, 0.9 * 32.0);
        let pixels = (0..cell * cell)
            .map(|i| {
                let (x, y) = (i % cell, i / cell);
                let d = ((x as f64 + 0.5 - 32.0).hypot(y as f64 + 0.5 - 32.0)) / radius;
                let mu = (1.0 - d * d).max(0.0).sqrt();
                let v = if d < 1.0 && (0.4..0.5).contains(&mu) {
                    rim(x, y)
                } else {
                    1.0
                };
                [v, v, v, 1.0]
            })
            .collect();
        Rgba {
            width: cell,
            height: cell,
            pixels,
        }
    }

    /// A grazing ring brighter than 100 % by more than the ring tolerance creates energy;
    /// one that reads so only by its noise (a few pixels far apart) does not.
    #[test]
    fn a_ring_creates_only_beyond_its_noise() {
        let j = AuditJudging::default();
        let judge = |image: &Rgba| {
            let grid = Grid {
                image,
                columns: 1,
                cell: 64,
                radius_fraction: 0.9,
            };
            grid.brightness(0).unwrap()
        };
        let bright = judge(&sphere(|_, _| 1.06));
        assert!(bright.max_ring > 1.05 && creates(&bright, &j), "{bright:?}");
        let noisy = judge(&sphere(|x, y| if (x + y) % 2 == 0 { 0.7 } else { 1.42 }));
        assert!(
            noisy.max_ring > 1.03,
            "the noisy ring reads bright: {noisy:?}"
        );
        assert!(!creates(&noisy, &j), "{noisy:?}");
    }

    /// A job whose grid its image does not hold is the file's error.
    #[test]
    fn a_cell_outside_the_image_is_an_error() {
        let job = |columns: usize, cells: &[(usize, usize)]| JobRun {
            result: serde_json::from_value(serde_json::json!({
                "columns": columns,
                "materials": cells.iter().map(|(c, t)| serde_json::json!({
                    "name": "m", "cell": c, "twin_cell": t
                })).collect::<Vec<_>>(),
            }))
            .unwrap(),
            log: "blender.log".into(),
            exr: None,
            twin_exr: None,
        };
        let image = Rgba {
            width: 64,
            height: 32,
            pixels: vec![[1.0; 4]; 64 * 32],
        };
        assert!(check_grid(&job(2, &[(0, 1), (2, 3)]), Some(&image), 32).is_err());
        assert!(check_grid(&job(2, &[(0, 1)]), Some(&image), 32).is_ok());
        assert!(check_grid(&job(0, &[(0, 1)]), Some(&image), 32).is_err());
        assert!(check_grid(&job(4, &[(0, 1)]), Some(&image), 32).is_err());
        assert!(check_grid(&job(4, &[(0, 1)]), None, 32).is_ok());
        let message = check_grid(&job(2, &[(0, 5)]), Some(&image), 32)
            .unwrap_err()
            .to_string();
        assert!(
            message.contains("64 x 32 px") && message.contains("cell 5"),
            "{message}"
        );
    }
}
