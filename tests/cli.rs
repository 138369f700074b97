//! The `gloffuse` binary driven as a user would, including bad input: every bad input must
//! exit 2 with a message naming the input, never panic, and never leave a file behind.
//!
//! Tier: fast (no Blender; `scripts/test.sh --fast` runs it).

mod common;

use predicates::prelude::*;
use serde_json::Value;
use std::f64::consts::LN_2;

use common::gloffuse;

fn json_of(args: &[&str]) -> Value {
    let out = gloffuse()
        .args(args)
        .assert()
        .success()
        .get_output()
        .stdout
        .clone();
    serde_json::from_slice(&out).unwrap()
}

#[test]
fn help_and_version() {
    gloffuse()
        .arg("--version")
        .assert()
        .success()
        .stdout(predicate::str::contains(env!("CARGO_PKG_VERSION")));
    gloffuse().arg("--help").assert().success().stdout(
        predicate::str::contains("lose energy").and(predicate::str::contains("Exit codes")),
    );
    // Every command that exits 1 on a failing check is named beside exit code 1 (as
    // wrapped to any width).
    let help = gloffuse()
        .arg("--help")
        .assert()
        .success()
        .get_output()
        .stdout
        .clone();
    let help = String::from_utf8(help).unwrap();
    let words: Vec<&str> = help.split_whitespace().collect();
    assert!(
        words
            .join(" ")
            .contains("1 a check failed (verify, refresh, audit, report merge)"),
        "{help}"
    );
    gloffuse()
        .args(["albedo", "--help"])
        .assert()
        .success()
        .stdout(predicate::str::contains("view cosine"));
}

/// A stdout whose reader is already gone (`gloffuse … | true`): every write fails with
/// EPIPE. The program must end quietly with exit code 0, as ripgrep does, not panic.
#[test]
fn a_closed_stdout_ends_quietly_with_exit_0() {
    use std::os::fd::{FromRawFd, OwnedFd};
    let cases: [&[&str]; 5] = [
        &["coefficients", "show", "blender-4", "--json"],
        &["coefficients", "show", "seed"],
        &["albedo", "-d", "ggx", "-r", "1", "--json"],
        &["fit", "-d", "ggx", "--point", "0.5:85", "--point", "1:59"],
        &["albedo", "--model", "lambert"],
    ];
    for args in cases {
        let mut fds = [0; 2];
        // SAFETY: pipe() fills two new descriptors; each is owned exactly once below.
        assert_eq!(unsafe { libc::pipe(fds.as_mut_ptr()) }, 0);
        let (reader, writer) =
            unsafe { (OwnedFd::from_raw_fd(fds[0]), OwnedFd::from_raw_fd(fds[1])) };
        drop(reader);
        let out = std::process::Command::new(assert_cmd::cargo::cargo_bin("gloffuse"))
            .args(args)
            .stdout(writer)
            .output()
            .expect("gloffuse starts");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(0), "{args:?}: {stderr}");
        assert!(stderr.is_empty(), "{args:?} printed: {stderr}");
    }
}

#[test]
fn albedo_matches_closed_forms() {
    let v = json_of(&[
        "albedo",
        "--distribution",
        "GGX",
        "--roughness",
        "1",
        "--json",
    ]);
    assert!((v["directional_albedo"].as_f64().unwrap() - (1.0 - LN_2)).abs() < 1e-6);
    assert_eq!(v["masking"], "height-correlated");
    let v = json_of(&[
        "albedo",
        "-d",
        "ASHIKHMIN_SHIRLEY",
        "-r",
        "1",
        "--json",
        "--blender-version",
        "3.4",
    ]);
    assert!((v["directional_albedo"].as_f64().unwrap() - (2f64.sqrt() - 1.0) / 3.0).abs() < 1e-6);
    assert_eq!(v["masking"], "separable");
    gloffuse()
        .args(["albedo", "-d", "ggx", "-r", "1"])
        .assert()
        .success()
        .stdout(predicate::str::contains("E(mu = 1) = 0.306853"));
}

