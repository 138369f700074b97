//! A cached bpy venv whose Python has moved (issue 20, case 11), as after a CI image
//! update: detected before it runs, and either reinstalled (with a notice) or refused with
//! an error that names the folder and the exact fix. Every test works in a temporary
//! `XDG_CACHE_HOME`; the real caches are never touched.
//!
//! What is not tested here: a successful reinstall, which downloads bpy (~370 MB; ~950 MB installed) from
//! PyPI. The repair is followed up to pip: the broken venv is removed, a fresh venv is made
//! with the real Python 3.11, and pip (offline) fails; the same install path with a
//! reachable PyPI is what `tests/blender_runner.rs` covers for a first install.
//!
//! Tier: blender (needs the Blenders and tools `scripts/test.sh` installs).

mod common;

use std::path::PathBuf;

use common::gloffuse;

/// A temporary cache whose `gloffuse/bpy-4.5` is a venv whose Python has moved, and an
/// empty PATH folder (no `blender`).
struct Broken {
    tmp: tempfile::TempDir,
    venv: PathBuf,
    bin: PathBuf,
}

fn broken(how: &str) -> Broken {
    let tmp = tempfile::tempdir().unwrap();
    let venv = tmp.path().join("cache/gloffuse/bpy-4.5");
    let bin = tmp.path().join("bin");
    std::fs::create_dir_all(venv.join("bin")).unwrap();
    std::fs::create_dir_all(&bin).unwrap();
    let gone = tmp.path().join("old-image/python3.11");
    match how {
        // bin/python points at an interpreter that was removed.
        "dangling" => std::os::unix::fs::symlink(&gone, venv.join("bin/python")).unwrap(),
        // bin/python still runs (a Python of the new image), but pyvenv.cfg's is gone.
        _ => std::os::unix::fs::symlink("/bin/true", venv.join("bin/python")).unwrap(),
    }
    std::fs::write(
        venv.join("pyvenv.cfg"),
        format!(
            "home = {}\nversion = 3.11.2\nexecutable = {}\n",
            gone.parent().unwrap().display(),
            gone.display()
        ),
    )
    .unwrap();
    std::fs::write(venv.join("marker"), "the user's old venv").unwrap();
    Broken { tmp, venv, bin }
}

impl Broken {
    /// `gloffuse generate --blend OUT ARGS` with this cache and PATH; exit code, stderr.
    fn generate(&self, args: &[&str], extra_env: &[(&str, &str)]) -> (i32, String) {
        let mut cmd = gloffuse();
        cmd.args(["generate", "--blend"])
            .arg(self.tmp.path().join("lib.blend"))
            .args(args)
            .env("PATH", &self.bin)
            .env("XDG_CACHE_HOME", self.tmp.path().join("cache"))
            .env_remove("GLOFFUSE_BLENDER");
        for (k, v) in extra_env {
            cmd.env(k, v);
        }
        let out = cmd.output().unwrap();
        (
            out.status.code().unwrap_or(-1),
            String::from_utf8_lossy(&out.stderr).into_owned(),
        )
    }

    fn rm_rf(&self) -> String {
        format!("rm -rf {}", self.venv.display())
    }
}

#[test]
fn a_dangling_venv_python_is_refused_with_the_exact_fix_under_no_provision() {
    for how in ["dangling", "moved-home"] {
        let b = broken(how);
        let (code, stderr) = b.generate(&["--no-provision"], &[]);
        assert_ne!(code, 0, "{how}: {stderr}");
        assert!(
            stderr.contains(&format!(
                "the cached bpy 4.5 at {} is broken",
                b.venv.display()
            )),
            "{how}: {stderr}"
        );
        let why = if how == "dangling" {
            "is a dangling link"
        } else {
            "which no longer exists"
        };
        assert!(stderr.contains(why), "{how}: {stderr}");
        assert!(stderr.contains(&b.rm_rf()), "{how}: {stderr}");
        assert!(stderr.contains("drop --no-provision"), "{how}: {stderr}");
        // Refused, not touched.
        assert!(b.venv.join("marker").exists(), "{how}");
    }
}

#[test]
fn a_repair_without_python_3_11_keeps_the_venv_and_names_the_fix() {
    let b = broken("dangling");
    let (code, stderr) = b.generate(&[], &[]);
    assert_ne!(code, 0, "{stderr}");
    assert!(stderr.contains("needs CPython 3.11"), "{stderr}");
    assert!(stderr.contains(&b.rm_rf()), "{stderr}");
    assert!(
        b.venv.join("marker").exists(),
        "removed with no way to reinstall"
    );
}

/// The real Python 3.11 the suite's bpy 4.5 venv was made with (from its pyvenv.cfg).
fn python_3_11() -> Option<PathBuf> {
    let venv = common::blender::real_blender("4.5")?;
    let cfg = std::fs::read_to_string(venv.parent()?.parent()?.join("pyvenv.cfg")).ok()?;
    let exe = cfg.lines().find_map(|l| l.strip_prefix("executable = "))?;
    Some(PathBuf::from(exe.trim()))
}

#[test]
fn a_broken_venv_is_replaced_by_a_fresh_install() {
    let Some(python) = python_3_11() else {
        return;
    };
    let b = broken("dangling");
    std::os::unix::fs::symlink(&python, b.bin.join("python3.11")).unwrap();
    // pip runs offline, so the install fails at the download; everything before is real.
    let (code, stderr) = b.generate(&[], &[("PIP_NO_INDEX", "1")]);
    assert_ne!(code, 0, "{stderr}");
    assert!(
        stderr.contains(&format!(
            "the cached bpy 4.5 at {} is broken ({} is a dangling link",
            b.venv.display(),
            b.venv.join("bin/python").display()
        )) && stderr.contains("reinstalling it"),
        "no repair notice: {stderr}"
    );
    // The broken venv is gone, and nothing half-made took its name.
    assert!(!b.venv.exists(), "the broken venv is still there");
    let parent = b.venv.parent().unwrap();
    // `generate` shows pip's own output: pip ran, in a fresh venv, and found no bpy offline.
    assert!(stderr.contains("installing bpy 4.5 into"), "{stderr}");
    assert!(
        stderr.contains("No matching distribution found for bpy"),
        "pip did not run: {stderr}"
    );
    // Removed already: no advice to remove it, no command naming the removed temporary
    // venv as one to rerun, and the way to retry.
    assert!(!stderr.contains("rm -rf"), "{stderr}");
    assert!(!stderr.contains("command: "), "{stderr}");
    assert!(
        stderr.contains("run this gloffuse command again"),
        "{stderr}"
    );
    let left: Vec<_> = std::fs::read_dir(parent)
        .unwrap()
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with(".bpy-4.5.partial") || n == "bpy-4.5")
        .collect();
    assert!(left.is_empty(), "left behind: {left:?}");
}
