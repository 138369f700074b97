//! The files `generate` writes into or replaces, in real Blender: a user's own group with a
//! gloffuse name is renamed out of the way, never rebuilt (`--into`); `--blend` replaces
//! only a gloffuse library (or with `--force`), and nothing at all when the catalog file
//! cannot be written; catalogs added during the run are kept; catalog files Blender would
//! ignore are refused. The files are inspected by `tests/blender/user_file.py`, in Blender,
//! independently of gloffuse's package.
//!
//! Tier: blender (needs the Blenders and tools `scripts/test.sh` installs).

mod common;

use std::path::{Path, PathBuf};
use std::process::Stdio;
use std::time::{Duration, Instant};

use serde_json::Value;

use common::user_file::{inspect, listing, make};

const USER_GROUP: &str = "Gloffuse (GGX)";

/// `gloffuse generate --no-provision --blender BLENDER ARGS`.
fn generate(blender: &Path, args: &[&std::ffi::OsStr]) -> assert_cmd::assert::Assert {
    common::gloffuse()
        .arg("generate")
        .args(args)
        .arg("--blender")
        .arg(blender)
        .arg("--no-provision")
        .assert()
}

/// Case 6: in 3.4, 4.5 and 5.0, two `--into` runs on a file whose material uses the
/// user's own `Gloffuse (GGX)`: the first renames it (and says so, in JSON and in text),
/// the second has nothing to rename; the user's group keeps its nodes and its material,
/// and the new group of that name is gloffuse's, tagged with the version.
fn a_users_group_with_a_gloffuse_name_is_renamed_never_rebuilt(
    label: &'static str,
    blender: PathBuf,
) {
    let dir = tempfile::tempdir().unwrap();
    let blend = dir.path().join("chair.blend");
    make(&blender, &blend, &["--group", USER_GROUP]);
    let into = ["--into".as_ref(), blend.as_os_str()];
    let first = generate(&blender, &[&into[..], &["--json".as_ref()]].concat()).success();
    let first: Value = serde_json::from_slice(&first.get_output().stdout).unwrap();
    assert_eq!(
        first["renamed"],
        serde_json::json!([{"group": USER_GROUP, "renamed_to": "Gloffuse (GGX) (yours)"}]),
        "Blender {label}: the first run names the rename"
    );
    // The second run: the text summary, which has nothing to rename.
    let second = generate(&blender, &into).success();
    let text = String::from_utf8_lossy(&second.get_output().stdout).to_string();
    assert!(
        text.contains("groups: ") && !text.contains("renamed:"),
        "{text}"
    );

    let seen = inspect(&blender, &blend);
    let yours = &seen["groups"]["Gloffuse (GGX) (yours)"];
    assert_eq!(
        yours["nodes"],
        serde_json::json!(["Group Output", "user value"]),
        "Blender {label}: the user's group keeps its nodes: {seen}"
    );
    assert!(yours["tag"].is_null(), "Blender {label}: {seen}");
    assert_eq!(
        seen["materials"]["Chair Paint"],
        serde_json::json!(["Gloffuse (GGX) (yours)"]),
        "Blender {label}: the material still uses the user's group"
    );
    let ours = &seen["groups"][USER_GROUP];
    assert_eq!(ours["tag"], env!("CARGO_PKG_VERSION"), "{label}: {seen}");
    assert!(
        ours["nodes"]
            .as_array()
            .unwrap()
            .contains(&"Glossy BSDF".into()),
        "Blender {label}: the new group is gloffuse's: {seen}"
    );
    // Every group gloffuse made carries the tag; only the user's does not.
    for (name, group) in seen["groups"].as_object().unwrap() {
        assert_eq!(group["tag"].is_null(), name.ends_with("(yours)"), "{name}");
    }
}

common::blender::per_blender!(a_users_group_with_a_gloffuse_name_is_renamed_never_rebuilt);