#[test]
fn albedo_table_writes_a_full_grid() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("ggx table.csv");
    gloffuse()
        .args(["albedo", "-d", "ggx", "--table"])
        .arg(&path)
        .args(["--grid", "8"])
        .assert()
        .success();
    let text = std::fs::read_to_string(&path).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines[0], "roughness,mu,albedo,average_albedo");
    assert_eq!(lines.len(), 1 + 64);
    for l in &lines[1..] {
        let v: Vec<f64> = l.split(',').map(|x| x.parse().unwrap()).collect();
        assert!((0.0..=1.0).contains(&v[2]) && (0.0..=1.0).contains(&v[3]));
        if v[0] == 0.0 {
            assert_eq!(v[2], 1.0);
        }
    }
}

#[test]
fn fit_reproduces_the_seed_exactly() {
    let v = json_of(&[
        "fit", "-d", "beckmann", "-p", "0.5:97", "-p", "1:71", "--json",
    ]);
    let f = &v["fits"][0];
    assert!((f["a"].as_f64().unwrap() + 34.0).abs() < 1e-9);
    assert!((f["b"].as_f64().unwrap() - 5.0).abs() < 1e-9);
    assert_eq!(f["c"].as_f64().unwrap(), 0.0);
    assert_eq!(f["d"].as_f64().unwrap(), 100.0);
    let v = json_of(&[
        "fit",
        "--distribution",
        "GGX",
        "--point",
        "0.5:85",
        "--point",
        "1:59",
        "--json",
    ]);
    let f = &v["fits"][0];
    assert!((f["a"].as_f64().unwrap() - 38.0).abs() < 1e-9);
    assert!((f["b"].as_f64().unwrap() + 79.0).abs() < 1e-9);
    gloffuse()
        .args(["fit", "-d", "ggx", "-p", "0.5:85", "-p", "1:59"])
        .assert()
        .success()
        .stdout(predicate::str::contains("a = 38, b = -79, c = 0, d = 100"));
}

#[test]
fn fit_from_integrator_writes_a_coefficients_file_that_show_reads() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("coefficients.json");
    gloffuse()
        .args([
            "fit",
            "--from",
            "integrator",
            "--blender-version",
            "3.4",
            "--degree",
            "6",
            "--out",
        ])
        .arg(&path)
        .env("SOURCE_DATE_EPOCH", "0")
        .assert()
        .success();
    let v: Value = serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    assert_eq!(v["format_version"], 1);
    assert_eq!(v["distributions"]["ggx"]["masking"], "separable");
    assert_eq!(
        v["distributions"]["ggx"]["provenance"]["date"],
        "1970-01-01"
    );
    assert!(
        v["distributions"]["ggx"]["residuals"]["max_gain_error"]
            .as_f64()
            .unwrap()
            < 1e-3
    );
    gloffuse()
        .args(["coefficients", "show"])
        .arg(&path)
        .assert()
        .success()
        .stdout(predicate::str::contains("Ashikhmin-Shirley: f(r) ="));
}

#[test]
fn coefficients_show_lists_and_reads_presets() {
    gloffuse()
        .args(["coefficients", "show"])
        .assert()
        .success()
        .stdout(predicate::str::contains("seed").and(predicate::str::contains("blender-4")));
    gloffuse()
        .args(["coefficients", "show", "seed"])
        .assert()
        .success()
        .stdout(predicate::str::contains("display-referred"));
    let v = json_of(&["coefficients", "show", "blender-4", "--json"]);
    assert_eq!(v["distributions"]["beckmann"]["color_space"], "linear");
}

