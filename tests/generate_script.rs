//! Generated Python without Blender: byte-stable, parses, and no parameter text can become
//! code (checked by CPython's own parser on arbitrary Unicode, see check_script.py).
//!
//! Tier: fast (no Blender; `scripts/test.sh --fast` runs it).

mod common;

use gloffuse::generate::bundle::{bundle, bundle_from, concatenate};
use gloffuse::generate::{Job, assemble};
use proptest::prelude::*;
use std::path::Path;
use std::process::Command;

/// Runs check_script.py on (script, expected parameters) pairs against a benign reference.
fn check_scripts(dir: &Path, cases: &[(String, serde_json::Value)]) {
    let reference = dir.join("reference.py");
    std::fs::write(&reference, assemble(&common::seed_params(), Job::Generate)).unwrap();
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

/// `text` equals the golden file `name` in `tests/golden/`; `GLOFFUSE_BLESS=1` writes it.
fn assert_golden(name: &str, text: &str) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/golden")
        .join(name);
    if std::env::var_os("GLOFFUSE_BLESS").is_some() {
        std::fs::write(&path, text).unwrap();
    }
    let golden = std::fs::read_to_string(&path)
        .unwrap_or_else(|e| panic!("{} ({e}; write it with GLOFFUSE_BLESS=1)", path.display()));
    assert_eq!(
        text, golden,
        "{name} changed; if intended, rerun with GLOFFUSE_BLESS=1 and review the diff"
    );
}

/// The modules of the fixture package `tests/fixtures/bundle/`, by name.
fn fixture_package() -> Vec<(String, String)> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/bundle");
    let mut modules: Vec<(String, String)> = std::fs::read_dir(dir)
        .unwrap()
        .map(|entry| {
            let path = entry.unwrap().path();
            let name = path.file_stem().unwrap().to_str().unwrap().to_string();
            (name, std::fs::read_to_string(&path).unwrap())
        })
        .collect();
    modules.sort();
    modules
}

/// The bundler on a package of four tiny modules: the order their imports give, the
/// package imports dropped, a standard import made once, the unimported module left out.
#[test]
fn the_bundler_makes_the_golden_bundle_of_the_fixture_package() {
    let modules = fixture_package();
    let modules: Vec<(&str, &str)> = modules
        .iter()
        .map(|(n, t)| (n.as_str(), t.as_str()))
        .collect();
    let bundled = concatenate(&bundle_from(&modules, None, "job").unwrap());
    assert_eq!(
        bundled,
        concatenate(&bundle_from(&modules, None, "job").unwrap())
    );
    assert_golden("bundle-fixture.py", &bundled);
}

/// The seed library's parameter document, as the generate job gets it (pretty-printed
/// here; the script holds it on one line).
#[test]
fn the_seed_document_is_the_golden_one() {
    let document = serde_json::to_string_pretty(&common::seed_params()).unwrap();
    assert_golden("generate-seed.json", &format!("{document}\n"));
}

/// A generate script is the header with the document, the bundle of the generate job's
/// modules, and the call of its main; made twice, it is the same bytes.
#[test]
fn the_seed_script_is_byte_stable_and_holds_the_bundle() {
    let script = assemble(&common::seed_params(), Job::Generate);
    assert_eq!(script, assemble(&common::seed_params(), Job::Generate));
    let document = serde_json::to_string(&common::seed_params()).unwrap();
    let literal = serde_json::to_string(&document).unwrap();
    let header = script.split_once(&format!("GLOFFUSE_PARAMS = {literal}\n"));
    let (_, rest) = header.expect("the document's literal on its own line");
    let bundled = concatenate(&bundle(Job::Generate.module()).unwrap());
    let main = rest
        .strip_prefix(&bundled)
        .expect("the bundle after the header");
    assert!(main.ends_with("    main(GLOFFUSE_PARAMS)\n"), "{main}");
    let dir = tempfile::tempdir().unwrap();
    let expect = serde_json::to_value(common::seed_params()).unwrap();
    check_scripts(dir.path(), &[(script, expect)]);
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
            let mut p = common::seed_params();
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
                let mut p = common::seed_params();
                p.groups[0].families[0].coefficients_source = pair[0].clone();
                p.groups[0].families[1].description = pair[1].clone();
                p.groups[1].correction_group = pair[0].clone();
                (assemble(&p, Job::Generate), serde_json::to_value(&p).unwrap())
            })
            .collect();
        check_scripts(dir.path(), &cases);
    }
}
