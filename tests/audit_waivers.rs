//! Waivers, severities, `--select`/`--ignore` and a fix's exit code, on files made in each
//! real Blender by `tests/blender/waived_materials.py`: a rough single-scatter GGX material
//! waived by its own `gloffuse_ignore` property, by its node's, by its group node's and by a
//! `gloffuse.toml`, one not waived, one half waived, and waivers gloffuse cannot read (an int,
//! a group of properties). The exit codes, the JSON report and the files' bytes are checked
//! with the rules alone (`--no-render`); the furnace's measured verdicts in Blender 4.5 only.
//!
//! Tier: blender (needs the Blenders and tools `scripts/test.sh` installs).

mod common;

use std::path::{Path, PathBuf};

use serde_json::Value;

use common::audit_json as audit;
use common::audit_material as material;

/// The configuration beside the files: it waives one material by name.
const CONFIG: &str = "# the studio's audit configuration\n\n[[waiver]]\nrules = \
                      [\"glossy-single-scatter\"]\nreason = \"legacy library, re-authored in \
                      2027\"\nmaterials = [\"waived-config\"]\n";

/// Makes the files in `dir` with `blender`, and the configuration beside them.
fn make_files(blender: &Path, dir: &Path) {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/blender/waived_materials.py");
    let made = common::blender::run_in_blender(blender, &script, &["--".as_ref(), dir.as_os_str()]);
    assert!(
        made.status.success() && dir.join("measured.blend").exists(),
        "{made:?}"
    );
    std::fs::write(dir.join("gloffuse.toml"), CONFIG).unwrap();
}

/// The findings of `m` of rule `rule`.
fn findings<'a>(m: &'a Value, rule: &str) -> Vec<&'a Value> {
    m["findings"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|f| f["rule"] == rule)
        .collect()
}

/// Every .blend of `dir` (and below) with its bytes.
fn blends(dir: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    let mut found = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for entry in std::fs::read_dir(&d).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                stack.push(path);
            } else if path.extension().is_some_and(|e| e == "blend") {
                found.push((path.clone(), std::fs::read(&path).unwrap()));
            }
        }
    }
    found.sort();
    found
}