/// Each case: arguments, a fragment the error must contain.
const BAD_INPUT: &[(&[&str], &str)] = &[
    (
        &["albedo", "-d", "phong", "-r", "0.5"],
        "invalid distribution 'phong'",
    ),
    (
        &["albedo", "-d", "ggx", "-r", "1.5"],
        "invalid roughness '1.5'",
    ),
    (
        &["albedo", "-d", "ggx", "-r", "-0.1"],
        "invalid roughness '-0.1'",
    ),
    (
        &["albedo", "-d", "ggx", "-r", "NaN"],
        "invalid roughness 'NaN'",
    ),
    (
        &["albedo", "-d", "ggx", "-r", "inf"],
        "invalid roughness 'inf'",
    ),
    (
        &["albedo", "-d", "ggx", "-r", "0.5", "--mu", "0"],
        "invalid view cosine '0'",
    ),
    (
        &[
            "albedo",
            "-d",
            "ggx",
            "-r",
            "0.5",
            "--blender-version",
            "2.79",
        ],
        "Blender 3.0 or later",
    ),
    (&["albedo", "-d", "ggx"], "--roughness"),
    (&["fit", "-d", "ggx", "-p", "0.5"], "invalid point '0.5'"),
    (
        &["fit", "-d", "ggx", "-p", "0.5:abc"],
        "invalid point '0.5:abc'",
    ),
    (
        &["fit", "-d", "ggx", "-p", "2:50"],
        "roughness outside [0, 1]",
    ),
    (&["fit", "-d", "ggx", "-p", "0.5:NaN"], "invalid point"),
    (
        &["fit", "-d", "ggx", "-p", "0.5:85", "-p", "0.5:80"],
        "duplicate roughness 0.5",
    ),
    (
        &["fit", "-d", "ggx", "-p", "0.5:85"],
        "needs at least 2 points",
    ),
    (
        &[
            "fit", "-d", "ggx", "-p", "0.5:85", "-p", "1:59", "--degree", "4",
        ],
        "needs at least 3 points",
    ),
    (
        &[
            "fit", "-d", "ggx", "-p", "0.5:85", "-p", "1:59", "--degree", "9",
        ],
        "invalid --degree '9'",
    ),
    (&["fit", "-p", "0.5:85", "-p", "1:59"], "--distribution"),
    (
        &["coefficients", "show", "no-such-preset"],
        "no such preset or file",
    ),
];

#[test]
fn bad_input_is_refused_clearly() {
    for (args, fragment) in BAD_INPUT {
        let out = gloffuse().args(*args).assert().code(2).get_output().clone();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(
            stderr.contains(fragment),
            "{args:?}: stderr lacks {fragment:?}:\n{stderr}"
        );
        assert!(!stderr.contains("panicked"), "{args:?} panicked");
    }
}

#[test]
fn unwritable_outputs_leave_no_file() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("no such dir").join("c.json");
    gloffuse()
        .args(["fit", "-d", "ggx", "-p", "0.5:85", "-p", "1:59", "--out"])
        .arg(&missing)
        .assert()
        .code(2)
        .stderr(predicate::str::contains("does not exist"));
    gloffuse()
        .args(["fit", "-d", "ggx", "-p", "0.5:85", "-p", "1:59", "--out"])
        .arg(dir.path())
        .assert()
        .code(2)
        .stderr(predicate::str::contains("is a directory"));
    // A curve that reaches 0 on [0, 1] would make the gain blow up: refused, nothing written.
    let out = dir.path().join("zero.json");
    gloffuse()
        .args([
            "fit",
            "-d",
            "ggx",
            "-p",
            "0.5:30",
            "-p",
            "1:5",
            "--weighting",
            "absolute",
            "--out",
        ])
        .arg(&out)
        .assert()
        .code(2)
        .stderr(predicate::str::contains("must stay above 0"));
    assert!(!out.exists());
    assert_eq!(
        std::fs::read_dir(dir.path()).unwrap().count(),
        0,
        "leftover files"
    );
}

