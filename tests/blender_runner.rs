//! The Blender runner: discovery and headless runs, first against stand-in executables that
//! misbehave on purpose (shell scripts written into a temporary directory), then against the
//! real Blender 3.4 and bpy 4.5 / 5.0.
//!
//! Real Blenders are found as `tests/common/blender.rs` says: a missing one fails the test
//! unless `GLOFFUSE_SKIP_BLENDER_TESTS=1` asks to skip it.
//!
//! Tier: blender (needs the Blenders and tools `scripts/test.sh` installs).

mod common;

use std::ffi::OsString;
use std::fs;
use std::os::unix::fs::PermissionsExt;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use gloffuse::Error;
use gloffuse::blender::InstallerOutput;
use gloffuse::blender::discover::{FindOptions, Step, find_blender, find_blender_in, search_plan};
use gloffuse::blender::environment::{Environment, bpy_venv_dir, cache_dir};
use gloffuse::blender::probe::{Blender, BlenderKind, Source};
use gloffuse::blender::run::{Run, command_line, run_script};
use gloffuse::measure::BlenderVersion;
use gloffuse::progress::Quiet;

// ---------------------------------------------------------------------------------------
// Stand-ins

/// Writes an executable shell script.
fn script(path: &Path, body: &str) -> PathBuf {
    fs::create_dir_all(path.parent().unwrap()).unwrap();
    fs::write(path, format!("#!/bin/sh\n{body}\n")).unwrap();
    fs::set_permissions(path, fs::Permissions::from_mode(0o755)).unwrap();
    path.to_path_buf()
}

/// A stand-in `blender` executable: answers `--version` with `version_line`, and runs
/// `body` for anything else.
fn fake_blender(dir: &Path, version_line: &str, body: &str) -> PathBuf {
    script(
        &dir.join("blender"),
        &format!(
            "case \"$*\" in *--version*) echo '{version_line}'; echo '  build date: never'; exit 0;; esac\n{body}"
        ),
    )
}

/// A stand-in Python with bpy: the real `python3` with a fake `bpy` module on its path.
fn fake_bpy_python(path: &Path, version_string: &str) -> PathBuf {
    let lib = path.parent().unwrap().join("fake_bpy_lib");
    fs::create_dir_all(&lib).unwrap();
    fs::write(
        lib.join("bpy.py"),
        format!("class app:\n    version_string = {version_string:?}\n"),
    )
    .unwrap();
    script(
        path,
        &format!("PYTHONPATH='{}' exec python3 \"$@\"", lib.display()),
    )
}

/// A stand-in Blender 3.6 whose runs do `body`.
fn blender_running(dir: &Path, body: &str) -> Blender {
    let program = fake_blender(dir, "Blender 3.6.0", body);
    find(&program).unwrap()
}

fn find(program: &Path) -> Result<Blender, Error> {
    find_blender(
        &FindOptions {
            explicit: Some(program.to_path_buf()),
            installer_output: InstallerOutput::Log,
            ..FindOptions::default()
        },
        &Quiet,
    )
}

fn run_of<'a>(blender: &'a Blender, script: &'a Path, dir: &Path, timeout: u64) -> Run<'a> {
    Run {
        blender,
        script,
        args: vec!["--spheres".into(), "a b".into(), "it's".into()],
        timeout: Duration::from_secs(timeout),
        cancel: Default::default(),
        log: dir.join("run.log"),
    }
}

fn blender_error(e: Error) -> (String, Option<PathBuf>, Option<String>) {
    match e {
        Error::Blender {
            message,
            log,
            command,
        } => (message.to_string(), log, command),
        other => panic!("expected Error::Blender, got {other:?}"),
    }
}

// ---------------------------------------------------------------------------------------
// Runs that go wrong

