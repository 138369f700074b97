//! Writers of a user's file under hostile and concurrent conditions, in real Blender: every
//! case of issue 39's "data loss" list and its signal case. A user's file is never lost:
//!
//! - two `audit --in-place` runs of one folder at once, and `generate --into` beside an
//!   in-place audit, take turns on the file's lock: the file ends with both runs' changes
//!   and its `.blend1` holds the bytes the user had before either;
//! - a file another program saves while gloffuse works on it is left as that program saved
//!   it (gloffuse's change is refused, and says so);
//! - a file name that is not UTF-8 reaches Blender byte for byte: that very file is fixed,
//!   never a sibling whose name is its lossy spelling;
//! - `--fix-dir` refuses two inputs that would be written to one path, naming both;
//! - one file that cannot be fixed (empty, from a newer Blender) is that file's error, and
//!   the others are fixed;
//! - a library whose catalog file cannot be replaced stays as it was, catalogs and all;
//! - a stop between Blender runs leaves no temporary file or staging folder behind and says
//!   which files were already written.
//!
//! Tier: blender (needs the Blenders and tools `scripts/test.sh` installs).

mod common;

use std::ffi::{OsStr, OsString};
use std::fs;
use std::os::unix::ffi::OsStrExt;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

use serde_json::Value;

/// A user's scene whose material "Chair Paint" is a rough single-scatter GGX glossy.
fn fixable(blender: &Path, path: &Path) {
    common::user_file::make(blender, path, &["--glossy"]);
}

/// The distributions of "Chair Paint"'s BSDF nodes, and the file's gloffuse-tagged groups.
fn contents(blender: &Path, path: &Path) -> (Vec<String>, Vec<String>) {
    let seen = common::user_file::inspect(blender, path);
    let distributions = seen["distributions"]["Chair Paint"]
        .as_array()
        .unwrap()
        .iter()
        .map(|d| d.as_str().unwrap().to_string())
        .collect();
    let tagged = seen["groups"]
        .as_object()
        .unwrap()
        .iter()
        .filter(|(_, g)| !g["tag"].is_null())
        .map(|(name, _)| name.clone())
        .collect();
    (distributions, tagged)
}

/// `gloffuse COMMAND --no-provision --blender BLENDER`, with its own cache.
fn gloffuse(command: &str, blender: &Path, cache: &Path) -> Command {
    let mut cmd = Command::new(assert_cmd::cargo::cargo_bin("gloffuse"));
    cmd.arg(command)
        .arg("--no-provision")
        .arg("--blender")
        .arg(blender)
        .env("XDG_CACHE_HOME", cache)
        .env_remove("GLOFFUSE_BLENDER")
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    cmd
}

/// `gloffuse audit ARGS --json --no-render` started in `blender`.
fn audit(blender: &Path, cache: &Path, args: &[&OsStr]) -> Command {
    let mut cmd = gloffuse("audit", blender, cache);
    cmd.args(args).args(["--json", "--no-render"]);
    cmd
}

fn text(out: &Output) -> String {
    format!(
        "exit {:?}\n{}\n{}",
        out.status.code(),
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    )
}

/// Names in `dir` that gloffuse must not leave: its temporary files and lock files.
fn leftovers(dir: &Path) -> Vec<String> {
    fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with(".gloffuse-") || n.ends_with(".gloffuse-lock"))
        .collect()
}

fn assert_nothing_left(dir: &Path) {
    let left = leftovers(dir);
    assert!(left.is_empty(), "left beside the files: {left:?}");
}

fn finish(child: Child) -> Output {
    child.wait_with_output().unwrap()
}