#[test]
fn malformed_coefficient_files_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let good = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/presets/blender-4.json"
    ))
    .unwrap();
    let cases = [
        ("not json", "not valid JSON".to_string()),
        (
            "{\"format\": \"other\"}",
            "not a coefficients file".to_string(),
        ),
        ("", "not valid JSON".to_string()),
    ];
    let mut all: Vec<(String, String)> = cases
        .iter()
        .map(|(a, b)| (a.to_string(), b.clone()))
        .collect();
    all.push((
        good.replace("\"format_version\": 1", "\"format_version\": 7"),
        "format_version 7 is not supported".into(),
    ));
    all.push((
        good.replacen("100.0,\n", "100.5,\n", 1),
        "f(0) must be 100".into(),
    ));
    for (i, (text, fragment)) in all.iter().enumerate() {
        let path = dir.path().join(format!("c{i}.json"));
        std::fs::write(&path, text).unwrap();
        gloffuse()
            .args(["coefficients", "show"])
            .arg(&path)
            .assert()
            .code(2)
            .stderr(
                predicate::str::contains(fragment.as_str())
                    .and(predicate::str::contains(path.to_str().unwrap())),
            );
    }
}

#[test]
fn albedo_of_classic_models_matches_closed_forms() {
    let v = json_of(&[
        "albedo", "--model", "lambert", "--rho", "0.7", "--mu", "0.3", "--json",
    ]);
    assert!((v["directional_albedo"].as_f64().unwrap() - 0.7).abs() < 1e-3);
    // Fresnel blend: E(μ) = Rd (1 − Rs)(1 − (1 − μ/2)⁵).
    let v = json_of(&[
        "albedo",
        "--model",
        "fresnel-blend",
        "--rho",
        "1",
        "--rs",
        "0.04",
        "--json",
    ]);
    let want = 0.96 * (1.0 - 0.5f64.powi(5));
    assert!((v["directional_albedo"].as_f64().unwrap() - want).abs() < 1e-3);
    for m in ["phong", "ward", "cook-torrance"] {
        let v = json_of(&["albedo", "--model", m, "--mu", "0.5", "--json"]);
        let e = v["directional_albedo"].as_f64().unwrap();
        assert!(e > 0.0 && e <= 1.0 + 1e-9, "{m}: {e}");
    }
    gloffuse()
        .args(["albedo", "--model", "lambert", "--rho", "2"])
        .assert()
        .code(2)
        .stderr(predicate::str::contains("reflectance rho '2'"));
    gloffuse()
        .args(["albedo", "--model", "blinn"])
        .assert()
        .code(2)
        .stderr(predicate::str::contains("blinn"));
}

/// `lut` end to end: the file the binary writes is what its summary says, and a texel of
/// the Kulla–Conty table (Monte Carlo over Cycles' BSDF) agrees with `albedo` (deterministic
/// quadrature) — two independent estimators of the same E(μ, r).
#[test]
fn lut_writes_the_table_its_summary_describes() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("kc.exr");
    let p = path.to_str().unwrap();
    let summary = json_of(&[
        "lut",
        "--kind",
        "kulla-conty",
        "-d",
        "ggx",
        "--size",
        "16",
        "--bits",
        "32",
        "--out",
        p,
        "--json",
    ]);
    assert_eq!(summary["width"], 16);
    assert_eq!(summary["channels"].as_array().unwrap().len(), 4);
    assert_eq!(
        summary["bytes"].as_u64().unwrap(),
        std::fs::metadata(&path).unwrap().len()
    );

    let image = exr::prelude::read_first_flat_layer_from_file(&path).unwrap();
    let layer = &image.layer_data;
    let channel = |name: &str| {
        layer
            .channel_data
            .list
            .iter()
            .find(|c| c.name.to_string() == name)
            .unwrap_or_else(|| panic!("no channel {name}"))
    };
    let (x, y) = (8usize, 12usize); // r = 8.5/16, μ = 12.5/16
    let at = |name: &str| {
        channel(name)
            .sample_data
            .value_by_flat_index(y * 16 + x)
            .to_f32() as f64
    };
    let (r, mu) = (8.5 / 16.0, 12.5 / 16.0);
    let albedo = json_of(&[
        "albedo",
        "-d",
        "ggx",
        "-r",
        &r.to_string(),
        "--mu",
        &mu.to_string(),
        "--json",
    ]);
    let e = albedo["directional_albedo"].as_f64().unwrap();
    let e_avg = albedo["average_albedo"].as_f64().unwrap();
    assert!(
        (at("R") + at("G") - e).abs() < 5e-4,
        "R+G {} vs E {e}",
        at("R") + at("G")
    );
    assert!(
        (at("A") - e_avg).abs() < 2e-3,
        "A {} vs E_avg {e_avg}",
        at("A")
    );
    assert!(at("B") > 0.0 && at("B") < 1.0 - e + 0.01);

    // The human summary names the file and the layout.
    gloffuse()
        .args([
            "lut",
            "--size",
            "8",
            "--out",
            dir.path().join("s.dds").to_str().unwrap(),
        ])
        .assert()
        .success()
        .stdout(
            predicate::str::contains("DXGI_FORMAT_R16G16_FLOAT")
                .and(predicate::str::contains("uv = (roughness, N·V)")),
        );
}

