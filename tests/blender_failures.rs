//! Blenders that misbehave, driven through the real `gloffuse` binary: `generate --blend`
//! and `verify` each meet a stand-in `blender` (a shell script in a temporary directory)
//! that answers the version probe like Blender 4.5 and then, asked to run a script,
//! (a) crashes, (b) hangs with a child process, (c) raises a Python traceback, (d) exits 0
//! with a result line but writes nothing, (e) writes a truncated file, or that (f) reports
//! Blender 2.79.
//!
//! Every one must end in exit code 2 (docs/GUIDE.md: "Blender could not be found, crashed, timed
//! out or wrote nothing"), with a message that says what went wrong and, for a run, names
//! its log (kept with the script in the run directory under `$XDG_CACHE_HOME/gloffuse/runs`,
//! a temporary directory here) and the command to rerun it; no panic; and no output: neither
//! `OUT.blend`, nor the `.gloffuse-*.blend` it is saved as first, nor `--script`'s file, nor
//! `--report`'s directory.
//!
//! Tier: fast (no Blender; `scripts/test.sh --fast` runs it).

mod common;

use std::fs;
use std::os::unix::fs::PermissionsExt;
use std::path::{Path, PathBuf};
use std::process::Output;
use std::time::{Duration, Instant};

use exr::prelude::{Compression, Encoding, Image, SpecificChannels, Vec2, WritableImage};
use tempfile::TempDir;

/// The stand-in `blender`. The version probe gloffuse runs is
/// `blender -b --factory-startup -noaudio --version` (crates/gloffuse/src/blender/discover.rs): it must exit
/// 0 with a line starting `Blender X.Y`. A run is
/// `blender -b --factory-startup -noaudio --python-exit-code 1 --python SCRIPT -- ARGS`
/// (crates/gloffuse/src/blender/run.rs); the stand-in finds SCRIPT (the run directory is its folder) and
/// generate's `--save OUT`, then does `body`.
fn stand_in(dir: &Path, version_line: &str, body: &str) -> PathBuf {
    fs::create_dir_all(dir).unwrap();
    let path = dir.join("blender");
    let text = format!(
        r#"#!/bin/sh
case "$*" in *--version*) echo '{version_line}'; echo '	build date: 2025-07-15'; exit 0;; esac
script=""; save=""
while [ $# -gt 0 ]; do
  case "$1" in
    --python) script="$2"; shift;;
    --save) save="$2"; shift;;
  esac
  shift
done
rundir=$(dirname "$script")
echo "Blender stand-in: running $script"
{body}
"#
    );
    fs::write(&path, text).unwrap();
    fs::set_permissions(&path, fs::Permissions::from_mode(0o755)).unwrap();
    path
}

fn awkward(prefix: &str) -> TempDir {
    tempfile::Builder::new()
        .prefix(&format!("gloffuse {prefix} Grüße ☀ "))
        .tempdir()
        .unwrap()
}

/// A stand-in, a cache, and a fresh output directory for one misbehaviour.
struct Setup {
    _home: TempDir,
    blender: PathBuf,
    cache: PathBuf,
    out: PathBuf,
    /// Where the stand-in may leave notes (pids, fixtures).
    notes: PathBuf,
}

fn setup(version_line: &str, body: impl FnOnce(&Path) -> String) -> Setup {
    let home = awkward("blender failures");
    let notes = home.path().join("notes");
    let cache = home.path().join("cache");
    let out = home.path().join("out é");
    for d in [&notes, &cache, &out] {
        fs::create_dir(d).unwrap();
    }
    let body = body(&notes);
    let blender = stand_in(&home.path().join("bin"), version_line, &body);
    Setup {
        blender,
        cache,
        out,
        notes,
        _home: home,
    }
}

impl Setup {
    fn gloffuse(&self, args: &[&std::ffi::OsStr]) -> Output {
        common::gloffuse()
            .args(args)
            .arg("--blender")
            .arg(&self.blender)
            .args(["--no-provision", "--timeout", "2"])
            .current_dir(&self.out)
            .env("XDG_CACHE_HOME", &self.cache)
            .env_remove("GLOFFUSE_BLENDER")
            .output()
            .unwrap()
    }

    /// `gloffuse generate --blend OUT.blend --script OUT.py …`
    fn generate(&self) -> Output {
        let blend = self.out.join("library ü.blend");
        let script = self.out.join("library ü.py");
        self.gloffuse(&[
            "generate".as_ref(),
            "--blend".as_ref(),
            blend.as_os_str(),
            "--script".as_ref(),
            script.as_os_str(),
        ])
    }

