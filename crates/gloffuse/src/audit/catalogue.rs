//! The audit as data for the Blender extension's panel (issue 42): the rule catalogue
//! (ids, effects, severities, version ranges, why and fix), the names of the twins' groups,
//! the tolerance of the verdict without a render, and the integrator's predictions on a grid.
//! `gloffuse generate --extension` writes it into the extension as [`FILE_NAME`] (through
//! [`EXTENSION`], which the CLI hands to generate, an earlier stage); the
//! panel's Python (`blender/gloffuse_blender/panel_verdict.py`) only looks values up in it,
//! so the words and numbers the panel shows are the ones `gloffuse audit --no-render` gives.
//!
//! The twins' names and the predictions depend on the Blender (its masking, which lobes it
//! compensates), and an add-on built by one Blender runs in every later one: the catalogue
//! holds them for each Blender series from the one that builds it on (`by_blender`, an
//! entry only where they change), and the panel takes the newest entry not after its own.
//!
//! The predictions are [`Predictor::predict`]'s own values at the grid's points: the panel
//! interpolates linearly in roughness (and IOR for the hand-made layering), the one part of
//! the prediction it computes. [`MAX_INTERPOLATION_ERROR`] bounds that interpolation, checked
//! below against the predictor between the grid's points.

use std::collections::{BTreeMap, HashMap};

use serde::Serialize;

use super::rules::{Predictor, RULES};
use super::twins::TwinNames;
use super::verdict::AuditJudging;
use crate::generate::extension::AuditCatalogue;
use crate::measure::{BlenderVersion, Distribution, Masking};

/// The file's name inside the extension.
pub const FILE_NAME: &str = "audit_catalogue.json";

/// Roughness 0..1 in this many steps (0.02 apart).
pub const ROUGHNESS_STEPS: usize = 50;

/// The IORs of the layering table: 1..3 (the range the predictor models) in this many steps.
pub const IOR_STEPS: usize = 10;
const IOR_RANGE: (f64, f64) = (1.0, 3.0);

/// How far the panel's interpolated prediction may be from the predictor's (1.0 = 100 %).
pub const MAX_INTERPOLATION_ERROR: f64 = 5e-4;

#[derive(Clone, Debug, Serialize)]
struct CatalogueRule {
    id: &'static str,
    effect: &'static str,
    severity: &'static str,
    from: [u32; 2],
    before: Option<[u32; 2]>,
    why: &'static str,
    fix: &'static str,
}

/// The predictor's values on the grid, by Blender distribution enum.
#[derive(Clone, Debug, Serialize)]
pub struct Predictions {
    pub roughness: Vec<f64>,
    pub ior: Vec<f64>,
    /// `glossy-single-scatter`: a white lobe's E_avg at each roughness.
    pub glossy: BTreeMap<&'static str, Vec<f64>>,
    /// `mix-fresnel-layering`: the hand-made mix's mean over a white base, by roughness
    /// (outer) and IOR (inner).
    pub layering: BTreeMap<&'static str, Vec<Vec<f64>>>,
}

/// Everything the panel reads.
#[derive(Clone, Debug, Serialize)]
pub struct Catalogue {
    /// The gloffuse that wrote it.
    pub gloffuse: &'static str,
    /// The verdict's tolerance without a render (`gloffuse audit`'s default; a
    /// gloffuse.toml may set another for the command line).
    pub tolerance: f64,
    rules: Vec<CatalogueRule>,
    /// The first Blender the add-on's groups do not suit (3.5 for one built by 3.0–3.4:
    /// their Cycles corrections fit the masking before it); none: every later one.
    pub suits_before: Option<[u32; 2]>,
    /// What the panel reads of its Blender, oldest first.
    pub by_blender: Vec<ForBlender>,
}

/// The twins' names and the predictions from Blender `from` on (until the next entry).
#[derive(Clone, Debug, Serialize)]
pub struct ForBlender {
    pub from: [u32; 2],
    twin_names: TwinNames,
    pub predictions: Predictions,
}

/// The Blender series an add-on may run in: every one gloffuse knows, and the two after
/// them read in Cycles' source (newer ones take the last entry).
const SERIES: [(u32, u32); 14] = [
    (3, 0),
    (3, 1),
    (3, 2),
    (3, 3),
    (3, 4),
    (3, 5),
    (3, 6),
    (4, 0),
    (4, 1),
    (4, 2),
    (4, 3),
    (4, 4),
    (4, 5),
    (5, 0),
];

fn grid(from: f64, to: f64, steps: usize) -> Vec<f64> {
    (0..=steps)
        .map(|i| from + (to - from) * i as f64 / steps as f64)
        .collect()
}