/// The summary in text names the rename too (bpy 4.5).
#[test]
fn the_text_summary_names_a_renamed_group() {
    let Some(blender) = common::blender::real_blender("4.5") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let blend = dir.path().join("chair.blend");
    make(&blender, &blend, &["--group", USER_GROUP]);
    generate(&blender, &["--into".as_ref(), blend.as_os_str()])
        .success()
        .stdout(predicates::str::contains(
            "renamed: your group 'Gloffuse (GGX)' (not made by gloffuse) is now \
             'Gloffuse (GGX) (yours)'",
        ));
}

/// Case 8: `--blend` on a user's scene is refused (exit 2, the file byte-identical, nothing
/// left beside it), and so is a file that is no .blend; `--force` replaces it with a
/// library (no objects, the scene marked); a gloffuse library is replaced without it.
#[test]
fn blend_replaces_only_a_gloffuse_library_unless_forced() {
    let Some(blender) = common::blender::real_blender("4.5") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let blend = dir.path().join("scene.blend");
    make(&blender, &blend, &[]);
    let before = std::fs::read(&blend).unwrap();
    let args = ["--blend".as_ref(), blend.as_os_str()];
    let refused = generate(&blender, &args).code(2);
    let stderr = String::from_utf8_lossy(&refused.get_output().stderr).to_string();
    for needle in [
        blend.to_str().unwrap(),
        "no gloffuse library marker",
        "1 object",
        "1 material",
        "--force",
    ] {
        assert!(stderr.contains(needle), "{needle:?} not in: {stderr}");
    }
    assert_eq!(std::fs::read(&blend).unwrap(), before, "byte-identical");
    assert_eq!(listing(dir.path()), ["scene.blend"], "nothing written");

    generate(&blender, &[&args[..], &["--force".as_ref()]].concat()).success();
    let seen = inspect(&blender, &blend);
    assert_eq!(seen["objects"], 0, "{seen}");
    assert_eq!(
        seen["scene_tags"],
        serde_json::json!([env!("CARGO_PKG_VERSION")])
    );
    assert!(seen["groups"][USER_GROUP]["tag"].is_string(), "{seen}");
    // Now a gloffuse library: replaced without --force.
    let library = std::fs::read(&blend).unwrap();
    generate(&blender, &args).success();
    assert!(std::fs::read(&blend).unwrap() != library, "replaced");

    // Not a .blend at all: refused before Blender runs.
    let text = dir.path().join("notes.blend");
    std::fs::write(&text, "my notes\n").unwrap();
    generate(&blender, &["--blend".as_ref(), text.as_os_str()])
        .code(2)
        .stderr(predicates::str::contains("it is not a .blend file"))
        .stderr(predicates::str::contains("--force"));
    assert_eq!(std::fs::read_to_string(&text).unwrap(), "my notes\n");
}

/// Case 8: the catalog file's destination cannot be written (it is a folder): exit 2, the
/// existing library byte-identical, no temporary file left.
#[test]
fn an_unwritable_catalog_file_leaves_the_library_untouched() {
    let Some(blender) = common::blender::real_blender("4.5") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let blend = dir.path().join("library.blend");
    let args = ["--blend".as_ref(), blend.as_os_str()];
    generate(&blender, &args).success();
    let before = std::fs::read(&blend).unwrap();
    let catalogs = dir.path().join("blender_assets.cats.txt");
    std::fs::remove_file(&catalogs).unwrap();
    std::fs::create_dir(&catalogs).unwrap();
    generate(&blender, &args)
        .code(2)
        .stderr(predicates::str::contains(catalogs.to_str().unwrap()));
    assert_eq!(std::fs::read(&blend).unwrap(), before, "byte-identical");
    assert_eq!(
        listing(dir.path()),
        ["blender_assets.cats.txt", "library.blend"]
    );
    assert!(listing(&catalogs).is_empty());
}

