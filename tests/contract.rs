//! The Rust↔Python contract from the Python side, under plain CPython: the documents the
//! library builds pass the package's validators (`contract.py`'s `check_fields`, and
//! `params.py`'s `load_params` for the generate document), and each kind of bad document
//! is refused with its message (`tests/blender/check_contract.py`). The library's unit
//! tests (`crates/gloffuse/src/contract.rs`) check the same documents against the contract
//! from the Rust side.
//!
//! Tier: fast (no Blender; `scripts/test.sh --fast` runs it).

mod common;

use std::path::Path;
use std::process::Command;

use gloffuse::audit::job::{FixItem, document};
use gloffuse::bench::audit::library_document;
use gloffuse::generate::Mode;
use gloffuse::measure::{BlenderVersion, Distribution, Engine, Roughness};
use gloffuse::verify::{Plan, RenderSettings};

#[test]
fn the_python_validators_accept_the_real_documents_and_refuse_bad_ones() {
    let dir = tempfile::tempdir().unwrap();
    let generate = common::seed_params();
    let render = RenderSettings::for_engine(Engine::Cycles);
    let plan = Plan::verify(
        &[Distribution::Ggx],
        &[Roughness::new(0.5).unwrap()],
        &[],
        render,
    );
    let exr = Path::new("audit.exr");
    let fix = [FixItem {
        material: 0,
        scale: None,
    }];
    let documents = [
        ("generate_document", serde_json::to_value(&generate)),
        (
            "furnace_document",
            serde_json::to_value(plan.params(&generate, Mode::Roughness, [1.0; 3], exr)),
        ),
        (
            "audit_document",
            serde_json::to_value(document(BlenderVersion::OLDEST, None, None, exr, exr, &[])),
        ),
        (
            "audit_document+groups",
            serde_json::to_value(document(
                BlenderVersion::NEWEST_KNOWN,
                Some(&generate),
                Some(render),
                exr,
                exr,
                &fix,
            )),
        ),
        (
            "bench_library_document",
            Ok(library_document(Path::new("bench.blend"), 0, 4)),
        ),
    ];
    for (kind, value) in documents {
        let text = serde_json::to_string(&value.unwrap()).unwrap();
        std::fs::write(dir.path().join(format!("{kind}.json")), text).unwrap();
    }
    let root = env!("CARGO_MANIFEST_DIR");
    let out = Command::new("python3")
        .arg(format!("{root}/tests/blender/check_contract.py"))
        .arg(format!("{root}/blender/gloffuse_blender"))
        .arg(dir.path())
        .output()
        .expect("python3 runs");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(stdout.contains(" passed, 0 failed"), "{stdout}");
}
