//! The bundler: the Python package `blender/gloffuse_blender/` as single-file scripts.
//!
//! Every module is embedded below, keyed by its name. A bundle starts from one module (a
//! job's main, or a test's own) and holds the modules it imports, depth first: each
//! module's imports in the order it writes them, every dependency before its dependants,
//! each module once. The order comes from the `from .x import a, b` lines (or
//! `from gloffuse_blender.x import a, b`), never from a list. Those lines are dropped from
//! the bundle, whose modules share one namespace; the other imports (the standard
//! library, `bpy`, `bmesh`) stay where they are, each made once: where the first module
//! of the bundle that makes it does.
//!
//! The bundler refuses what one namespace cannot hold: two modules defining the same
//! top-level name, an import of a module or a name that does not exist, an import cycle,
//! and the import forms that would need a module object (`import gloffuse_blender.x`,
//! `from . import x`, `*`, `as`).

use std::collections::{BTreeMap, BTreeSet};
use std::fmt;

/// The package's name, as imports spell it.
pub const PACKAGE: &str = "gloffuse_blender";

/// Every module of the package, by name.
pub const MODULES: &[(&str, &str)] = &[
    (
        "__init__",
        include_str!("../../../../blender/gloffuse_blender/__init__.py"),
    ),
    (
        "addon",
        include_str!("../../../../blender/gloffuse_blender/addon.py"),
    ),
    (
        "anisotropic_groups",
        include_str!("../../../../blender/gloffuse_blender/anisotropic_groups.py"),
    ),
    (
        "audit_job",
        include_str!("../../../../blender/gloffuse_blender/audit_job.py"),
    ),
    (
        "audit_rules",
        include_str!("../../../../blender/gloffuse_blender/audit_rules.py"),
    ),
    (
        "audit_twin",
        include_str!("../../../../blender/gloffuse_blender/audit_twin.py"),
    ),
    (
        "bench_library",
        include_str!("../../../../blender/gloffuse_blender/bench_library.py"),
    ),
    (
        "compat",
        include_str!("../../../../blender/gloffuse_blender/compat.py"),
    ),
    (
        "contract",
        include_str!("../../../../blender/gloffuse_blender/contract.py"),
    ),
    (
        "furnace",
        include_str!("../../../../blender/gloffuse_blender/furnace.py"),
    ),
    (
        "furnace_job",
        include_str!("../../../../blender/gloffuse_blender/furnace_job.py"),
    ),
    (
        "generate",
        include_str!("../../../../blender/gloffuse_blender/generate.py"),
    ),
    (
        "glass_groups",
        include_str!("../../../../blender/gloffuse_blender/glass_groups.py"),
    ),
    (
        "groups",
        include_str!("../../../../blender/gloffuse_blender/groups.py"),
    ),
    (
        "layered_groups",
        include_str!("../../../../blender/gloffuse_blender/layered_groups.py"),
    ),
    (
        "meshes",
        include_str!("../../../../blender/gloffuse_blender/meshes.py"),
    ),
    (
        "nodes",
        include_str!("../../../../blender/gloffuse_blender/nodes.py"),
    ),
    (
        "normal_group",
        include_str!("../../../../blender/gloffuse_blender/normal_group.py"),
    ),
    (
        "panel_ui",
        include_str!("../../../../blender/gloffuse_blender/panel_ui.py"),
    ),
    (
        "panel_verdict",
        include_str!("../../../../blender/gloffuse_blender/panel_verdict.py"),
    ),
    (
        "params",
        include_str!("../../../../blender/gloffuse_blender/params.py"),
    ),
    (
        "previews",
        include_str!("../../../../blender/gloffuse_blender/previews.py"),
    ),
    (
        "roughness_groups",
        include_str!("../../../../blender/gloffuse_blender/roughness_groups.py"),
    ),
    (
        "runtime",
        include_str!("../../../../blender/gloffuse_blender/runtime.py"),
    ),
    (
        "view_groups",
        include_str!("../../../../blender/gloffuse_blender/view_groups.py"),
    ),
];

