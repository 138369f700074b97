//! Issue 25 (7): every example in docs/GUIDE.md runs, and says what the guide says it says.
//!
//! The guide's examples are ```console blocks: `$ COMMAND` lines, each followed by the
//! output it shows. This test runs the blocks in order, in one folder (so an example may
//! use what an earlier one wrote), with the built `gloffuse` first on PATH and Blender
//! (bpy 4.5, which every example can use) in `GLOFFUSE_BLENDER`. The folder starts with
//! the files the guide assumes a reader has: `assets/` (the tests' library of user
//! materials) and `scene.blend` (a user's scene).
//!
//! How shown output is compared with what ran (stdout and stderr together):
//! - each shown line must appear, in order; lines the guide leaves out may come between;
//! - `…` inside a line stands for any text (times, noise, paths), and a line that is only
//!   `…` says lines were left out;
//! - `[exit N]` says the command ends with status N (else it must end with 0).
//!
//! ```yaml blocks (CI jobs) are configuration for other systems: their `gloffuse`
//! command lines are run too, and must end with 0. So are the `gloffuse` lines of the
//! README's ```sh blocks (its first uses), after the guide's, unless the guide ran the same
//! command already.
//!
//! Tier: blender (needs the Blenders and tools `scripts/test.sh` installs).

mod common;

use std::path::Path;
use std::process::Command;

const GUIDE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/docs/GUIDE.md");
const README: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/README.md");

/// One example: where it is, a command, the output lines shown under it, the exit status
/// it expects.
#[derive(Debug)]
struct Example {
    file: &'static str,
    line: usize,
    command: String,
    shown: Vec<String>,
    exit: i32,
}

/// The examples of `text` (the file `file`), in order.
fn examples(file: &'static str, text: &str) -> Vec<Example> {
    let mut out: Vec<Example> = Vec::new();
    let mut block: Option<&str> = None;
    for (n, line) in text.lines().enumerate() {
        if let Some(info) = line.strip_prefix("```") {
            block = match block {
                None => Some(info.trim()),
                Some(_) => None,
            };
            continue;
        }
        match block {
            Some("console") => {
                if let Some(command) = line.strip_prefix("$ ") {
                    out.push(Example {
                        file,
                        line: n + 1,
                        command: command.to_string(),
                        shown: Vec::new(),
                        exit: 0,
                    });
                } else if let Some(example) = out.last_mut() {
                    if let Some(code) = line
                        .strip_prefix("[exit ")
                        .and_then(|c| c.strip_suffix(']'))
                    {
                        example.exit = code.parse().expect("[exit N] holds a number");
                    } else if !line.trim().is_empty() {
                        example.shown.push(line.to_string());
                    }
                } else {
                    panic!("{file}:{}: output before any `$ ` command", n + 1);
                }
            }
            Some("yaml" | "sh") => {
                let code = line.trim_start().trim_start_matches("- ");
                let code = code.strip_prefix("run: ").unwrap_or(code);
                // A trailing comment is the reader's, not the shell's business.
                let code = code.split(" #").next().unwrap_or(code).trim_end();
                if code.starts_with("gloffuse ") {
                    out.push(Example {
                        file,
                        line: n + 1,
                        command: code.to_string(),
                        shown: Vec::new(),
                        exit: 0,
                    });
                }
            }
            _ => {}
        }
    }
    out
}

/// Whether `pattern` (with `…` for any text) matches the whole of `line`.
fn line_matches(pattern: &str, line: &str) -> bool {
    let parts: Vec<&str> = pattern.split('…').collect();
    let line = line.trim_end();
    let last = parts.len() - 1;
    let mut rest = line;
    for (i, part) in parts.iter().enumerate() {
        let part = if i == last { part.trim_end() } else { part };
        if i == 0 {
            let Some(r) = rest.strip_prefix(part) else {
                return false;
            };
            rest = r;
        } else if i == last {
            return rest.ends_with(part);
        } else {
            let Some(at) = rest.find(part) else {
                return false;
            };
            rest = &rest[at + part.len()..];
        }
    }
    last == 0 && rest.is_empty()
}

