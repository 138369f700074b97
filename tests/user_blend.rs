//! `generate --into` changes a user's own .blend and nothing else about it, in real Blender:
//! a newer file is not downgraded, the file keeps its mode, its compression and its
//! relative paths (through a symbolic link too), and a failing run leaves the file and its
//! earlier `.blend1` byte for byte as they were, with no temporary file beside them.
//!
//! Tier: blender (needs the Blenders and tools `scripts/test.sh` installs).

mod common;

use std::os::unix::fs::PermissionsExt;
use std::path::{Path, PathBuf};

use serde_json::Value;

use common::user_file::{inspect, listing, make};

/// `gloffuse generate --coefficients seed --into FILE --blender B` with `extra` arguments.
fn into(blender: &Path, file: &Path, extra: &[&str]) -> assert_cmd::assert::Assert {
    common::gloffuse()
        .args(["generate", "--coefficients", "seed", "--into"])
        .arg(file)
        .arg("--blender")
        .arg(blender)
        .arg("--no-provision")
        .args(extra)
        .assert()
}

fn stderr_of(assert: &assert_cmd::assert::Assert) -> String {
    String::from_utf8_lossy(&assert.get_output().stderr).into_owned()
}

#[test]
fn a_file_from_a_newer_blender_is_refused_unless_a_downgrade_is_allowed() {
    let (Some(old), Some(new)) = (
        common::blender::real_blender("4.5"),
        common::blender::real_blender("5.0"),
    ) else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    for compress in [false, true] {
        let file = dir.path().join(format!("from-5.0-{compress}.blend"));
        make(&new, &file, if compress { &["--compress"] } else { &[] });
        let before = std::fs::read(&file).unwrap();
        let refused = into(&old, &file, &[]).code(2);
        let message = stderr_of(&refused);
        for expected in [
            "saved by Blender 5.0",
            "Blender 4.5 or older",
            "--blender",
            "--allow-downgrade",
        ] {
            assert!(message.contains(expected), "{expected:?} in:\n{message}");
        }
        assert_eq!(
            std::fs::read(&file).unwrap(),
            before,
            "the file is untouched"
        );
    }
    assert_eq!(
        listing(dir.path()),
        ["from-5.0-false.blend", "from-5.0-true.blend"],
        "nothing was written beside the files"
    );
    // The same Blender (or a newer one) opens it without a word; an older one when allowed.
    let file = dir.path().join("from-5.0-false.blend");
    into(&new, &file, &[]).success();
    into(&old, &file, &["--allow-downgrade"]).success();
    let saved = inspect(&old, &file);
    assert_eq!(
        (&saved["version"][0], &saved["version"][1]),
        (&Value::from(4), &Value::from(5)),
        "saved by 4.5 when allowed: {saved}"
    );
}

#[test]
fn the_file_keeps_its_mode_and_its_compression() {
    let Some(blender) = common::blender::real_blender("4.5") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    for mode in [0o600, 0o444, 0o640] {
        let file = dir.path().join(format!("mode-{mode:o}.blend"));
        make(&blender, &file, &[]);
        std::fs::set_permissions(&file, std::fs::Permissions::from_mode(mode)).unwrap();
        into(&blender, &file, &[]).success();
        let kept = std::fs::metadata(&file).unwrap().permissions().mode() & 0o7777;
        assert_eq!(kept, mode, "{}: mode {kept:o}", file.display());
        let backup = PathBuf::from(format!("{}1", file.display()));
        let backup_mode = std::fs::metadata(&backup).unwrap().permissions().mode() & 0o7777;
        assert_eq!(backup_mode, mode, "the .blend1 keeps the mode too");
    }
    let plain = dir.path().join("plain.blend");
    let packed = dir.path().join("packed.blend");
    make(&blender, &plain, &[]);
    make(&blender, &packed, &["--compress"]);
    into(&blender, &plain, &[]).success();
    into(&blender, &packed, &[]).success();
    let head = |p: &Path| std::fs::read(p).unwrap()[..7].to_vec();
    assert_eq!(
        head(&plain),
        b"BLENDER",
        "an uncompressed file stays uncompressed"
    );
    assert_eq!(
        head(&packed)[..4],
        [0x28, 0xb5, 0x2f, 0xfd],
        "a zstd file stays zstd"
    );
    let (plain_len, packed_len) = (
        std::fs::metadata(&plain).unwrap().len(),
        std::fs::metadata(&packed).unwrap().len(),
    );
    assert!(
        packed_len * 3 < plain_len,
        "compressed {packed_len} B vs uncompressed {plain_len} B with the same groups"
    );
    let groups = inspect(&blender, &packed);
    assert!(
        groups["groups"].get("Gloffuse (GGX)").is_some(),
        "the compressed file holds the groups: {groups}"
    );
}

