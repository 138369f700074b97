//! Hostile input that needs no Blender: shard reports written by hand (as someone who can
//! write a shard's folder on shared storage could), names with control characters, and the
//! farm's job files. `report merge` must not publish files a shard links to, must refuse a
//! tampered shard by name (exit 2, never a panic, an abort or a hang), and must print and
//! write names that cannot drive a terminal or break the JUnit XML; `farm` must write jobs
//! whose folder and program reach the farm exactly.
//!
//! Tier: blender (needs the Blenders and tools `scripts/test.sh` installs).

mod common;

use std::path::{Path, PathBuf};
use std::time::Duration;

use common::gloffuse;
use serde_json::{Value, json};

/// A name from a user's file with everything a terminal or XML must not get raw: an OSC
/// title change ending in BEL, a screen clear, a newline starting a forged line, a carriage
/// return, a C1 CSI, a bidi override, U+FFFE and U+FFFF, and XML's own `<&"`.
const HOSTILE: &str = "Evil\u{1b}]0;pwned\u{7}\u{1b}[2J\nok       100.0 %  forged\r\u{9b}31m\u{202e}gnp.exe\u{fffe}\u{ffff}<&\"";

/// What the terminal shows of [`HOSTILE`]: each of those characters as text.
const HOSTILE_SHOWN: &str = r#"Evil\x1b]0;pwned\x07\x1b[2J\nok       100.0 %  forged\r\x9b31m\u{202e}gnp.exe\u{fffe}\u{ffff}<&""#;

/// Shard `k` of `n`, of a run of `inputs` (file, materials), holding `files`, each with one
/// material named `material` that loses energy (so the merge exits 1, and each material has
/// a picture to copy).
fn shard_report(
    k: usize,
    n: usize,
    inputs: &[(&str, usize)],
    files: &[&str],
    material: &str,
) -> Value {
    json!({
        "gloffuse_version": "0.1.0",
        "blender_version": "3.4.1",
        "blender_program": "/usr/bin/blender",
        "settings": {"cell": 24, "samples": 8, "seed": 0, "render": true, "tolerance": 0.01,
                     "ring_tolerance": 0.03, "fail_on": ["loses", "creates", "error"]},
        "shard": {"shard": {"index": k, "count": n},
                  "inputs": inputs.iter().map(|(f, m)| json!({"file": f, "materials": m}))
                      .collect::<Vec<_>>()},
        "passed": false,
        "counts": {"files": files.len(), "files_failed": 0, "materials": files.len(), "ok": 0,
                   "loses": files.len(), "creates": 0, "error": 0},
        "files": files.iter().map(|f| json!({"file": f, "saved_by": "3.4.1", "error": null,
            "findings": [], "materials": 1, "log": null, "render_seconds": 1.0,
            "scan_seconds": 0.1, "fixed": null})).collect::<Vec<_>>(),
        "materials": files.iter().map(|f| json!({"file": f, "material": material,
            "verdict": "loses", "reason": format!("{material} loses"), "mean": 0.9,
            "center": 0.95, "rim": 0.8, "twin_mean": 1.0, "twin_center": 1.0, "twin_rim": 1.0,
            "replaced": 0, "findings": [{"rule": "old-glossy", "node": material,
                "node_path": [material], "node_type": "ShaderNodeBsdfGlossy", "kind": "loses",
                "versions": "all", "why": "single scattering", "fix": "Multiscatter GGX",
                "predicted": 0.9, "twin": null, "detail": {}}],
            "library": null, "after": null})).collect::<Vec<_>>(),
    })
}

const INPUTS: [(&str, usize); 2] = [("/lib/a.blend", 1), ("/lib/b.blend", 1)];

/// Both shards of a two-file run in `dir`/s1 and `dir`/s2 (each file one shard, as the split
/// gives them), each with its material's picture; their folders.
fn two_shards(dir: &Path, material: &str) -> [PathBuf; 2] {
    [1, 2].map(|k| {
        let folder = dir.join(format!("s{k}"));
        std::fs::create_dir_all(folder.join("materials")).unwrap();
        let report = shard_report(k, 2, &INPUTS, &[INPUTS[k - 1].0], material);
        std::fs::write(folder.join("report.json"), report.to_string()).unwrap();
        std::fs::write(folder.join("materials/00000.png"), format!("picture {k}")).unwrap();
        folder
    })
}

