//! Which materials a fix rewrites. A fix is never worse than the material: only a material
//! whose verdict fails is rewritten, and only when its conserving twin, measured in the
//! furnace beside it, is safe (it creates no energy, and it is not darker than a material
//! that loses). An Add Shader that creates energy is scaled back to 100 % by the brightness
//! measured, never halved. Where no safe twin exists, the reason is the material's.

use super::judge::creates;
use super::rules::Effect;
use super::verdict::{AuditJudging, Brightness, Finding, Verdict};

/// How a material is fixed: its twin's replacements, and the scale of the Add Shader that
/// makes it create energy (1 over the brightness measured), if that is what it needs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MaterialFix {
    pub scale: Option<f64>,
}

fn pct(x: f64) -> String {
    format!("{:.1} %", 100.0 * x)
}

/// The fix of one judged material: `Ok(None)` when it needs none (its verdict passes or is
/// an error), `Err(why)` when its verdict fails and no safe fix exists.
pub fn choose(
    verdict: Verdict,
    findings: &[Finding],
    replaced: usize,
    measured: Option<(Brightness, Brightness)>,
    j: &AuditJudging,
) -> Result<Option<MaterialFix>, String> {
    if !matches!(verdict, Verdict::Loses | Verdict::Creates) {
        return Ok(None);
    }
    if let Some(why) = in_a_library(findings) {
        return Err(why);
    }
    let Some((own, twin)) = measured else {
        // The rules alone (no furnace render): their replacements, unmeasured.
        return match replaced {
            0 => Err(no_safe_twin(findings, None)),
            _ => Ok(Some(MaterialFix { scale: None })),
        };
    };
    // The Add Shader whose sum is the whole surface: scaling it by the brightness measured
    // brings the material to 100 %.
    let add = findings
        .iter()
        .find(|f| f.rule == "add-reflecting" && f.detail["feeds_output"] == true);
    if creates(&twin, j) {
        return match add {
            Some(_) if twin.mean > 1.0 => Ok(Some(MaterialFix {
                scale: Some(1.0 / twin.mean),
            })),
            _ => Err(no_safe_twin(findings, Some(twin).filter(|_| replaced > 0))),
        };
    }
    if replaced == 0 {
        return Err(no_safe_twin(findings, None));
    }
    let noise = 3.0 * own.standard_error.hypot(twin.standard_error);
    if verdict == Verdict::Loses && twin.mean < own.mean - j.tolerance - noise {
        return Err(format!(
            "no safe fix: its twin renders at {}, darker than the material's {}",
            pct(twin.mean),
            pct(own.mean)
        ));
    }
    Ok(Some(MaterialFix { scale: None }))
}

/// Why a failing lobe cannot be fixed here: it lies inside what a `linked-library`
/// finding names (the material itself, or a group on its path), which only its library
/// file can change.
fn in_a_library(findings: &[Finding]) -> Option<String> {
    let failing = findings
        .iter()
        .filter(|f| matches!(f.kind, Effect::Loses | Effect::Creates));
    for f in failing {
        let linked = findings
            .iter()
            .find(|l| l.rule == "linked-library" && f.node_path.starts_with(&l.node_path));
        if let Some(l) = linked {
            let library = l.detail["library"].as_str().unwrap_or("its library");
            return Some(format!(
                "no safe fix for {} at {}: it is linked from {library}, so fix that file",
                f.rule, f.node
            ));
        }
    }
    None
}