#[test]
fn a_traceback_and_exit_1_are_reported_with_log_and_command() {
    let dir = tempfile::tempdir().unwrap();
    let blender = blender_running(
        dir.path(),
        r#"echo "Read blend: factory startup"
cat >&2 <<'EOF'
Traceback (most recent call last):
  File "/tmp/furnace.py", line 12, in <module>
    main()
  File "/tmp/furnace.py", line 9, in main
    1 / 0
ZeroDivisionError: division by zero
EOF
echo "Blender quit"
exit 1"#,
    );
    let script = dir.path().join("furnace.py");
    let run = run_of(&blender, &script, dir.path(), 30);
    let err = run_script(&run).unwrap_err();
    let shown = err.to_string();
    let (message, log, command) = blender_error(err);
    assert!(message.contains("exited with status 1"), "{message}");
    assert!(
        message.contains("ZeroDivisionError: division by zero"),
        "{message}"
    );
    assert!(message.contains("line 9, in main"), "{message}");
    assert!(!message.contains("Blender quit"), "{message}");
    let log = log.unwrap();
    assert_eq!(log, run.log);
    let text = fs::read_to_string(&log).unwrap();
    assert!(text.contains("Read blend") && text.contains("ZeroDivisionError"));
    assert_eq!(command.as_deref(), Some(command_line(&run).as_str()));
    assert!(
        shown.contains(&format!("log: {}", log.display())),
        "{shown}"
    );
    assert!(shown.contains("command: "), "{shown}");
}

#[test]
fn a_cancel_passed_in_stops_the_run_and_only_its_own() {
    let dir = tempfile::tempdir().unwrap();
    let blender = blender_running(dir.path(), "sleep 1000");
    let script = dir.path().join("hang.py");
    let mut run = run_of(&blender, &script, dir.path(), 600);
    let cancel = gloffuse::blender::Cancel::default();
    run.cancel = cancel.clone();
    let other = gloffuse::blender::Cancel::default();
    let start = Instant::now();
    let stopper = std::thread::spawn(move || {
        std::thread::sleep(Duration::from_millis(500));
        // Nothing waits on `other`; the run waits on `cancel`.
        (other.request(), cancel.request())
    });
    let err = run_script(&run).unwrap_err();
    let took = start.elapsed();
    assert_eq!(stopper.join().unwrap(), (false, true));
    assert!(matches!(err, Error::Interrupted { .. }), "{err:?}");
    assert!(took < Duration::from_secs(10), "{took:?}");
}

#[test]
fn a_hang_is_killed_with_its_whole_process_group() {
    let dir = tempfile::tempdir().unwrap();
    let pids = dir.path().display().to_string();
    let blender = blender_running(
        dir.path(),
        &format!(
            "echo $$ > '{pids}/child.pid'\nsleep 1000 &\necho $! > '{pids}/grandchild.pid'\nwait"
        ),
    );
    let script = dir.path().join("hang.py");
    let run = run_of(&blender, &script, dir.path(), 2);
    let start = Instant::now();
    let err = run_script(&run).unwrap_err();
    let took = start.elapsed();
    assert!(took >= Duration::from_secs(2), "{took:?}");
    assert!(took < Duration::from_secs(10), "{took:?}");
    let shown = err.to_string();
    assert!(
        shown.starts_with("Blender timed out after 2 s (timeout); log: "),
        "{shown}"
    );
    // The field is typed, so the CLI can name its flag.
    let typed = err.render(|f| format!("<{f:?}>"));
    assert!(
        typed.starts_with("Blender timed out after 2 s (<Timeout>); log: "),
        "{typed}"
    );
    assert!(shown.contains("; command: "), "{shown}");
    assert!(run.log.exists());

    let pid = |name: &str| -> u32 {
        fs::read_to_string(dir.path().join(name))
            .unwrap()
            .trim()
            .parse()
            .unwrap()
    };
    // The child was reaped by run_script: not even a zombie is left.
    let child = pid("child.pid");
    assert!(
        !Path::new(&format!("/proc/{child}")).exists(),
        "child {child} still exists"
    );
    // The grandchild was killed with the group (it may linger briefly as a zombie until
    // whoever inherited it reaps it).
    let grandchild = pid("grandchild.pid");
    let deadline = Instant::now() + Duration::from_secs(5);
    loop {
        let alive = match fs::read_to_string(format!("/proc/{grandchild}/stat")) {
            Err(_) => false,
            Ok(stat) => {
                let state = stat.rsplit(')').next().unwrap_or("").trim_start();
                !state.starts_with('Z') && !state.starts_with('X')
            }
        };
        if !alive {
            break;
        }
        assert!(
            Instant::now() < deadline,
            "grandchild {grandchild} (sleep 1000) survived the timeout"
        );
        std::thread::sleep(Duration::from_millis(50));
    }
}