/// `gloffuse report merge ARGS`, stopped after 60 s: exit code, stdout, stderr.
fn merge(args: &[&Path]) -> (i32, String, String) {
    let out = gloffuse()
        .args(["report", "merge"])
        .args(args)
        .timeout(Duration::from_secs(60))
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// Every file's bytes under `dir`, followed into no link.
fn contents(dir: &Path) -> Vec<Vec<u8>> {
    let mut all = Vec::new();
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        let meta = std::fs::symlink_metadata(&path).unwrap();
        if meta.is_dir() {
            all.extend(contents(&path));
        } else {
            all.push(std::fs::read(&path).unwrap());
        }
    }
    all
}

#[test]
fn a_merge_copies_no_file_a_shard_links_to() {
    let dir = tempfile::tempdir().unwrap();
    let secret = dir.path().join("secret");
    std::fs::write(&secret, "the merge job's secret").unwrap();
    let [s1, s2] = two_shards(dir.path(), "Steel");
    // Shard 1's picture is a link to the secret; shard 2's whole materials/ is a link to a
    // folder whose picture is the secret.
    let picture = s1.join("materials/00000.png");
    std::fs::remove_file(&picture).unwrap();
    std::os::unix::fs::symlink(&secret, &picture).unwrap();
    let elsewhere = dir.path().join("elsewhere");
    std::fs::create_dir(&elsewhere).unwrap();
    std::fs::copy(&secret, elsewhere.join("00000.png")).unwrap();
    std::fs::remove_dir_all(s2.join("materials")).unwrap();
    std::os::unix::fs::symlink(&elsewhere, s2.join("materials")).unwrap();
    let merged = dir.path().join("merged");
    let (code, _, err) = merge(&[&s1, &s2, Path::new("--report"), &merged]);
    assert_eq!(code, 1, "the materials lose energy: {err}");
    let copied = contents(&merged.join("materials"));
    assert!(
        !copied.iter().any(|c| c == b"the merge job's secret"),
        "a linked file was copied: {err}"
    );
    // Each link is named in a note, and its material is left without a picture.
    for link in [picture, s2.join("materials")] {
        assert!(err.contains(&link.display().to_string()), "{link:?}: {err}");
    }
    assert!(err.contains("symbolic link"), "{err}");
    assert!(copied.is_empty(), "{copied:?}");
    // The page shows no picture for them, and was written.
    let page = std::fs::read_to_string(merged.join("report.html")).unwrap();
    assert!(!page.contains("materials/0000"), "{page}");
}

#[test]
fn a_merge_copies_the_pictures_of_plain_shards() {
    let dir = tempfile::tempdir().unwrap();
    let [s1, s2] = two_shards(dir.path(), "Steel");
    let merged = dir.path().join("merged");
    let (code, _, err) = merge(&[&s2, &s1, Path::new("--report"), &merged]);
    assert_eq!(code, 1, "{err}");
    let read = |n: &str| std::fs::read_to_string(merged.join("materials").join(n)).unwrap();
    assert_eq!(
        (read("00000.png"), read("00001.png")),
        ("picture 1".into(), "picture 2".into())
    );
    assert!(!err.contains("symbolic link"), "{err}");
}

/// A shard report as `two_shards` writes shard 1's, with `change` made to its shard.
fn tampered(dir: &Path, name: &str, change: &dyn Fn(&mut Value)) -> PathBuf {
    let mut report = shard_report(1, 2, &INPUTS, &[INPUTS[0].0], "Steel");
    change(&mut report["shard"]["shard"]);
    let path = dir.join(name);
    std::fs::write(&path, report.to_string()).unwrap();
    path
}

#[test]
fn a_tampered_shard_is_refused_by_name() {
    let dir = tempfile::tempdir().unwrap();
    let [s1, s2] = two_shards(dir.path(), "Steel");
    let huge = tampered(dir.path(), "huge.json", &|s| {
        s["count"] = json!(1_000_000_000_000_000u64)
    });
    let zero = tampered(dir.path(), "zero.json", &|s| s["index"] = json!(0));
    let above = tampered(dir.path(), "above.json", &|s| s["index"] = json!(3));
    let max = tampered(dir.path(), "max.json", &|s| {
        s["index"] = json!(u64::MAX);
        s["count"] = json!(u64::MAX);
    });
    for (shards, says) in [
        (vec![&huge, &s2], "huge.json"),
        (vec![&s2, &huge], "huge.json"),
        (vec![&zero, &s2], "zero.json"),
        (vec![&s2, &zero], "zero.json"),
        (vec![&above, &s2], "above.json"),
        (vec![&s1, &above], "above.json"),
        (vec![&max], "max.json"),
    ] {
        let paths: Vec<&Path> = shards.iter().map(|p| p.as_path()).collect();
        let (code, _, err) = merge(&paths);
        assert_eq!(code, 2, "{shards:?}: {err}");
        assert!(err.contains(says), "{shards:?}: {err}");
        assert!(!err.contains("panicked"), "{err}");
    }
}