#[test]
fn lut_bad_input_exits_2_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let cases: &[(&[&str], &str)] = &[
        (&["--out", "t.png"], "--out"),
        (&["--size", "0", "--out", "t.exr"], "--size"),
        (
            &["--kind", "split-sum", "-d", "beckmann", "--out", "t.exr"],
            "--distribution",
        ),
        (&["--bits", "8", "--out", "t.exr"], "--bits"),
        // The default split-sum method is quadrature: it takes no samples.
        (&["--samples", "64", "--out", "t.exr"], "--samples"),
        (
            &["--method", "visible-normals", "--out", "t.exr"],
            "--method",
        ),
        (
            &["--kind", "albedo", "--method", "classic", "--out", "t.exr"],
            "--method",
        ),
        (&["--out", "missing/t.exr"], "missing"),
    ];
    for (args, named) in cases {
        gloffuse()
            .current_dir(dir.path())
            .arg("lut")
            .args(*args)
            .assert()
            .code(2)
            .stderr(predicate::str::contains(*named));
    }
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
}

/// A pipe whose reader has gone, named as an output (`--out /dev/stdout | true`, or
/// `/proc/self/fd/1`), is no error, the same as `--out -`: the command's own outcome (0)
/// stands, and the summary (on stderr, as the output is stdout) is printed whole.
#[test]
fn an_output_pipe_whose_reader_has_gone_is_not_an_error() {
    use std::os::fd::{FromRawFd, OwnedFd};
    for out in ["-", "/dev/stdout", "/proc/self/fd/1"] {
        let mut fds = [0; 2];
        // SAFETY: pipe() fills two new descriptors; each is owned exactly once below.
        assert_eq!(unsafe { libc::pipe(fds.as_mut_ptr()) }, 0);
        let (reader, writer) =
            unsafe { (OwnedFd::from_raw_fd(fds[0]), OwnedFd::from_raw_fd(fds[1])) };
        drop(reader);
        let run = std::process::Command::new(assert_cmd::cargo::cargo_bin("gloffuse"))
            .args(["lut", "--kind", "kulla-conty", "-d", "ggx", "--size", "8"])
            .args(["--samples", "64", "--format", "exr", "--out", out])
            .stdout(writer)
            .output()
            .expect("gloffuse starts");
        let stderr = String::from_utf8_lossy(&run.stderr);
        assert_eq!(run.status.code(), Some(0), "--out {out}: {stderr}");
        assert!(stderr.contains(&format!("wrote {out} (")), "{stderr}");
        assert!(!stderr.contains("error"), "--out {out}: {stderr}");
    }
}