/// Why modules cannot be bundled.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum BundleError {
    /// `module` imports a module the package does not have.
    UnknownModule { module: String, imports: String },
    /// `module` imports `name` from `from`, which does not define it at top level.
    UnknownName {
        module: String,
        from: String,
        name: String,
    },
    /// Two modules of one bundle define (or import) the same top-level name.
    DuplicateName {
        name: String,
        first: String,
        second: String,
    },
    /// The modules import each other in a circle (listed in import order).
    Cycle(Vec<String>),
    /// An import the bundler cannot resolve into one namespace.
    Unsupported { module: String, line: String },
}

impl fmt::Display for BundleError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::UnknownModule { module, imports } => {
                write!(
                    f,
                    "{module}.py imports {imports}, which {PACKAGE} does not have"
                )
            }
            Self::UnknownName { module, from, name } => {
                write!(
                    f,
                    "{module}.py imports {name} from {from}.py, which does not define it"
                )
            }
            Self::DuplicateName {
                name,
                first,
                second,
            } => write!(
                f,
                "{first}.py and {second}.py both define {name} (a bundle is one namespace)"
            ),
            Self::Cycle(path) => write!(f, "the modules import each other: {}", path.join(" -> ")),
            Self::Unsupported { module, line } => write!(
                f,
                "{module}.py: the bundler resolves only `from .module import name, ...`, not {line:?}"
            ),
        }
    }
}

impl std::error::Error for BundleError {}

/// One module in a bundle: its label (`compat.py`) and its text without the package imports.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Part {
    pub label: String,
    pub text: String,
}

/// What the bundler reads from a module.
#[derive(Debug, Default)]
struct Parsed {
    /// `(module, names)` of each package import, in the order written.
    imports: Vec<(String, Vec<String>)>,
    /// Names bound at top level by `def`, `class` and assignments.
    defines: BTreeSet<String>,
    /// Names bound at top level by the other imports (the standard library, bpy).
    imported: BTreeSet<String>,
    /// The module's text without the package imports, in pieces: each other import
    /// statement is a piece of its own, with the statement (sans comment) as its key.
    pieces: Vec<(Option<String>, String)>,
}

impl Parsed {
    fn push(&mut self, text: &str) {
        match self.pieces.last_mut() {
            Some((None, last)) => last.push_str(text),
            _ => self.pieces.push((None, text.to_string())),
        }
    }

    fn push_import(&mut self, statement: &str) {
        let key = statement.split('#').next().unwrap_or("").trim().to_string();
        self.pieces.push((Some(key), statement.to_string()));
    }
}

fn is_identifier(s: &str) -> bool {
    let mut chars = s.chars();
    chars
        .next()
        .is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
        && chars.all(|c| c.is_ascii_alphanumeric() || c == '_')
}

/// The name a top-level `def`, `class` or assignment line binds.
fn defined_name(line: &str) -> Option<&str> {
    for keyword in ["def ", "async def ", "class "] {
        if let Some(rest) = line.strip_prefix(keyword) {
            let end = rest
                .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
                .unwrap_or(rest.len());
            return Some(&rest[..end]);
        }
    }
    let end = line.find(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))?;
    let (name, rest) = line.split_at(end);
    let rest = rest.trim_start();
    let assigns = (rest.starts_with('=') && !rest.starts_with("=="))
        || (rest.starts_with(':') && rest.contains('='));
    (is_identifier(name) && assigns && !matches!(name, "if" | "for" | "while" | "with" | "else"))
        .then_some(name)
}

/// The package module a `from X import` names, if X is the package: `.x` or
/// `gloffuse_blender.x`.
fn package_module(from: &str) -> Option<&str> {
    from.strip_prefix('.')
        .or_else(|| from.strip_prefix(PACKAGE).and_then(|m| m.strip_prefix('.')))
}