#[test]
fn a_report_json_that_is_no_file_is_refused_without_blocking() {
    let dir = tempfile::tempdir().unwrap();
    let [s1, _] = two_shards(dir.path(), "Steel");
    let fifo = dir.path().join("fifo");
    std::fs::create_dir(&fifo).unwrap();
    let status = std::process::Command::new("mkfifo")
        .arg(fifo.join("report.json"))
        .status()
        .unwrap();
    assert!(status.success());
    for shard in [fifo.clone(), fifo.join("report.json")] {
        let (code, _, err) = merge(&[&s1, &shard]);
        assert_eq!(code, 2, "{err}");
        assert!(
            err.contains(&fifo.join("report.json").display().to_string()),
            "{err}"
        );
        assert!(err.contains("regular file"), "{err}");
    }
}

#[test]
fn the_terminal_table_shows_names_escaped() {
    let dir = tempfile::tempdir().unwrap();
    let [s1, s2] = two_shards(dir.path(), HOSTILE);
    let (code, out, err) = merge(&[&s1, &s2]);
    assert_eq!(code, 1, "{err}");
    // No control character, no bidi override, no forged line; the name shown.
    let raw = |c: char| (c.is_control() && c != '\n') || ('\u{202a}'..='\u{202e}').contains(&c);
    assert!(!out.chars().any(raw), "{out:?}");
    assert!(out.contains(HOSTILE_SHOWN), "{out}");
    assert!(!out.lines().any(|l| l.starts_with("ok ")), "{out}");
}

#[test]
fn the_junit_of_hostile_names_parses() {
    let dir = tempfile::tempdir().unwrap();
    let [s1, s2] = two_shards(dir.path(), HOSTILE);
    let junit = dir.path().join("merged.xml");
    let (code, _, err) = merge(&[&s1, &s2, Path::new("--junit"), &junit]);
    assert_eq!(code, 1, "{err}");
    // XML a parser accepts, each name as the terminal shows it but for the bidi override,
    // which XML holds (and `<&"`, which the writer escapes).
    let xml = std::fs::read_to_string(&junit).unwrap();
    let doc = roxmltree::Document::parse(&xml).unwrap_or_else(|e| panic!("{e}:\n{xml}"));
    let names: Vec<&str> = doc
        .descendants()
        .filter(|n| n.has_tag_name("testcase"))
        .map(|n| n.attribute("name").unwrap())
        .collect();
    let in_xml = HOSTILE_SHOWN.replace(r"\u{202e}", "\u{202e}");
    assert_eq!(names, [in_xml.as_str(), in_xml.as_str()]);
    // The failure's text keeps its lines, with the node's name escaped the same way.
    let failure = doc
        .descendants()
        .find(|n| n.has_tag_name("failure"))
        .unwrap();
    let text = failure.text().unwrap();
    assert!(text.contains("\\x1b]0;pwned\\x07\\x1b[2J\nok"), "{text:?}");
}

