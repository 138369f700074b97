//! The Flamenco job type (`contrib/flamenco/gloffuse-audit.js`): its own Node tests (the task
//! graph its `compileJob` builds, against a recording stand-in for Flamenco's `author`), and
//! the commands it builds, given to the real `gloffuse`, which must accept every flag (no
//! Flamenco farm runs here: docs/GUIDE.md says so).
//!
//! Tier: blender (needs the Blenders and tools `scripts/test.sh` installs).

mod common;

use std::path::Path;
use std::process::Command;

use common::blender::SKIP_VAR;
use common::gloffuse;

fn flamenco_dir() -> &'static Path {
    concat!(env!("CARGO_MANIFEST_DIR"), "/contrib/flamenco").as_ref()
}

/// Node.js, or `None` when skipping was asked for.
fn node() -> Option<&'static str> {
    if Command::new("node").arg("--version").output().is_ok() {
        return Some("node");
    }
    common::skip(SKIP_VAR, "node is not on PATH");
    None
}

#[test]
fn the_job_types_node_tests_pass() {
    let Some(node) = node() else { return };
    let out = Command::new(node)
        .arg("--test")
        .arg(flamenco_dir())
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{text}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        text.contains("# fail 0") && !text.contains("# pass 0"),
        "{text}"
    );
}

/// Compiles a 2-shard job and prints each task's (type, dependencies, exe, args) as JSON.
const COMPILE: &str = r#"
const fs = require("fs"), vm = require("vm");
const tasks = [];
const author = {
  Task(name, type) {
    const t = { name, type, commands: [], deps: [] };
    t.addCommand = (c) => t.commands.push(c);
    t.addDependency = (d) => t.deps.push(d.name);
    return t;
  },
  Command(type, params) { return { type, params }; },
};
const ctx = vm.createContext({ author, print() {}, shellSplit: (s) => s.split(" ").filter(Boolean),
  formatTimestampLocal: () => "now" });
vm.runInContext(fs.readFileSync(process.argv[1], "utf8"), ctx);
ctx.compileJob({ settings: { paths: process.argv[2], shards: 2, output_dir: process.argv[3],
  gloffuse_exe: "gloffuse", extra_args: "--spp 8" }, created: new Date(), addTask: (t) => tasks.push(t) });
console.log(JSON.stringify(tasks.map((t) => ({ type: t.type, deps: t.deps,
  command: t.commands[0].type, args: t.commands[0].params.args }))));
"#;

#[test]
fn gloffuse_accepts_every_command_the_job_builds() {
    let Some(node) = node() else { return };
    let out = Command::new(node)
        .args(["-e", COMPILE])
        .arg(flamenco_dir().join("gloffuse-audit.js"))
        .args(["/nowhere/assets; /nowhere/more assets", "/nowhere/out"])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let tasks: Vec<serde_json::Value> = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(tasks.len(), 3);
    let kinds: Vec<(&str, usize)> = tasks
        .iter()
        .map(|t| {
            (
                t["type"].as_str().unwrap(),
                t["deps"].as_array().unwrap().len(),
            )
        })
        .collect();
    assert_eq!(kinds, [("blender", 0), ("blender", 0), ("misc", 2)]);
    for task in &tasks {
        assert_eq!(task["command"], "exec");
        let args: Vec<String> = task["args"]
            .as_array()
            .unwrap()
            .iter()
            .map(|a| a.as_str().unwrap().replace("{blender}", "/nowhere/blender"))
            .collect();
        // The flags parse: what fails is the missing input, named, with exit 2 — never
        // clap's "unexpected argument".
        let run = gloffuse().args(&args).output().unwrap();
        let err = String::from_utf8_lossy(&run.stderr);
        assert_eq!(run.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains("/nowhere/"), "{args:?}: {err}");
        assert!(!err.contains("unexpected argument"), "{args:?}: {err}");
    }
}
