//! The audit tests' own library of user materials, made inside a real Blender by
//! `tests/blender/audit_library.py` independently of gloffuse's package (it is the oracle's
//! input), and what the audit should find in it in that Blender (`expected.json`).

use std::collections::{BTreeMap, BTreeSet};
use std::ffi::OsStr;
use std::path::{Path, PathBuf};

use serde::Deserialize;

fn script() -> &'static Path {
    concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/blender/audit_library.py"
    )
    .as_ref()
}

/// What `gloffuse audit` should report for the library, in the Blender that made it.
#[derive(Debug, Clone, Deserialize)]
pub struct Expected {
    /// The Blender that made the library, e.g. "4.5.15".
    pub blender_version: String,
    /// Its major and minor version.
    pub version: [u32; 2],
    /// The version ranges the oracle assumes for the rules that depend on the Blender.
    pub rule_versions: BTreeMap<String, RuleVersions>,
    /// Per file, by its path relative to the library's folder ("rules.blend",
    /// "nested/deeper/nested.blend", "unusual.blend", "linked.blend", "corrected.blend").
    pub files: BTreeMap<String, ExpectedFile>,
}

/// A rule applies when `from <= version` and (`before` is none or `version < before`).
#[derive(Debug, Clone, Deserialize)]
pub struct RuleVersions {
    pub from: [u32; 2],
    pub before: Option<[u32; 2]>,
}

/// One .blend of the library.
#[derive(Debug, Clone, Deserialize)]
pub struct ExpectedFile {
    /// Scene-level findings (filter-glossy: node `["scene", SCENE]`).
    pub file_findings: Vec<ExpectedFinding>,
    /// Every material of the file (local and linked), by name.
    pub materials: BTreeMap<String, ExpectedMaterial>,
}

/// One material and what its audit should say.
#[derive(Debug, Clone, Deserialize)]
pub struct ExpectedMaterial {
    /// The rule ids of its findings (no other rule may fire).
    pub rules: BTreeSet<String>,
    /// Each finding with its node path: material ▸ group node(s) ▸ node (node names).
    pub findings: Vec<ExpectedFinding>,
    /// "ok", "loses", "creates" or "error".
    pub verdict: String,
    /// Why, in one line (the physics, with the author's furnace numbers).
    pub reason: String,
    /// The library it is linked from, as written in the file ("//rules.blend"), if any.
    pub library: Option<String>,
}

/// A finding the audit should report.
#[derive(Debug, Clone, Deserialize, PartialEq, Eq, PartialOrd, Ord)]
pub struct ExpectedFinding {
    pub rule: String,
    pub node: Vec<String>,
}

impl Expected {
    /// The expectations for the file at `relative` (as in [`Expected::files`]).
    pub fn file(&self, relative: &str) -> &ExpectedFile {
        self.files
            .get(relative)
            .unwrap_or_else(|| panic!("expected.json has no file {relative:?}"))
    }

    /// The expectations for material `name` of the file at `relative`.
    pub fn material(&self, relative: &str, name: &str) -> &ExpectedMaterial {
        self.file(relative)
            .materials
            .get(name)
            .unwrap_or_else(|| panic!("expected.json has no material {name:?} in {relative:?}"))
    }

    /// Every (file, material name, expectations), files and names sorted.
    pub fn materials(&self) -> impl Iterator<Item = (&str, &str, &ExpectedMaterial)> {
        self.files.iter().flat_map(|(file, expected)| {
            expected
                .materials
                .iter()
                .map(move |(name, material)| (file.as_str(), name.as_str(), material))
        })
    }

    /// Whether the rule `id` applies in this Blender under [`Expected::rule_versions`]
    /// (a rule not listed there applies in every version).
    pub fn rule_applies(&self, id: &str) -> bool {
        self.rule_versions.get(id).is_none_or(|range| {
            range.from <= self.version && range.before.is_none_or(|before| self.version < before)
        })
    }
}

/// Makes the library in `dir` with `blender` (an executable or a bpy Python): rules.blend,
/// nested/deeper/nested.blend, unusual.blend, linked.blend and, with `gloffuse_library` (a
/// .blend holding `Gloffuse View (GGX)`, see [`view_library`]), corrected.blend; returns
/// its expected.json.
pub fn make_library(blender: &Path, dir: &Path, gloffuse_library: Option<&Path>) -> Expected {
    let mut args: Vec<&OsStr> = vec!["--out".as_ref(), dir.as_os_str()];
    if let Some(library) = gloffuse_library {
        args.extend(["--gloffuse-library".as_ref(), library.as_os_str()]);
    }
    let run = super::blender::run_in_blender(blender, script(), &args);
    let expected = dir.join("expected.json");
    assert!(
        run.status.success() && expected.is_file(),
        "audit_library.py in {} failed ({}):\n{}\n{}",
        blender.display(),
        run.status,
        String::from_utf8_lossy(&run.stdout),
        String::from_utf8_lossy(&run.stderr)
    );
    let text = std::fs::read_to_string(&expected).unwrap();
    serde_json::from_str(&text).unwrap_or_else(|e| panic!("{}: {e}\n{text}", expected.display()))
}

/// The gloffuse library whose `Gloffuse View (GGX)` corrected.blend uses: the script of
/// `gloffuse generate --script DIR/gloffuse-view.py --mode view`, saved by `blender` as
/// DIR/gloffuse-view.blend (the groups `--blend` builds, without its asset previews, which
/// the audit does not need).
pub fn view_library(blender: &Path, dir: &Path) -> PathBuf {
    let script = dir.join("gloffuse-view.py");
    let library = dir.join("gloffuse-view.blend");
    super::gloffuse()
        .args(["generate", "--mode", "view", "--script"])
        .arg(&script)
        .assert()
        .success();
    let run =
        super::blender::run_in_blender(blender, &script, &["--save".as_ref(), library.as_os_str()]);
    assert!(
        run.status.success() && library.is_file(),
        "the view library in {} ({}):\n{}",
        blender.display(),
        run.status,
        String::from_utf8_lossy(&run.stderr)
    );
    library
}