#[test]
fn exit_0_without_a_result_line_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let blender = blender_running(
        dir.path(),
        "echo 'Fra:1 Mem:12M'\necho 'Blender quit'\nexit 0",
    );
    let script = dir.path().join("quiet.py");
    let run = run_of(&blender, &script, dir.path(), 30);
    let (message, log, _) = blender_error(run_script(&run).unwrap_err());
    assert!(message.contains("no result line"), "{message}");
    assert!(message.contains("Blender quit"), "{message}");
    assert!(log.unwrap().exists());
}

/// Success is exit 0 and a result line, never words in the log: a traceback Blender printed
/// for a driver or handler, or a folder named like one, does not fail the run; without the
/// result line the traceback is quoted.
#[test]
fn exit_0_with_a_result_succeeds_whatever_the_log_says() {
    let dir = tempfile::tempdir().unwrap();
    let noise = "echo 'Traceback (most recent call last):'\necho '  File \"x\", line 1'\necho 'KeyError: 1'\necho 'Error: Traceback (most recent call last)/x.blend'";
    let blender = blender_running(
        dir.path(),
        &format!("{noise}\necho 'GLOFFUSE_RESULT {{\"ok\": 1}}'"),
    );
    let script = dir.path().join("x.py");
    let out = run_script(&run_of(&blender, &script, dir.path(), 30)).unwrap();
    assert_eq!(out.result, serde_json::json!({"ok": 1}));

    let quiet = tempfile::tempdir().unwrap();
    let blender = blender_running(quiet.path(), noise);
    let (message, _, _) =
        blender_error(run_script(&run_of(&blender, &script, quiet.path(), 30)).unwrap_err());
    assert!(
        message.contains("no result line") && message.contains("KeyError: 1"),
        "{message}"
    );
}