/// The predictions for Blender `version`.
pub fn predictions(version: BlenderVersion) -> Predictions {
    let mut predictor = Predictor::new(version);
    let roughness = grid(0.0, 1.0, ROUGHNESS_STEPS);
    let ior = grid(IOR_RANGE.0, IOR_RANGE.1, IOR_STEPS);
    let mut glossy = BTreeMap::new();
    let mut layering = BTreeMap::new();
    for d in Distribution::ALL {
        let name = d.blender_enum();
        let mut at = |rule: &str, detail: serde_json::Value| {
            predictor.predict(rule, &detail).unwrap_or(f64::NAN)
        };
        let row: Vec<f64> = roughness
            .iter()
            .map(|&r| {
                at(
                    "glossy-single-scatter",
                    serde_json::json!({"distribution": name, "roughness": r}),
                )
            })
            .collect();
        glossy.insert(name, row);
        let table: Vec<Vec<f64>> = roughness
            .iter()
            .map(|&r| {
                ior.iter()
                    .map(|&n| {
                        at(
                            "mix-fresnel-layering",
                            serde_json::json!({"distribution": name, "roughness": r, "ior": n}),
                        )
                    })
                    .collect()
            })
            .collect();
        layering.insert(name, table);
    }
    Predictions {
        roughness,
        ior,
        glossy,
        layering,
    }
}

/// The first Blender the groups built by `built_with` do not suit: their Cycles
/// corrections fit `built_with`'s masking (generate's `suits`).
fn suits_before(built_with: BlenderVersion) -> Option<BlenderVersion> {
    (built_with.masking() == Masking::Separable).then_some(BlenderVersion::HEIGHT_CORRELATED_FROM)
}

/// The entries for Blender `built_with` and every later series its groups suit, each only
/// where the twins' names or the predictions change.
fn by_blender(built_with: BlenderVersion) -> Vec<ForBlender> {
    let mut entries: Vec<(String, ForBlender)> = Vec::new();
    // The predictor depends on the Blender only through its masking: two grids at most.
    let mut grids: HashMap<Masking, Predictions> = HashMap::new();
    let later = SERIES
        .iter()
        .map(|&(major, minor)| BlenderVersion { major, minor })
        .filter(|&v| v > built_with && suits_before(built_with).is_none_or(|end| v < end));
    for version in std::iter::once(built_with).chain(later) {
        let entry = ForBlender {
            from: [version.major, version.minor],
            twin_names: TwinNames::new(version),
            predictions: grids
                .entry(version.masking())
                .or_insert_with(|| predictions(version))
                .clone(),
        };
        let same = serde_json::to_string(&(&entry.twin_names, &entry.predictions))
            .expect("an entry serialises");
        if entries.last().is_none_or(|(last, _)| *last != same) {
            entries.push((same, entry));
        }
    }
    entries.into_iter().map(|(_, entry)| entry).collect()
}

/// The catalogue an add-on built by Blender `version` carries.
pub fn catalogue(version: BlenderVersion) -> Catalogue {
    Catalogue {
        gloffuse: env!("CARGO_PKG_VERSION"),
        tolerance: AuditJudging::default().tolerance,
        rules: RULES
            .iter()
            .map(|r| CatalogueRule {
                id: r.id,
                effect: r.effect.key(),
                severity: r.severity.key(),
                from: [r.from.major, r.from.minor],
                before: r.before.map(|b| [b.major, b.minor]),
                why: r.why,
                fix: r.fix,
            })
            .collect(),
        suits_before: suits_before(version).map(|v| [v.major, v.minor]),
        by_blender: by_blender(version),
    }
}

/// The catalogue as the extension carries it.
pub fn to_json(version: BlenderVersion) -> String {
    serde_json::to_string(&catalogue(version)).expect("the catalogue serialises")
}

/// What `gloffuse generate --extension` writes into the extension (generate is an earlier
/// stage than the audit: the CLI hands this in through `GenerateOptions::audit_catalogue`).
pub const EXTENSION: AuditCatalogue = AuditCatalogue {
    file_name: FILE_NAME,
    write: to_json,
};

#[cfg(test)]
mod tests {
    use super::*;

    /// Linear interpolation of `values` on the evenly spaced `points` at `x` (a second
    /// computation of what panel_verdict.py does).
    fn lerp(points: &[f64], values: &[f64], x: f64) -> f64 {
        let steps = points.len() - 1;
        let at = (x - points[0]) / (points[steps] - points[0]) * steps as f64;
        let i = (at.floor() as usize).min(steps - 1);
        let t = at - i as f64;
        values[i] * (1.0 - t) + values[i + 1] * t
    }

