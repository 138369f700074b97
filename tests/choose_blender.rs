//! A Blender chosen per job (issue 20, case 16): with Debian's Blender 3.4 first on PATH,
//! `generate --extension` (which needs 4.2+) passes it over with a notice and uses the bpy
//! 4.5 in the cache, and so does `audit` of a file saved by 4.5 (issue 38), while a 3.4
//! file is audited in 3.4 and a 3.4 the user named audits what it is given, saying so; with `--no-provision` and nothing newer, or a 3.4 the user named, it
//! fails saying exactly that. No error names `--blender` unless the user passed it.
//! Real Blenders only: the test suite's 3.4 and bpy 4.5, the latter linked into a temporary
//! cache where gloffuse's own search finds it.
//!
//! Tier: blender (needs the Blenders and tools `scripts/test.sh` installs).

mod common;

use std::path::{Path, PathBuf};

use common::blender::real_blender;
use common::gloffuse;

/// A temporary `PATH` folder whose `blender` is the real 3.4, and a temporary cache.
struct Setup {
    _tmp: tempfile::TempDir,
    bin: PathBuf,
    cache: PathBuf,
    out: PathBuf,
}

fn setup(blender_34: &Path) -> Setup {
    let tmp = tempfile::tempdir().unwrap();
    let bin = tmp.path().join("bin");
    let cache = tmp.path().join("cache");
    std::fs::create_dir_all(&bin).unwrap();
    std::fs::create_dir_all(cache.join("gloffuse")).unwrap();
    std::os::unix::fs::symlink(blender_34, bin.join("blender")).unwrap();
    Setup {
        out: tmp.path().join("out"),
        _tmp: tmp,
        bin,
        cache,
    }
}

impl Setup {
    /// Puts the suite's bpy 4.5 venv where gloffuse provisions it (`cache/gloffuse/bpy-4.5`).
    fn with_cached_bpy(self, bpy_python: &Path) -> Self {
        let venv = bpy_python.parent().unwrap().parent().unwrap();
        std::os::unix::fs::symlink(venv, self.cache.join("gloffuse/bpy-4.5")).unwrap();
        self
    }

    /// `gloffuse generate --extension OUT/x.zip ARGS` in this PATH and cache: exit code,
    /// stderr.
    fn extension(&self, args: &[&str], env_blender: Option<&Path>) -> (i32, String) {
        let zip = self.out.join("x.zip");
        let zip = zip.to_str().unwrap();
        let args: Vec<&str> = ["generate", "--extension", zip]
            .into_iter()
            .chain(args.iter().copied())
            .collect();
        self.gloffuse(&args, env_blender)
    }

    /// `gloffuse ARGS` in this PATH and cache: exit code, stderr.
    fn gloffuse(&self, args: &[&str], env_blender: Option<&Path>) -> (i32, String) {
        let mut cmd = gloffuse();
        cmd.args(args)
            .env(
                "PATH",
                std::env::join_paths([&self.bin, Path::new("/usr/bin"), Path::new("/bin")])
                    .unwrap(),
            )
            .env("XDG_CACHE_HOME", &self.cache)
            .env_remove("GLOFFUSE_BLENDER");
        if let Some(b) = env_blender {
            cmd.env("GLOFFUSE_BLENDER", b);
        }
        std::fs::create_dir_all(&self.out).unwrap();
        let out = cmd.output().unwrap();
        (
            out.status.code().unwrap_or(-1),
            String::from_utf8_lossy(&out.stderr).into_owned(),
        )
    }
}

#[test]
fn an_old_blender_on_path_is_passed_over_for_the_cached_bpy() {
    let (Some(b34), Some(b45)) = (real_blender("3.4"), real_blender("4.5")) else {
        return;
    };
    let s = setup(&b34).with_cached_bpy(&b45);
    let (code, stderr) = s.extension(&[], None);
    assert_eq!(code, 0, "{stderr}");
    let zip = std::fs::read(s.out.join("x.zip")).unwrap();
    assert_eq!(&zip[..2], b"PK", "not a zip");
    assert!(
        stderr.contains("not using `blender` on PATH")
            && stderr.contains("Blender 3.4")
            && stderr.contains("is older than 4.2, which --extension needs"),
        "no notice about the passed-over 3.4: {stderr}"
    );
    assert!(stderr.contains("using Blender 4.5"), "{stderr}");
    assert!(!stderr.contains("--blender"), "{stderr}");
}

#[test]
fn no_provision_with_only_an_old_blender_says_so_without_naming_blender_flag() {
    let Some(b34) = real_blender("3.4") else {
        return;
    };
    let s = setup(&b34);
    let (code, stderr) = s.extension(&["--no-provision"], None);
    assert_ne!(code, 0, "{stderr}");
    assert!(
        stderr.contains("no Blender 4.2 or later, which --extension needs, was found"),
        "{stderr}"
    );
    assert!(stderr.contains("Blender 3.4"), "{stderr}");
    assert!(
        stderr.contains("--no-provision forbids installing bpy 4.5"),
        "{stderr}"
    );
    assert!(!stderr.contains("--blender"), "{stderr}");
    assert!(!s.out.join("x.zip").exists());
    // Nothing was installed into the cache.
    assert!(!s.cache.join("gloffuse/bpy-4.5").exists());
}