/// A run of one file with one material that loses energy, one lobe replaced by its fix:
/// every count the table, the page and the JUnit print agrees with its number; the JUnit's
/// finding reads as sentences; the page's title is a banner in the verdict's colour, as
/// verify's is, and bolds the failing count, not "ok".
#[test]
fn counts_of_one_read_singular_and_the_verdict_stands_out() {
    let dir = tempfile::tempdir().unwrap();
    let shard = dir.path().join("s1");
    std::fs::create_dir_all(shard.join("materials")).unwrap();
    let mut report = shard_report(1, 1, &INPUTS[..1], &[INPUTS[0].0], "Mat");
    report["files"][0]["fixed"] =
        json!({"path": "/lib/fixed/a.blend", "replaced": 1, "backup": null, "after_error": null});
    std::fs::write(shard.join("report.json"), report.to_string()).unwrap();
    let merged = dir.path().join("merged");
    let junit = dir.path().join("merged.xml");
    let (code, out, err) = merge(&[
        &shard,
        Path::new("--report"),
        &merged,
        Path::new("--junit"),
        &junit,
    ]);
    assert_eq!(code, 1, "{err}");
    for shown in [
        "Audit of 1 material in 1 file,",
        "FAIL: 0 ok, 1 loses energy, 0 create energy, 0 errors (failing on:",
        "(1 lobe replaced)",
    ] {
        assert!(out.contains(shown), "{shown}:\n{out}");
    }
    let xml = std::fs::read_to_string(&junit).unwrap();
    assert!(
        xml.contains("old-glossy at Mat: single scattering. Fix: Multiscatter GGX.\n"),
        "{xml}"
    );
    let page = merged.join("report.html");
    let html = std::fs::read_to_string(&page).unwrap();
    for shown in [
        "<header><h1>gloffuse audit: FAIL</h1>",
        "1 material in 1 file,",
        "0 ok, <b>1 loses energy</b>, 0 create energy, 0 errors.",
    ] {
        assert!(html.contains(shown), "{shown}:\n{html}");
    }
    let Some(chromium) = common::browser() else {
        return;
    };
    let image = common::screenshot(&chromium, &page);
    let banner = common::pixels_of(&image, gloffuse::report::page::FAIL_COLOUR);
    assert!(banner > 10_000, "{banner} pixels of the FAIL banner");
}

#[test]
fn an_error_quoting_a_hostile_path_prints_it_escaped() {
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("bad\u{1b}[2J\u{1b}]0;x\u{7}.json");
    std::fs::write(&bad, "{}").unwrap();
    let (code, _, err) = merge(&[&bad]);
    assert_eq!(code, 2, "{err}");
    assert!(!err.contains('\u{1b}') && !err.contains('\u{7}'), "{err:?}");
    assert!(err.contains(r"bad\x1b[2J\x1b]0;x\x07.json"), "{err}");
}

/// A fake .blend for the farm commands, which check only that the paths are .blend files.
fn fake_blend(dir: &Path) -> PathBuf {
    let blend = dir.join("x.blend");
    std::fs::write(&blend, b"BLENDER").unwrap();
    blend
}

#[test]
fn a_relative_gloffuse_becomes_absolute_in_the_openjd_template() {
    let dir = tempfile::tempdir().unwrap();
    let blend = fake_blend(dir.path());
    let job = dir.path().join("job");
    gloffuse()
        .current_dir(dir.path())
        .args(["farm", "openjd"])
        .arg(&blend)
        .args(["--shards", "2", "--gloffuse", "bin/gloffuse", "--out"])
        .arg(&job)
        .assert()
        .success();
    let read = |name: &str| -> Value {
        serde_json::from_str(&std::fs::read_to_string(job.join(name)).unwrap()).unwrap()
    };
    let template = read("gloffuse-audit.template.json");
    let program = &template["parameterDefinitions"][0];
    assert_eq!(program["name"], "Gloffuse");
    let expected = std::fs::canonicalize(dir.path())
        .unwrap()
        .join("bin/gloffuse");
    assert_eq!(program["default"], expected.display().to_string());
    // A bare name is a command the workers find on their PATH, as a shell would.
    gloffuse()
        .current_dir(dir.path())
        .args(["farm", "openjd"])
        .arg(&blend)
        .args(["--shards", "2", "--gloffuse", "gloffuse", "--out"])
        .arg(&job)
        .assert()
        .success();
    let template = read("gloffuse-audit.template.json");
    assert_eq!(template["parameterDefinitions"][0]["default"], "gloffuse");
}

#[test]
fn a_slurm_job_folder_with_a_backslash_is_refused() {
    // sbatch drops a log path's backslashes and then reads no `%a` in it.
    let dir = tempfile::tempdir().unwrap();
    let blend = fake_blend(dir.path());
    let job = dir.path().join("a\\b");
    let out = gloffuse()
        .args(["farm", "slurm"])
        .arg(&blend)
        .args(["--shards", "2", "--out"])
        .arg(&job)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("--out") && err.contains("backslash"), "{err}");
    assert!(!job.exists());
}