    /// `gloffuse verify -r 0.5 --report DIR …`
    fn verify(&self) -> Output {
        let report = self.out.join("report ü");
        self.gloffuse(&[
            "verify".as_ref(),
            "-r".as_ref(),
            "0.5".as_ref(),
            "--report".as_ref(),
            report.as_os_str(),
        ])
    }

    /// The run directories Blender runs left under the cache.
    fn runs(&self) -> Vec<PathBuf> {
        match fs::read_dir(self.cache.join("gloffuse/runs")) {
            Ok(d) => d.map(|e| e.unwrap().path()).collect(),
            Err(_) => Vec::new(),
        }
    }
}

/// What a failed command must show: exit code 2, every fragment in stderr, no panic, no
/// output; for a run, its run directory (`job-…`) holds the log that stderr names.
fn check(setup: &Setup, job: &str, out: &Output, fragments: &[&str], ran: bool) -> String {
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    let context = format!("{job}: stderr:\n{stderr}");
    assert_eq!(out.status.code(), Some(2), "{context}");
    assert!(!stderr.contains("panicked"), "{context}");
    for f in fragments {
        assert!(stderr.contains(f), "{job}: stderr lacks {f:?}:\n{stderr}");
    }
    assert!(out.stdout.is_empty(), "{job}: stdout: {:?}", out.stdout);
    let left: Vec<_> = fs::read_dir(&setup.out)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert!(
        left.is_empty(),
        "{job}: left in the output directory: {left:?}"
    );

    let runs: Vec<PathBuf> = setup
        .runs()
        .into_iter()
        .filter(|r| {
            r.file_name()
                .unwrap()
                .to_string_lossy()
                .starts_with(&format!("{job}-"))
        })
        .collect();
    if !ran {
        assert!(runs.is_empty(), "{job}: a run directory was made: {runs:?}");
        return stderr;
    }
    assert_eq!(runs.len(), 1, "{job}: run directories {runs:?}");
    let log = runs[0].join("blender.log");
    let text = fs::read_to_string(&log).unwrap_or_else(|e| panic!("{}: {e}", log.display()));
    assert!(
        text.contains("Blender stand-in: running"),
        "{job}: log:\n{text}"
    );
    assert!(
        stderr.contains(&format!("log: {}", log.display())),
        "{job}: stderr does not name the log {}:\n{stderr}",
        log.display()
    );
    assert!(stderr.contains("command: "), "{context}");
    assert!(
        stderr.contains(&setup.blender.display().to_string()),
        "{job}: the command does not name the stand-in:\n{stderr}"
    );
    stderr
}

#[test]
fn a_crash_is_reported_with_the_signal_and_the_log() {
    let s = setup("Blender 4.5.0", |_| {
        // No core file: this is a test, not a crash to debug.
        "echo 'Fra:1 Mem:12.00M | Rendering'\nulimit -c 0\nkill -SEGV $$".into()
    });
    for (job, out) in [("generate", s.generate()), ("verify", s.verify())] {
        check(
            &s,
            job,
            &out,
            &["Blender was killed by signal 11", "Fra:1 Mem:12.00M"],
            true,
        );
    }
}

/// Processes still alive (not zombies) in process group `pgid`.
fn alive_in_group(pgid: u32) -> Vec<String> {
    let mut found = Vec::new();
    for entry in fs::read_dir("/proc").unwrap().flatten() {
        let Ok(stat) = fs::read_to_string(entry.path().join("stat")) else {
            continue;
        };
        // pid (comm) state ppid pgrp …; comm may hold spaces or parentheses.
        let Some((_, rest)) = stat.rsplit_once(')') else {
            continue;
        };
        let fields: Vec<&str> = rest.split_whitespace().collect();
        let (state, pgrp) = (fields[0], fields[2]);
        if pgrp == pgid.to_string() && state != "Z" && state != "X" {
            found.push(stat.trim().to_string());
        }
    }
    found
}