/// The first shown line that does not appear, in order, in `output`.
fn first_missing<'a>(shown: &'a [String], output: &str) -> Option<&'a str> {
    let mut lines = output.lines();
    'shown: for pattern in shown {
        if pattern.trim() == "…" {
            continue;
        }
        for line in lines.by_ref() {
            if line_matches(pattern, line) {
                continue 'shown;
            }
        }
        return Some(pattern);
    }
    None
}

#[test]
fn the_matcher_can_fail() {
    assert!(line_matches("PASS: all … spheres", "PASS: all 6 spheres"));
    assert!(line_matches("a … b … c", "a 1 b 2 c"));
    assert!(!line_matches("PASS: all … spheres", "FAIL: all 6 spheres"));
    assert!(!line_matches("exact", "exact and more"));
    let shown = ["one".to_string(), "…".to_string(), "three".to_string()];
    assert_eq!(first_missing(&shown, "one\ntwo\nthree\n"), None);
    assert_eq!(first_missing(&shown, "three\none\n"), Some("three"));
    let parsed = examples(
        "t.md",
        "```console\n$ gloffuse x\nout …\n[exit 1]\n```\n```yaml\n  - run: gloffuse y --z\n```\n\
         ```sh\ngloffuse w   # a comment\ncargo build\n```\n",
    );
    assert_eq!(parsed.len(), 3);
    assert_eq!((parsed[0].exit, parsed[0].shown.len()), (1, 1));
    assert_eq!(parsed[1].command, "gloffuse y --z");
    assert_eq!(parsed[2].command, "gloffuse w");
}

/// One test, not one per example: the examples run in order in one folder, a later one
/// using what an earlier one wrote, so one example alone cannot run; the first to fail is
/// named with its file and line.
#[test]
fn every_guide_example_runs_and_shows_what_the_guide_says() {
    let guide = std::fs::read_to_string(GUIDE).unwrap();
    let readme = std::fs::read_to_string(README).unwrap();
    let mut all = examples("docs/GUIDE.md", &guide);
    assert!(all.len() >= 20, "the guide's examples were read: {all:?}");
    let first_uses = examples("README.md", &readme);
    assert!(
        first_uses.len() >= 5,
        "the README's examples were read: {first_uses:?}"
    );
    for example in first_uses {
        if !all.iter().any(|e| e.command == example.command) {
            all.push(example);
        }
    }
    let Some(blender) = common::blender::real_blender("4.5") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let work = dir.path().join("work");
    let home = dir.path().join("home");
    std::fs::create_dir_all(&home).unwrap();
    common::audit_library::make_library(&blender, &work.join("assets"), None);
    common::user_file::make(&blender, &work.join("scene.blend"), &[]);
    let bin = Path::new(env!("CARGO_BIN_EXE_gloffuse")).parent().unwrap();
    let path = std::env::join_paths(std::iter::once(bin.to_path_buf()).chain(
        std::env::split_paths(&std::env::var_os("PATH").unwrap_or_default()),
    ))
    .unwrap();
    for example in &all {
        let out = Command::new("bash")
            .arg("-c")
            .arg(format!("{} 2>&1", example.command))
            .current_dir(&work)
            .env("PATH", &path)
            .env("HOME", &home)
            .env("GLOFFUSE_BLENDER", &blender)
            .output()
            .unwrap();
        let output = String::from_utf8_lossy(&out.stdout);
        let code = out.status.code().unwrap_or(-1);
        assert_eq!(
            code, example.exit,
            "{}:{}: `{}` ended with {code}:\n{output}",
            example.file, example.line, example.command
        );
        if let Some(missing) = first_missing(&example.shown, &output) {
            panic!(
                "{}:{}: `{}` did not show\n  {missing}\nin order; it showed:\n{output}",
                example.file, example.line, example.command
            );
        }
    }
}