/// Why the material has no safe twin, naming the finding that needs one: its twin creates
/// energy (`twin`, measured), or nothing in it can be replaced.
fn no_safe_twin(findings: &[Finding], twin: Option<Brightness>) -> String {
    let failing = findings
        .iter()
        .find(|f| matches!(f.kind, Effect::Loses | Effect::Creates));
    let what = failing.map_or_else(String::new, |f| format!(" for {} at {}", f.rule, f.node));
    if let Some(twin) = twin {
        return format!(
            "no safe fix{what}: its conserving twin renders at {} (above 100 %)",
            pct(twin.mean)
        );
    }
    match failing {
        Some(f) if f.rule == "add-reflecting" && f.detail["feeds_output"] == true => format!(
            "no safe fix{what}: the share of the Add Shader to take away is measured by the \
             furnace render, which this audit skipped"
        ),
        Some(f) if f.rule == "add-reflecting" => format!(
            "no safe fix{what}: the Add Shader is not the material's whole surface, so the \
             share to take away cannot be measured here"
        ),
        _ => format!("no safe fix{what}: no conserving replacement exists in this Blender"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn b(mean: f64) -> Brightness {
        Brightness {
            mean,
            center: mean,
            rim: mean,
            max_ring: mean,
            ring_floor: mean,
            standard_error: 0.001,
            opacity: 1.0,
        }
    }

    fn finding(rule: &str, kind: Effect, detail: serde_json::Value) -> Finding {
        Finding {
            rule: rule.into(),
            node: format!("M ▸ {rule}"),
            node_path: vec!["M".into(), rule.into()],
            node_type: String::new(),
            kind,
            versions: String::new(),
            why: String::new(),
            fix: String::new(),
            predicted: None,
            twin: Some("t".into()),
            detail,
            severity: Default::default(),
            waived: None,
        }
    }

    #[test]
    fn an_ok_material_is_never_fixed() {
        let j = AuditJudging::default();
        let found = [finding(
            "glossy-single-scatter",
            Effect::Loses,
            serde_json::json!({}),
        )];
        assert_eq!(
            choose(Verdict::Ok, &found, 1, Some((b(0.8), b(0.805))), &j),
            Ok(None)
        );
        assert_eq!(choose(Verdict::Error, &found, 1, None, &j), Ok(None));
    }

    #[test]
    fn a_twin_that_creates_is_no_fix() {
        let j = AuditJudging::default();
        let found = [finding(
            "principled-single-scatter",
            Effect::Loses,
            serde_json::json!({}),
        )];
        let why = choose(Verdict::Loses, &found, 1, Some((b(0.974), b(1.023))), &j).unwrap_err();
        assert!(why.contains("102.3 %"), "{why}");
        assert_eq!(
            choose(Verdict::Loses, &found, 1, Some((b(0.9), b(1.0))), &j),
            Ok(Some(MaterialFix { scale: None }))
        );
    }

    #[test]
    fn an_add_that_is_the_surface_is_scaled_by_what_it_measured() {
        let j = AuditJudging::default();
        let root = [finding(
            "add-reflecting",
            Effect::Creates,
            serde_json::json!({"feeds_output": true}),
        )];
        let fix = choose(Verdict::Creates, &root, 0, Some((b(1.09), b(1.09))), &j);
        let scale = fix.unwrap().unwrap().scale.unwrap();
        assert!((scale * 1.09 - 1.0).abs() < 1e-12, "{scale}");
        let nested = [finding(
            "add-reflecting",
            Effect::Creates,
            serde_json::json!({"feeds_output": false}),
        )];
        let why = choose(Verdict::Creates, &nested, 0, Some((b(1.09), b(1.09))), &j).unwrap_err();
        assert!(why.contains("not the material's whole surface"), "{why}");
    }

    #[test]
    fn a_lobe_inside_a_linked_group_is_its_library_to_fix() {
        let j = AuditJudging::default();
        let mut lobe = finding(
            "glossy-single-scatter",
            Effect::Loses,
            serde_json::json!({}),
        );
        lobe.node_path = vec!["M".into(), "Group".into(), "Glossy".into()];
        let mut linked = finding(
            "linked-library",
            Effect::Info,
            serde_json::json!({"library": "//lib.blend"}),
        );
        linked.node_path = vec!["M".into(), "Group".into()];
        let found = [linked.clone(), lobe.clone()];
        let why = choose(Verdict::Loses, &found, 1, Some((b(0.8), b(1.0))), &j).unwrap_err();
        assert!(why.contains("linked from //lib.blend"), "{why}");
        // A linked group beside the lobe, not above it, leaves it to fix.
        linked.node_path = vec!["M".into(), "Other".into()];
        let found = [linked, lobe];
        assert!(choose(Verdict::Loses, &found, 1, Some((b(0.8), b(1.0))), &j).is_ok());
    }

    #[test]
    fn a_twin_darker_than_a_losing_material_is_no_fix() {
        let j = AuditJudging::default();
        let found = [finding(
            "glossy-single-scatter",
            Effect::Loses,
            serde_json::json!({}),
        )];
        assert!(choose(Verdict::Loses, &found, 1, Some((b(0.9), b(0.8))), &j).is_err());
        assert_eq!(
            choose(Verdict::Loses, &found, 1, None, &j),
            Ok(Some(MaterialFix { scale: None })),
            "unrendered, the rules' replacement"
        );
        assert!(choose(Verdict::Loses, &found, 0, None, &j).is_err());
    }
}
