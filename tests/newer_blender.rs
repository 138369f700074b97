//! Case 18 (issue 20): a Blender newer than the newest gloffuse knows (5.0) runs on 5.0's
//! rules with a notice naming them; the known ones (3.4, 4.5, 5.0) run without one, and
//! compat.py's answers there are what each version's Blender and Cycles do.
//!
//! No bpy wheel of 5.1 or 5.2 installs here, so the notice for them is tested on the
//! version logic (unit tests in `blender::probe` and `measure::version`), and what compat.py
//! does there was read in Cycles' source, not run (`docs/BLENDER-VERSIONS.md`). These tests
//! run the real Blenders: the compat functions are the oracle's subject, each version's
//! known behaviour (from its release notes and the Cycles source) the oracle.
//!
//! Tier: blender (needs the Blenders and tools `scripts/test.sh` installs).

mod common;

use std::path::PathBuf;

use std::sync::Mutex;
use std::time::Duration;

use serde_json::{Value, json};

use gloffuse::blender::{BlenderOptions, Run, probe, run_script};
use gloffuse::generate::assemble_with_main;
use gloffuse::progress::Progress;

/// Asks compat.py what it does in this Blender, and checks its socket lookups against
/// Blender's own sockets.
const MAIN: &str = r#"
import json

import bpy

from gloffuse_blender.compat import (
    compat_eevee_engine,
    compat_node_tree,
    compat_principled_dielectric,
    find_socket,
    glossy_node,
    has_bump_map_correction,
    masking_family,
    multiply_color_node,
    valid_reflection_rule,
)
from gloffuse_blender.runtime import run_main


def lookups_agree(node):
    # Each socket found by identifier is the one the name-and-type fallback
    # finds (an identifier no Blender has forces the fallback).
    wanted = [(node.inputs, "Factor_Float", "Factor", "VALUE"),
              (node.inputs, "A_Color", "A", "RGBA"),
              (node.inputs, "B_Color", "B", "RGBA"),
              (node.outputs, "Result_Color", "Result", "RGBA")]
    if node.bl_idname != "ShaderNodeMix":
        return None
    return all(find_socket(sockets, ident) == find_socket(sockets, "renamed", name, kind)
               for sockets, ident, name, kind in wanted)


def probe_main():
    material = bpy.data.materials.new("compat probe")
    tree = compat_node_tree(material)
    mix, a, b, out = multiply_color_node(tree.nodes)
    glossy = glossy_node(tree.nodes, "GGX")
    principled = tree.nodes.new("ShaderNodeBsdfPrincipled")
    compat_principled_dielectric(principled, 1.5)
    specular = principled.inputs.get("Specular")
    thin_wall = principled.inputs.get("Thin Wall")
    # This test's own result, not one of the package's jobs (contract.py holds those).
    print("GLOFFUSE_RESULT " + json.dumps({
        "masking": masking_family([3, 5]),
        "reflection_rule": valid_reflection_rule(),
        "bump_map_correction": has_bump_map_correction(),
        "eevee_engine": compat_eevee_engine(),
        "mix": mix.bl_idname,
        "mix_sockets": [a.type, b.type, out.type],
        "lookups_agree": lookups_agree(mix),
        "glossy_distribution": glossy.distribution,
        "glossy_roughness": glossy.inputs["Roughness"].default_value,
        "principled_ior": principled.inputs["IOR"].default_value,
        "principled_specular": None if specular is None else specular.default_value,
        "thin_wall": None if thin_wall is None else bool(thin_wall.default_value),
    }, sort_keys=True))


def main(document_text):
    run_main(probe_main)
"#;

/// What compat.py says in the real Blender `label`.
fn compat_answers(label: &str) -> Option<Value> {
    let program = common::blender::real_blender(label)?;
    let blender = probe(&program).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let script = dir.path().join("compat_probe.py");
    let text = assemble_with_main(&json!({}), "compat_probe.py", MAIN).unwrap();
    std::fs::write(&script, text).unwrap();
    let run = Run {
        blender: &blender,
        script: &script,
        args: Vec::new(),
        timeout: Duration::from_secs(300),
        cancel: Default::default(),
        log: dir.path().join("compat_probe.log"),
    };
    let output = run_script(&run).unwrap_or_else(|e| panic!("Blender {label}: {e}"));
    Some(output.result)
}