fn waivers_and_severities(label: &'static str, blender: PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let root = dir.path();
    make_files(&blender, root);
    let before = blends(root);
    let waived = root.join("waived.blend");
    let plain = root.join("plain.blend");
    let no_render = "--no-render".as_ref();

    // Every failing material of waived.blend is waived: the check passes.
    let (code, report, stderr) = audit(&blender, &[waived.as_os_str(), no_render]);
    assert_eq!(code, 0, "Blender {label}: {report}\n{stderr}");
    assert_eq!(report["passed"], true);
    for (name, from, place) in [
        ("waived-material", "material", "waived-material"),
        ("waived-node", "node", "waived-node ▸ Glossy"),
        ("waived-group", "node", "waived-group ▸ Coat"),
        ("waived-config", "config", "gloffuse.toml"),
    ] {
        let m = material(&report, name);
        assert_eq!(m["verdict"], "loses", "Blender {label}: {m}");
        assert_eq!(m["fails"], false, "Blender {label}: {m}");
        assert!(
            m["suppressed"]
                .as_str()
                .unwrap()
                .starts_with("loses not failing"),
            "{m}"
        );
        let glossy = findings(m, "glossy-single-scatter");
        assert_eq!(glossy.len(), 1, "Blender {label}: {m}");
        let w = &glossy[0]["waived"];
        assert_eq!(w["from"], from, "{m}");
        assert!(w["where"].as_str().unwrap().ends_with(place), "{m}");
        assert_eq!(glossy[0]["severity"], "error");
    }
    let config = &findings(material(&report, "waived-config"), "glossy-single-scatter")[0];
    assert_eq!(config["waived"]["line"], 3, "{config}");
    assert_eq!(
        config["waived"]["reason"],
        "legacy library, re-authored in 2027"
    );
    let group = &findings(material(&report, "waived-group"), "glossy-single-scatter")[0];
    assert_eq!(group["waived"]["reason"], "the shared coat", "{group}");
    assert_eq!(group["node_path"][1], "Coat");
    // Waivers gloffuse cannot read are warnings that say what they are, and waive nothing.
    let bad = material(&report, "bad-waivers");
    assert_eq!(
        (&bad["verdict"], &bad["fails"]),
        (&"ok".into(), &false.into())
    );
    let invalid = findings(bad, "invalid-waiver");
    assert_eq!(invalid.len(), 2, "Blender {label}: {bad}");
    let whys: Vec<&str> = invalid.iter().map(|f| f["why"].as_str().unwrap()).collect();
    assert!(whys.iter().any(|w| w.contains("type int")), "{whys:?}");
    assert!(
        whys.iter().any(|w| w.contains("type IDPropertyGroup")),
        "{whys:?}"
    );
    assert!(invalid.iter().all(|f| f["severity"] == "warning"));
    assert_eq!(report["counts"]["suppressed"], 4, "{}", report["counts"]);
    assert_eq!(report["counts"]["failing"], 0);
    assert_eq!(report["counts"]["waived_findings"], 4);

    // The files' own properties disregarded, only the configuration waives.
    let (code, report, stderr) = audit(
        &blender,
        &[
            waived.as_os_str(),
            no_render,
            "--no-property-waivers".as_ref(),
        ],
    );
    assert_eq!(code, 1, "Blender {label}: {stderr}");
    assert_eq!(material(&report, "waived-material")["fails"], true);
    assert_eq!(material(&report, "waived-config")["fails"], false);
    assert!(findings(material(&report, "bad-waivers"), "invalid-waiver").is_empty());

    // The not waived and the half waived materials fail, and so does the run.
    let (code, report, stderr) = audit(&blender, &[root.as_os_str(), no_render]);
    assert_eq!(code, 1, "Blender {label}: {stderr}");
    assert_eq!(report["passed"], false);
    for name in ["not-waived", "half-waived"] {
        let m = material(&report, name);
        assert_eq!(
            (&m["verdict"], &m["fails"]),
            (&"loses".into(), &true.into()),
            "{m}"
        );
        assert!(m["suppressed"].is_null(), "{m}");
    }
    let half = findings(material(&report, "half-waived"), "glossy-single-scatter");
    let waived_nodes: Vec<&Value> = half
        .iter()
        .filter(|f| !f["waived"].is_null())
        .map(|f| &f["node_path"][1])
        .collect();
    assert_eq!(waived_nodes, [&Value::from("Glossy A")], "{half:?}");

    // --ignore: the rule does not run, so nothing loses; --select of another rule likewise.
    for args in [
        ["--ignore", "glossy-single-scatter"],
        ["--select", "color-above-one"],
    ] {
        let (code, report, stderr) = audit(
            &blender,
            &[
                root.as_os_str(),
                no_render,
                args[0].as_ref(),
                args[1].as_ref(),
            ],
        );
        assert_eq!(code, 0, "Blender {label} {args:?}: {stderr}");
        assert!(
            findings(material(&report, "not-waived"), "glossy-single-scatter").is_empty(),
            "{args:?}"
        );
        assert!(
            report["settings"]["skipped_rules"]
                .as_array()
                .unwrap()
                .contains(&"glossy-single-scatter".into())
        );
    }

    // The nearest configuration wins, alone: below it, a severity lowered to warning passes
    // plain.blend, and the parent's waiver no longer holds.
    let sub = root.join("sub");
    std::fs::create_dir(&sub).unwrap();
    std::fs::copy(&plain, sub.join("plain.blend")).unwrap();
    std::fs::copy(&waived, sub.join("waived.blend")).unwrap();
    std::fs::write(
        sub.join("gloffuse.toml"),
        "[severity]\nglossy-single-scatter = \"warning\"\n",
    )
    .unwrap();
    let (code, report, stderr) = audit(&blender, &[sub.as_os_str(), no_render]);
    assert_eq!(code, 0, "Blender {label}: {stderr}");
    let m = material(&report, "not-waived");
    assert_eq!(m["fails"], false);
    assert_eq!(
        findings(m, "glossy-single-scatter")[0]["severity"],
        "warning"
    );
    let config = &findings(material(&report, "waived-config"), "glossy-single-scatter")[0];
    assert!(config["waived"].is_null(), "{config}");

    // A fix: exit 1 without it; with it, the fixed copy has no failure left, so exit 0, and
    // the report still says the file as it was fails.
    let (code, _, stderr) = audit(&blender, &[sub.join("plain.blend").as_os_str(), no_render]);
    assert_eq!(code, 0, "with the warning severity: {stderr}");
    let (code, _, stderr) = audit(&blender, &[plain.as_os_str(), no_render]);
    assert_eq!(code, 1, "Blender {label}: {stderr}");
    let fixed = root.join("out").join("plain-fixed.blend");
    std::fs::create_dir(root.join("out")).unwrap();
    let (code, report, stderr) = audit(
        &blender,
        &[
            plain.as_os_str(),
            no_render,
            "--fix".as_ref(),
            fixed.as_os_str(),
        ],
    );
    assert_eq!(code, 0, "Blender {label}: {report}\n{stderr}");
    assert_eq!(report["passed"], false);
    assert_eq!(report["passed_after_fix"], true);
    let m = material(&report, "not-waived");
    assert_eq!(
        (&m["after"]["verdict"], &m["after"]["fails"]),
        (&"ok".into(), &false.into())
    );

    // The files audited are never changed.
    let after: Vec<(PathBuf, Vec<u8>)> = blends(root)
        .into_iter()
        .filter(|(p, _)| {
            p.starts_with(root) && !p.starts_with(&sub) && !p.starts_with(root.join("out"))
        })
        .collect();
    assert!(after == before, "Blender {label}: an audited file changed");
}