/// Case 1: two `audit --in-place` of one folder at once (a farm retry, two CI jobs). Both
/// succeed; the file is fixed once, and its `.blend1` holds the original bytes (before the
/// lock, both fixed the file and the `.blend1` held a fixed version).
#[test]
fn two_in_place_audits_at_once_keep_the_original_as_blend1() {
    let Some(blender) = common::blender::real_blender("3.4") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let cache = tempfile::tempdir().unwrap();
    let file = dir.path().join("scene.blend");
    fixable(&blender, &file);
    let original = fs::read(&file).unwrap();
    let args = [dir.path().as_os_str(), "--in-place".as_ref()];
    // The first run's Blender is frozen once it has read the file and saved its fix (the
    // temporary file beside it has bytes), so the second starts while the first is mid-way,
    // whatever the machine's speed.
    let first = audit(&blender, cache.path(), &args).spawn().unwrap();
    let job = audit_child(first.id());
    let deadline = Instant::now() + Duration::from_secs(60);
    while !saved_beside(dir.path()) {
        assert!(
            Instant::now() < deadline,
            "the first run never saved its fix"
        );
        std::thread::sleep(Duration::from_millis(2));
    }
    // SAFETY: killpg only signals the group of the Blender job just found.
    unsafe { libc::killpg(job as libc::pid_t, libc::SIGSTOP) };
    let mut second = audit(&blender, cache.path(), &args).spawn().unwrap();
    // Without a lock the second run fixes the file meanwhile (a few seconds); with one it
    // waits for the first.
    let deadline = Instant::now() + Duration::from_secs(20);
    while Instant::now() < deadline && second.try_wait().unwrap().is_none() {
        std::thread::sleep(Duration::from_millis(100));
    }
    // SAFETY: as above.
    unsafe { libc::killpg(job as libc::pid_t, libc::SIGCONT) };
    let (first, second) = (finish(first), finish(second));
    for out in [&first, &second] {
        assert_ne!(out.status.code(), Some(2), "{}", text(out));
    }
    let fixed: Vec<u64> = [&first, &second]
        .iter()
        .map(|out| {
            let report: Value = serde_json::from_slice(&out.stdout).unwrap();
            report["files"][0]["fixed"]["replaced"]
                .as_u64()
                .unwrap_or(0)
        })
        .collect();
    assert_eq!(
        fixed.iter().filter(|&&n| n > 0).count(),
        1,
        "one run fixes, the other finds nothing left to fix: {fixed:?}\n{}\n{}",
        text(&first),
        text(&second)
    );
    assert_eq!(
        fs::read(dir.path().join("scene.blend1")).unwrap(),
        original,
        "the .blend1 holds what the user had"
    );
    // The fix adds a Multiscatter GGX twin beside the glossy it replaces: once.
    let (distributions, _) = contents(&blender, &file);
    assert_eq!(
        distributions,
        ["GGX", "MULTI_GGX"],
        "the file is fixed once"
    );
    assert_nothing_left(dir.path());
}

/// Case 2: `generate --into F` and `audit F --in-place` at once. F ends with generate's
/// groups and the audit's fix, and F.blend1 with the original bytes, whichever ran first
/// (before the lock, one run's change was lost and the original was gone).
#[test]
fn generate_into_beside_an_in_place_audit_loses_nothing() {
    let Some(blender) = common::blender::real_blender("3.4") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let cache = tempfile::tempdir().unwrap();
    let file = dir.path().join("scene.blend");
    fixable(&blender, &file);
    let original = fs::read(&file).unwrap();
    let mut generate = gloffuse("generate", &blender, cache.path());
    generate.arg("--into").arg(&file);
    let generate = generate.spawn().unwrap();
    let audit = audit(
        &blender,
        cache.path(),
        &[file.as_os_str(), "--in-place".as_ref()],
    )
    .spawn()
    .unwrap();
    let (generate, audit) = (finish(generate), finish(audit));
    assert_eq!(generate.status.code(), Some(0), "{}", text(&generate));
    assert_ne!(audit.status.code(), Some(2), "{}", text(&audit));
    let (distributions, tagged) = contents(&blender, &file);
    assert_eq!(
        distributions,
        ["GGX", "MULTI_GGX"],
        "the audit's fix (a Multiscatter GGX twin) is in the file"
    );
    assert!(
        tagged.iter().any(|g| g.starts_with("Gloffuse")),
        "generate's groups are in the file: {tagged:?}"
    );
    assert_eq!(fs::read(dir.path().join("scene.blend1")).unwrap(), original);
    assert_nothing_left(dir.path());
}

/// Whether a temporary save beside the files holds bytes: a job has saved its fix.
fn saved_beside(dir: &Path) -> bool {
    fs::read_dir(dir).unwrap().any(|e| {
        let e = e.unwrap();
        e.file_name().to_string_lossy().starts_with(".gloffuse-")
            && e.metadata().is_ok_and(|m| m.len() > 0)
    })
}

