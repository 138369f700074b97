//! A sharded audit, for real: `--shard K/N` run three times and merged must give the report
//! of one unsharded run; the merge refuses incomplete or mixed shards; the same audit runs
//! as a Slurm array job on the one-node cluster `scripts/test.sh` starts
//! (`scripts/slurm/local-cluster.sh`) and as an Open Job Description template under PyPI's
//! `openjd run`. Blender 3.4 (Debian's), whose start is the quickest.
//!
//! Tier: blender (needs the Blenders and tools `scripts/test.sh` installs).

mod common;

use std::path::{Path, PathBuf};
use std::sync::OnceLock;
use std::time::{Duration, Instant};

use common::blender::{SKIP_VAR, real_blender};
use common::gloffuse;
use serde_json::Value;

/// A small library of three files: two copies of the nested Beckmann file (one in a
/// folder) and the file of unusual materials, made once for every test here (in cargo's
/// temporary folder for tests, since a static is never dropped), with the Blender that made it.
fn library() -> Option<&'static (PathBuf, PathBuf)> {
    static LIBRARY: OnceLock<Option<(PathBuf, PathBuf)>> = OnceLock::new();
    LIBRARY
        .get_or_init(|| {
            let blender = real_blender("3.4")?;
            let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("farm-library");
            let _ = std::fs::remove_dir_all(&dir);
            let made = dir.join("made");
            common::audit_library::make_library(&blender, &made, None);
            let lib = dir.join("lib");
            std::fs::create_dir_all(lib.join("b")).unwrap();
            let nested = made.join("nested/deeper/nested.blend");
            std::fs::copy(&nested, lib.join("nested.blend")).unwrap();
            std::fs::copy(&nested, lib.join("b/nested.blend")).unwrap();
            std::fs::copy(made.join("unusual.blend"), lib.join("unusual.blend")).unwrap();
            Some((blender, lib))
        })
        .as_ref()
}

const RENDER: [&str; 4] = ["--resolution", "24", "--spp", "8"];

