//! The PBR range rules (`pbr-albedo-range`, `pbr-dark-albedo`, `pbr-metal-reflectance`) in
//! Blender 3.4, 4.5 and 5.0, with `--no-render`: a .blend made in the test
//! (`tests/blender/pbr_cases.py`, none of gloffuse's code) holds colours at, just inside and
//! just outside every bound, and the findings each material gets are exactly the ones an
//! sRGB conversion written here expects.
//!
//! Tier: blender (needs the Blenders `scripts/test.sh` installs).

mod common;

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use serde_json::{Value, json};

use common::audit_json as audit;
use common::blender::run_in_blender;

/// An 8-bit sRGB value (0–255, not rounded) as a linear channel: IEC 61966-2-1's decoding.
fn linear(srgb: f64) -> f64 {
    let v = srgb / 255.0;
    if v <= 0.04045 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    }
}

/// A linear channel as an 8-bit sRGB value (0–255, not rounded): the encoding.
fn srgb(linear: f64) -> f64 {
    let v = if linear <= 0.003_130_8 {
        12.92 * linear
    } else {
        1.055 * linear.powf(1.0 / 2.4) - 0.055
    };
    255.0 * v
}

/// What the rules should find for one case, decided here from the published ranges.
fn expected(case: &Value) -> BTreeSet<String> {
    let mut rules = BTreeSet::new();
    if case["via"] == "texture" || case["transmission"].as_f64().unwrap_or(0.0) != 0.0 {
        return rules;
    }
    let rgb: Vec<f64> = case["color"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c.as_f64().unwrap())
        .collect();
    let metallic = case["metallic"].as_f64().unwrap_or(0.0);
    let metal = match case["node"].as_str().unwrap() {
        "glossy" => Some(true),
        "diffuse" => Some(false),
        _ if metallic >= 0.9 => Some(true),
        _ if metallic <= 0.1 => Some(false),
        _ => None,
    };
    let Some(metal) = metal else {
        return rules;
    };
    // Unity: the luminance of the linear colour (Rec. 709), encoded.
    let luminance = srgb(0.2126729 * rgb[0] + 0.7151522 * rgb[1] + 0.0721750 * rgb[2]);
    let darkest = rgb.iter().map(|&c| srgb(c)).fold(f64::INFINITY, f64::min);
    if (metal && luminance < 186.0) || (!metal && !(50.0..=243.0).contains(&luminance)) {
        rules.insert("pbr-albedo-range".to_string());
    }
    if !metal && darkest < 50.0 {
        let strict = if darkest < 30.0 { " strict" } else { "" };
        rules.insert(format!("pbr-dark-albedo{strict}"));
    }
    if metal && darkest < 0.6 * 255.0 {
        rules.insert("pbr-metal-reflectance".to_string());
    }
    rules
}

/// The cases: (name, node, sRGB colour, metallic, transmission, how the colour arrives).
fn cases() -> Vec<Value> {
    let case = |name: &str, node: &str, rgb: [f64; 3], metallic: f64, via: &str| {
        json!({"name": name, "node": node, "color": rgb.map(linear), "metallic": metallic,
               "transmission": 0.0, "via": via})
    };
    let grey = |v: f64| [v; 3];
    let mut cases = vec![
        // Unity's non-metal range, 50–243, by luminance (a grey's luminance is its value).
        case("non-metal 49", "principled", grey(49.0), 0.0, "socket"),
        case("non-metal 51", "principled", grey(51.0), 0.0, "socket"),
        case("non-metal 242", "principled", grey(242.0), 0.0, "socket"),
        case("non-metal 244", "principled", grey(244.0), 0.0, "socket"),
        // Substance's dark floor, 30 strict and 50 recommended, per channel.
        case("non-metal 29", "principled", grey(29.0), 0.0, "socket"),
        case("non-metal 31", "principled", grey(31.0), 0.0, "socket"),
        case(
            "blue channel 49",
            "principled",
            [120.0, 120.0, 49.0],
            0.0,
            "socket",
        ),
        case(
            "blue channel 51",
            "principled",
            [120.0, 120.0, 51.0],
            0.0,
            "socket",
        ),
        case("pure red", "diffuse", [255.0, 0.0, 0.0], 0.0, "socket"),
        // Unity's metal floor, 186, by luminance.
        case("metal 185", "principled", grey(185.0), 1.0, "socket"),
        case("metal 187", "principled", grey(187.0), 1.0, "socket"),
        // Substance's metal reflectance, 60 % (153 sRGB), per channel.
        case(
            "metal blue 152",
            "principled",
            [230.0, 230.0, 152.0],
            1.0,
            "socket",
        ),
        case(
            "metal blue 154",
            "principled",
            [230.0, 230.0, 154.0],
            1.0,
            "socket",
        ),
        // What counts as a metal: Metallic 0.9 and above; a non-metal: 0.1 and below.
        case(
            "metallic 0.9 at 185",
            "principled",
            grey(185.0),
            0.9,
            "socket",
        ),
        case(
            "metallic 0.1 at 49",
            "principled",
            grey(49.0),
            0.1,
            "socket",
        ),
        case(
            "metallic 0.5 at 10",
            "principled",
            grey(10.0),
            0.5,
            "socket",
        ),
        case(
            "metallic 0.85 at 10",
            "principled",
            grey(10.0),
            0.85,
            "socket",
        ),
        // Diffuse is a non-metal, Glossy a metal's reflectance.
        case("diffuse 49", "diffuse", grey(49.0), 0.0, "socket"),
        case(
            "diffuse 244 by RGB node",
            "diffuse",
            grey(244.0),
            0.0,
            "rgb",
        ),
        case(
            "diffuse 10 by texture",
            "diffuse",
            grey(10.0),
            0.0,
            "texture",
        ),
        case("glossy 185", "glossy", grey(185.0), 0.0, "socket"),
        case(
            "glossy blue 152 by RGB node",
            "glossy",
            [255.0, 255.0, 152.0],
            0.0,
            "rgb",
        ),
        case("glossy white", "glossy", grey(255.0), 0.0, "socket"),
        // Gold (linear 1.0, 0.766, 0.336) is a plausible metal.
        json!({"name": "gold", "node": "principled", "color": [1.0, 0.766, 0.336],
               "metallic": 1.0, "transmission": 0.0, "via": "socket"}),
    ];
    // A glass's colour is its tint: not judged.
    let mut glass = case("glass 10", "principled", grey(10.0), 0.0, "socket");
    glass["transmission"] = json!(1.0);
    cases.push(glass);
    cases
}

