//! Helpers shared by the integration tests, one module per job: independent oracles
//! (`oracle`), real Blenders (`blender`), a user's own .blend (`user_file`), the audit's
//! library of user materials and its expectations (`audit_library`), the binary itself
//! ([`gloffuse`]), and skipping a test whose install is missing ([`skip`]).
#![allow(dead_code)]

pub mod audit_library;
pub mod blender;
pub mod oracle;
pub mod user_file;

/// The generate parameters of the `seed` preset in roughness mode, both masking families:
/// the document the golden file and the contract's checks start from.
pub fn seed_params() -> gloffuse::generate::GenerateParams {
    use gloffuse::generate::{ColorModel, Curves, GenerateParams, Mode};
    let seed = gloffuse::fit::Coefficients::load("seed").unwrap();
    let curves = Curves::Pinned {
        coefficients: &seed,
        name: "seed",
    };
    let masking = &gloffuse::measure::Masking::ALL;
    GenerateParams::new(curves, masking, &[Mode::Roughness], ColorModel::Exact).unwrap()
}

/// The `gloffuse` binary under test.
pub fn gloffuse() -> assert_cmd::Command {
    assert_cmd::Command::cargo_bin("gloffuse").expect("the gloffuse binary is built")
}

/// `gloffuse verify --json --no-provision ARGS --blender BLENDER`: its exit code and the
/// JSON report (null if stdout holds none).
pub fn verify_json(blender: &std::path::Path, args: &[&str]) -> (i32, serde_json::Value) {
    let out = gloffuse()
        .args(["verify", "--json", "--no-provision"])
        .args(args)
        .arg("--blender")
        .arg(blender)
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        serde_json::from_slice(&out.stdout).unwrap_or(serde_json::Value::Null),
    )
}

/// `gloffuse audit --json --no-provision ARGS --blender BLENDER`: its exit code, the JSON
/// report (null if stdout holds none) and stderr.
pub fn audit_json(
    blender: &std::path::Path,
    args: &[&std::ffi::OsStr],
) -> (i32, serde_json::Value, String) {
    let out = gloffuse()
        .args(["audit", "--json", "--no-provision"])
        .args(args)
        .arg("--blender")
        .arg(blender)
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        serde_json::from_slice(&out.stdout).unwrap_or(serde_json::Value::Null),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// The material `name` of an audit's JSON report (panics, naming it, if there is none).
pub fn audit_material<'a>(report: &'a serde_json::Value, name: &str) -> &'a serde_json::Value {
    report["materials"]
        .as_array()
        .unwrap()
        .iter()
        .find(|m| m["material"] == name)
        .unwrap_or_else(|| panic!("no material {name} in {report}"))
}

/// A headless browser for the report page: `$GLOFFUSE_TEST_CHROMIUM`, else Debian's
/// `/usr/bin/chromium` (which `scripts/test.sh` installs). A missing one fails the test
/// unless `GLOFFUSE_SKIP_BROWSER_TESTS=1` ([`skip`]).
pub fn browser() -> Option<std::path::PathBuf> {
    let path = std::env::var_os("GLOFFUSE_TEST_CHROMIUM")
        .map_or_else(|| std::path::PathBuf::from("/usr/bin/chromium"), Into::into);
    if path.exists() {
        return Some(path);
    }
    let why = format!(
        "{} not found (set GLOFFUSE_TEST_CHROMIUM, or run scripts/test.sh)",
        path.display()
    );
    skip("GLOFFUSE_SKIP_BROWSER_TESTS", &why);
    None
}

/// Names the file `scripts/test.sh` collects the skips in, one line each, to list them in its
/// summary (a skipped test passes as `ok`, so cargo's own summary cannot tell).
pub const SKIPS_FILE_VAR: &str = "GLOFFUSE_TEST_SKIPS";

/// The running test gives up because `why` (something `scripts/test.sh` installs is
/// missing): allowed only when `skip_var` is `1`, else the test fails saying so.
pub fn skip(skip_var: &str, why: &str) {
    let asked = std::env::var_os(skip_var).is_some_and(|v| v == "1");
    assert!(asked, "{why}; set {skip_var}=1 to skip");
    record_skip(&format!("{why} ({skip_var}=1)"));
}

/// The running test gives up because of `why`: said on stderr, and `TEST: why` appended to
/// `$GLOFFUSE_TEST_SKIPS` when set.
pub fn record_skip(why: &str) {
    eprintln!("skipped: {why}");
    let Some(file) = std::env::var_os(SKIPS_FILE_VAR) else {
        return;
    };
    // libtest runs each test in a thread named after it.
    let thread = std::thread::current();
    let test = thread.name().unwrap_or("?");
    let line = format!("{}::{test}: {why}\n", env!("CARGO_CRATE_NAME"));
    // One short write in append mode: the lines of parallel tests do not mix.
    let mut skips = std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(&file)
        .unwrap_or_else(|e| panic!("{SKIPS_FILE_VAR}: {e}"));
    std::io::Write::write_all(&mut skips, line.as_bytes()).unwrap();
}

/// `page` as headless `chromium` draws it in a 1200 × 900 window.
pub fn screenshot(chromium: &std::path::Path, page: &std::path::Path) -> image::RgbImage {
    let dir = tempfile::tempdir().unwrap();
    let shot = dir.path().join("page.png");
    let profile = dir.path().join("profile");
    let run = std::process::Command::new(chromium)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--disable-quic",
            "--no-first-run",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--window-size=1200,900",
        ])
        .arg(format!("--user-data-dir={}", profile.display()))
        .arg(format!("--screenshot={}", shot.display()))
        .arg(format!("file://{}", page.display()))
        .output()
        .unwrap();
    assert!(
        shot.exists(),
        "no screenshot: {}",
        String::from_utf8_lossy(&run.stderr)
    );
    image::open(&shot).unwrap().to_rgb8()
}

/// How many of `image`'s pixels are exactly `colour` (`#rrggbb`).
pub fn pixels_of(image: &image::RgbImage, colour: &str) -> usize {
    let want = [1, 3, 5].map(|i| u8::from_str_radix(&colour[i..i + 2], 16).unwrap());
    image.pixels().filter(|p| p.0 == want).count()
}
