//! `gloffuse generate` end to end in real Blender 3.4, 4.5 and 5.0: the .blend it writes
//! holds the public groups with their exact sockets, defaults and asset marks, and Cycles
//! itself, evaluating the groups, gives gains equal to 100/f(r) from the coefficients
//! (computed here in Rust: an independent evaluation of the same curve).
//!
//! Tier: blender (needs the Blenders and tools `scripts/test.sh` installs).

mod common;

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use gloffuse::fit::Coefficients;
use gloffuse::generate::{correction_group_name, shader_group_name};
use gloffuse::measure::Engine;
use serde_json::{Value, json};

const PROBES: [f64; 6] = [0.0, 0.2, 0.5, 0.75, 1.0, 1.5];

fn expectations(preset: &str) -> Value {
    let c = Coefficients::load(preset).unwrap();
    let groups: Vec<Value> = c
        .distributions
        .iter()
        .map(|(&d, e)| {
            json!({
                "correction_group": correction_group_name(Engine::Cycles, d),
                "shader_group": shader_group_name(Engine::Cycles, d),
                "distribution": d.blender_enum(),
                // r = 1.5 probes the clamp: Blender must treat it as 1.
                "probe": PROBES.iter().map(|&r| json!([r, e.curve.gain(r.min(1.0))])).collect::<Vec<_>>(),
            })
        })
        .collect();
    json!({ "groups": groups })
}

/// A catalog file as a user might have it: their own `Shader` catalog and another one.
const USER_CATALOGS: &str = "VERSION 1\n\n# my studio's catalogs\n\
     0e5a7f27-7e0e-4a11-9a35-1f4b2a7c9d01:Shader:My shaders\n\
     1b2c3d4e-0000-4000-8000-000000000001:Props/Chairs:Props-Chairs\n";

/// `tests/blender/check_assets.py` on a generated library: catalogs from the file beside
/// it, real previews, licence, and nothing but the groups in it; then the shader groups'
/// previews, as Blender stored them, compared pixel by pixel ([`previews_tell_groups_apart`]).
fn check_assets(label: &str, blender: &std::path::Path, blend: &std::path::Path) {
    let checker = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/blender/check_assets.py");
    let dir = tempfile::tempdir().unwrap();
    let result = dir.path().join("assets.json");
    let previews = dir.path().join("previews");
    let run = common::blender::run_in_blender(
        blender,
        checker.as_ref(),
        &[
            "--blend".as_ref(),
            blend.as_os_str(),
            "--out".as_ref(),
            result.as_os_str(),
            "--previews".as_ref(),
            previews.as_os_str(),
        ],
    );
    let report: Value = std::fs::read_to_string(&result)
        .ok()
        .and_then(|t| serde_json::from_str(&t).ok())
        .unwrap_or(Value::Null);
    assert!(
        run.status.success() && report["failures"].as_array().is_some_and(|f| f.is_empty()),
        "Blender {label}: check_assets failed\nfailures: {}\nstderr:\n{}",
        report["failures"],
        String::from_utf8_lossy(&run.stderr)
    );
    previews_tell_groups_apart(label, &previews);
}

