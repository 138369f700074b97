//! Outputs the user points at are written without being destroyed (`crates/gloffuse/src/output.rs`): a
//! symbolic link is written through to its target and stays a link; a FIFO, a character
//! device or `/dev/stdout` is streamed to; `-` is standard output (and the summary moves to
//! stderr); a regular file is replaced atomically; and no output makes a missing folder.
//!
//! Tier: blender (needs the Blenders and tools `scripts/test.sh` installs).

mod common;

use std::ffi::CString;
use std::fs;
use std::io::Read;
use std::os::unix::ffi::OsStrExt;
use std::os::unix::fs::{FileTypeExt, symlink};
use std::path::Path;

fn mkfifo(path: &Path) {
    let c = CString::new(path.as_os_str().as_bytes()).unwrap();
    // SAFETY: mkfifo reads the NUL-terminated path and touches nothing else.
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o644) }, 0);
}

fn is_link(path: &Path) -> bool {
    fs::symlink_metadata(path).unwrap().file_type().is_symlink()
}

const TINY_LUT: [&str; 4] = ["lut", "--size", "4", "--bits"];

#[test]
fn a_symbolic_link_is_written_through_and_stays_a_link() {
    let dir = tempfile::tempdir().unwrap();
    let real = dir.path().join("real");
    fs::create_dir(&real).unwrap();
    let target = real.join("table.csv");
    fs::write(&target, "old").unwrap();
    let link = dir.path().join("table link.csv");
    symlink(&target, &link).unwrap();
    common::gloffuse()
        .args(["albedo", "-d", "ggx", "--grid", "3", "--table"])
        .arg(&link)
        .assert()
        .success();
    assert!(is_link(&link), "the link was replaced");
    let text = fs::read_to_string(&target).unwrap();
    assert!(
        text.starts_with("roughness,mu,albedo,average_albedo\n"),
        "{text}"
    );
    // A dangling link: the file it names is made, the link kept.
    let later = real.join("later.exr");
    let dangling = dir.path().join("dangling.exr");
    symlink("real/later.exr", &dangling).unwrap();
    common::gloffuse()
        .args(TINY_LUT)
        .args(["32", "--out"])
        .arg(&dangling)
        .assert()
        .success();
    assert!(is_link(&dangling));
    assert!(exr::prelude::read_first_flat_layer_from_file(&later).is_ok());
    let left: Vec<_> = fs::read_dir(&real)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(left.len(), 2, "no temporary file left: {left:?}");
}

#[test]
fn a_fifo_is_streamed_to_and_stays_a_fifo() {
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("pipe.csv");
    mkfifo(&fifo);
    let reader = {
        let fifo = fifo.clone();
        std::thread::spawn(move || {
            let mut text = String::new();
            fs::File::open(&fifo)
                .unwrap()
                .read_to_string(&mut text)
                .unwrap();
            text
        })
    };
    common::gloffuse()
        .args(["albedo", "-d", "beckmann", "--grid", "3", "--table"])
        .arg(&fifo)
        .timeout(std::time::Duration::from_secs(60))
        .assert()
        .success();
    let text = reader.join().unwrap();
    assert_eq!(text.lines().count(), 1 + 9, "{text}");
    assert!(fs::metadata(&fifo).unwrap().file_type().is_fifo());
    assert_eq!(
        fs::read_dir(dir.path()).unwrap().count(),
        1,
        "nothing beside the FIFO"
    );
}

#[test]
fn dash_and_dev_stdout_write_to_standard_output() {
    for out in ["-", "/dev/stdout"] {
        let run = common::gloffuse()
            .args(TINY_LUT)
            .args(["16", "--format", "dds", "--out", out])
            .assert()
            .success();
        let o = run.get_output();
        assert!(
            o.stdout.starts_with(b"DDS "),
            "{out}: {:?}",
            &o.stdout[..8.min(o.stdout.len())]
        );
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert!(
            stderr.contains("split-sum 4×4 dds"),
            "{out}: the summary goes to stderr: {stderr}"
        );
    }
    assert!(
        is_link(Path::new("/dev/stdout")),
        "/dev/stdout is still a link"
    );
    // A coefficients file to stdout is the whole, valid file; the fit summary is on stderr.
    let run = common::gloffuse()
        .args([
            "fit", "-d", "ggx", "--point", "0.5:85", "--point", "1:59", "--out", "-",
        ])
        .assert()
        .success();
    let o = run.get_output();
    let file: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(file["format"], "gloffuse-coefficients");
    assert!(String::from_utf8_lossy(&o.stderr).contains("f(r) = 38 r^3"));
}

#[test]
fn a_character_device_is_written_in_place() {
    common::gloffuse()
        .args(TINY_LUT)
        .args(["16", "--out", "/dev/null", "--format", "exr"])
        .assert()
        .success();
    let meta = fs::metadata("/dev/null").unwrap();
    assert!(
        meta.file_type().is_char_device(),
        "/dev/null is still a device"
    );
}

#[test]
fn no_output_makes_a_missing_folder() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("missing");
    let cases: [(&[&str], std::path::PathBuf); 3] = [
        (&["lut", "--out"], missing.join("t.exr")),
        (&["generate", "--script"], missing.join("g.py")),
        (
            &["verify", "--no-provision", "--report"],
            missing.join("report"),
        ),
    ];
    for (args, path) in cases {
        common::gloffuse()
            .args(args)
            .arg(&path)
            .env("GLOFFUSE_BLENDER", "/nonexistent/blender")
            .assert()
            .code(2)
            .stderr(predicates::str::contains("does not exist"));
        assert!(!missing.exists(), "{args:?} made {}", missing.display());
    }
}

/// `generate --blend` through a link, with real Blender: the .blend lands at the target,
/// the link stays.
#[test]
fn a_blend_through_a_link() {
    let Some(blender) = common::blender::real_blender("4.5") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    fs::create_dir(dir.path().join("lib")).unwrap();
    let link = dir.path().join("gloffuse.blend");
    symlink("lib/real.blend", &link).unwrap();
    common::gloffuse()
        .args(["generate", "--no-provision", "--blend"])
        .arg(&link)
        .arg("--blender")
        .arg(&blender)
        .assert()
        .success();
    assert!(is_link(&link));
    let bytes = fs::read(dir.path().join("lib/real.blend")).unwrap();
    assert!(bytes.starts_with(b"BLENDER"), "a .blend at the target");
}