/// The pid of a Blender child of `pid` running an audit job, once it runs.
fn audit_child(pid: u32) -> u32 {
    let deadline = Instant::now() + Duration::from_secs(60);
    loop {
        let children =
            fs::read_to_string(format!("/proc/{pid}/task/{pid}/children")).unwrap_or_default();
        let job = children
            .split_whitespace()
            .filter_map(|p| p.parse::<u32>().ok())
            .find(|child| {
                fs::read(format!("/proc/{child}/cmdline"))
                    .is_ok_and(|c| String::from_utf8_lossy(&c).contains("gloffuse-audit.py"))
            });
        if let Some(child) = job {
            return child;
        }
        assert!(Instant::now() < deadline, "no audit job started");
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// A file saved by another program (Blender's own UI, say) while gloffuse's job worked on
/// it: the fix is refused, naming the file, and the other program's save stays.
#[test]
fn a_file_saved_by_another_program_meanwhile_is_left_as_it_saved_it() {
    let Some(blender) = common::blender::real_blender("3.4") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let cache = tempfile::tempdir().unwrap();
    let file = dir.path().join("scene.blend");
    fixable(&blender, &file);
    let child = audit(
        &blender,
        cache.path(),
        &[file.as_os_str(), "--in-place".as_ref()],
    )
    .spawn()
    .unwrap();
    let job = audit_child(child.id());
    // SAFETY: killpg only signals the group of the Blender job just found.
    unsafe { libc::killpg(job as libc::pid_t, libc::SIGSTOP) };
    // The other program's save: a new version of the file, as Blender writes one.
    let theirs = dir.path().join("theirs.blend");
    common::user_file::make(&blender, &theirs, &[]);
    let saved = fs::read(&theirs).unwrap();
    fs::rename(&theirs, &file).unwrap();
    // SAFETY: as above.
    unsafe { libc::killpg(job as libc::pid_t, libc::SIGCONT) };
    let out = finish(child);
    assert_eq!(fs::read(&file).unwrap(), saved, "{}", text(&out));
    assert!(!dir.path().join("scene.blend1").exists(), "{}", text(&out));
    let report: Value = serde_json::from_slice(&out.stdout).unwrap_or(Value::Null);
    let error = report["files"][0]["error"].as_str().unwrap_or_default();
    assert!(
        error.contains("changed by another program"),
        "{}",
        text(&out)
    );
    assert_eq!(out.status.code(), Some(1), "{}", text(&out));
    assert_nothing_left(dir.path());
}

/// Case 3: a file named with a byte that is not UTF-8, beside a sibling whose name is its
/// lossy spelling (U+FFFD). In every Blender, the file itself is audited and fixed in
/// place; the sibling is untouched (before, the sibling was audited and its fixed copy
/// replaced the real file).
fn a_name_that_is_not_utf8_reaches_blender_byte_for_byte(label: &'static str, blender: PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let cache = tempfile::tempdir().unwrap();
    let made = dir.path().join("made.blend");
    fixable(&blender, &made);
    let raw = dir.path().join(OsStr::from_bytes(b"caf\xe9 scene.blend"));
    let sibling = dir.path().join("caf\u{FFFD} scene.blend");
    fs::rename(&made, &raw).unwrap();
    common::user_file::make(&blender, &sibling, &[]);
    let (raw_before, sibling_before) = (fs::read(&raw).unwrap(), fs::read(&sibling).unwrap());
    let out = finish(
        audit(
            &blender,
            cache.path(),
            &[raw.as_os_str(), "--in-place".as_ref()],
        )
        .spawn()
        .unwrap(),
    );
    let what = format!("Blender {label}: {}", text(&out));
    assert_eq!(fs::read(&sibling).unwrap(), sibling_before, "{what}");
    let mut backup = raw.clone().into_os_string();
    backup.push("1");
    assert_eq!(fs::read(&backup).unwrap(), raw_before, "{what}");
    let report: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(report["files"][0]["fixed"]["replaced"], 1, "{what}");
    // The fixed file is audited again: nothing is left to replace.
    assert_eq!(report["materials"][0]["after"]["verdict"], "ok", "{what}");
    assert!(leftovers(dir.path()).is_empty(), "{what}");
}

common::blender::per_blender!(a_name_that_is_not_utf8_reaches_blender_byte_for_byte);

/// Case 4: `--fix-dir` with two inputs of one relative name is refused before Blender
/// starts, naming both (before, the second fixed copy silently replaced the first).
#[test]
fn fix_dir_refuses_two_inputs_of_one_name() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a"), dir.path().join("b"));
    for folder in [&a, &b] {
        fs::create_dir(folder).unwrap();
        fs::write(folder.join("x.blend"), "BLENDER-v405").unwrap();
    }
    let out = common::gloffuse()
        .arg("audit")
        .arg(a.join("x.blend"))
        .arg(b.join("x.blend"))
        .arg("--fix-dir")
        .arg(dir.path().join("out"))
        .args(["--no-provision", "--blender", "/nonexistent/blender"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("--fix-dir"), "{stderr}");
    for named in [a.join("x.blend"), b.join("x.blend")] {
        assert!(stderr.contains(&named.display().to_string()), "{stderr}");
    }
    assert!(
        !stderr.contains("/nonexistent/blender"),
        "refused before Blender: {stderr}"
    );
    assert!(!dir.path().join("out").exists());
}

/// Case 5: an empty file and one from a newer Blender in the folder: each is its own error,
/// and the good file is fixed in place (before, the whole folder was refused with exit 2).
#[test]
fn one_bad_file_does_not_block_the_fixes_of_the_others() {
    let Some(blender) = common::blender::real_blender("4.5") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let cache = tempfile::tempdir().unwrap();
    let good = dir.path().join("good.blend");
    fixable(&blender, &good);
    fs::write(dir.path().join("empty.blend"), "").unwrap();
    // The header of a file saved by a Blender 9.9 that does not exist yet.
    fs::write(dir.path().join("newer.blend"), "BLENDER17-01v0909").unwrap();
    let out = finish(
        audit(
            &blender,
            cache.path(),
            &[dir.path().as_os_str(), "--in-place".as_ref()],
        )
        .spawn()
        .unwrap(),
    );
    assert_eq!(out.status.code(), Some(1), "{}", text(&out));
    let report: Value = serde_json::from_slice(&out.stdout).unwrap();
    let file = |name: &str| {
        report["files"]
            .as_array()
            .unwrap()
            .iter()
            .find(|f| f["file"].as_str().unwrap().ends_with(name))
            .unwrap_or_else(|| panic!("{name} not in the report: {}", text(&out)))
            .clone()
    };
    assert!(file("empty.blend")["error"].is_string(), "{}", text(&out));
    let newer = file("newer.blend")["error"].as_str().unwrap().to_string();
    assert!(newer.contains("9.9"), "{newer}");
    assert_eq!(file("good.blend")["fixed"]["replaced"], 1, "{}", text(&out));
    assert!(dir.path().join("good.blend1").is_file());
    assert_eq!(fs::read(dir.path().join("empty.blend")).unwrap(), b"");
}

/// Case 6: `generate --blend` over an existing library whose catalog file cannot be
/// replaced (immutable): the run fails naming the catalog file, and the library is the
/// very file it was (before, the library was replaced and only the catalogs were not).
#[test]
fn a_library_whose_catalogs_cannot_be_replaced_is_left_as_it_was() {
    let Some(blender) = common::blender::real_blender("4.5") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let cache = tempfile::tempdir().unwrap();
    let library = dir.path().join("gloffuse.blend");
    let catalogs = dir.path().join("blender_assets.cats.txt");
    let generate = || {
        let mut cmd = gloffuse("generate", &blender, cache.path());
        cmd.arg("--blend").arg(&library);
        finish(cmd.spawn().unwrap())
    };
    let first = generate();
    assert_eq!(first.status.code(), Some(0), "{}", text(&first));
    let (library_before, catalogs_before) =
        (fs::read(&library).unwrap(), fs::read(&catalogs).unwrap());
    let immutable = |on: bool| {
        let flag = if on { "+i" } else { "-i" };
        let status = Command::new("chattr").arg(flag).arg(&catalogs).status();
        assert!(
            status.is_ok_and(|s| s.success()),
            "chattr {flag} {} failed: this test needs e2fsprogs' chattr on a filesystem \
             with the immutable attribute (and root)",
            catalogs.display()
        );
    };
    immutable(true);
    let second = generate();
    immutable(false);
    assert_eq!(second.status.code(), Some(2), "{}", text(&second));
    assert!(
        String::from_utf8_lossy(&second.stderr).contains("blender_assets.cats.txt"),
        "{}",
        text(&second)
    );
    assert_eq!(
        fs::read(&library).unwrap(),
        library_before,
        "{}",
        text(&second)
    );
    assert_eq!(fs::read(&catalogs).unwrap(), catalogs_before);
    assert_nothing_left(dir.path());
}

/// Holds the writers' lock of `file` as gloffuse takes it (the test stands in for another
/// gloffuse run): an advisory lock on `.NAME.gloffuse-lock` beside the file.
fn hold_lock(file: &Path) -> fs::File {
    let name = file.file_name().unwrap().to_string_lossy();
    let lock = file.with_file_name(format!(".{name}.gloffuse-lock"));
    let handle = fs::OpenOptions::new()
        .create(true)
        .truncate(false)
        .write(true)
        .open(&lock)
        .unwrap();
    handle.try_lock().unwrap();
    handle
}

/// Case 14: a stop while no Blender runs, after one file was already replaced: the second
/// file's lock is held, so gloffuse waits between its Blender runs. SIGTERM then ends it
/// with 143, the message names the file already written, and nothing is left behind: no
/// temporary file beside the files, and no report folder (nor its staging folder) (before, the
/// process ended at once saying "nothing was written").
#[test]
fn a_stop_between_blender_runs_says_what_was_written_and_leaves_nothing() {
    let Some(blender) = common::blender::real_blender("4.5") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let cache = tempfile::tempdir().unwrap();
    let out_dir = tempfile::tempdir().unwrap();
    let (first, second) = (dir.path().join("a.blend"), dir.path().join("b.blend"));
    fixable(&blender, &first);
    fixable(&blender, &second);
    let second_before = fs::read(&second).unwrap();
    let held = hold_lock(&second);
    let report = out_dir.path().join("report");
    let mut cmd = audit(
        &blender,
        cache.path(),
        &[dir.path().as_os_str(), "--in-place".as_ref()],
    );
    cmd.arg("--report").arg(&report);
    let child = cmd.spawn().unwrap();
    // Waiting for b.blend's lock: a.blend was replaced (its .blend1 is there).
    let deadline = Instant::now() + Duration::from_secs(120);
    while !dir.path().join("a.blend1").exists() {
        assert!(Instant::now() < deadline, "a.blend was never fixed");
        std::thread::sleep(Duration::from_millis(50));
    }
    std::thread::sleep(Duration::from_millis(500));
    // SAFETY: kill only signals the child spawned above.
    unsafe { libc::kill(child.id() as libc::pid_t, libc::SIGTERM) };
    let out = finish(child);
    drop(held);
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(out.status.code(), Some(143), "{}", text(&out));
    assert!(stderr.contains("interrupted"), "{stderr}");
    assert!(
        stderr.contains(&first.display().to_string()) && !stderr.contains("nothing was written"),
        "the message names what was written: {stderr}"
    );
    assert_eq!(fs::read(&second).unwrap(), second_before);
    let left: Vec<String> = leftovers(dir.path())
        .into_iter()
        .filter(|n| n != ".b.blend.gloffuse-lock")
        .collect();
    assert!(left.is_empty(), "{left:?}");
    let left_of_report: Vec<OsString> = fs::read_dir(out_dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert!(
        left_of_report.is_empty(),
        "the report folder this run made, or its staging, is left: {left_of_report:?}"
    );
}

/// The lock files are what the test above holds: the name gloffuse's own lock uses.
#[test]
fn the_lock_the_tests_hold_is_the_one_gloffuse_takes() {
    let file = PathBuf::from("/some/folder/b.blend");
    assert_eq!(
        gloffuse::file_lock::lock_path(&file),
        PathBuf::from("/some/folder/.b.blend.gloffuse-lock")
    );
}