/// A preview as RGBA in [0, 1], row 0 at the top.
fn preview(dir: &std::path::Path, group: &str) -> image::Rgba32FImage {
    let path = dir.join(format!("{group}.png"));
    image::open(&path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .to_rgba32f()
}

/// How many pixels of `a` and `b` in rows `rows` differ by more than `by` in some channel.
fn pixels_apart(
    a: &image::Rgba32FImage,
    b: &image::Rgba32FImage,
    rows: std::ops::Range<u32>,
    by: f32,
) -> usize {
    assert_eq!(a.dimensions(), b.dimensions());
    rows.flat_map(|y| (0..a.width()).map(move |x| (x, y)))
        .filter(|&(x, y)| {
            let (p, q) = (a.get_pixel(x, y), b.get_pixel(x, y));
            (0..4).any(|c| (p[c] - q[c]).abs() > by)
        })
        .count()
}

/// Issue 25 (5): an artist picks from thumbnails, so every shader group's preview must
/// look different from every other: a caption (distribution and kind) or a colour, at
/// least a word's worth of pixels clearly apart. And the sphere itself, above the
/// caption, must show its distribution: the sun's highlight differs between GGX and
/// Beckmann of the same kind, not only the words under it.
fn previews_tell_groups_apart(label: &str, dir: &std::path::Path) {
    let mut groups: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter_map(|n| n.strip_suffix(".png").map(str::to_string))
        .collect();
    groups.sort();
    // Three distributions, each with its roughness, view and multiscatter group, and the
    // anisotropic GGX and (from 3.5) Beckmann groups, and the Glass and Refraction groups of
    // GGX and Beckmann.
    let anisotropic = if label == "3.4" { 1 } else { 2 };
    assert_eq!(
        groups.len(),
        9 + anisotropic + 4,
        "Blender {label}: {groups:?}"
    );
    let images: Vec<_> = groups.iter().map(|g| preview(dir, g)).collect();
    let height = images[0].height();
    // Nothing is cut off at the sides: the outer columns stay transparent.
    for (group, image) in groups.iter().zip(&images) {
        let edge = [0, image.width() - 1];
        let cut = (0..height).any(|y| edge.iter().any(|&x| image.get_pixel(x, y)[3] > 0.01));
        assert!(!cut, "Blender {label}: {group}'s preview reaches its side");
    }
    for (i, a) in images.iter().enumerate() {
        for (j, b) in images.iter().enumerate().skip(i + 1) {
            let apart = pixels_apart(a, b, 0..height, 0.1);
            assert!(
                apart >= WORD_PIXELS,
                "Blender {label}: the previews of {} and {} differ in {apart} pixels only",
                groups[i],
                groups[j]
            );
        }
    }
    // The sphere's part of the picture: above the caption (the lower quarter).
    let sphere = 0..height * 3 / 4;
    for kind in ["Gloffuse", "Gloffuse View"] {
        let ggx = preview(dir, &format!("{kind} (GGX)"));
        let beckmann = preview(dir, &format!("{kind} (Beckmann)"));
        let apart = pixels_apart(&ggx, &beckmann, sphere.clone(), 0.03);
        assert!(
            apart >= HIGHLIGHT_PIXELS,
            "Blender {label}: {kind}'s GGX and Beckmann spheres differ in {apart} pixels only"
        );
    }
    // The anisotropic group's highlight is stretched: not the view group's sphere.
    let view = preview(dir, "Gloffuse View (GGX)");
    let anisotropic = preview(dir, "Gloffuse Anisotropic (GGX)");
    let apart = pixels_apart(&view, &anisotropic, sphere, 0.03);
    assert!(
        apart >= HIGHLIGHT_PIXELS,
        "Blender {label}: the anisotropic and view GGX spheres differ in {apart} pixels only"
    );
}

/// At least this many pixels clearly apart: about one short caption word.
const WORD_PIXELS: usize = 100;
/// At least this many sphere pixels apart: a highlight's rim (about 1,900 of 12,288 in
/// bpy 5.0.1; Ashikhmin-Shirley and Beckmann lobes are too alike to compare).
const HIGHLIGHT_PIXELS: usize = 500;

fn generated_blend_works_in_every_blender(label: &'static str, blender: PathBuf) {
    let checker = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/blender/check_generated.py"
    );
    let dir = tempfile::tempdir().unwrap();
    let sub = dir.path().join("a dir é 'q\"");
    std::fs::create_dir(&sub).unwrap();
    let blend = sub.join("gloffuse library.blend");
    let script = sub.join("gen erate.py");
    // The user's own catalogs: kept, and their "Shader" catalog is the one used.
    let cats = sub.join("blender_assets.cats.txt");
    std::fs::write(&cats, USER_CATALOGS).unwrap();
    let preset = if label == "3.4" {
        "blender-3"
    } else {
        "blender-4"
    };
    let out = common::gloffuse()
        .args([
            "generate",
            "--json",
            "--mode",
            "roughness",
            "--mode",
            "view",
        ])
        .args([
            "--mode",
            "multiscatter",
            "--mode",
            "anisotropic",
            "--mode",
            "glass",
        ])
        .arg("--blend")
        .arg(&blend)
        .arg("--script")
        .arg(&script)
        .arg("--blender")
        .arg(&blender)
        .args(["--no-provision", "--timeout", "300"])
        .assert()
        .success()
        .get_output()
        .stdout
        .clone();
    let summary: Value = serde_json::from_slice(&out).unwrap();
    // Without --coefficients the preset follows the Blender's masking family.
    assert_eq!(summary["coefficients"], preset, "Blender {label}");
    assert!(summary["blender"].as_str().unwrap().starts_with(label));
    let leftovers: Vec<_> = std::fs::read_dir(&sub)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(
        leftovers.len(),
        3,
        "Blender {label}: only the .blend, its catalogs and the script: {leftovers:?}"
    );
    let merged = std::fs::read_to_string(&cats).unwrap();
    assert!(
        merged.starts_with(USER_CATALOGS) && merged.matches(":Shader:").count() == 1,
        "Blender {label}: the user's catalogs are kept as they are:\n{merged}"
    );
    check_assets(label, &blender, &blend);

    let expect = dir.path().join("expect.json");
    std::fs::write(&expect, expectations(preset).to_string()).unwrap();
    let result = dir.path().join("result.json");
    let run = common::blender::run_in_blender(
        &blender,
        checker.as_ref(),
        &[
            "--blend".as_ref(),
            blend.as_os_str(),
            "--expect".as_ref(),
            expect.as_os_str(),
            "--out".as_ref(),
            result.as_os_str(),
            "--generator".as_ref(),
            script.as_os_str(),
        ],
    );
    let report: Value = std::fs::read_to_string(&result)
        .ok()
        .and_then(|t| serde_json::from_str(&t).ok())
        .unwrap_or(Value::Null);
    assert!(
        run.status.success() && report["failures"].as_array().is_some_and(|f| f.is_empty()),
        "Blender {label}: check_generated failed\nfailures: {}\nstdout:\n{}\nstderr:\n{}",
        report["failures"],
        String::from_utf8_lossy(&run.stdout),
        String::from_utf8_lossy(&run.stderr)
    );
}