fn unsupported(module: &str, line: &str) -> BundleError {
    BundleError::Unsupported {
        module: module.to_string(),
        line: line.trim_end().to_string(),
    }
}

fn parse(module: &str, source: &str) -> Result<Parsed, BundleError> {
    let mut parsed = Parsed::default();
    let mut in_string: Option<&str> = None;
    let mut lines = source.split_inclusive('\n');
    while let Some(line) = lines.next() {
        let top_level = in_string.is_none();
        in_string = string_after(in_string, line);
        if !top_level {
            parsed.push(line);
        } else if line.starts_with("from ") {
            parse_from(module, line, &mut lines, &mut parsed)?;
        } else if let Some(rest) = line.strip_prefix("import ") {
            parse_import(module, line, rest, &mut parsed)?;
        } else if line.starts_with("if __name__") {
            // The bundle itself ends with the call of the entry's main.
            return Err(unsupported(module, line));
        } else {
            if let Some(name) = defined_name(line) {
                parsed.defines.insert(name.to_string());
            }
            parsed.push(line);
        }
    }
    Ok(parsed)
}

/// The triple-quoted string open after `line` (`None`: none is), given the one open
/// before it.
fn string_after<'q>(mut in_string: Option<&'q str>, line: &str) -> Option<&'q str> {
    for quote in ["\"\"\"", "'''"] {
        if in_string.is_none_or(|q| q == quote) && line.matches(quote).count() % 2 == 1 {
            in_string = if in_string.is_some() {
                None
            } else {
                Some(quote)
            };
        }
    }
    in_string
}

/// A top-level `from X import …` statement starting at `line` (a parenthesised list
/// continues on the next of `lines`): a package import is recorded, any other kept.
fn parse_from<'a>(
    module: &str,
    line: &'a str,
    lines: &mut impl Iterator<Item = &'a str>,
    parsed: &mut Parsed,
) -> Result<(), BundleError> {
    let rest = &line["from ".len()..];
    let (from, names) = rest
        .split_once(" import ")
        .ok_or_else(|| unsupported(module, line))?;
    let from = from.trim();
    let mut statement = line.to_string();
    let mut names = names.to_string();
    if names.trim_start().starts_with('(') {
        while !names.contains(')') {
            let next = lines
                .next()
                .ok_or_else(|| unsupported(module, &statement))?;
            statement.push_str(next);
            names.push_str(next);
        }
    }
    let names = imported_names(&names);
    if from == "." || from == PACKAGE {
        return Err(unsupported(module, &statement));
    }
    match package_module(from) {
        Some(target) if is_identifier(target) && names.iter().all(|n| is_identifier(n)) => {
            parsed.imports.push((target.to_string(), names));
        }
        Some(_) => return Err(unsupported(module, &statement)),
        None if from.starts_with('.') => return Err(unsupported(module, &statement)),
        None => {
            // `from os import path as p` binds p.
            let bound = names.iter().map(|n| match n.split_once(" as ") {
                Some((_, alias)) => alias.trim().to_string(),
                None => n.clone(),
            });
            parsed.imported.extend(bound);
            parsed.push_import(&statement);
        }
    }
    Ok(())
}

/// The names of an import list, with or without parentheses, comments dropped.
fn imported_names(list: &str) -> Vec<String> {
    list.lines()
        .map(|l| l.split('#').next().unwrap_or(""))
        .flat_map(|l| l.split(','))
        .map(|n| n.trim().trim_matches(|c| c == '(' || c == ')').trim())
        .filter(|n| !n.is_empty())
        .map(str::to_string)
        .collect()
}

/// A top-level `import …` line (`rest` after the keyword): kept, unless it names the
/// package.
fn parse_import(
    module: &str,
    line: &str,
    rest: &str,
    parsed: &mut Parsed,
) -> Result<(), BundleError> {
    for item in rest.split('#').next().unwrap_or("").split(',') {
        let item = item.trim();
        if item == PACKAGE || item.starts_with(&format!("{PACKAGE}.")) {
            return Err(unsupported(module, line));
        }
        let bound = match item.split_once(" as ") {
            Some((_, alias)) => alias.trim(),
            None => item.split('.').next().unwrap_or(item),
        };
        parsed.imported.insert(bound.to_string());
    }
    parsed.push_import(line);
    Ok(())
}