#[test]
fn a_hang_is_killed_after_the_timeout_with_its_children() {
    let s = setup("Blender 4.5.0", |notes| {
        let notes = notes.display();
        format!(
            "echo $$ > '{notes}/'$(basename \"$rundir\").pid\n\
             sleep 1000 &\n\
             echo $! > '{notes}/'$(basename \"$rundir\").child\n\
             echo 'Fra:1 Mem:12.00M | Synchronizing object'\n\
             wait"
        )
    });
    for job in ["generate", "verify"] {
        let start = Instant::now();
        let out = if job == "generate" {
            s.generate()
        } else {
            s.verify()
        };
        let took = start.elapsed();
        check(
            &s,
            job,
            &out,
            &["Blender timed out after 2 s (--timeout)"],
            true,
        );
        assert!(took >= Duration::from_secs(2), "{job}: {took:?}");
        assert!(took < Duration::from_secs(20), "{job}: {took:?}");
        let run = s
            .runs()
            .into_iter()
            .find(|r| r.file_name().unwrap().to_string_lossy().starts_with(job))
            .unwrap();
        let name = run.file_name().unwrap().to_string_lossy().into_owned();
        let pid = |ext: &str| -> u32 {
            let path = s.notes.join(format!("{name}.{ext}"));
            fs::read_to_string(&path)
                .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
                .trim()
                .parse()
                .unwrap()
        };
        // The stand-in ran in a process group of its own (its pid is the group id); every
        // member, the `sleep 1000` included, must be gone (a zombie waiting for a reaper
        // that never comes, as pid 1 may be here, counts as gone).
        let (group, child) = (pid("pid"), pid("child"));
        let deadline = Instant::now() + Duration::from_secs(5);
        loop {
            let alive = alive_in_group(group);
            if alive.is_empty() {
                break;
            }
            assert!(
                Instant::now() < deadline,
                "{job}: still alive in the stand-in's group {group} (child {child}): {alive:?}"
            );
            std::thread::sleep(Duration::from_millis(50));
        }
    }
}

/// A Blender that hangs at start-up, in its version probe: `--timeout` bounds the probes
/// too (each would otherwise wait up to 60 s, and there are two: as an executable, then as
/// a Python with bpy).
#[test]
fn a_hang_in_the_version_probe_ends_at_the_timeout() {
    let s = setup("Blender 4.5.0", |_| String::new());
    fs::write(&s.blender, "#!/bin/sh\nsleep 1000\n").unwrap();
    for job in ["generate", "verify"] {
        let start = Instant::now();
        let out = if job == "generate" {
            s.generate()
        } else {
            s.verify()
        };
        let took = start.elapsed();
        check(
            &s,
            job,
            &out,
            &["did not answer within 2 s (--timeout)"],
            false,
        );
        assert!(took < Duration::from_secs(10), "{job}: {took:?}");
    }
}

/// Ctrl-C while Blender renders: gloffuse stops Blender (its whole process group), says
/// so, writes no report, and exits 130.
#[test]
fn ctrl_c_stops_blender_and_exits_130() {
    let s = setup("Blender 4.5.0", |notes| {
        let notes = notes.display();
        format!("echo $$ > '{notes}/group'\nsleep 1000 &\nwait")
    });
    let report = s.out.join("report");
    let child = std::process::Command::new(assert_cmd::cargo::cargo_bin("gloffuse"))
        .args(["verify", "-r", "0.5", "--no-provision", "--report"])
        .arg(&report)
        .arg("--blender")
        .arg(&s.blender)
        .current_dir(&s.out)
        .env("XDG_CACHE_HOME", &s.cache)
        .env_remove("GLOFFUSE_BLENDER")
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let group = s.notes.join("group");
    let deadline = Instant::now() + Duration::from_secs(30);
    while !group.exists() {
        assert!(Instant::now() < deadline, "the stand-in never started");
        std::thread::sleep(Duration::from_millis(50));
    }
    std::thread::sleep(Duration::from_millis(300));
    // SAFETY: kill only sends a signal to the child we spawned.
    assert_eq!(
        unsafe { libc::kill(child.id() as libc::pid_t, libc::SIGINT) },
        0
    );
    let start = Instant::now();
    let out = child.wait_with_output().unwrap();
    assert!(
        start.elapsed() < Duration::from_secs(10),
        "{:?}",
        start.elapsed()
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(130), "{stderr}");
    assert!(
        stderr.contains("interrupted: Blender was stopped and nothing was written"),
        "{stderr}"
    );
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert!(!report.exists(), "no report after an interrupt");
    let group: u32 = fs::read_to_string(&group).unwrap().trim().parse().unwrap();
    let deadline = Instant::now() + Duration::from_secs(5);
    while !alive_in_group(group).is_empty() {
        assert!(
            Instant::now() < deadline,
            "the stand-in's group outlived the interrupt"
        );
        std::thread::sleep(Duration::from_millis(50));
    }
}