/// The run folder of the `generate` run under `cache` once its Blender log exists.
fn wait_for_blender_log(cache: &Path, deadline: Instant) -> PathBuf {
    let runs = cache.join("gloffuse").join("runs");
    loop {
        let log = std::fs::read_dir(&runs).ok().and_then(|entries| {
            entries
                .filter_map(Result::ok)
                .map(|e| e.path().join("blender.log"))
                .find(|log| log.exists())
        });
        if let Some(log) = log {
            return log;
        }
        assert!(Instant::now() < deadline, "no Blender log under {runs:?}");
        std::thread::sleep(Duration::from_millis(5));
    }
}

/// Case 9: a catalog the user adds while Blender runs (after the file was first read) is in
/// the final file, with gloffuse's, and no lock file is left.
#[test]
fn a_catalog_added_during_the_run_is_kept() {
    let Some(blender) = common::blender::real_blender("4.5") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let cache = dir.path().join("cache");
    let library = dir.path().join("lib");
    std::fs::create_dir(&library).unwrap();
    let catalogs = library.join("blender_assets.cats.txt");
    std::fs::write(
        &catalogs,
        "VERSION 1\n1b2c3d4e-0000-4000-8000-000000000001:Props/Chairs:Props-Chairs\n",
    )
    .unwrap();
    let child = std::process::Command::new(assert_cmd::cargo::cargo_bin("gloffuse"))
        .args(["generate", "--no-provision", "--blend"])
        .arg(library.join("library.blend"))
        .arg("--blender")
        .arg(&blender)
        .env("XDG_CACHE_HOME", &cache)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    wait_for_blender_log(&cache, Instant::now() + Duration::from_secs(120));
    let added = "2c3d4e5f-0000-4000-8000-000000000002:Props/Lamps:Props-Lamps\n";
    let mut file = std::fs::OpenOptions::new()
        .append(true)
        .open(&catalogs)
        .unwrap();
    std::io::Write::write_all(&mut file, added.as_bytes()).unwrap();
    drop(file);
    let out = child.wait_with_output().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(&catalogs).unwrap();
    assert!(text.starts_with("VERSION 1\n1b2c3d4e"), "{text}");
    assert!(text.contains(added), "the added catalog is kept: {text}");
    assert!(text.contains(":Shader:Shader\n"), "{text}");
    assert!(
        text.contains(":Shader/Gloffuse Helpers:Shader-Gloffuse Helpers\n"),
        "{text}"
    );
    assert_eq!(
        listing(&library),
        ["blender_assets.cats.txt", "library.blend"]
    );
}

/// Case 13: a catalog file Blender would ignore (no `VERSION 1`, or `VERSION 2`) or misread
/// (a line whose id is not a UUID) is refused: exit 2, the file named (with the line), the
/// file as it was, no library written.
#[test]
fn catalog_files_blender_would_ignore_are_refused() {
    let Some(blender) = common::blender::real_blender("4.5") else {
        return;
    };
    let cases = [
        (
            "1b2c3d4e-0000-4000-8000-000000000001:Props:Props\n",
            "line 1",
        ),
        ("# mine\nVERSION 2\n", "line 2"),
        (
            "VERSION 1\n\nnot-a-uuid:Props/Chairs:Props-Chairs\n",
            "line 3",
        ),
    ];
    for (text, line) in cases {
        let dir = tempfile::tempdir().unwrap();
        let catalogs = dir.path().join("blender_assets.cats.txt");
        std::fs::write(&catalogs, text).unwrap();
        let blend = dir.path().join("library.blend");
        generate(&blender, &["--blend".as_ref(), blend.as_os_str()])
            .code(2)
            .stderr(predicates::str::contains(format!(
                "{}, {line}",
                catalogs.display()
            )))
            .stderr(predicates::str::contains("VERSION 1"));
        assert_eq!(std::fs::read_to_string(&catalogs).unwrap(), text);
        assert_eq!(listing(dir.path()), ["blender_assets.cats.txt"]);
    }
}