/// The modules `entry` needs and `entry` itself, dependencies first, from the package
/// `modules` (`(name, text)`, as `MODULES`) plus `extra` (a module outside the package,
/// such as a test's main, as `(name, text)`); `entry` is a name in either.
pub fn bundle_from(
    modules: &[(&str, &str)],
    extra: Option<(&str, &str)>,
    entry: &str,
) -> Result<Vec<Part>, BundleError> {
    let mut parsed = BTreeMap::new();
    for &(name, text) in modules.iter().chain(extra.as_ref()) {
        parsed.insert(name.to_string(), parse(name, text)?);
    }
    check_entry(&parsed, extra, entry)?;
    // Depth first: a module is emitted once everything it imports is.
    let mut order: Vec<String> = Vec::new();
    visit(entry, &parsed, &mut order, &mut Vec::new())?;
    check_one_namespace(&parsed, &order)?;
    Ok(parts(order, parsed))
}

/// `entry` must be a module, and `extra` (not part of the package) imported by none.
fn check_entry(
    parsed: &BTreeMap<String, Parsed>,
    extra: Option<(&str, &str)>,
    entry: &str,
) -> Result<(), BundleError> {
    if !parsed.contains_key(entry) {
        return Err(BundleError::UnknownModule {
            module: entry.to_string(),
            imports: entry.to_string(),
        });
    }
    if let Some((extra_name, _)) = extra {
        // The extra module may not be imported by the package (it is not part of it).
        if let Some((importer, _)) = parsed
            .iter()
            .find(|(n, p)| *n != extra_name && p.imports.iter().any(|(t, _)| t == extra_name))
        {
            return Err(BundleError::UnknownModule {
                module: importer.clone(),
                imports: format!("{PACKAGE}.{extra_name}"),
            });
        }
    }
    Ok(())
}

/// Appends `name` to `order` after everything it imports, depth first; `path` is the
/// chain of imports being followed, to name a cycle.
fn visit(
    name: &str,
    parsed: &BTreeMap<String, Parsed>,
    order: &mut Vec<String>,
    path: &mut Vec<String>,
) -> Result<(), BundleError> {
    if order.iter().any(|n| n == name) {
        return Ok(());
    }
    if let Some(start) = path.iter().position(|n| n == name) {
        let mut cycle = path[start..].to_vec();
        cycle.push(name.to_string());
        return Err(BundleError::Cycle(cycle));
    }
    path.push(name.to_string());
    for (target, names) in &parsed[name].imports {
        let Some(module) = parsed.get(target) else {
            return Err(BundleError::UnknownModule {
                module: name.to_string(),
                imports: format!("{PACKAGE}.{target}"),
            });
        };
        if let Some(missing) = names.iter().find(|n| !module.defines.contains(*n)) {
            return Err(BundleError::UnknownName {
                module: name.to_string(),
                from: target.clone(),
                name: missing.clone(),
            });
        }
        visit(target, parsed, order, path)?;
    }
    path.pop();
    order.push(name.to_string());
    Ok(())
}

/// One namespace: each top-level name bound by one module only (an import of the same
/// standard module by several is the same binding, and is allowed).
fn check_one_namespace(
    parsed: &BTreeMap<String, Parsed>,
    order: &[String],
) -> Result<(), BundleError> {
    let mut defined_by: BTreeMap<&str, &str> = BTreeMap::new();
    for name in order {
        for defined in &parsed[name].defines {
            if let Some(first) = defined_by.insert(defined, name) {
                return Err(BundleError::DuplicateName {
                    name: defined.clone(),
                    first: first.to_string(),
                    second: name.clone(),
                });
            }
        }
    }
    for name in order {
        for imported in &parsed[name].imported {
            if let Some(&owner) = defined_by.get(imported.as_str()) {
                return Err(BundleError::DuplicateName {
                    name: imported.clone(),
                    first: owner.to_string(),
                    second: name.clone(),
                });
            }
        }
    }
    Ok(())
}