    #[test]
    fn the_grid_interpolates_the_predictor_within_the_bound() {
        let v45 = BlenderVersion { major: 4, minor: 5 };
        let table = predictions(v45);
        let mut predictor = Predictor::new(v45);
        let mut worst: f64 = 0.0;
        for d in Distribution::ALL {
            let name = d.blender_enum();
            for r in [0.003, 0.017, 0.055, 0.125, 0.333, 0.505, 0.777, 0.995] {
                let want = predictor
                    .predict(
                        "glossy-single-scatter",
                        &serde_json::json!({"distribution": name, "roughness": r}),
                    )
                    .unwrap();
                let got = lerp(&table.roughness, &table.glossy[name], r);
                worst = worst.max((got - want).abs());
                let n = 1.45;
                let want = predictor
                    .predict(
                        "mix-fresnel-layering",
                        &serde_json::json!({"distribution": name, "roughness": r, "ior": n}),
                    )
                    .unwrap();
                let rows: Vec<f64> = table.layering[name]
                    .iter()
                    .map(|row| lerp(&table.ior, row, n))
                    .collect();
                let got = lerp(&table.roughness, &rows, r);
                worst = worst.max((got - want).abs());
            }
        }
        eprintln!("worst interpolation error {worst}");
        assert!(worst < MAX_INTERPOLATION_ERROR, "worst {worst}");
        assert!(worst > 0.0, "points between the grid's are interpolated");
    }

    #[test]
    fn the_catalogue_carries_every_rule_and_the_twin_groups() {
        let v = BlenderVersion { major: 4, minor: 5 };
        let json: serde_json::Value = serde_json::from_str(&to_json(v)).unwrap();
        let ids: Vec<&str> = json["rules"]
            .as_array()
            .unwrap()
            .iter()
            .map(|r| r["id"].as_str().unwrap())
            .collect();
        assert_eq!(ids, RULES.iter().map(|r| r.id).collect::<Vec<_>>());
        assert_eq!(json["rules"][6]["before"], serde_json::json!([4, 0]));
        assert!(json["by_blender"][0]["twin_names"]["multiscatter"]["BECKMANN"].is_string());
        assert_eq!(json["by_blender"][0]["from"], serde_json::json!([4, 5]));
        assert_eq!(json["tolerance"], 0.01);
    }

    /// The entry a Blender takes, as panel_verdict.py takes it: the newest not after it.
    fn entry_for(json: &serde_json::Value, major: u32, minor: u32) -> &serde_json::Value {
        json["by_blender"]
            .as_array()
            .unwrap()
            .iter()
            .rfind(|e| {
                e["from"][0].as_u64().unwrap() * 100 + e["from"][1].as_u64().unwrap()
                    <= u64::from(major * 100 + minor)
            })
            .unwrap()
    }

    #[test]
    fn every_later_blender_finds_its_own_twins_and_predictions() {
        let v35 = BlenderVersion { major: 3, minor: 5 };
        let json: serde_json::Value = serde_json::from_str(&to_json(v35)).unwrap();
        assert_eq!(json["suits_before"], serde_json::Value::Null);
        let from: Vec<&serde_json::Value> = json["by_blender"]
            .as_array()
            .unwrap()
            .iter()
            .map(|e| &e["from"])
            .collect();
        // 3.6 changes the glass twin; no entry repeats the one before.
        assert_eq!(
            from[..2],
            [&serde_json::json!([3, 5]), &serde_json::json!([3, 6])]
        );
        for (major, minor) in [(3, 5), (3, 6), (4, 1), (5, 2)] {
            let v = BlenderVersion { major, minor };
            let entry = entry_for(&json, major, minor);
            let own = serde_json::json!({
                "twin_names": TwinNames::new(v),
                "predictions": predictions(v),
            });
            assert_eq!(entry["twin_names"], own["twin_names"], "{major}.{minor}");
            assert_eq!(entry["predictions"], own["predictions"], "{major}.{minor}");
        }
    }

    #[test]
    fn groups_built_for_the_separable_masking_suit_no_later_blender() {
        let v34 = BlenderVersion { major: 3, minor: 4 };
        let json: serde_json::Value = serde_json::from_str(&to_json(v34)).unwrap();
        assert_eq!(json["suits_before"], serde_json::json!([3, 5]));
        assert_eq!(json["by_blender"].as_array().unwrap().len(), 1);
        assert_eq!(json["by_blender"][0]["from"], serde_json::json!([3, 4]));
    }
}