common::blender::per_blender!(waivers_and_severities);

/// In the furnace (Blender 4.5, 8 px cells, 4 spp): a waived rule suppresses the loss it
/// measures; a material brighter than 100 % that no rule flags is suppressed only by `*`.
#[test]
fn a_measured_verdict_is_waived_by_its_rule_or_by_a_star() {
    let Some(blender) = common::blender::real_blender("4.5") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    make_files(&blender, dir.path());
    let file = dir.path().join("measured.blend");
    let (code, report, stderr) = audit(
        &blender,
        &[
            file.as_os_str(),
            "--resolution".as_ref(),
            "8".as_ref(),
            "--spp".as_ref(),
            "4".as_ref(),
        ],
    );
    assert_eq!(code, 1, "{report}\n{stderr}");
    let glossy = material(&report, "glossy-waived");
    assert_eq!(glossy["verdict"], "loses", "{glossy}");
    assert!(glossy["mean"].as_f64().unwrap() < 0.8, "{glossy}");
    assert_eq!(glossy["fails"], false, "{glossy}");
    let star = material(&report, "bright-star");
    assert_eq!(star["verdict"], "creates", "{star}");
    assert!(star["mean"].as_f64().unwrap() > 1.5, "{star}");
    assert_eq!(star["fails"], false, "{star}");
    assert!(
        star["suppressed"]
            .as_str()
            .unwrap()
            .contains("creates waived: “a light card” (gloffuse_ignore on material bright-star)"),
        "{star}"
    );
    let rule = material(&report, "bright-rule");
    assert_eq!(
        (&rule["verdict"], &rule["fails"]),
        (&"creates".into(), &true.into()),
        "{rule}"
    );
    // No rule that judges energy flags it (the PBR range rules, info and warnings, read the
    // RGB node's colour: tests/audit_pbr.rs is their oracle).
    let judging: Vec<&Value> = rule["findings"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|f| !f["rule"].as_str().unwrap().starts_with("pbr-"))
        .collect();
    assert!(judging.is_empty(), "{rule}");
}

/// A wrong gloffuse.toml, or an unknown rule id, is refused (exit 2) before any Blender is
/// looked for, naming the file, the line and what would be right.
#[test]
fn a_bad_configuration_or_rule_id_is_refused_before_blender() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("x.blend");
    std::fs::write(&file, b"BLENDER-v304").unwrap();
    let missing = dir.path().join("no-blender");
    std::fs::write(
        dir.path().join("gloffuse.toml"),
        "[[waiver]]\nrules = [\"glosy-single-scatter\"]\nreason = \"typo\"\n",
    )
    .unwrap();
    let (code, _, stderr) = audit(&missing, &[file.as_os_str()]);
    assert_eq!(code, 2, "{stderr}");
    assert!(
        stderr.contains("gloffuse.toml, line 2: unknown rule `glosy-single-scatter`")
            && stderr.contains("glossy-single-scatter, anisotropic-multiscatter"),
        "{stderr}"
    );
    std::fs::remove_file(dir.path().join("gloffuse.toml")).unwrap();
    let (code, _, stderr) = audit(
        &missing,
        &[
            file.as_os_str(),
            "--select".as_ref(),
            "toon-smooth,nope".as_ref(),
        ],
    );
    assert_eq!(code, 2, "{stderr}");
    assert!(
        stderr.contains("--select 'nope'") && stderr.contains("invalid-waiver"),
        "{stderr}"
    );
}