#[test]
fn a_good_run_passes_arguments_and_reads_the_last_result_line() {
    let dir = tempfile::tempdir().unwrap();
    // Echo the arguments after `--` back as JSON; also write bytes that are not UTF-8.
    let blender = blender_running(
        dir.path(),
        r#"while [ "$1" != "--" ]; do shift; done; shift
printf 'GLOFFUSE_RESULT {"first": true}\n'
printf 'bad bytes: \377\376\n' >&2
printf 'GLOFFUSE_RESULT {"args": ["%s", "%s", "%s"], "n": %d}\n' "$1" "$2" "$3" $#
echo "Blender quit""#,
    );
    let script = dir.path().join("ok.py");
    let run = run_of(&blender, &script, dir.path(), 30);
    let out = run_script(&run).unwrap();
    assert_eq!(
        out.result,
        serde_json::json!({"args": ["--spheres", "a b", "it's"], "n": 3})
    );
    assert_eq!(out.log, run.log);
    assert!(out.seconds > 0.0 && out.seconds < 30.0);

    // The command line, pasted into a shell, does the same run.
    let line = command_line(&run);
    assert!(line.contains(" -- --spheres 'a b' 'it'\\''s'"), "{line}");
    let again = std::process::Command::new("sh")
        .arg("-c")
        .arg(&line)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&again.stdout);
    assert!(stdout.contains(r#""n": 3"#), "{stdout}");
}

#[test]
fn a_missing_program_is_a_run_error_not_a_panic() {
    let dir = tempfile::tempdir().unwrap();
    let blender = Blender {
        kind: BlenderKind::PythonModule,
        program: dir.path().join("gone/python"),
        version: BlenderVersion { major: 4, minor: 5 },
        version_string: "4.5.4 LTS".into(),
    };
    let script = dir.path().join("x.py");
    let (message, _, command) =
        blender_error(run_script(&run_of(&blender, &script, dir.path(), 30)).unwrap_err());
    assert!(message.contains("cannot start"), "{message}");
    assert!(command.unwrap().contains("gone/python"));
}

// ---------------------------------------------------------------------------------------
// Discovery with stand-ins

#[test]
fn blender_2_79_is_refused_by_version() {
    let dir = tempfile::tempdir().unwrap();
    let old = fake_blender(dir.path(), "Blender 2.79 (sub 0)", "exit 0");
    let err = find(&old).unwrap_err().to_string();
    assert!(err.contains("2.79"), "{err}");
    assert!(err.contains("3.0 or later"), "{err}");
    assert!(err.contains(&old.display().to_string()), "{err}");
}

#[test]
fn explicit_paths_are_used_or_refused_never_passed_over() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("no/such/blender");
    let err = find(&missing).unwrap_err();
    assert!(matches!(err, Error::BlenderNotFound(_)), "{err:?}");
    let shown = err.render(|f| format!("<{f:?}>"));
    assert!(
        shown.starts_with("<Blender> ") && shown.contains(&missing.display().to_string()),
        "{shown}"
    );

    let impostor = script(&dir.path().join("impostor"), "echo 'I am not Blender'");
    let shown = find(&impostor).unwrap_err().to_string();
    assert!(shown.contains("is neither a working Blender"), "{shown}");
    assert!(shown.contains(&impostor.display().to_string()), "{shown}");
    assert!(shown.contains("I am not Blender"), "{shown}");

    // GLOFFUSE_BLENDER is just as binding, even with a good Blender on PATH.
    let bin = dir.path().join("bin");
    fake_blender(&bin, "Blender 4.2.0 LTS", "exit 0");
    let env = Environment {
        gloffuse_blender: Some(missing.clone().into()),
        path: Some(bin.clone().into()),
        ..Default::default()
    };
    let shown = find_blender_in(&FindOptions::default(), &env, &Quiet)
        .unwrap_err()
        .to_string();
    assert!(shown.contains("GLOFFUSE_BLENDER"), "{shown}");
}

#[test]
fn kinds_are_told_apart_by_probing() {
    let dir = tempfile::tempdir().unwrap();
    let b = find(&fake_blender(dir.path(), "Blender 4.5.4 LTS", "exit 0")).unwrap();
    assert_eq!(b.kind, BlenderKind::Binary);
    assert_eq!(b.version, BlenderVersion { major: 4, minor: 5 });
    assert_eq!(b.version_string, "4.5.4 LTS");

    // A Python with bpy, under a name that does not say "python".
    let py = fake_bpy_python(&dir.path().join("venv/bin/interp"), "5.0.1");
    let b = find(&py).unwrap();
    assert_eq!(b.kind, BlenderKind::PythonModule);
    assert_eq!(b.version, BlenderVersion { major: 5, minor: 0 });
    assert_eq!(b.version_string, "5.0.1");
    assert!(b.describe().contains("bpy module"));

    // A venv directory is looked into for bin/python.
    fake_bpy_python(&dir.path().join("venv2/bin/python"), "4.5.4 LTS");
    let b = find(&dir.path().join("venv2")).unwrap();
    assert_eq!(b.program, dir.path().join("venv2/bin/python"));
}