#[test]
fn an_old_blender_the_user_named_is_refused_by_the_name_they_used() {
    let Some(b34) = real_blender("3.4") else {
        return;
    };
    let s = setup(&b34);
    let flag = b34.to_str().unwrap();
    let (code, stderr) = s.extension(&["--blender", flag], None);
    assert_ne!(code, 0, "{stderr}");
    assert!(
        stderr.contains("--blender 'Blender 3.4")
            && stderr.contains("4.2 or later for --extension"),
        "{stderr}"
    );
    let (code, stderr) = s.extension(&[], Some(&b34));
    assert_ne!(code, 0, "{stderr}");
    assert!(
        stderr.contains("GLOFFUSE_BLENDER names Blender 3.4")
            && stderr.contains("unset GLOFFUSE_BLENDER"),
        "{stderr}"
    );
    assert!(!stderr.contains("--blender"), "{stderr}");
    assert!(!s.out.join("x.zip").exists());
}

/// The audit asks for a Blender as new as the newest file: a 4.5 file passes the 3.4 on
/// PATH over for the cached bpy 4.5; a 3.4 file is audited by that 3.4; a 3.4 named with
/// --blender audits the 4.5 file (it crashes on it) and the table says the file is newer.
/// `generate --into` chooses the same way, and a refusal names gloffuse's own bpy.
#[test]
fn the_audit_uses_a_blender_as_new_as_the_file() {
    let (Some(b34), Some(b45)) = (real_blender("3.4"), real_blender("4.5")) else {
        return;
    };
    let s = setup(&b34).with_cached_bpy(&b45);
    std::fs::create_dir_all(&s.out).unwrap();
    let (old, new) = (s.out.join("old.blend"), s.out.join("new.blend"));
    for (blender, file) in [(&b34, &old), (&b45, &new)] {
        let script = format!(
            "import bpy; bpy.ops.wm.read_factory_settings(use_empty=True); \
             bpy.data.materials.new('m'); bpy.data.materials['m'].use_fake_user = True; \
             bpy.ops.wm.save_as_mainfile(filepath={:?})",
            file.to_str().unwrap()
        );
        let made = if blender == &b34 {
            std::process::Command::new(blender)
                .args(["-b", "--factory-startup", "--python-expr", &script])
                .output()
        } else {
            std::process::Command::new(blender)
                .args(["-c", &script])
                .output()
        };
        assert!(file.exists(), "{made:?}");
    }
    let audit = |file: &Path, extra: &[&str]| {
        let mut args = vec!["audit", "--no-render", file.to_str().unwrap()];
        args.extend_from_slice(extra);
        s.gloffuse(&args, None)
    };
    let (_, stderr) = audit(&new, &[]);
    assert!(
        stderr.contains("not using `blender` on PATH")
            && stderr.contains("is older than 4.5")
            && stderr.contains("using Blender 4.5"),
        "{stderr}"
    );
    let (_, stderr) = audit(&old, &[]);
    assert!(stderr.contains("using Blender 3.4"), "{stderr}");
    assert!(!stderr.contains("not using"), "{stderr}");
    let named = b34.to_str().unwrap();
    let mut cmd = gloffuse();
    let out = cmd
        .args(["audit", "--no-render", "--blender", named])
        .arg(&new)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        stdout.contains("saved by Blender 4.5, audited in 3.4.1"),
        "{stdout}"
    );
    // 3.4 crashes on 4.5's meshes (the default cube): the error says so in a sentence, not
    // as Blender's log.
    let cube = s.out.join("cube.blend");
    let script = format!(
        "import bpy; bpy.ops.wm.read_factory_settings(); \
         bpy.ops.wm.save_as_mainfile(filepath={:?})",
        cube.to_str().unwrap()
    );
    let made = std::process::Command::new(&b45)
        .args(["-c", &script])
        .output();
    assert!(cube.exists(), "{made:?}");
    let out = gloffuse()
        .args(["audit", "--no-render", "--blender", named])
        .arg(&cube)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        stdout.contains(
            "Blender 3.4 could not audit this file, saved by the newer Blender 4.5: audit it in \
             Blender 4.5 or later (Blender was killed by signal 11); log: "
        ) && !stdout.contains("the log ends"),
        "{stdout}"
    );

    // `generate --into` saves the file: the 4.5 file is updated by the cached bpy 4.5, not
    // by the 3.4 on PATH; with 3.4 named, the refusal names gloffuse's own bpy 4.5.
    let into = |extra: &[&str]| {
        let mut args = vec!["generate", "--coefficients", "seed", "--into"];
        args.push(new.to_str().unwrap());
        args.extend_from_slice(extra);
        s.gloffuse(&args, None)
    };
    let (code, stderr) = into(&[]);
    assert_eq!(code, 0, "{stderr}");
    assert!(
        stderr.contains("not using `blender` on PATH") && stderr.contains("using Blender 4.5"),
        "{stderr}"
    );
    let (code, stderr) = into(&["--blender", named]);
    assert_eq!(code, 2, "{stderr}");
    assert!(
        stderr.contains("saved by Blender 4.5")
            && stderr.contains("gloffuse's own bpy 4.5 reads it")
            && stderr.contains("--no-provision"),
        "{stderr}"
    );
}