/// The modules in `order` as parts. An import an earlier module of the bundle made
/// already is not repeated: the name is bound in the one namespace, to the same module.
fn parts(order: Vec<String>, mut parsed: BTreeMap<String, Parsed>) -> Vec<Part> {
    let mut imported = BTreeSet::new();
    order
        .into_iter()
        .map(|name| {
            let mut text = String::new();
            for (key, piece) in parsed.remove(&name).map(|p| p.pieces).unwrap_or_default() {
                if key.is_none_or(|key| imported.insert(key)) {
                    text.push_str(&piece);
                }
            }
            Part {
                label: format!("{name}.py"),
                text,
            }
        })
        .collect()
}

/// The package modules the module `entry` needs and `entry` itself, dependencies first.
pub fn bundle(entry: &str) -> Result<Vec<Part>, BundleError> {
    bundle_from(MODULES, None, entry)
}

/// The package modules the module `text` (named `name`, not part of the package: a test's
/// own main) imports, dependencies first, then it.
pub fn bundle_with(name: &str, text: &str) -> Result<Vec<Part>, BundleError> {
    bundle_from(MODULES, Some((name, text)), name)
}

/// The parts written one after the other, each under its label.
pub fn concatenate(parts: &[Part]) -> String {
    let mut s = String::new();
    for part in parts {
        s.push_str(&format!(
            "\n# ======== gloffuse part: {} ========\n",
            part.label
        ));
        s.push_str(&part.text);
        if !part.text.ends_with('\n') {
            s.push('\n');
        }
    }
    s
}

