//! Finding the real Blenders the end-to-end tests run in, and running a script in one.
//!
//! Each Blender comes from an environment variable that `scripts/test.sh` sets, else from
//! where that script installs it. A missing one fails the test, unless
//! `GLOFFUSE_SKIP_BLENDER_TESTS=1` is set: then the test records the skip and passes. A test
//! about one Blender is stamped once per version by [`per_blender`].

use std::path::{Path, PathBuf};

use gloffuse::blender::{Run, probe, run};

/// Set to `1` to skip the tests that need a real Blender (each says what it skipped).
pub const SKIP_VAR: &str = "GLOFFUSE_SKIP_BLENDER_TESTS";

/// Where `scripts/test.sh` installs the bpy wheels: `$GLOFFUSE_TEST_CACHE`, else
/// `${XDG_CACHE_HOME:-$HOME/.cache}/gloffuse/test-blenders`.
fn test_cache() -> PathBuf {
    if let Some(dir) = std::env::var_os("GLOFFUSE_TEST_CACHE") {
        return dir.into();
    }
    let cache = std::env::var_os("XDG_CACHE_HOME")
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| Path::new(&h).join(".cache")))
        .unwrap_or_else(|| PathBuf::from("/nonexistent"));
    cache.join("gloffuse").join("test-blenders")
}

/// The real Blenders' labels, oldest first.
pub const LABELS: [&str; 3] = ["3.4", "4.5", "5.0"];

/// The real Blender labelled `label` (`"3.4"`: Debian's binary, `"4.5"`, `"5.0"`: bpy), from
/// its variable, else where `scripts/test.sh` installs it. A missing one fails the test
/// unless skipping was asked for ([`SKIP_VAR`], [`super::skip`]): then `None`.
pub fn real_blender(label: &str) -> Option<PathBuf> {
    let (var, default) = match label {
        "3.4" => (
            "GLOFFUSE_TEST_BLENDER_34",
            PathBuf::from("/usr/bin/blender"),
        ),
        "4.5" => (
            "GLOFFUSE_TEST_BPY_45",
            test_cache().join("bpy-4.5/bin/python"),
        ),
        "5.0" => (
            "GLOFFUSE_TEST_BPY_50",
            test_cache().join("bpy-5.0/bin/python"),
        ),
        other => panic!("no real Blender is labelled {other}"),
    };
    let path = std::env::var_os(var).map_or(default, PathBuf::from);
    if path.exists() {
        return Some(path);
    }
    let why = format!(
        "Blender {label}: {} not found (set {var}, or run scripts/test.sh)",
        path.display()
    );
    super::skip(SKIP_VAR, &why);
    None
}

/// Every real Blender found, as (label, program), under the rules of [`real_blender`]: for
/// the tests that compare the versions, where one missing leaves the others to compare.
/// Every other test runs once per version ([`per_blender`]).
pub fn real_blenders() -> Vec<(&'static str, PathBuf)> {
    LABELS
        .into_iter()
        .filter_map(|label| Some((label, real_blender(label)?)))
        .collect()
}

/// The label of a test stamped by [`per_blender`], from its name.
pub fn label_of(test: &str) -> &'static str {
    match test {
        "in_blender_3_4" => "3.4",
        "in_blender_4_5" => "4.5",
        "in_blender_5_0" => "5.0",
        other => panic!("{other} names no real Blender"),
    }
}

/// `per_blender!(NAME)` stamps one `#[test]` per real Blender for `fn NAME(label: &'static
/// str, blender: PathBuf)`: a module `NAME` holding `in_blender_3_4`, `in_blender_4_5` and
/// `in_blender_5_0`, each calling `NAME` with its Blender (skipped as [`real_blender`]
/// says), so one failing version hides no other. `per_blender!(NAME: in_blender_4_5, …)`
/// stamps only those listed; attributes before `NAME` (`#[ignore]`) go on every test.
#[allow(unused_macros)]
macro_rules! per_blender {
    (@test [$($attr:tt)*] $name:ident $test:ident) => {
        #[test]
        $($attr)*
        fn $test() {
            let label = $crate::common::blender::label_of(stringify!($test));
            if let Some(blender) = $crate::common::blender::real_blender(label) {
                super::$name(label, blender);
            }
        }
    };
    ($(#[$attr:meta])* $name:ident) => {
        $crate::common::blender::per_blender!(
            $(#[$attr])* $name: in_blender_3_4, in_blender_4_5, in_blender_5_0
        );
    };
    ($(#[$attr:meta])* $name:ident: $($test:ident),+) => {
        $crate::common::blender::per_blender!(@tests [$(#[$attr])*] $name: $($test),+);
    };
    (@tests $attrs:tt $name:ident: $($test:ident),+) => {
        mod $name {
            $($crate::common::blender::per_blender!(@test $attrs $name $test);)+
        }
    };
}
#[allow(unused_imports)]
pub(crate) use per_blender;

/// Runs a Python file inside `blender` (an executable or a bpy Python) with script args,
/// with the command line gloffuse itself uses (the library builds it).
pub fn run_in_blender(
    blender: &Path,
    script: &Path,
    args: &[&std::ffi::OsStr],
) -> std::process::Output {
    let blender = probe(blender).expect("a working Blender");
    let argv = run::argv(&Run {
        blender: &blender,
        script,
        args: args.iter().map(|a| a.to_os_string()).collect(),
        timeout: std::time::Duration::from_secs(600),
        cancel: Default::default(),
        log: PathBuf::new(),
    });
    std::process::Command::new(&argv[0])
        .args(&argv[1..])
        .output()
        .expect("Blender starts")
}

/// Runs `tests/blender/<script>` with the cases `request` asks for in the real Blender
/// `label` (the script writes `{"renders": [[R of every pixel, bottom row first], …]}`):
/// each render's `px × px` pixels; none when that Blender is missing and skipping was asked
/// for.
pub fn render_cases(
    label: &str,
    script: &str,
    request: &serde_json::Value,
    px: usize,
) -> Option<Vec<Vec<f64>>> {
    let blender = real_blender(label)?;
    let dir = tempfile::tempdir().unwrap();
    let (request_path, out) = (dir.path().join("cases.json"), dir.path().join("out.json"));
    std::fs::write(&request_path, request.to_string()).unwrap();
    let script = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/blender")
        .join(script);
    let output = run_in_blender(
        &blender,
        &script,
        &[request_path.as_os_str(), out.as_os_str()],
    );
    assert!(
        output.status.success() && out.exists(),
        "Blender {label}: {}\n{}",
        String::from_utf8_lossy(&output.stdout),
        String::from_utf8_lossy(&output.stderr)
    );
    let result: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    let renders: Vec<Vec<f64>> = result["renders"]
        .as_array()
        .unwrap()
        .iter()
        .map(|render| {
            render
                .as_array()
                .unwrap()
                .iter()
                .map(|v| v.as_f64().unwrap())
                .collect()
        })
        .collect();
    assert!(renders.iter().all(|pixels| pixels.len() == px * px));
    Some(renders)
}