common::blender::per_blender!(generated_blend_works_in_every_blender);

#[test]
fn into_replaces_groups_in_place_and_keeps_a_backup() {
    let Some(blender) = common::blender::real_blender("4.5") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let blend = dir.path().join("scene.blend");
    let run = |coefficients: &str| {
        common::gloffuse()
            .args(["generate", "--coefficients", coefficients, "--into"])
            .arg(&blend)
            .arg("--blender")
            .arg(&blender)
            .arg("--no-provision")
            .assert()
    };
    // --into needs an existing file: refused, nothing created.
    run("seed")
        .code(2)
        .stderr(predicates::str::contains("an existing .blend file"));
    assert!(!blend.exists());
    common::gloffuse()
        .args(["generate", "--coefficients", "seed", "--blend"])
        .arg(&blend)
        .arg("--blender")
        .arg(&blender)
        .assert()
        .success();
    let first = std::fs::read(&blend).unwrap();
    run("blender-4").success();
    let backup = dir.path().join("scene.blend1");
    assert_eq!(
        std::fs::read(&backup).unwrap(),
        first,
        "the .blend1 holds the previous file"
    );
    let mut names: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    names.sort();
    assert_eq!(
        names,
        ["blender_assets.cats.txt", "scene.blend", "scene.blend1"]
    );
}

/// The extension built in bpy 4.5: Blender's validator accepts it, and in bpy 4.5 and 5.0
/// it installs, enables, registers its library with the generated groups, and cleans up
/// on disable (tests/blender/check_extension.py, in a fresh user-resources folder). One
/// test, not one per version: the one extension bpy 4.5 built is what each Blender installs.
#[test]
fn the_extension_installs_and_brings_the_groups() {
    let Some(builder) = common::blender::real_blender("4.5") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let zip = dir.path().join("gloffuse.zip");
    let out = common::gloffuse()
        .args([
            "generate",
            "--json",
            "--mode",
            "roughness,view,multiscatter",
        ])
        .arg("--extension")
        .arg(&zip)
        .arg("--blender")
        .arg(&builder)
        .args(["--no-provision", "--timeout", "300"])
        .assert()
        .success()
        .get_output()
        .stdout
        .clone();
    let summary: Value = serde_json::from_slice(&out).unwrap();
    let leftovers: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
    assert_eq!(leftovers.len(), 1, "only the .zip: {leftovers:?}");
    let groups = dir.path().join("groups.json");
    std::fs::write(&groups, summary["groups"].to_string()).unwrap();
    let checker = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/blender/check_extension.py"
    );
    for label in ["4.5", "5.0"] {
        let Some(blender) = common::blender::real_blender(label) else {
            continue;
        };
        let user = tempfile::tempdir().unwrap();
        let result = dir.path().join(format!("extension {label}.json"));
        let run = common::blender::run_in_blender(
            &blender,
            checker.as_ref(),
            &[
                "--zip".as_ref(),
                zip.as_os_str(),
                "--groups".as_ref(),
                groups.as_os_str(),
                "--user-resources".as_ref(),
                user.path().as_os_str(),
                "--out".as_ref(),
                result.as_os_str(),
            ],
        );
        let report: Value = std::fs::read_to_string(&result)
            .ok()
            .and_then(|t| serde_json::from_str(&t).ok())
            .unwrap_or(Value::Null);
        assert!(
            run.status.success() && report["failures"].as_array().is_some_and(|f| f.is_empty()),
            "Blender {label}: check_extension failed\nfailures: {}\nstderr:\n{}",
            report["failures"],
            String::from_utf8_lossy(&run.stderr)
        );
        assert_eq!(
            report["assets"].as_array().map(Vec::len),
            summary["groups"].as_array().map(Vec::len)
        );
    }
}