#[test]
fn cache_dir_follows_xdg_then_home() {
    let env = |xdg: Option<&str>, home: Option<&str>| Environment {
        xdg_cache_home: xdg.map(OsString::from),
        home: home.map(OsString::from),
        ..Default::default()
    };
    assert_eq!(
        cache_dir(&env(Some("/x/cache"), Some("/home/u"))),
        Some(PathBuf::from("/x/cache/gloffuse"))
    );
    assert_eq!(
        cache_dir(&env(None, Some("/home/u"))),
        Some(PathBuf::from("/home/u/.cache/gloffuse"))
    );
    // A relative XDG_CACHE_HOME is invalid and ignored.
    assert_eq!(
        bpy_venv_dir(&env(Some("rel"), Some("/home/u"))),
        Some(PathBuf::from("/home/u/.cache/gloffuse/bpy-4.5"))
    );
    assert_eq!(cache_dir(&env(None, None)), None);
}

#[test]
fn search_order_flag_then_variable_then_path_then_cache_then_provision() {
    let dir = tempfile::tempdir().unwrap();
    let bin = dir.path().join("bin");
    let on_path = fake_blender(&bin, "Blender 4.2.0 LTS", "exit 0");
    let xdg = dir.path().join("xdg");
    let env = Environment {
        gloffuse_blender: Some("/from/env".into()),
        path: Some(bin.clone().into()),
        xdg_cache_home: Some(xdg.clone().into()),
        home: None,
    };
    let explicit = FindOptions {
        explicit: Some("/from/flag".into()),
        ..Default::default()
    };
    let only = |plan: Vec<Step>| -> (Source, PathBuf, bool) {
        assert_eq!(plan.len(), 1, "{plan:?}");
        match plan.into_iter().next().unwrap() {
            Step::Probe {
                source,
                program,
                required,
                ..
            } => (source, program, required),
            other => panic!("{other:?}"),
        }
    };
    assert_eq!(
        only(search_plan(&explicit, &env)),
        (Source::Explicit, "/from/flag".into(), true)
    );
    assert_eq!(
        only(search_plan(&FindOptions::default(), &env)),
        (Source::EnvVar, "/from/env".into(), true)
    );

    let env = Environment {
        gloffuse_blender: Some("".into()), // set but empty counts as unset
        ..env
    };
    let venv = xdg.join("gloffuse/bpy-4.5");
    let plan = search_plan(&FindOptions::default(), &env);
    let probes: Vec<_> = plan
        .iter()
        .filter_map(|s| match s {
            Step::Probe {
                source, required, ..
            } => Some((*source, *required)),
            _ => None,
        })
        .collect();
    assert_eq!(probes, [(Source::SystemPath, false)]);
    assert!(matches!(plan.first(), Some(Step::Absent { .. })));
    assert!(plan.contains(&Step::Probe {
        source: Source::SystemPath,
        program: on_path,
        kind: Some(BlenderKind::Binary),
        required: false,
    }));
    assert_eq!(plan.last(), Some(&Step::Provision { venv: venv.clone() }));

    // A venv without its Python is broken: repaired, not probed.
    fs::create_dir_all(venv.join("bin")).unwrap();
    let plan = search_plan(&FindOptions::default(), &env);
    assert!(
        matches!(plan.last(), Some(Step::Repair { venv: v, .. }) if *v == venv),
        "{plan:?}"
    );
    // Once the venv exists, it is probed instead of provisioned.
    fs::write(venv.join("bin/python"), "").unwrap();
    let plan = search_plan(&FindOptions::default(), &env);
    assert!(!plan.iter().any(|s| matches!(s, Step::Provision { .. })));
    assert_eq!(
        plan.last(),
        Some(&Step::Probe {
            source: Source::Cache,
            program: venv.join("bin/python"),
            kind: Some(BlenderKind::PythonModule),
            required: true,
        })
    );
}

