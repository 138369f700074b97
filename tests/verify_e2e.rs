//! `gloffuse verify` and `refresh` end to end in real Blender 3.4, 4.5 and 5.0.
//!
//! Two independent routes must agree: Cycles' rendered furnace spheres (read back from EXR)
//! and gloffuse's integrator. And the product's promise: with the default coefficients every
//! corrected sphere is 100 % ± 1 %; with the display-referred seed curve it is not.
//!
//! Tier: blender (needs the Blenders and tools `scripts/test.sh` installs).

mod common;

use std::path::PathBuf;

use serde_json::Value;

fn verify_json(blender: &std::path::Path, extra: &[&str]) -> (i32, Value, String) {
    let out = common::gloffuse()
        .arg("verify")
        .arg("--blender")
        .arg(blender)
        .args(["--no-provision", "--timeout", "300"])
        .args(extra)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    let v = serde_json::from_slice(&out.stdout).unwrap_or(Value::Null);
    (out.status.code().unwrap_or(-1), v, stderr)
}

fn default_coefficients_pass_in_every_blender(label: &'static str, blender: PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let report = dir.path().join("report dir é");
    let (code, v, stderr) =
        verify_json(&blender, &["--json", "--report", report.to_str().unwrap()]);
    assert_eq!(code, 0, "Blender {label}: {stderr}\n{v:#}");
    assert_eq!(v["pass"], true);
    assert!(
        v["render"]["blender_version"]
            .as_str()
            .unwrap()
            .starts_with(label)
    );
    let rows = v["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 33, "3 distributions × 11 roughness values");
    // The preset of this Blender: nothing to note.
    assert_eq!(v["notes"], serde_json::json!([]), "Blender {label}");
    for (i, r) in rows.iter().enumerate() {
        // Rows are numbered in order; roughness is a plain number.
        assert_eq!(r["id"].as_u64(), Some(i as u64), "Blender {label}");
        assert!(
            r["roughness"].is_f64(),
            "Blender {label}: {}",
            r["roughness"]
        );
        let what = format!("Blender {label} {} r={}", r["distribution"], r["roughness"]);
        let corrected = r["corrected"]["mean"].as_f64().unwrap();
        assert!(
            (corrected - 1.0).abs() <= 0.01,
            "{what}: corrected {corrected}"
        );
        // Render vs integrator, uncorrected: two independent routes to E_avg.
        let rendered = r["uncorrected"]["mean"].as_f64().unwrap();
        let predicted = r["predicted_uncorrected"].as_f64().unwrap();
        assert!(
            (rendered / predicted - 1.0).abs() < 0.005,
            "{what}: rendered {rendered}, predicted {predicted}"
        );
        assert!(
            r["corrected"]["standard_error"].as_f64().unwrap() <= 0.002,
            "{what}: standard error"
        );
    }
    for m in v["reference"].as_array().unwrap() {
        let mean = m["stats"]["mean"].as_f64().unwrap();
        assert!(
            (mean - 1.0).abs() < 0.01,
            "Blender {label}: Multiscatter GGX {mean}"
        );
    }
    for name in [
        "report.json",
        "sweep.exr",
        "contact-sheet.png",
        "brightness.png",
    ] {
        let p = report.join(name);
        assert!(
            std::fs::metadata(&p).map(|m| m.len() > 0).unwrap_or(false),
            "{}",
            p.display()
        );
    }
    // The report's EXR reads back with the same statistics the report holds.
    let img = gloffuse::verify::image::read_rgba(&report.join("sweep.exr")).unwrap();
    assert_eq!((img.width, img.height), (11 * 64, 7 * 64));
}

common::blender::per_blender!(default_coefficients_pass_in_every_blender);

#[test]
fn seed_coefficients_fail_and_say_why() {
    let Some(blender) = common::blender::real_blender("4.5") else {
        return;
    };
    let out = common::gloffuse()
        .args([
            "verify",
            "--coefficients",
            "seed",
            "--no-provision",
            "--blender",
        ])
        .arg(&blender)
        .assert()
        .code(1)
        .get_output()
        .stdout
        .clone();
    let text = String::from_utf8_lossy(&out);
    // The verdict counts the failures first and names the passes and the target.
    let failed = text.lines().filter(|l| l.ends_with("  FAIL")).count();
    let passed = text.lines().filter(|l| l.ends_with("  ok")).count();
    let headline = format!(
        "FAIL: {failed} of {} corrected spheres (roughness mode) missed their target by more than ±",
        failed + passed
    );
    assert!(failed > 0 && text.contains(&headline), "{headline}\n{text}");
    assert!(
        text.contains(&format!("; the other {passed} passed")),
        "{text}"
    );
    assert!(text.contains("the target is 100 %"), "{text}");
    assert!(text.contains("rings are shown, not judged"), "{text}");
    assert!(text.contains("display-referred"), "{text}");
    // Both ways: at r = 0.4 the seed's GGX gain 100/f = 100/89.79 times E_avg = 0.9405 is
    // 104.7 %; at r = 1 it is 69 %.
    assert!(
        text.contains("Over-corrected:") && text.contains("worst GGX r = 0.4 at 104.7 %"),
        "{text}"
    );
    assert!(
        text.contains("Under-corrected:") && text.contains("worst GGX r = 1 at 69."),
        "{text}"
    );
    let (code, v, _) = verify_json(
        &blender,
        &["--coefficients", "seed", "--json", "-r", "1", "-d", "ggx"],
    );
    assert_eq!(code, 1);
    let ggx = v["rows"][0]["corrected"]["mean"].as_f64().unwrap();
    // The seed's gain at r = 1 is 100/59 = 1.69; E_avg(1) = 0.409, so about 69 %.
    assert!((ggx - 0.409 * 100.0 / 59.0).abs() < 0.01, "{ggx}");
    // The note as data: one under-corrected sphere (that row), none over.
    let notes = v["notes"].as_array().unwrap();
    assert_eq!(notes.len(), 1, "{notes:?}");
    let note = &notes[0];
    assert_eq!(note["kind"], "display-referred");
    assert_eq!(note["coefficients"], "seed");
    assert!(note.get("over").is_none(), "{note}");
    let under = &note["under"];
    assert_eq!(under["count"], 1);
    assert_eq!(under["distribution"], "ggx");
    assert_eq!(under["roughness"], 1.0);
    assert_eq!(under["brightness"], v["rows"][0]["brightness"]);
    let needed = 1.0 / v["rows"][0]["predicted_uncorrected"].as_f64().unwrap();
    assert!((under["needed_gain"].as_f64().unwrap() - needed).abs() < 1e-12);
    assert!((under["gain"].as_f64().unwrap() - 100.0 / 59.0).abs() < 1e-9);
}

#[test]
fn refresh_measures_fits_and_verifies() {
    let Some(blender) = common::blender::real_blender("4.5") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("measured.json");
    let run = common::gloffuse()
        .args([
            "refresh",
            "--json",
            "--spp",
            "32",
            "--no-provision",
            "--out",
        ])
        .arg(&out)
        .arg("--blender")
        .arg(&blender)
        .output()
        .unwrap();
    assert_eq!(
        run.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let v: Value = serde_json::from_slice(&run.stdout).unwrap();
    assert_eq!(v["verify"]["pass"], true);
    assert_eq!(
        v["warnings"].as_array().unwrap().len(),
        0,
        "{:#}",
        v["warnings"]
    );
    let file: Value = serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    let p = &file["distributions"]["ggx"]["provenance"];
    assert_eq!(p["source"], "blender");
    assert!(p["blender_version"].as_str().unwrap().starts_with("4.5"));
    assert_eq!(p["samples"], "32 spp");
    // The file is a valid coefficients file for every other command.
    common::gloffuse()
        .args(["coefficients", "show"])
        .arg(&out)
        .assert()
        .success();
}

#[test]
fn verify_refuses_bad_input_before_rendering() {
    let Some(blender) = common::blender::real_blender("4.5") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("a file");
    std::fs::write(&file, "x").unwrap();
    let cases: Vec<(Vec<String>, &str)> = vec![
        (
            vec!["-r".into(), "0.5,1.5".into()],
            "invalid roughness '1.5'",
        ),
        (vec!["-r".into(), "".into()], "invalid roughness ''"),
        (vec!["-r".into(), "0.5,0.5".into()], "each roughness once"),
        (
            vec!["--tolerance".into(), "0".into()],
            "invalid tolerance '0'",
        ),
        (vec!["--spp".into(), "0".into()], "--spp"),
        (vec!["--resolution".into(), "4".into()], "--resolution"),
        (
            vec!["--report".into(), file.to_str().unwrap().into()],
            "needs a directory",
        ),
        (
            vec!["--coefficients".into(), "nope.json".into()],
            "no such preset or file",
        ),
        (
            vec![
                "--coefficients".into(),
                "seed".into(),
                "-d".into(),
                "ashikhmin-shirley".into(),
            ],
            "one the coefficients 'seed' hold",
        ),
        (
            vec!["-d".into(), "phong".into()],
            "invalid distribution 'phong'",
        ),
    ];
    for (args, fragment) in cases {
        common::gloffuse()
            .arg("verify")
            .args(&args)
            .arg("--blender")
            .arg(&blender)
            .assert()
            .code(2)
            .stderr(predicates::str::contains(fragment));
    }
}

/// The CI outputs of a failing check (the seed coefficients, Blender 4.5): JUnit XML that
/// CPython's own XML parser reads, with one test case per sphere, failures exactly where
/// the table says FAIL, measured/predicted/tolerance properties, and the message and rerun
/// command on each failure; and report.html, loaded and screenshotted by a real headless
/// Chromium, whose banner shows the verdict's colour, with the brightness plot on the page
/// and the deviation column saying why a sphere judged on its mean has a coloured disc.
#[test]
fn junit_and_html_reports_of_a_failing_check() {
    let Some(blender) = common::blender::real_blender("4.5") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let junit = dir.path().join("junit.xml");
    let report = dir.path().join("report");
    let (code, v, stderr) = verify_json(
        &blender,
        &[
            "--coefficients",
            "seed",
            "--json",
            "-r",
            "0.5,1",
            "--junit",
            junit.to_str().unwrap(),
            "--report",
            report.to_str().unwrap(),
        ],
    );
    assert_eq!(code, 1, "{stderr}");
    let last = stderr.lines().last().unwrap_or_default();
    let page_line = format!("report: {}", report.join("report.html").display());
    assert!(last.starts_with(&page_line), "{stderr}");
    let failed: Vec<String> = v["rows"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|r| r["pass"] == false)
        .map(|r| {
            let roughness = r["roughness"].as_f64().unwrap();
            format!("{} r={roughness} mean", label(&r["distribution"]))
        })
        .collect();
    assert!(!failed.is_empty());
    let parsed = std::process::Command::new("python3")
        .arg("-c")
        .arg(
            "import json, sys, xml.etree.ElementTree as ET\n\
             root = ET.parse(sys.argv[1]).getroot()\n\
             cases = root.findall('.//testcase')\n\
             out = {'tests': root.get('tests'), 'failures': root.get('failures'),\n\
                    'failed': [c.get('name') for c in cases if c.find('failure') is not None],\n\
                    'props': sorted({p.get('name') for c in cases for p in c.findall('.//property')}),\n\
                    'text': [c.find('failure').text for c in cases if c.find('failure') is not None]}\n\
             print(json.dumps(out))",
        )
        .arg(&junit)
        .output()
        .unwrap();
    assert!(
        parsed.status.success(),
        "{}",
        String::from_utf8_lossy(&parsed.stderr)
    );
    let x: Value = serde_json::from_slice(&parsed.stdout).unwrap();
    assert_eq!(x["tests"], v["rows"].as_array().unwrap().len().to_string());
    let mut junit_failed: Vec<String> = x["failed"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f.as_str().unwrap().to_string())
        .collect();
    junit_failed.sort();
    let mut want = failed.clone();
    want.sort();
    assert_eq!(junit_failed, want);
    for p in ["measured_percent", "predicted_percent", "tolerance_percent"] {
        assert!(x["props"].as_array().unwrap().iter().any(|q| q == p), "{p}");
    }
    for text in x["text"].as_array().unwrap() {
        let text = text.as_str().unwrap();
        assert!(
            text.contains("rerun: ") && text.contains("--coefficients seed"),
            "{text}"
        );
    }

    let page = report.join("report.html");
    let html = std::fs::read_to_string(&page).unwrap();
    assert_eq!(html.matches("<tr class=\"fail\">").count(), failed.len());
    // Failures first.
    let first_ok = html.find("<tr class=\"ok\">").unwrap_or(usize::MAX);
    assert!(html.rfind("<tr class=\"fail\">").unwrap() < first_ok);
    // The banner says how many failed of how many; the page says rings are not judged in
    // this mode; the legend sits above the table it explains.
    let total = v["rows"].as_array().unwrap().len();
    let headline = format!("<h1>FAIL: {} of {total} corrected spheres", failed.len());
    assert!(html.contains(&headline), "{headline}");
    assert!(html.contains("worst ring (not judged)"));
    assert!(html.find("class=\"legend\"").unwrap() < html.find("<th>status</th>").unwrap());
    // Why an ok sphere's disc is coloured, in the deviation column's own header; the
    // brightness plot on the page, above the table, and in the folder.
    let header = &html[html.find("<th>deviation").unwrap()..];
    let header = &header[..header.find("</th>").unwrap()];
    assert!(header.contains("corrects the mean only"), "{header}");
    let plot = html
        .find("<img class=\"plot\" src=\"brightness.png\"")
        .unwrap();
    assert!(plot < html.find("<th>status</th>").unwrap());
    assert!(report.join("brightness.png").is_file());
    column_labels_sit_over_the_cells(&report.join("deviation.png"));
    let Some(chromium) = common::browser() else {
        return;
    };
    let image = common::screenshot(&chromium, &page);
    let banner_pixels = common::pixels_of(&image, gloffuse::report::page::FAIL_COLOUR);
    assert!(
        banner_pixels > 10_000,
        "{banner_pixels} pixels of the FAIL banner"
    );
    // The thumbnails were drawn: plenty of distinct colours below the banner.
    let distinct: std::collections::HashSet<[u8; 3]> = image.pixels().map(|p| p.0).collect();
    assert!(distinct.len() > 200, "{} colours", distinct.len());
}

/// deviation.png labels its columns: light text on the dark background in the band just
/// above the first false-colour cell (found by its colour: the rest is grey).
fn column_labels_sit_over_the_cells(path: &std::path::Path) {
    let image = image::open(path).unwrap().to_rgb8();
    let coloured = |p: &image::Rgb<u8>| {
        let [r, g, b] = p.0.map(i32::from);
        (r - g).abs().max((g - b).abs()) > 20
    };
    let (top, x0) = image
        .enumerate_pixels()
        .find(|(_, _, p)| coloured(p))
        .map(|(x, y, _)| (y, x))
        .expect("false-colour cells");
    let band = top.saturating_sub(20)..top;
    let lit = band
        .flat_map(|y| (x0.saturating_sub(24)..x0 + 24).map(move |x| (x, y)))
        .filter(|&(x, y)| x < image.width() && image.get_pixel(x, y).0[1] > 150)
        .count();
    assert!(
        lit > 10,
        "{lit} text pixels over the first column of {}",
        path.display()
    );
    // The lines over the cells fit: none reaches the picture's right margin (a two-column
    // sweep is narrower than its scope line).
    let margin = image.width() - 8..image.width();
    let at_edge = (0..top.saturating_sub(20))
        .flat_map(|y| margin.clone().map(move |x| (x, y)))
        .filter(|&(x, y)| image.get_pixel(x, y).0[1] > 150)
        .count();
    assert_eq!(
        at_edge,
        0,
        "text runs into the right margin of {}",
        path.display()
    );
}

fn label(distribution: &Value) -> &'static str {
    match distribution.as_str().unwrap() {
        "beckmann" => "Beckmann",
        "ggx" => "GGX",
        _ => "Ashikhmin-Shirley",
    }
}

/// Coefficients of the other masking family: the note names the preset that suits this
/// Blender (never a flag), and the command line adds the flag that checks with it.
#[test]
fn masking_mismatch_names_the_preset_and_the_cli_the_flag() {
    let label = "3.4";
    let Some(blender) = common::blender::real_blender(label) else {
        return;
    };
    let args = ["--coefficients", "blender-4", "-r", "1", "-d", "ggx"];
    let (_, v, stderr) = verify_json(&blender, &[&args[..], &["--json"]].concat());
    let notes = v["notes"].as_array().unwrap_or_else(|| panic!("{stderr}"));
    assert_eq!(notes.len(), 1, "Blender {label}: {notes:?}");
    let n = &notes[0];
    assert_eq!(n["kind"], "masking-mismatch");
    assert_eq!(n["distribution"], "ggx");
    assert_eq!(n["fitted"], "height-correlated");
    assert_eq!(n["masking"], "separable");
    assert_eq!(n["blender"], "3.4");
    assert_eq!(n["suggested"], "blender-3");
    let out = common::gloffuse()
        .args(["verify", "--no-provision", "--blender"])
        .arg(&blender)
        .args(args)
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    let note = text
        .lines()
        .find(|l| l.starts_with("note: "))
        .unwrap_or_else(|| panic!("{text}"));
    assert!(
        note.contains("'blender-3'") && !note.contains("--"),
        "{note}"
    );
    assert!(
        text.lines()
            .any(|l| l == "hint: rerun with --coefficients blender-3"),
        "{text}"
    );
}