fn pbr_rules_fire_exactly_at_their_bounds(label: &'static str, blender: PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let (cases_path, file) = (dir.path().join("cases.json"), dir.path().join("pbr.blend"));
    let cases = cases();
    std::fs::write(&cases_path, serde_json::to_string(&cases).unwrap()).unwrap();
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/blender/pbr_cases.py");
    let made = run_in_blender(
        &blender,
        &script,
        &[cases_path.as_os_str(), file.as_os_str()],
    );
    assert!(
        made.status.success() && file.is_file(),
        "Blender {label}: {}",
        String::from_utf8_lossy(&made.stderr)
    );
    let (code, report, stderr) = audit(&blender, &[file.as_os_str(), "--no-render".as_ref()]);
    assert!(code == 0 || code == 1, "Blender {label}: {code} {stderr}");
    let mut found: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for m in report["materials"].as_array().unwrap() {
        let rules = found
            .entry(m["material"].as_str().unwrap().to_string())
            .or_default();
        for f in m["findings"].as_array().unwrap() {
            let rule = f["rule"].as_str().unwrap();
            if !rule.starts_with("pbr-") {
                continue;
            }
            let strict = if f["detail"]["strict"] == true {
                " strict"
            } else {
                ""
            };
            rules.insert(format!("{rule}{strict}"));
            assert_eq!(
                f["node"],
                format!("{} ▸ Shader", m["material"].as_str().unwrap())
            );
        }
    }
    let mut firing = 0;
    for case in &cases {
        let name = case["name"].as_str().unwrap();
        let want = expected(case);
        firing += want.len();
        assert_eq!(
            found.get(name),
            Some(&want),
            "Blender {label}: {name} ({})",
            case["color"]
        );
    }
    assert_eq!(found.len(), cases.len(), "Blender {label}: every case once");
    // The oracle is no vacuous pass: every rule fires somewhere and many cases do not.
    assert!(firing >= 15, "{firing}");
    // The finding says what it read, in sRGB.
    let m = report["materials"]
        .as_array()
        .unwrap()
        .iter()
        .find(|m| m["material"] == "non-metal 29")
        .unwrap();
    let dark = m["findings"]
        .as_array()
        .unwrap()
        .iter()
        .find(|f| f["rule"] == "pbr-dark-albedo")
        .unwrap();
    let why = dark["why"].as_str().unwrap();
    assert!(
        why.contains("Substance")
            && why.contains("Base Color sRGB 29.0, 29.0, 29.0")
            && why.contains("strict floor (30)"),
        "{why}"
    );
}
common::blender::per_blender!(pbr_rules_fire_exactly_at_their_bounds);

/// The test's own sRGB conversion round-trips, and has the linear segment.
#[test]
fn the_tests_srgb_conversion_round_trips() {
    for v in [0.0, 1.0, 10.0, 29.0, 49.0, 153.0, 186.0, 243.0, 255.0] {
        assert!((srgb(linear(v)) - v).abs() < 1e-9, "{v}");
    }
    assert!((linear(10.0) - 10.0 / 255.0 / 12.92).abs() < 1e-12);
    assert!((srgb(0.5) - 187.5).abs() < 0.1, "{}", srgb(0.5));
}