#[test]
fn an_unusable_blender_on_path_gives_way_to_the_cached_bpy() {
    let dir = tempfile::tempdir().unwrap();
    let bin = dir.path().join("bin");
    fake_blender(&bin, "Blender 2.79 (sub 0)", "exit 0");
    let xdg = dir.path().join("xdg");
    let env = Environment {
        path: Some(bin.clone().into()),
        xdg_cache_home: Some(xdg.clone().into()),
        ..Default::default()
    };
    let no_provision = FindOptions::default();
    let shown = find_blender_in(&no_provision, &env, &Quiet)
        .unwrap_err()
        .to_string();
    assert!(shown.contains("2.79"), "{shown}");

    let python = fake_bpy_python(&xdg.join("gloffuse/bpy-4.5/bin/python"), "4.5.4 LTS");
    let b = find_blender_in(&no_provision, &env, &Quiet).unwrap();
    assert_eq!((b.kind, b.program), (BlenderKind::PythonModule, python));
}

#[test]
fn nothing_found_without_provisioning_says_where_and_how() {
    let dir = tempfile::tempdir().unwrap();
    let env = Environment {
        path: Some(dir.path().join("empty-bin").into()),
        home: Some(dir.path().join("home").into()),
        ..Default::default()
    };
    let err = find_blender_in(&FindOptions::default(), &env, &Quiet).unwrap_err();
    assert!(matches!(err, Error::BlenderNotFound(_)), "{err:?}");
    // Fields shown as <Field>: the CLI names them by their flags.
    let shown = err.render(|f| format!("<{f:?}>"));
    for needle in [
        "no Blender found",
        "GLOFFUSE_BLENDER: not set",
        "`blender` on PATH: not found",
        "home/.cache/gloffuse/bpy-4.5: not provisioned",
        "<Blender> PATH",
        "apt-get install blender",
        "drop <NoProvision>",
    ] {
        assert!(shown.contains(needle), "missing {needle:?} in:\n{shown}");
    }
}

/// A stand-in `python3.11` whose `-m venv DIR` makes a venv whose `pip` runs `pip_body`
/// and whose `python -c` imports a fake bpy 4.5.
fn fake_base_python(bin: &Path, pip_body: &str) {
    let lib = bin.join("fake_bpy_lib");
    fs::create_dir_all(&lib).unwrap();
    fs::write(
        lib.join("bpy.py"),
        "class app:\n    version_string = '4.5.9 LTS'\n",
    )
    .unwrap();
    let venv_python = format!(
        "#!/bin/sh\nif [ \"$1\" = -m ] && [ \"$2\" = pip ]; then {pip_body}; fi\nPYTHONPATH='{}' exec python3 \"$@\"\n",
        lib.display()
    );
    script(
        &bin.join("python3.11"),
        &format!(
            "if [ \"$1\" = -c ]; then echo 3.11; exit 0; fi\n\
             mkdir -p \"$3/bin\" && cat > \"$3/bin/python\" <<'EOF'\n{venv_python}EOF\n\
             chmod +x \"$3/bin/python\""
        ),
    );
}

fn provisioning_env(dir: &Path) -> (Environment, PathBuf) {
    // Only the stand-in python3.11 on PATH (and sh/python3 for the stand-ins themselves,
    // which use absolute shebangs and the real PATH of the test process).
    let xdg = dir.join("xdg");
    let env = Environment {
        path: Some(dir.join("bin").into()),
        xdg_cache_home: Some(xdg.clone().into()),
        ..Default::default()
    };
    (env, xdg.join("gloffuse"))
}

fn leftovers(cache: &Path) -> Vec<String> {
    fs::read_dir(cache)
        .map(|d| {
            d.map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
                .filter(|n| {
                    (n.starts_with("bpy-4.5") && !n.ends_with(".log")) || n.contains("partial")
                })
                .collect()
        })
        .unwrap_or_default()
}

