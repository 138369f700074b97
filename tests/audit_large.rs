//! `gloffuse audit` on what a large or awkward library meets, in real Blenders: compressed
//! files of thousands of materials (made by `tests/blender/many_materials.py`, counted by
//! Blender itself), a grid too large for one render, and a fixed copy saved to a full disk.
//!
//! Tier: blender (needs the Blenders and tools `scripts/test.sh` installs).

mod common;

use std::path::{Path, PathBuf};

use serde_json::Value;

use gloffuse::blend_file::{MATERIAL, count_blocks};

/// Materials in the large file: half of them with a twin, 4,200 cells, so that 1,024-pixel
/// cells cannot fit in one 65,536-pixel render (64² = 4,096 cells at most).
const MANY: usize = 2800;

use common::audit_json as audit;

/// `count` materials saved compressed by `blender` as DIR/many.blend, and how many
/// materials Blender lists when it opens the file again.
fn many_materials(blender: &Path, dir: &Path, count: usize) -> (PathBuf, usize) {
    let file = dir.join("many.blend");
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/blender/many_materials.py");
    let count = count.to_string();
    let run = common::blender::run_in_blender(
        blender,
        &script,
        &[
            "--out".as_ref(),
            file.as_os_str(),
            "--count".as_ref(),
            count.as_ref(),
        ],
    );
    assert!(
        run.status.success(),
        "many_materials.py in {}:\n{}",
        blender.display(),
        String::from_utf8_lossy(&run.stderr)
    );
    let listed: Value =
        serde_json::from_slice(&std::fs::read(dir.join("many.json")).unwrap()).unwrap();
    (file, listed["materials"].as_u64().unwrap() as usize)
}

/// Blender writes a compressed file as many zstd frames (one per 256 KiB) and a seek table:
/// gloffuse counts the materials Blender lists, in each Blender.
fn a_compressed_file_is_counted_through_every_frame(label: &'static str, blender: PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let (file, listed) = many_materials(&blender, dir.path(), MANY);
    assert_eq!(listed, MANY, "Blender {label}");
    let bytes = std::fs::read(&file).unwrap();
    assert_eq!(
        bytes[..4],
        [0x28, 0xb5, 0x2f, 0xfd],
        "Blender {label}: zstd"
    );
    assert!(bytes.len() > 256 * 1024, "Blender {label}: several frames");
    assert_eq!(count_blocks(&file, MATERIAL), Ok(listed), "Blender {label}");
}

common::blender::per_blender!(a_compressed_file_is_counted_through_every_frame);

/// A compressed file of 2,800 materials in 3.4: every material judged (half lose, half are
/// ok), a picture each; its grid is laid out square (a grid two columns wide, 67,200 px
/// high at 32 px, would be clamped by Blender). `--timeout 30` is far shorter than the job
/// (over a minute on two cores), which finishes since each material adds its share of time.
/// At 1,024-pixel cells the grid cannot fit in one render: the file's error names the limit.
#[test]
fn thousands_of_materials_are_judged_and_a_grid_too_large_is_an_error() {
    let Some(blender) = common::blender::real_blender("3.4") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let (file, listed) = many_materials(&blender, dir.path(), MANY);
    let report_dir = dir.path().join("report");
    let (code, report, stderr) = audit(
        &blender,
        &[
            file.as_os_str(),
            "--resolution".as_ref(),
            "32".as_ref(),
            "--spp".as_ref(),
            "2".as_ref(),
            "--timeout".as_ref(),
            "30".as_ref(),
            "--report".as_ref(),
            report_dir.as_os_str(),
        ],
    );
    assert_eq!(code, 1, "half the materials lose\n{stderr}");
    assert!(report["files"][0]["error"].is_null(), "{}", report["files"]);
    let materials = report["materials"].as_array().unwrap();
    assert_eq!(materials.len(), listed);
    for m in materials {
        let name = m["material"].as_str().unwrap();
        let k: usize = name.trim_start_matches("material-").parse().unwrap();
        let expected = if k.is_multiple_of(2) { "loses" } else { "ok" };
        assert_eq!(m["verdict"], expected, "{name}: {}", m["reason"]);
    }
    let pictures = std::fs::read_dir(report_dir.join("materials"))
        .unwrap()
        .count();
    assert_eq!(pictures, listed);

    let (code, report, stderr) = audit(
        &blender,
        &[file.as_os_str(), "--resolution".as_ref(), "1024".as_ref()],
    );
    assert_eq!(code, 1, "{stderr}");
    let error = report["files"][0]["error"].as_str().unwrap_or_default();
    assert!(
        error.contains("2800 spheres of 1024 px") && error.contains("at most 256 spheres fit"),
        "{error}\n{stderr}"
    );
}

/// A tmpfs of `size` mounted on `dir` (unmounted on drop); `None`, recorded as a skip, where
/// mounting is not allowed (not root, or a container without the capability).
struct Tmpfs(PathBuf);

impl Tmpfs {
    fn mount(dir: &Path, size: &str) -> Option<Tmpfs> {
        let out = std::process::Command::new("mount")
            .args(["-t", "tmpfs", "-o", &format!("size={size}"), "tmpfs"])
            .arg(dir)
            .output();
        match out {
            Ok(out) if out.status.success() => Some(Tmpfs(dir.to_path_buf())),
            Ok(out) => {
                common::record_skip(&format!(
                    "cannot mount a tmpfs on {} ({})",
                    dir.display(),
                    String::from_utf8_lossy(&out.stderr).trim()
                ));
                None
            }
            Err(e) => {
                common::record_skip(&format!("cannot run mount ({e})"));
                None
            }
        }
    }
}

impl Drop for Tmpfs {
    fn drop(&mut self) {
        let _ = std::process::Command::new("umount").arg(&self.0).status();
    }
}

/// A fixed copy that does not fit on its disk: the file's error says the disk is full and
/// names the destination, in each Blender (Blender itself says "Error: Success" or "No such
/// file or directory").
fn a_full_disk_is_named_when_a_fix_cannot_be_saved(label: &'static str, blender: PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let full = dir.path().join("full");
    std::fs::create_dir(&full).unwrap();
    let Some(_mounted) = Tmpfs::mount(&full, "256k") else {
        return;
    };
    // Leave a few pages free: room for the temporary file's name, not for a .blend.
    std::fs::write(full.join("filler"), vec![0u8; 240 * 1024]).unwrap();
    let library = tempfile::tempdir().unwrap();
    common::audit_library::make_library(&blender, library.path(), None);
    let out = full.join("fixed.blend");
    let (_, report, stderr) = audit(
        &blender,
        &[
            library.path().join("rules.blend").as_os_str(),
            "--no-render".as_ref(),
            "--fix".as_ref(),
            out.as_os_str(),
        ],
    );
    let error = report["files"][0]["error"].as_str().unwrap_or_default();
    assert!(
        error.contains("no space left on the device") && error.contains(&*full.to_string_lossy()),
        "Blender {label}: {error}\n{stderr}"
    );
    assert!(!out.exists(), "Blender {label}");
}

common::blender::per_blender!(a_full_disk_is_named_when_a_fix_cannot_be_saved);