/// An extension needs a Blender with extensions to build it: 3.4 is refused before it runs,
/// naming what would work, and nothing is written.
#[test]
fn blender_3_4_cannot_build_an_extension() {
    let Some(blender) = common::blender::real_blender("3.4") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let zip = dir.path().join("gloffuse.zip");
    common::gloffuse()
        .args(["generate", "--extension"])
        .arg(&zip)
        .arg("--blender")
        .arg(&blender)
        .assert()
        .code(2)
        .stderr(predicates::str::contains(
            "Blender 4.2 or later for --extension",
        ));
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
}

/// The script `generate --mode view --script` writes without any Blender, and the groups its
/// summary names: made once for the per-version tests (in cargo's temporary folder for tests,
/// since a static is never dropped).
fn view_script() -> &'static (PathBuf, Vec<String>) {
    static SCRIPT: OnceLock<(PathBuf, Vec<String>)> = OnceLock::new();
    SCRIPT.get_or_init(|| {
        let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("one-script");
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let script = dir.join("gloffuse.py");
        let out = common::gloffuse()
            .args(["generate", "--mode", "view", "--json", "--script"])
            .arg(&script)
            .env("GLOFFUSE_BLENDER", "/nonexistent/blender")
            .assert()
            .success()
            .get_output()
            .stdout
            .clone();
        let summary: Value = serde_json::from_slice(&out).unwrap();
        let named: Vec<String> = summary["groups"]
            .as_array()
            .unwrap()
            .iter()
            .map(|g| g.as_str().unwrap().to_string())
            .collect();
        assert!(
            named.iter().any(|g| g == "Gloffuse View (GGX)"),
            "{named:?}"
        );
        assert!(
            !named.iter().any(|g| g.contains("Multiscatter")),
            "{named:?}"
        );
        (script, named)
    })
}

/// One script, written without any Blender, run in Blender 3.4, 4.5 and 5.0: each builds
/// the groups of its own masking family (3.4 the blender-3 curves, 4.5 and 5.0 the
/// blender-4 ones), measured through Cycles by check_generated.py; and `--mode view` alone
/// builds the view groups and not the multiscatter ones, exactly the groups the summary names.
fn one_script_serves_every_blender(label: &'static str, blender: PathBuf) {
    let checker = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/blender/check_generated.py"
    );
    let (script, named) = view_script();
    let dir = tempfile::tempdir().unwrap();
    let preset = if label == "3.4" {
        "blender-3"
    } else {
        "blender-4"
    };
    let blend = dir.path().join(format!("groups-{label}.blend"));
    let run =
        common::blender::run_in_blender(&blender, script, &["--save".as_ref(), blend.as_os_str()]);
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(
        run.status.success(),
        "Blender {label}: {stdout}{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let result: Value = stdout
        .lines()
        .rev()
        .find_map(|l| l.strip_prefix("GLOFFUSE_RESULT "))
        .map(|l| serde_json::from_str(l).unwrap())
        .expect("a result line");
    let built: Vec<&str> = result["groups"]
        .as_array()
        .unwrap()
        .iter()
        .map(|g| g.as_str().unwrap())
        .collect();
    assert_eq!(
        built, *named,
        "Blender {label} builds what the summary names"
    );
    let expect = dir.path().join(format!("expect-{label}.json"));
    std::fs::write(&expect, expectations(preset).to_string()).unwrap();
    let report = dir.path().join(format!("report-{label}.json"));
    let check = common::blender::run_in_blender(
        &blender,
        checker.as_ref(),
        &[
            "--blend".as_ref(),
            blend.as_os_str(),
            "--expect".as_ref(),
            expect.as_os_str(),
            "--out".as_ref(),
            report.as_os_str(),
        ],
    );
    let report: Value = std::fs::read_to_string(&report)
        .ok()
        .and_then(|t| serde_json::from_str(&t).ok())
        .unwrap_or(Value::Null);
    assert!(
        check.status.success() && report["failures"].as_array().is_some_and(|f| f.is_empty()),
        "Blender {label}: the script's groups are not {preset}'s: {}\n{}",
        report["failures"],
        String::from_utf8_lossy(&check.stderr)
    );
}

common::blender::per_blender!(one_script_serves_every_blender);