#[test]
fn a_failed_install_leaves_nothing_that_looks_valid() {
    let dir = tempfile::tempdir().unwrap();
    fake_base_python(
        &dir.path().join("bin"),
        "echo 'ERROR: No matching distribution found for bpy<4.6,>=4.5' >&2; exit 1",
    );
    let (env, cache) = provisioning_env(dir.path());
    let opts = FindOptions {
        allow_provision: true,
        installer_output: InstallerOutput::Log,
        ..Default::default()
    };
    let (message, log, command) = blender_error(find_blender_in(&opts, &env, &Quiet).unwrap_err());
    assert!(message.contains("installing bpy 4.5"), "{message}");
    assert!(message.contains("No matching distribution"), "{message}");
    // The pip command ran in a venv that is gone: the advice is to rerun gloffuse instead.
    assert_eq!(command, None);
    assert!(
        message.contains("run this gloffuse command again"),
        "{message}"
    );
    assert!(log.unwrap().exists());
    assert_eq!(leftovers(&cache), Vec::<String>::new());
}

#[test]
fn a_successful_install_is_renamed_into_place_and_found_next_time() {
    let dir = tempfile::tempdir().unwrap();
    fake_base_python(
        &dir.path().join("bin"),
        "echo 'Successfully installed bpy-4.5.9'; exit 0",
    );
    let (env, cache) = provisioning_env(dir.path());
    let opts = FindOptions {
        allow_provision: true,
        installer_output: InstallerOutput::Log,
        ..Default::default()
    };
    let b = find_blender_in(&opts, &env, &Quiet).unwrap();
    let python = cache.join("bpy-4.5/bin/python");
    assert_eq!(b.kind, BlenderKind::PythonModule);
    assert_eq!(b.program, python);
    assert_eq!(b.version_string, "4.5.9 LTS");
    assert_eq!(leftovers(&cache), ["bpy-4.5"]);
    let again = find_blender_in(&FindOptions::default(), &env, &Quiet).unwrap();
    assert_eq!(again, b);
}

#[test]
fn without_python_3_11_provisioning_fails_before_touching_the_cache() {
    let dir = tempfile::tempdir().unwrap();
    let (env, cache) = provisioning_env(dir.path());
    let opts = FindOptions {
        allow_provision: true,
        installer_output: InstallerOutput::Log,
        ..Default::default()
    };
    let shown = find_blender_in(&opts, &env, &Quiet)
        .unwrap_err()
        .to_string();
    assert!(shown.contains("CPython 3.11"), "{shown}");
    assert!(!cache.exists());
}

// ---------------------------------------------------------------------------------------
// Real Blenders

const PROBE_SCRIPT: &str = r#"
import json, sys
import bpy
argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:]
if argv and argv[0] == "fail":
    raise RuntimeError("asked to fail")
result = {"version": list(bpy.app.version[:2]), "args": argv,
          "engine": bpy.context.scene.render.engine}
sys.stdout.write("GLOFFUSE_RESULT " + json.dumps(result) + "\n")
sys.stdout.flush()
"#;

fn check_real(label: &str, kind: BlenderKind, major: u32, minor: u32) {
    let Some(program) = common::blender::real_blender(label) else {
        return;
    };
    let blender = find(&program).unwrap();
    assert_eq!(blender.kind, kind);
    assert_eq!(blender.version, BlenderVersion { major, minor });
    assert!(
        blender
            .version_string
            .starts_with(&format!("{major}.{minor}"))
    );

    let dir = tempfile::tempdir().unwrap();
    let script = dir.path().join("probe script.py");
    fs::write(&script, PROBE_SCRIPT).unwrap();
    let mut run = Run {
        blender: &blender,
        script: &script,
        args: vec!["a b".into(), "ünï".into(), "--x=1".into()],
        timeout: Duration::from_secs(120),
        cancel: Default::default(),
        log: dir.path().join("ok.log"),
    };
    let out = run_script(&run).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(
        out.result,
        serde_json::json!({"version": [major, minor], "args": ["a b", "ünï", "--x=1"],
                           "engine": out.result["engine"].clone()})
    );
    assert!(out.log.exists());

    run.args = vec!["fail".into()];
    run.log = dir.path().join("fail.log");
    let (message, log, _) = blender_error(run_script(&run).unwrap_err());
    assert!(message.contains("RuntimeError: asked to fail"), "{message}");
    assert!(message.contains("exited with status 1"), "{message}");
    assert_eq!(log.as_deref(), Some(dir.path().join("fail.log").as_path()));
}