#[test]
fn a_linked_file_keeps_its_relative_paths_and_its_link() {
    let Some(blender) = common::blender::real_blender("4.5") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let real_dir = dir.path().join("real");
    let link_dir = dir.path().join("elsewhere/deeper");
    std::fs::create_dir_all(&real_dir).unwrap();
    std::fs::create_dir_all(&link_dir).unwrap();
    let real = real_dir.join("scene.blend");
    make(&blender, &real, &["--texture"]);
    std::fs::write(real_dir.join("tex.png"), b"not read by this test").unwrap();
    let link = link_dir.join("scene.blend");
    std::os::unix::fs::symlink("../../real/scene.blend", &link).unwrap();

    into(&blender, &link, &[]).success();
    assert_eq!(
        std::fs::read_link(&link).unwrap(),
        Path::new("../../real/scene.blend"),
        "the link is still the same link"
    );
    assert_eq!(
        listing(&link_dir),
        ["scene.blend"],
        "nothing beside the link"
    );
    assert_eq!(
        listing(&real_dir),
        ["scene.blend", "scene.blend1", "tex.png"]
    );
    let saved = inspect(&blender, &real);
    assert_eq!(
        saved["images"]["tex"], "//tex.png",
        "the relative path is the one the user set: {saved}"
    );
    assert!(
        saved["groups"].get("Gloffuse (GGX)").is_some(),
        "the groups went into the real file: {saved}"
    );
}

/// Sets or clears the immutable attribute (root on ext4 and most Linux filesystems).
fn chattr(flag: &str, path: &Path) {
    let status = std::process::Command::new("chattr")
        .arg(flag)
        .arg(path)
        .status()
        .expect("chattr runs");
    assert!(
        status.success(),
        "chattr {flag} {} (this test needs root on a filesystem with the immutable attribute)",
        path.display()
    );
}

#[test]
fn a_failing_run_leaves_the_file_and_its_backup_as_they_were() {
    let Some(blender) = common::blender::real_blender("4.5") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("scene.blend");
    let backup = dir.path().join("scene.blend1");
    make(&blender, &file, &[]);
    std::fs::write(&backup, b"the user's own earlier version").unwrap();
    let (file_before, backup_before) = (
        std::fs::read(&file).unwrap(),
        std::fs::read(&backup).unwrap(),
    );
    let unchanged = |case: &str| {
        assert_eq!(
            std::fs::read(&file).unwrap(),
            file_before,
            "{case}: the file"
        );
        assert_eq!(
            std::fs::read(&backup).unwrap(),
            backup_before,
            "{case}: the .blend1"
        );
        assert_eq!(
            listing(dir.path()),
            ["scene.blend", "scene.blend1"],
            "{case}: nothing left beside"
        );
    };

    // A full disk: Blender cannot write the new file (a file-size limit stands in for it).
    let limited = std::process::Command::new("bash")
        .arg("-c")
        .arg("ulimit -f 200; exec \"$@\"")
        .arg("bash")
        .arg(assert_cmd::cargo::cargo_bin("gloffuse"))
        .args(["generate", "--coefficients", "seed", "--into"])
        .arg(&file)
        .arg("--blender")
        .arg(&blender)
        .arg("--no-provision")
        .output()
        .unwrap();
    assert_eq!(
        limited.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&limited.stderr)
    );
    unchanged("a full disk");

    // An immutable file: the rename over it fails after Blender saved.
    chattr("+i", &file);
    let refused = into(&blender, &file, &[]);
    chattr("-i", &file);
    let message = stderr_of(&refused.code(2));
    assert!(
        message.contains("is unchanged"),
        "says what was kept:\n{message}"
    );
    unchanged("an immutable file");

    // The last step fails (a folder holds the .blend1 name): the file is updated and its
    // previous version is kept under the name the message gives.
    std::fs::remove_file(&backup).unwrap();
    std::fs::create_dir(&backup).unwrap();
    std::fs::write(backup.join("something"), b"x").unwrap();
    let failed = into(&blender, &file, &[]).code(2);
    let message = stderr_of(&failed);
    let kept = message
        .split("it is kept as ")
        .nth(1)
        .map(|rest| PathBuf::from(rest.split_whitespace().next().unwrap()))
        .unwrap_or_else(|| panic!("names where the previous version is:\n{message}"));
    assert_eq!(
        std::fs::read(&kept).unwrap(),
        file_before,
        "the previous version is whole"
    );
    assert_ne!(
        std::fs::read(&file).unwrap(),
        file_before,
        "the file was updated"
    );
}