/// The extension's `__init__.py`: `addon.py` bundled with what it imports (the panel and
/// the audit's own rules and fixes), or as it is when it imports nothing.
pub fn addon() -> String {
    let parts = bundle("addon").expect("the embedded add-on bundles");
    match parts.as_slice() {
        [alone] => alone.text.clone(),
        _ => concatenate(&parts),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn labels(parts: &[Part]) -> Vec<&str> {
        parts.iter().map(|p| p.label.as_str()).collect()
    }

    #[test]
    fn the_table_holds_every_module_of_the_package() {
        let dir = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../blender/gloffuse_blender"
        );
        let mut on_disk: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().into_string().unwrap())
            .filter_map(|n| n.strip_suffix(".py").map(str::to_string))
            .collect();
        on_disk.sort();
        let table: Vec<&str> = MODULES.iter().map(|(n, _)| *n).collect();
        assert_eq!(on_disk, table);
    }

    #[test]
    fn order_follows_the_imports_depth_first() {
        let modules = [
            (
                "a",
                "from .b import f\nfrom .c import g\n\ndef main(x):\n    f(g(x))\n",
            ),
            ("b", "from .c import g\n\n\ndef f(x):\n    return g(x)\n"),
            ("c", "import math\n\n\ndef g(x):\n    return math.sqrt(x)\n"),
        ];
        let parts = bundle_from(&modules, None, "a").unwrap();
        assert_eq!(labels(&parts), ["c.py", "b.py", "a.py"]);
        assert_eq!(parts[1].text, "\n\ndef f(x):\n    return g(x)\n");
        assert_eq!(parts[2].text, "\ndef main(x):\n    f(g(x))\n");
        assert!(parts[0].text.starts_with("import math\n"));
        let modules = [
            ("a", "import math  # again\nfrom .c import g\n"),
            ("c", "import math\n\n\ndef g(x):\n    return math.sqrt(x)\n"),
        ];
        let parts = bundle_from(&modules, None, "a").unwrap();
        assert_eq!(parts[1].text, "");
    }

    #[test]
    fn multi_line_and_absolute_imports_are_resolved_and_dropped() {
        let modules = [("c", "X = 1\n\n\ndef g():\n    \"\"\"Text\nY = 2\n\"\"\"\n")];
        let main = "import os\nfrom gloffuse_blender.c import (\n    X,  # one\n    g,\n)\n\n\ndef main(t):\n    g()\n";
        let parts = bundle_from(&modules, Some(("t", main)), "t").unwrap();
        assert_eq!(labels(&parts), ["c.py", "t.py"]);
        assert_eq!(parts[1].text, "import os\n\n\ndef main(t):\n    g()\n");
    }

    #[test]
    fn two_modules_defining_one_name_are_refused() {
        let modules = [
            ("a", "from .b import f\n\n\ndef g():\n    pass\n"),
            ("b", "def f():\n    pass\n\n\ng = 1\n"),
        ];
        let err = bundle_from(&modules, None, "a").unwrap_err();
        assert!(
            matches!(&err, BundleError::DuplicateName { name, .. } if name == "g"),
            "{err}"
        );
        let modules = [
            ("a", "from .b import f\nimport math\n"),
            ("b", "def math():\n    pass\n\n\ndef f():\n    pass\n"),
        ];
        let err = bundle_from(&modules, None, "a").unwrap_err();
        assert!(
            matches!(&err, BundleError::DuplicateName { name, .. } if name == "math"),
            "{err}"
        );
    }

    #[test]
    fn unknown_modules_names_and_cycles_are_refused() {
        let modules = [("a", "from .b import f\n"), ("b", "def g():\n    pass\n")];
        let err = bundle_from(&modules, None, "a").unwrap_err();
        assert!(
            matches!(&err, BundleError::UnknownName { name, .. } if name == "f"),
            "{err}"
        );
        let modules = [("a", "from .nothing import f\n")];
        let err = bundle_from(&modules, None, "a").unwrap_err();
        assert!(matches!(err, BundleError::UnknownModule { .. }), "{err}");
        let modules = [
            ("a", "from .b import f\n\n\ndef g():\n    pass\n"),
            ("b", "from .a import g\n\n\ndef f():\n    pass\n"),
        ];
        let err = bundle_from(&modules, None, "a").unwrap_err();
        assert_eq!(
            err,
            BundleError::Cycle(vec!["a".into(), "b".into(), "a".into()])
        );
        for import in [
            "from . import b\n",
            "from .b import f as h\n",
            "from .b import *\n",
            "import gloffuse_blender.b\n",
            "if __name__ == \"__main__\":\n    pass\n",
        ] {
            let modules = [("a", import), ("b", "def f():\n    pass\n")];
            let err = bundle_from(&modules, None, "a").unwrap_err();
            assert!(
                matches!(err, BundleError::Unsupported { .. }),
                "{import}: {err}"
            );
        }
    }

    #[test]
    fn every_job_bundles_with_compat_first_and_its_main_last() {
        for entry in ["generate", "furnace_job"] {
            let parts = bundle(entry).unwrap();
            assert_eq!(parts[0].label, "compat.py");
            assert_eq!(parts.last().unwrap().label, format!("{entry}.py"));
            assert!(parts.iter().all(|p| !p.text.contains("from .")), "{entry}");
        }
        let generate = bundle("generate").unwrap();
        assert!(labels(&generate).contains(&"previews.py"));
        assert!(!labels(&generate).contains(&"furnace.py"));
    }

    #[test]
    fn the_addon_bundles_the_audits_own_rules_and_fixes() {
        let parts = bundle("addon").unwrap();
        let labels = labels(&parts);
        for module in [
            "audit_rules.py",
            "audit_twin.py",
            "panel_verdict.py",
            "panel_ui.py",
        ] {
            assert!(labels.contains(&module), "{module} in {labels:?}");
        }
        assert_eq!(labels.last(), Some(&"addon.py"));
        let text = addon();
        assert!(text.contains("def scan_material(") && text.contains("def apply_finding("));
        assert!(!text.contains("from ."), "package imports resolved");
    }
}
