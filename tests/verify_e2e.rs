//! `gloffuse verify` and `refresh` end to end in real Blender 3.4, 4.5 and 5.0.
//!
//! Two independent routes must agree: Cycles' rendered furnace spheres (read back from EXR)
//! and gloffuse's integrator. And the product's promise: with the default coefficients every
//! corrected sphere is 100 % ± 1 %; with the display-referred seed curve it is not.

mod common;

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

#[test]
fn default_coefficients_pass_in_every_blender() {
    for (label, blender) in common::blender::real_blenders() {
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
        for r in rows {
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
}

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
    assert!(text.contains("FAIL"), "{text}");
    assert!(text.contains("display-referred"), "{text}");
    let (code, v, _) = verify_json(
        &blender,
        &["--coefficients", "seed", "--json", "-r", "1", "-d", "ggx"],
    );
    assert_eq!(code, 1);
    let ggx = v["rows"][0]["corrected"]["mean"].as_f64().unwrap();
    // The seed's gain at r = 1 is 100/59 = 1.69; E_avg(1) = 0.409, so about 69 %.
    assert!((ggx - 0.409 * 100.0 / 59.0).abs() < 0.01, "{ggx}");
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