/// `gloffuse audit LIB ARGS --blender B`: exit code and stderr.
fn audit(blender: &Path, lib: &Path, args: &[&str]) -> (i32, String) {
    let out = gloffuse()
        .arg("audit")
        .arg(lib)
        .args(args)
        .arg("--no-provision")
        .arg("--blender")
        .arg(blender)
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn json(path: &Path) -> Value {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    serde_json::from_str(&text).unwrap()
}

/// The report without what differs between any two runs: timings, log paths, the program.
fn comparable(mut report: Value) -> Value {
    report.as_object_mut().unwrap().remove("blender_program");
    for file in report["files"].as_array_mut().unwrap() {
        for key in ["render_seconds", "scan_seconds", "log"] {
            file.as_object_mut().unwrap().remove(key);
        }
    }
    report
}

/// Equal field by field; numbers within `rel` (Cycles' renders of one file differ in the
/// last digits from run to run: the sum order of its threads).
fn assert_same(a: &Value, b: &Value, rel: f64, at: &str) {
    match (a, b) {
        (Value::Number(x), Value::Number(y)) => {
            let (x, y) = (x.as_f64().unwrap(), y.as_f64().unwrap());
            assert!(
                (x - y).abs() <= rel * x.abs().max(y.abs()),
                "{at}: {x} ≠ {y}"
            );
        }
        (Value::Array(x), Value::Array(y)) => {
            assert_eq!(x.len(), y.len(), "{at}: lengths");
            for (i, (p, q)) in x.iter().zip(y).enumerate() {
                assert_same(p, q, rel, &format!("{at}[{i}]"));
            }
        }
        (Value::Object(x), Value::Object(y)) => {
            let keys = |o: &serde_json::Map<String, Value>| o.keys().cloned().collect::<Vec<_>>();
            assert_eq!(keys(x), keys(y), "{at}: keys");
            for (k, p) in x {
                assert_same(p, &y[k], rel, &format!("{at}.{k}"));
            }
        }
        _ => assert_eq!(a, b, "{at}"),
    }
}

/// Text without the lines that name the command that made it.
fn without_rerun(text: &str) -> String {
    text.lines()
        .filter(|l| !l.contains("rerun") && !l.contains("Rerun"))
        .map(|l| {
            // JUnit's time attributes are timings.
            l.split(" time=\"")
                .enumerate()
                .map(|(i, part)| {
                    if i == 0 {
                        part.to_string()
                    } else {
                        part.split_once('"')
                            .map_or(String::new(), |(_, r)| r.to_string())
                    }
                })
                .collect::<String>()
        })
        .collect::<Vec<_>>()
        .join("\n")
}

#[test]
fn three_shards_merge_into_the_report_of_one_run() {
    let Some((blender, lib)) = library() else {
        return;
    };
    let out = tempfile::tempdir().unwrap();
    let o = |name: &str| out.path().join(name);
    let s = |p: PathBuf| p.display().to_string();
    let one_run = unsharded_run().unwrap();
    let mut held = Vec::new();
    for k in 1..=3 {
        let (code, err) = audit(
            blender,
            lib,
            &[
                &RENDER[..],
                &[
                    "--shard",
                    &format!("{k}/3"),
                    "--report",
                    &s(o(&format!("s{k}"))),
                    "--exit-zero",
                ],
            ]
            .concat(),
        );
        assert_eq!(code, 0, "--exit-zero: {err}");
        let shard = json(&o(&format!("s{k}/report.json")));
        assert_eq!(
            shard["shard"]["shard"],
            serde_json::json!({"index": k, "count": 3})
        );
        held.push(shard["files"].as_array().unwrap().len());
    }
    // Three files, three shards: one each.
    assert_eq!(held, [1, 1, 1]);
    let merged = gloffuse()
        .args(["report", "merge"])
        .args([o("s3"), o("s1"), o("s2/report.json")])
        .arg("--report")
        .arg(o("merged"))
        .arg("--junit")
        .arg(o("merged.xml"))
        .arg("--json")
        .arg(o("merged.json"))
        .output()
        .unwrap();
    assert_eq!(
        merged.status.code(),
        Some(1),
        "{}",
        String::from_utf8_lossy(&merged.stderr)
    );
    let all = comparable(json(&one_run.join("report/report.json")));
    let m = comparable(json(&o("merged/report.json")));
    assert_same(&all, &m, 1e-6, "report");
    assert_eq!(json(&o("merged.json")), json(&o("merged/report.json")));
    assert_eq!(m["counts"], all["counts"]);
    assert_eq!(m["passed"], false);
    // Each merged material is its shard's, exactly (the merge copies; it never recomputes).
    for material in m["materials"].as_array().unwrap() {
        let found = (1..=3).any(|k| {
            comparable(json(&o(&format!("s{k}/report.json"))))["materials"]
                .as_array()
                .unwrap()
                .contains(material)
        });
        assert!(found, "{material}");
    }
    let read = |p: PathBuf| std::fs::read_to_string(p).unwrap();
    assert_eq!(
        without_rerun(&read(one_run.join("junit.xml"))),
        without_rerun(&read(o("merged.xml")))
    );
    assert_eq!(
        without_rerun(&read(one_run.join("report/report.html"))),
        without_rerun(&read(o("merged/report.html")))
    );
    let pictures = |d: &Path| {
        let mut names: Vec<String> = std::fs::read_dir(d.join("materials"))
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        names
    };
    assert_eq!(pictures(&one_run.join("report")), pictures(&o("merged")));
    assert!(!pictures(&o("merged")).is_empty());
    refusals(out.path(), &one_run.join("report"));
}

/// `report merge` of `shards`: its exit code and stderr.
fn merge(shards: &[PathBuf]) -> (i32, String) {
    let out = gloffuse()
        .args(["report", "merge"])
        .args(shards)
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// A missing shard, a shard twice, a shard of another run: each refused with exit 2, by name.
fn refusals(dir: &Path, unsharded: &Path) {
    let s = |k: usize| dir.join(format!("s{k}"));
    let (code, err) = merge(&[s(1), s(3)]);
    assert_eq!(code, 2);
    assert!(err.contains("missing 2/3"), "{err}");
    let (code, err) = merge(&[s(1), s(2), s(3), s(2)]);
    assert_eq!(code, 2);
    assert!(err.contains("shard 2/3 is also"), "{err}");
    let edit = |k: usize, name: &str, change: &dyn Fn(&mut Value)| {
        let mut report = json(&s(k).join("report.json"));
        change(&mut report);
        let path = dir.join(name);
        std::fs::write(&path, report.to_string()).unwrap();
        path
    };
    let other_blender = edit(2, "blender.json", &|r| {
        r["blender_version"] = "4.5.1".into()
    });
    let (code, err) = merge(&[s(1), other_blender, s(3)]);
    assert_eq!(code, 2);
    assert!(err.contains("it ran Blender 4.5.1"), "{err}");
    let other_sweep = edit(2, "sweep.json", &|r| r["settings"]["samples"] = 64.into());
    let (code, err) = merge(&[s(1), other_sweep, s(3)]);
    assert!(code == 2 && err.contains("its settings differ"), "{err}");
    let other_files = edit(3, "files.json", &|r| {
        r["shard"]["inputs"][0]["materials"] = 7.into()
    });
    let (code, err) = merge(&[s(1), s(2), other_files]);
    assert!(code == 2 && err.contains("input files differ"), "{err}");
    let unsharded = merge(&[unsharded.to_path_buf()]);
    assert!(
        unsharded.0 == 2 && unsharded.1.contains("--shard"),
        "{}",
        unsharded.1
    );
}

/// The library's audit rendered in one run: a folder with `report/` (`--report`) and
/// `junit.xml`, made once for the tests that compare shards with it.
fn unsharded_run() -> Option<&'static PathBuf> {
    static RUN: OnceLock<Option<PathBuf>> = OnceLock::new();
    RUN.get_or_init(|| {
        let (blender, lib) = library()?;
        let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("farm-unsharded");
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let (report, junit) = (dir.join("report"), dir.join("junit.xml"));
        let (code, err) = audit(
            blender,
            lib,
            &[
                &RENDER[..],
                &["--report", report.to_str().unwrap()],
                &["--junit", junit.to_str().unwrap()],
            ]
            .concat(),
        );
        assert_eq!(code, 1, "the library has failing materials: {err}");
        Some(dir)
    })
    .as_ref()
}

/// The rules-only audit of the library, unsharded: what the farms' merged reports must equal.
fn local_rules_report() -> Option<&'static Value> {
    static REPORT: OnceLock<Option<Value>> = OnceLock::new();
    REPORT
        .get_or_init(|| {
            let (blender, lib) = library()?;
            let out = gloffuse()
                .arg("audit")
                .arg(lib)
                .args(["--no-render", "--json", "--no-provision", "--blender"])
                .arg(blender)
                .output()
                .unwrap();
            assert_eq!(out.status.code(), Some(1));
            Some(comparable(serde_json::from_slice(&out.stdout).unwrap()))
        })
        .as_ref()
}