/// SIGTERM and SIGHUP (`timeout`, a CI cancel, a closed terminal) while no Blender runs
/// stop the command at once like Ctrl-C: exit 128 + the signal, and nothing written, not
/// even a temporary file.
#[test]
fn sigterm_and_sighup_exit_128_plus_the_signal_and_write_nothing() {
    for (signal, code) in [
        (libc::SIGTERM, 143),
        (libc::SIGHUP, 129),
        (libc::SIGINT, 130),
    ] {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("big.exr");
        let child = std::process::Command::new(assert_cmd::cargo::cargo_bin("gloffuse"))
            .args([
                "lut",
                "--kind",
                "kulla-conty",
                "-d",
                "ggx",
                "--size",
                "512",
                "--out",
            ])
            .arg(&path)
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        std::thread::sleep(std::time::Duration::from_millis(500));
        // SAFETY: kill only sends a signal to the child we spawned.
        assert_eq!(unsafe { libc::kill(child.id() as libc::pid_t, signal) }, 0);
        let out = child.wait_with_output().unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(code), "signal {signal}: {stderr}");
        assert!(stderr.contains("nothing was written"), "{stderr}");
        let left: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
        assert!(left.is_empty(), "signal {signal}: {left:?}");
    }
}

/// The text of one option in a `--help`, its lines joined by single spaces.
fn option_help(help: &str, flag: &str) -> String {
    let option = |l: &str| l.trim_start().starts_with('-') && l.contains(&format!("{flag} "));
    let mut lines = help.lines().skip_while(|l| !option(l));
    let first = lines.next().unwrap_or_else(|| panic!("{flag} in the help"));
    let rest = lines.take_while(|l| !l.trim_start().starts_with('-'));
    std::iter::once(first)
        .chain(rest)
        .flat_map(str::split_whitespace)
        .collect::<Vec<_>>()
        .join(" ")
}

/// The defaults `verify --help` spells out by hand are the ones each mode's spec holds: the
/// samples and thresholds per engine (a mode named where it differs from roughness mode's),
/// the roughness sweeps, the indices of refraction and the anisotropies.
#[test]
fn verify_help_spells_each_modes_defaults_as_its_spec_holds_them() {
    use gloffuse::generate::Mode;
    use gloffuse::measure::Engine;
    use gloffuse::verify::modes::{EngineDefaults, SecondAxis, spec};

    let help = help_of(&["verify"]);
    type Value = fn(&EngineDefaults) -> String;
    let numbers: [(&str, Value); 3] = [
        ("--spp", |d| d.samples.to_string()),
        ("--tolerance", |d| d.judging.tolerance_percent.to_string()),
        ("--ring-tolerance", |d| {
            d.judging.ring_tolerance_percent.to_string()
        }),
    ];
    let base = spec(Mode::Roughness);
    for (flag, value) in numbers {
        let text = option_help(&help, flag);
        let cycles = format!("Cycles {}", value(&base.cycles));
        let eevee = format!("EEVEE {}", value(&base.eevee));
        assert!(text.contains(&cycles), "{flag}: {cycles:?} in {text:?}");
        assert!(text.contains(&eevee), "{flag}: {eevee:?} in {text:?}");
        for mode in Mode::ALL {
            let own = value(&spec(mode).cycles);
            let named = format!("{} mode {own}", mode.key());
            if own == value(&base.cycles) {
                let mode_number = format!("{} mode ", mode.key());
                let numbered = text
                    .match_indices(&mode_number)
                    .any(|(i, m)| text[i + m.len()..].starts_with(|c: char| c.is_ascii_digit()));
                assert!(
                    !numbered,
                    "{flag}: no own value for {} mode in {text:?}",
                    mode.key()
                );
            } else {
                assert!(text.contains(&named), "{flag}: {named:?} in {text:?}");
            }
            if mode.engines().contains(&Engine::Eevee) {
                assert_eq!(
                    value(&spec(mode).eevee),
                    value(&base.eevee),
                    "{flag}: the help gives one EEVEE value, so {} mode has it too",
                    mode.key()
                );
            }
        }
    }

    let list = |values: Vec<String>, sep: &str| values.join(sep);
    let sweep = |mode: Mode| {
        (spec(mode).roughness)()
            .iter()
            .map(|r| r.get().to_string())
            .collect::<Vec<_>>()
    };
    let text = option_help(&help, "--roughness");
    let even: Vec<String> = (0..=10)
        .map(|i| (f64::from(i) / 10.0).to_string())
        .collect();
    assert_eq!(
        sweep(Mode::Roughness),
        even,
        "roughness mode sweeps 0, 0.1, …, 1"
    );
    assert!(text.contains("[default: 0, 0.1, …, 1;"), "{text:?}");
    let blocks: Vec<Mode> = Mode::ALL
        .into_iter()
        .filter(|&m| sweep(m) != even)
        .collect();
    assert_eq!(blocks, [Mode::Layered, Mode::Anisotropic, Mode::Glass]);
    for mode in &blocks {
        assert_eq!(sweep(*mode), sweep(blocks[0]));
    }
    let named = format!(
        "layered, anisotropic and glass mode: {}]",
        list(sweep(Mode::Layered), ", ")
    );
    assert!(text.contains(&named), "{named:?} in {text:?}");

    for (flag, mode) in [
        ("--ior", Mode::Glass),
        ("--ior", Mode::Layered),
        ("--anisotropy", Mode::Anisotropic),
    ] {
        let values = match spec(mode).axis {
            SecondAxis::Ior(v) | SecondAxis::Anisotropy(v) => v,
            SecondAxis::None => panic!("{} mode has a second axis", mode.key()),
        };
        let default = format!(
            "[default: {}]",
            list(values.iter().map(f64::to_string).collect(), ",")
        );
        let text = option_help(&help, flag);
        assert!(text.contains(&default), "{flag}: {default:?} in {text:?}");
    }
}