/// The answers every supported version shares.
fn assert_common(label: &str, got: &Value) {
    assert_eq!(
        got["mix_sockets"],
        json!(["RGBA", "RGBA", "RGBA"]),
        "{label}: {got}"
    );
    assert_eq!(got["glossy_distribution"], "GGX", "{label}: {got}");
    assert_eq!(got["glossy_roughness"], 0.5, "{label}: {got}");
    assert_eq!(got["principled_ior"], 1.5, "{label}: {got}");
    // No known version has Thin Wall (Cycles adds it in 5.2).
    assert_eq!(got["thin_wall"], Value::Null, "{label}: {got}");
}

#[test]
fn compat_answers_in_blender_3_4() {
    let Some(got) = compat_answers("3.4") else {
        return;
    };
    assert_common("3.4", &got);
    assert_eq!(got["masking"], "separable", "{got}");
    assert_eq!(got["reflection_rule"], "3.0", "{got}");
    assert_eq!(got["bump_map_correction"], false, "{got}");
    assert_eq!(got["eevee_engine"], "BLENDER_EEVEE", "{got}");
    assert_eq!(got["mix"], "ShaderNodeMix", "{got}");
    assert_eq!(got["lookups_agree"], true, "{got}");
    // Before 4.0 the specular F0 is 0.08 × Specular: IOR 1.5's F0 0.04 is Specular 0.5.
    let specular = got["principled_specular"].as_f64().unwrap();
    assert!((specular - 0.5).abs() < 1e-6, "{got}");
}

#[test]
fn compat_answers_in_bpy_4_5() {
    let Some(got) = compat_answers("4.5") else {
        return;
    };
    assert_common("4.5", &got);
    assert_eq!(got["masking"], "height-correlated", "{got}");
    assert_eq!(got["reflection_rule"], "3.6", "{got}");
    assert_eq!(got["bump_map_correction"], true, "{got}");
    assert_eq!(got["eevee_engine"], "BLENDER_EEVEE_NEXT", "{got}");
    assert_eq!(got["lookups_agree"], true, "{got}");
    assert_eq!(got["principled_specular"], Value::Null, "{got}");
}

#[test]
fn compat_answers_in_bpy_5_0() {
    let Some(got) = compat_answers("5.0") else {
        return;
    };
    assert_common("5.0", &got);
    assert_eq!(got["masking"], "height-correlated", "{got}");
    assert_eq!(got["reflection_rule"], "3.6", "{got}");
    assert_eq!(got["bump_map_correction"], true, "{got}");
    assert_eq!(got["eevee_engine"], "BLENDER_EEVEE", "{got}");
    assert_eq!(got["lookups_agree"], true, "{got}");
    assert_eq!(got["principled_specular"], Value::Null, "{got}");
}

/// Records every notice.
#[derive(Default)]
struct Notices(Mutex<Vec<String>>);

impl Progress for Notices {
    fn notice(&self, message: &str) {
        self.0.lock().unwrap().push(message.to_string());
    }
}

fn known_blenders_are_used_without_an_assumption_notice(label: &'static str, program: PathBuf) {
    let notices = Notices::default();
    let options = BlenderOptions {
        program: Some(program.clone()),
        provision: false,
        ..BlenderOptions::default()
    };
    let blender = options.find(&notices).unwrap();
    assert!(!blender.version.is_newer_than_known(), "{label}");
    let notices = notices.0.into_inner().unwrap();
    assert!(
        notices.iter().any(|n| n.starts_with("using Blender ")),
        "{label}: {notices:?}"
    );
    assert!(
        !notices.iter().any(|n| n.contains("newer than the newest")),
        "{label}: {notices:?}"
    );
}

common::blender::per_blender!(known_blenders_are_used_without_an_assumption_notice);