#[test]
fn real_blender_3_4() {
    check_real("3.4", BlenderKind::Binary, 3, 4);
}

#[test]
fn real_bpy_4_5() {
    check_real("4.5", BlenderKind::PythonModule, 4, 5);
}

#[test]
fn real_bpy_5_0() {
    check_real("5.0", BlenderKind::PythonModule, 5, 0);
}

/// Two first runs at once (parallel CI jobs sharing one cache): pip runs once, under a
/// lock; the second waits, says so, and uses the first one's install.
#[test]
fn concurrent_first_runs_install_once() {
    let dir = tempfile::tempdir().unwrap();
    let count = dir.path().join("pip-runs");
    fake_base_python(
        &dir.path().join("bin"),
        &format!(
            "echo run >> '{}'; sleep 2; echo 'Successfully installed bpy-4.5.9'; exit 0",
            count.display()
        ),
    );
    let (env, cache) = provisioning_env(dir.path());
    struct Notices(std::sync::Mutex<Vec<String>>);
    impl gloffuse::progress::Progress for Notices {
        fn notice(&self, message: &str) {
            self.0.lock().unwrap().push(message.to_string());
        }
    }
    let notices = Notices(std::sync::Mutex::new(Vec::new()));
    let found: Vec<Blender> = std::thread::scope(|scope| {
        let runs: Vec<_> = (0..2)
            .map(|i| {
                let (env, notices) = (&env, &notices);
                scope.spawn(move || {
                    std::thread::sleep(Duration::from_millis(300 * i));
                    let opts = FindOptions {
                        allow_provision: true,
                        installer_output: InstallerOutput::Log,
                        ..Default::default()
                    };
                    find_blender_in(&opts, env, notices).unwrap()
                })
            })
            .collect();
        runs.into_iter().map(|r| r.join().unwrap()).collect()
    });
    assert_eq!(found[0], found[1]);
    assert_eq!(
        fs::read_to_string(&count).unwrap().lines().count(),
        1,
        "pip ran once"
    );
    let notices = notices.0.into_inner().unwrap();
    assert!(
        notices.iter().any(|n| n.contains("waiting for it")),
        "{notices:?}"
    );
    assert_eq!(leftovers(&cache), ["bpy-4.5"]);
}

/// An install killed half-way leaves a `.partial` folder, never trusted: the next install
/// removes it and makes a complete venv.
#[test]
fn a_killed_install_is_never_trusted() {
    let dir = tempfile::tempdir().unwrap();
    fake_base_python(
        &dir.path().join("bin"),
        "echo 'Successfully installed bpy-4.5.9'; exit 0",
    );
    let (env, cache) = provisioning_env(dir.path());
    let stale = cache.join(".bpy-4.5.partial-killed");
    fs::create_dir_all(stale.join("bin")).unwrap();
    fs::write(stale.join("bin/python"), "half").unwrap();
    let opts = FindOptions {
        allow_provision: true,
        installer_output: InstallerOutput::Log,
        ..Default::default()
    };
    let b = find_blender_in(&opts, &env, &Quiet).unwrap();
    assert_eq!(b.program, cache.join("bpy-4.5/bin/python"));
    assert!(!stale.exists(), "the killed install's folder is gone");
    assert_eq!(leftovers(&cache), ["bpy-4.5"]);
}