/// A tool the test script installs, from `var`; missing, the test fails unless skipping.
fn tool(var: &str, what: &str) -> Option<String> {
    if let Some(v) = std::env::var_os(var) {
        return Some(v.to_string_lossy().into_owned());
    }
    let why = format!("{what}: {var} is not set (scripts/test.sh sets it)");
    common::skip(SKIP_VAR, &why);
    None
}

#[test]
fn slurm_runs_the_shards_then_the_merge() {
    let Some(conf) = tool("GLOFFUSE_TEST_SLURM_CONF", "a Slurm cluster") else {
        return;
    };
    let Some((blender, lib)) = library() else {
        return;
    };
    let expected = comparable(json(&unsharded_run().unwrap().join("report/report.json")));
    let dir = tempfile::tempdir().unwrap();
    let job = dir.path().join("job dir");
    let out = gloffuse()
        .env("SLURM_CONF", &conf)
        .args(["farm", "slurm"])
        .arg(lib)
        .args(["--shards", "3", "--submit", "--json", "--out"])
        .arg(&job)
        .arg("--")
        .args(RENDER)
        .args(["--no-provision", "--blender"])
        .arg(blender)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let ids: Value = serde_json::from_slice(&out.stdout).unwrap();
    let merge_job = ids["merge_job"].as_str().unwrap();
    let (state, exit) = wait_for_job(&conf, merge_job, Duration::from_secs(300));
    // The merge carries the verdict: the library fails the check.
    assert_eq!((state.as_str(), exit.as_str()), ("FAILED", "1:0"));
    for k in 1..=3 {
        assert!(job.join(format!("shard-{k}/report.json")).is_file());
        assert!(job.join(format!("logs/shard-{k}.log")).is_file());
    }
    // Rendered: as close to the local run as two runs are (see assert_same).
    assert_same(
        &expected,
        &comparable(json(&job.join("merged.json"))),
        1e-6,
        "slurm",
    );
    assert!(job.join("merged/report.html").is_file() && job.join("merged.xml").is_file());
    let count = |d: PathBuf| std::fs::read_dir(d).unwrap().count();
    let local = unsharded_run().unwrap().join("report/materials");
    assert_eq!(count(job.join("merged/materials")), count(local));
}

