//! Generated Python without Blender: byte-stable, parses, and no parameter text can become
//! code (checked by CPython's own parser on arbitrary Unicode, see check_script.py).
//!
//! Tier: fast (no Blender; `scripts/test.sh --fast` runs it).

use gloffuse::fit::Coefficients;
use gloffuse::generate::{ColorModel, Curves, GenerateParams, Job, Mode, assemble};
use gloffuse::measure::Masking;
use proptest::prelude::*;
use std::path::Path;
use std::process::Command;

fn seed_params() -> GenerateParams {
    let seed = Coefficients::load("seed").unwrap();
    let curves = Curves::Pinned {
        coefficients: &seed,
        name: "seed",
    };
    GenerateParams::new(curves, &Masking::ALL, &[Mode::Roughness], ColorModel::Exact).unwrap()
}

/// Runs check_script.py on (script, expected parameters) pairs against a benign reference.
fn check_scripts(dir: &Path, cases: &[(String, serde_json::Value)]) {
    let reference = dir.join("reference.py");
    std::fs::write(&reference, assemble(&seed_params(), Job::Generate)).unwrap();
    let mut cmd = Command::new("python3");
    cmd.arg(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/blender/check_script.py"
    ))
    .arg(&reference);
    for (i, (script, expect)) in cases.iter().enumerate() {
        let s = dir.join(format!("case{i}.py"));
        let e = dir.join(format!("case{i}.json"));
        std::fs::write(&s, script).unwrap();
        std::fs::write(&e, serde_json::to_string(expect).unwrap()).unwrap();
        cmd.arg(s).arg(e);
    }
    let out = cmd.output().expect("python3 runs");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        stdout.contains(&format!("{} passed, 0 failed", cases.len())),
        "{stdout}"
    );
}

#[test]
fn golden_seed_script_is_byte_stable() {
    let a = assemble(&seed_params(), Job::Generate);
    let b = assemble(&seed_params(), Job::Generate);
    assert_eq!(a, b);
    let golden_path = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/golden/generate-seed.py");
    if std::env::var_os("GLOFFUSE_BLESS").is_some() {
        std::fs::write(golden_path, &a).unwrap();
    }
    let golden = std::fs::read_to_string(golden_path)
        .expect("golden file (regenerate with GLOFFUSE_BLESS=1)");
    assert_eq!(
        a, golden,
        "generated script changed; if intended, rerun with GLOFFUSE_BLESS=1 and review the diff"
    );
    // The golden file is only trusted because it is also checked independently:
    let dir = tempfile::tempdir().unwrap();
    let expect = serde_json::to_value(seed_params()).unwrap();
    check_scripts(dir.path(), &[(golden, expect)]);
}

#[test]
fn hostile_text_round_trips_and_never_becomes_code() {
    let nasty = [
        "\"; import os; os.system('echo pwned') #",
        "''' \"\"\" \\ \\n \n\r\t\u{0} \u{1} \u{7f} \u{2028} \u{2029} \u{feff}",
        "\\\"\\\\\"",
        "é中文😀 r² — «»",
        "\")\nimport os\n(\"",
    ];
    let dir = tempfile::tempdir().unwrap();
    let cases: Vec<_> = nasty
        .iter()
        .map(|text| {
            let mut p = seed_params();
            for g in &mut p.groups {
                for f in &mut g.families {
                    f.coefficients_source = text.to_string();
                    f.description = format!("{text}{text}");
                }
                g.shader_group = format!("Gloffuse {text}");
            }
            (
                assemble(&p, Job::Generate),
                serde_json::to_value(&p).unwrap(),
            )
        })
        .collect();
    check_scripts(dir.path(), &cases);
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 4, ..ProptestConfig::default() })]
    #[test]
    fn arbitrary_unicode_round_trips(texts in proptest::collection::vec(any::<String>(), 48)) {
        let dir = tempfile::tempdir().unwrap();
        let cases: Vec<_> = texts
            .chunks(2)
            .map(|pair| {
                let mut p = seed_params();
                p.groups[0].families[0].coefficients_source = pair[0].clone();
                p.groups[0].families[1].description = pair[1].clone();
                p.groups[1].correction_group = pair[0].clone();
                (assemble(&p, Job::Generate), serde_json::to_value(&p).unwrap())
            })
            .collect();
        check_scripts(dir.path(), &cases);
    }
}