#[test]
fn a_traceback_is_quoted() {
    let s = setup("Blender 4.5.0", |_| {
        r#"cat >&2 <<'EOF'
Traceback (most recent call last):
  File "/tmp/gloffuse-main.py", line 40, in <module>
    main()
  File "/tmp/gloffuse-main.py", line 31, in main
    build_gain_group(tree)
KeyError: 'bpy_prop_collection[key]: key "Roughness" not found'
EOF
echo "Blender quit"
exit 1"#
            .into()
    });
    for (job, out) in [("generate", s.generate()), ("verify", s.verify())] {
        let stderr = check(
            &s,
            job,
            &out,
            &[
                "Blender exited with status 1; its Python script raised:",
                "    Traceback (most recent call last):",
                "line 31, in main",
                "KeyError: 'bpy_prop_collection[key]: key \"Roughness\" not found'",
            ],
            true,
        );
        assert!(!stderr.contains("Blender quit"), "{job}: {stderr}");
    }
}

#[test]
fn success_without_the_output_file_is_an_error() {
    let s = setup("Blender 4.5.0", |_| {
        r#"echo 'GLOFFUSE_RESULT {"blender_version": "4.5.0", "render_seconds": 0.5, "saved": null}'
exit 0"#
            .into()
    });
    let out = s.generate();
    check(
        &s,
        "generate",
        &out,
        &["Blender reported success but wrote no .blend", "is empty"],
        true,
    );
    let out = s.verify();
    let stderr = check(&s, "verify", &out, &["EXR ", "does not exist"], true);
    let run = s.runs().into_iter().find(|r| {
        r.file_name()
            .unwrap()
            .to_string_lossy()
            .starts_with("verify-")
    });
    let exr = run.unwrap().join("sweep.exr");
    assert!(
        stderr.contains(&format!("EXR {} does not exist", exr.display())),
        "{stderr}"
    );
}

/// A small RGBA EXR as Blender writes it (32-bit float, ZIP), cut to half its length.
fn truncated_exr(path: &Path) {
    let channels =
        SpecificChannels::rgba(|p: Vec2<usize>| (p.x() as f32 / 64.0, 0.5f32, 1.0f32, 1.0f32));
    let encoding = Encoding {
        compression: Compression::ZIP16,
        ..Encoding::default()
    };
    Image::from_encoded_channels((64, 64), encoding, channels)
        .write()
        .to_file(path)
        .unwrap();
    let bytes = fs::read(path).unwrap();
    fs::write(path, &bytes[..bytes.len() / 2]).unwrap();
}

#[test]
fn truncated_output_is_an_error() {
    let s = setup("Blender 4.5.0", |notes| {
        let exr = notes.join("half.exr");
        truncated_exr(&exr);
        // generate: the start of an uncompressed .blend header, then nothing (no ENDB
        // block); verify: the half EXR where the furnace script writes its sweep.
        format!(
            r#"if [ -n "$save" ]; then printf 'BLENDER-v405REND\0\0\0\0' > "$save"; fi
cp '{}' "$rundir/sweep.exr"
echo 'GLOFFUSE_RESULT {{"blender_version": "4.5.0", "render_seconds": 0.5}}'
exit 0"#,
            exr.display()
        )
    });
    let out = s.generate();
    check(
        &s,
        "generate",
        &out,
        &["Blender reported success but the .blend it wrote is truncated or corrupt"],
        true,
    );
    let out = s.verify();
    check(
        &s,
        "verify",
        &out,
        &["EXR ", "sweep.exr is truncated or corrupt"],
        true,
    );
}

#[test]
fn blender_2_79_is_refused_before_anything_runs() {
    let s = setup("Blender 2.79 (sub 0)", |notes| {
        format!("touch '{}/ran'\nexit 0", notes.display())
    });
    for (job, out) in [("generate", s.generate()), ("verify", s.verify())] {
        check(
            &s,
            job,
            &out,
            &[
                &format!("{} is Blender 2.79 (sub 0)", s.blender.display()),
                "gloffuse needs Blender 3.0 or later",
            ],
            false,
        );
    }
    assert!(
        !s.notes.join("ran").exists(),
        "a script was run in Blender 2.79"
    );
    assert!(s.runs().is_empty());
}

#[test]
fn stand_in_answers_the_probe_like_blender() {
    // The stand-ins are only meaningful if gloffuse takes them for Blender 4.5: a run that
    // does its job (writes a complete-looking .blend) succeeds.
    let s = setup("Blender 4.5.0", |_| {
        r#"printf 'BLENDER-v405REND\0\0\0\0ENDB\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0' > "$save"
echo 'GLOFFUSE_RESULT {"blender_version": "4.5.0", "groups": [], "saved": "x"}'"#
            .into()
    });
    let out = s.generate();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(
        stderr.contains("using Blender 4.5.0 (executable"),
        "{stderr}"
    );
    let mut left: Vec<_> = fs::read_dir(&s.out)
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    left.sort();
    assert_eq!(
        left,
        ["blender_assets.cats.txt", "library ü.blend", "library ü.py"]
    );
}