fn help_of(command: &[&str]) -> String {
    let out = gloffuse()
        .args(command)
        .arg("--help")
        .assert()
        .success()
        .get_output()
        .stdout
        .clone();
    String::from_utf8(out).unwrap()
}

/// The other defaults a `--help` spells by hand: each table kind's size and size range, the
/// measurement's samples per engine, and the verdicts that fail an audit.
#[test]
fn lut_refresh_and_audit_help_spell_the_librarys_defaults() {
    use gloffuse::audit::AuditJudging;
    use gloffuse::lut::Kind;
    use gloffuse::measure::Engine;
    use gloffuse::refresh::measure_samples;

    let size = option_help(&help_of(&["lut"]), "--size");
    let most = Kind::Albedo.facts().default_size;
    for kind in Kind::ALL {
        let facts = kind.facts();
        if facts.default_size != most {
            let named = format!("{} for {}", facts.default_size, facts.key);
            assert!(size.contains(&named), "{named:?} in {size:?}");
        }
        if let Some(limit) = &facts.size_limit {
            let range = if limit.min == 1 {
                format!("{} {}", facts.key, limit.max)
            } else {
                format!("{} {} to {}", facts.key, limit.min, limit.max)
            };
            assert!(size.contains(&range), "{range:?} in {size:?}");
        }
    }
    assert!(size.contains(&format!("{most} otherwise]")), "{size:?}");

    let spp = option_help(&help_of(&["refresh"]), "--spp");
    let named = format!(
        "[default: Cycles {}, EEVEE {}]",
        measure_samples(Engine::Cycles),
        measure_samples(Engine::Eevee)
    );
    assert!(spp.contains(&named), "{named:?} in {spp:?}");

    let fail_on = option_help(&help_of(&["audit"]), "--fail-on");
    let keys: Vec<&str> = AuditJudging::default()
        .fail_on
        .iter()
        .map(|v| v.key())
        .collect();
    let named = format!("[default: {}]", keys.join(","));
    assert!(fail_on.contains(&named), "{named:?} in {fail_on:?}");
}