/// A job folder named to break a shell script or an sbatch pattern: spaces, both quotes,
/// `$(…)` and backticks that would create a file if run, and `%` patterns. `submit.sh`, run
/// by bash as a person would, must run no command from it and have Slurm write the logs,
/// the shards and the merged report into that very folder.
#[test]
fn slurm_takes_a_hostile_job_folder_exactly() {
    let Some(conf) = tool("GLOFFUSE_TEST_SLURM_CONF", "a Slurm cluster") else {
        return;
    };
    let Some((blender, lib)) = library() else {
        return;
    };
    let expected = local_rules_report().unwrap();
    let dir = tempfile::tempdir().unwrap();
    let job = dir
        .path()
        .join("out $(touch made-by-dollar) `touch made-by-backtick` \"q\" 'q' %a %j %% 100%");
    gloffuse()
        .args(["farm", "slurm"])
        .arg(lib)
        .args(["--shards", "2", "--out"])
        .arg(&job)
        .args(["--", "--no-render", "--no-provision", "--blender"])
        .arg(blender)
        .assert()
        .success();
    let submit = std::process::Command::new("bash")
        .arg(job.join("submit.sh"))
        .current_dir(dir.path())
        .env("SLURM_CONF", &conf)
        .output()
        .unwrap();
    let said = String::from_utf8_lossy(&submit.stdout).into_owned();
    let err = String::from_utf8_lossy(&submit.stderr);
    assert!(submit.status.success(), "{said}{err}");
    // Its last line names the merged report's folder as it is.
    let merged = job.join("merged");
    assert!(
        said.trim_end()
            .ends_with(&format!("merged report: {}", merged.display())),
        "{said}"
    );
    let merge_job = said
        .split("merge: job ")
        .nth(1)
        .and_then(|r| r.split([';', ' ']).next())
        .unwrap_or_else(|| panic!("{said}"));
    let (state, exit) = wait_for_job(&conf, merge_job, Duration::from_secs(300));
    assert_eq!((state.as_str(), exit.as_str()), ("FAILED", "1:0"), "{said}");
    for made in ["made-by-dollar", "made-by-backtick"] {
        assert!(!dir.path().join(made).exists(), "{made}: a command ran");
    }
    for k in 1..=2 {
        assert!(job.join(format!("logs/shard-{k}.log")).is_file());
        assert!(job.join(format!("shard-{k}/report.json")).is_file());
    }
    assert!(job.join("logs/merge.log").is_file());
    assert_same(
        expected,
        &comparable(json(&job.join("merged.json"))),
        0.0,
        "slurm",
    );
    // Nothing was written beside the job's folder.
    let beside: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(beside, [job.file_name().unwrap()]);
}

/// Polls `scontrol show job ID` until the job ends: its JobState and ExitCode.
fn wait_for_job(conf: &str, id: &str, limit: Duration) -> (String, String) {
    let start = Instant::now();
    loop {
        let out = std::process::Command::new("scontrol")
            .env("SLURM_CONF", conf)
            .args(["show", "job", id])
            .output()
            .unwrap();
        let text = String::from_utf8_lossy(&out.stdout).into_owned();
        let field = |name: &str| {
            text.split_whitespace()
                .find_map(|w| w.strip_prefix(&format!("{name}=")))
                .unwrap_or_default()
                .to_string()
        };
        let state = field("JobState");
        if !["PENDING", "RUNNING", "CONFIGURING", "COMPLETING", ""].contains(&state.as_str()) {
            return (state, field("ExitCode"));
        }
        assert!(start.elapsed() < limit, "job {id} still {state}:\n{text}");
        std::thread::sleep(Duration::from_millis(500));
    }
}

#[test]
fn openjd_runs_the_template() {
    let Some(openjd) = tool("GLOFFUSE_TEST_OPENJD", "openjd-cli") else {
        return;
    };
    let Some((blender, lib)) = library() else {
        return;
    };
    let expected = local_rules_report().unwrap();
    let dir = tempfile::tempdir().unwrap();
    let job = dir.path().join("job");
    gloffuse()
        .args(["farm", "openjd"])
        .arg(lib)
        .args(["--shards", "3", "--out"])
        .arg(&job)
        .args(["--", "--no-render", "--no-provision", "--blender"])
        .arg(blender)
        .assert()
        .success();
    let template = job.join("gloffuse-audit.template.json");
    let check = std::process::Command::new(&openjd)
        .arg("check")
        .arg(&template)
        .output()
        .unwrap();
    assert!(
        check.status.success(),
        "{}",
        String::from_utf8_lossy(&check.stdout)
    );
    let run = std::process::Command::new(&openjd)
        .arg("run")
        .arg(&template)
        .arg("-p")
        .arg(format!("file://{}", job.join("parameters.json").display()))
        .output()
        .unwrap();
    let log = String::from_utf8_lossy(&run.stdout);
    // Every shard ran (exit 0 with --exit-zero), then the merge, whose exit 1 is the verdict.
    assert_eq!(run.status.code(), Some(1), "{log}");
    assert_same(
        expected,
        &comparable(json(&job.join("merged.json"))),
        0.0,
        "openjd",
    );
    for k in 1..=3 {
        assert!(job.join(format!("shard-{k}.xml")).is_file(), "{log}");
    }
}

#[test]
fn bad_farm_input_is_refused_by_name() {
    let dir = tempfile::tempdir().unwrap();
    let blend = dir.path().join("x.blend");
    std::fs::write(&blend, b"not read before the flags are checked").unwrap();
    let refused = |args: &[&str], says: &str| {
        let out = gloffuse().args(args).output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(says), "{args:?}: {err}");
    };
    let b = blend.to_str().unwrap();
    let out = dir.path().join("job");
    let o = out.to_str().unwrap();
    refused(&["audit", b, "--shard", "0/3"], "K/N with 1 ≤ K ≤ N");
    refused(&["audit", b, "--shard", "4/3"], "K/N with 1 ≤ K ≤ N");
    refused(
        &["farm", "slurm", b, "--shards", "0", "--out", o],
        "--shards",
    );
    refused(
        &[
            "farm", "slurm", b, "--shards", "2", "--out", o, "--", "--shard", "1/2",
        ],
        "the farm sets --shard",
    );
    refused(
        &[
            "farm", "openjd", b, "--shards", "2", "--out", o, "--", "--spp", "lots",
        ],
        "`gloffuse audit` flags after --",
    );
    refused(
        &[
            "farm",
            "openjd",
            b,
            "--shards",
            "2",
            "--out",
            o,
            "--",
            "--blender",
            "/x/{{y}}",
        ],
        "no `{{` or `}}`",
    );
    refused(&["report", "merge", b], "an audit report of a shard");
    // Nothing was written for a refused job.
    assert!(!out.exists());
}
