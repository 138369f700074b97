//! The structure docs/ARCHITECTURE.md describes, checked: which crate may depend on what
//! (the physics crate, the library and the binary each have their list), which stage may
//! import which (grouped `use crate::{…}` included), that the library never names a
//! command-line flag, that a long function (Rust or the Blender-side Python) says why it is long, and that
//! the module map names every Rust file.
//!
//! Tier: fast (no Blender; `scripts/test.sh --fast` runs it).

use std::collections::BTreeSet;
use std::fs;
use std::path::{Path, PathBuf};

const PHYSICS: &str = "crates/gloffuse-physics";
const LIBRARY: &str = "crates/gloffuse";
const CLI: &str = "src/cli";

/// The library's stages in the order data flows; each may import only those before it.
const STAGES: [&str; 6] = ["measure", "fit", "generate", "verify", "audit", "report"];

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn rust_files(dir: &Path) -> Vec<PathBuf> {
    let mut files = Vec::new();
    for entry in fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            files.extend(rust_files(&path));
        } else if path.extension().is_some_and(|e| e == "rs") {
            files.push(path);
        }
    }
    files.sort();
    files
}

/// The names in a manifest's `[dependencies]` table.
fn dependencies(manifest: &Path) -> BTreeSet<String> {
    let text = fs::read_to_string(manifest).unwrap();
    let mut names = BTreeSet::new();
    let mut inside = false;
    for line in text.lines() {
        let line = line.trim();
        if line.starts_with('[') {
            inside = line == "[dependencies]";
        } else if inside && !line.is_empty() && !line.starts_with('#') {
            let name = line.split(['=', '.', ' ']).next().unwrap();
            names.insert(name.trim().to_string());
        }
    }
    names
}

#[test]
fn the_physics_crate_has_no_blender_io_or_cli_dependencies() {
    let deps = dependencies(&root().join(PHYSICS).join("Cargo.toml"));
    let allowed = [
        "gauss-quad",
        "glam",
        "nalgebra",
        "rayon",
        "serde",
        "thiserror",
    ];
    for dep in &deps {
        assert!(
            allowed.contains(&dep.as_str()),
            "{PHYSICS} depends on {dep}: the physics crate holds only numerics (allowed: {allowed:?})"
        );
    }
    assert!(deps.contains("glam"), "the manifest was read: {deps:?}");
}

/// The standard library's ways out of a computation: the physics crate uses none of them.
const NOT_NUMERICS: [&str; 6] = [
    "std::fs",
    "std::process",
    "std::io",
    "std::path",
    "std::env",
    "std::net",
];

/// Each `(file, word)` where a physics file's code names one of [`NOT_NUMERICS`].
fn non_numeric_uses(files: &[(PathBuf, String)]) -> Vec<(PathBuf, &'static str)> {
    let mut found = Vec::new();
    for (file, text) in files {
        for word in NOT_NUMERICS {
            if text.lines().any(|line| code_of(line).contains(word)) {
                found.push((file.clone(), word));
            }
        }
    }
    found
}

#[test]
fn the_physics_crate_touches_no_file_process_or_environment() {
    let files: Vec<(PathBuf, String)> = rust_files(&root().join(PHYSICS).join("src"))
        .into_iter()
        .map(|f| {
            let text = fs::read_to_string(&f).unwrap();
            (f, text)
        })
        .collect();
    assert!(files.len() > 10, "the physics sources were found");
    let found = non_numeric_uses(&files);
    assert!(
        found.is_empty(),
        "the physics crate is numerics only, its error included (files, processes and the \
         environment belong to the library): {found:?}"
    );
    // The check sees a use where there is one, and not in a comment.
    let planted = [(
        PathBuf::from("error.rs"),
        "// std::path in a comment\nuse std::path::PathBuf;\n".to_string(),
    )];
    assert_eq!(
        non_numeric_uses(&planted),
        [(PathBuf::from("error.rs"), "std::path")]
    );
}

#[test]
fn the_binary_depends_only_on_the_library_and_the_command_line_crates() {
    let deps = dependencies(&root().join("Cargo.toml"));
    let allowed = [
        "gloffuse",
        "clap",
        "indicatif",
        "libc",
        "serde",
        "serde_json",
    ];
    for dep in &deps {
        assert!(
            allowed.contains(&dep.as_str()),
            "the binary depends on {dep}: work beyond parsing and printing belongs in the \
             library (allowed: {allowed:?})"
        );
    }
    assert!(deps.contains("clap"), "the manifest was read: {deps:?}");
}

#[test]
fn the_library_depends_on_no_cli_crate() {
    let deps = dependencies(&root().join(LIBRARY).join("Cargo.toml"));
    assert!(
        deps.contains("gloffuse-physics"),
        "the manifest was read: {deps:?}"
    );
    for cli_only in ["clap", "indicatif"] {
        assert!(!deps.contains(cli_only), "{LIBRARY} depends on {cli_only}");
    }
}

/// `crate::x` (and `gloffuse_physics::x`) module names a file's code (not its comments)
/// refers to, grouped ones included: `use crate::{audit, report::html}` names `audit` and
/// `report`.
fn imported_modules(text: &str) -> BTreeSet<String> {
    let text: String = text.lines().map(|l| format!("{}\n", code_of(l))).collect();
    let mut names = BTreeSet::new();
    for prefix in ["crate::", "gloffuse_physics::"] {
        for (i, _) in text.match_indices(prefix) {
            let rest = &text[i + prefix.len()..];
            match rest.strip_prefix('{') {
                Some(group) => names.extend(group_heads(group)),
                None => names.extend(leading_name(rest)),
            }
        }
    }
    names
}

/// The identifier `text` starts with, if any.
fn leading_name(text: &str) -> Option<String> {
    let name: String = text
        .trim_start()
        .chars()
        .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
        .collect();
    (!name.is_empty()).then_some(name)
}

/// The first name of each item of a `{…}` group, up to its closing brace (nested groups
/// belong to their item).
fn group_heads(group: &str) -> Vec<String> {
    let mut heads = Vec::new();
    let mut depth = 0;
    let mut item_start = true;
    for (i, c) in group.char_indices() {
        match c {
            '{' => depth += 1,
            '}' if depth == 0 => break,
            '}' => depth -= 1,
            ',' if depth == 0 => item_start = true,
            c if item_start && !c.is_whitespace() => {
                heads.extend(leading_name(&group[i..]));
                item_start = false;
            }
            _ => {}
        }
    }
    heads
}

#[test]
fn grouped_imports_are_read() {
    let text =
        "use crate::{\n    audit::{self, x},\n    report, // why\n};\nuse crate::fit::Curve;";
    let found = imported_modules(text);
    let want: BTreeSet<String> = ["audit", "report", "fit"].map(String::from).into();
    assert_eq!(found, want);
}

#[test]
fn stages_import_only_the_stages_before_them() {
    let src = root().join(LIBRARY).join("src");
    let mut checked = 0;
    for (i, stage) in STAGES.iter().enumerate() {
        let dir = src.join(stage);
        if !dir.is_dir() {
            continue; // measure lives in the physics crate
        }
        for file in rust_files(&dir) {
            let text = fs::read_to_string(&file).unwrap();
            for module in imported_modules(&text) {
                if let Some(j) = STAGES.iter().position(|s| *s == module) {
                    assert!(
                        j <= i,
                        "{} ({stage}) imports {module}, a later stage",
                        file.display()
                    );
                }
            }
            checked += 1;
        }
    }
    assert!(checked > 20, "only {checked} files checked");
    // The infrastructure serves the stages and imports none of them but measure.
    for infra in [
        "blender",
        "blend_file.rs",
        "file_lock.rs",
        "output.rs",
        "shard.rs",
        "user_blend.rs",
    ] {
        let path = src.join(infra);
        let files = if path.is_dir() {
            rust_files(&path)
        } else {
            vec![path]
        };
        for file in files {
            let text = fs::read_to_string(&file).unwrap();
            for module in imported_modules(&text) {
                assert!(
                    !STAGES[1..].contains(&module.as_str()),
                    "{} (infrastructure) imports the stage {module}",
                    file.display()
                );
            }
        }
    }
}

/// A line unless it is a `//` comment.
fn code_of(line: &str) -> &str {
    let trimmed = line.trim_start();
    if trimmed.starts_with("//") {
        return "";
    }
    line
}

/// The `--flag` words in a text.
fn flags_in(text: &str) -> BTreeSet<String> {
    let mut flags = BTreeSet::new();
    for (i, _) in text.match_indices("--") {
        let before = text[..i].chars().next_back();
        if before.is_some_and(|c| c.is_ascii_alphanumeric() || c == '-') {
            continue;
        }
        let word: String = text[i + 2..]
            .chars()
            .take_while(|c| c.is_ascii_lowercase() || *c == '-')
            .collect();
        if word.len() > 1 && !word.ends_with('-') {
            flags.insert(format!("--{word}"));
        }
    }
    flags
}

#[test]
fn only_the_cli_names_its_flags() {
    let mut cli_flags = BTreeSet::new();
    for file in rust_files(&root().join(CLI)) {
        cli_flags.extend(flags_in(&fs::read_to_string(file).unwrap()));
    }
    for known in [
        "--blender",
        "--coefficients",
        "--engine",
        "--roughness",
        "--timeout",
    ] {
        assert!(
            cli_flags.contains(known),
            "the CLI's flags were read: {known}"
        );
    }
    // Blender's own flags and the generated script's arguments, which the library passes.
    let passed_on = [
        "--python",
        "--save",
        "--open",
        "--factory-startup",
        "--version",
    ];
    let mut offenders = Vec::new();
    for crate_dir in [PHYSICS, LIBRARY] {
        for file in rust_files(&root().join(crate_dir).join("src")) {
            let text = fs::read_to_string(&file).unwrap();
            // Unit tests may name flags: they stand in for the CLI's mapping.
            let code = text.split("#[cfg(test)]").next().unwrap();
            for (n, line) in code.lines().enumerate() {
                for flag in flags_in(code_of(line)) {
                    if cli_flags.contains(&flag) && !passed_on.contains(&flag.as_str()) {
                        offenders.push(format!("{}:{}: {flag}", file.display(), n + 1));
                    }
                }
            }
        }
    }
    assert!(
        offenders.is_empty(),
        "the library names CLI flags (use a typed Field; the CLI maps it):\n{}",
        offenders.join("\n")
    );
}

/// Functions longer than `limit` lines with no `// Long on purpose:` comment in or just
/// above them.
fn unexplained_long_functions(file: &Path, limit: usize) -> Vec<String> {
    let text = fs::read_to_string(file).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    let mut found = Vec::new();
    for (i, line) in lines.iter().enumerate() {
        let trimmed = line.trim_start();
        let indent = &line[..line.len() - trimmed.len()];
        let is_fn = trimmed
            .split_whitespace()
            .take_while(|w| *w != "fn")
            .all(|w| {
                [
                    "pub",
                    "pub(crate)",
                    "pub(super)",
                    "const",
                    "unsafe",
                    "extern",
                    "\"C\"",
                ]
                .contains(&w)
            })
            && trimmed.split_whitespace().any(|w| w == "fn");
        if !is_fn || trimmed.ends_with(';') {
            continue;
        }
        let Some(end) =
            (i + 1..lines.len()).find(|&j| lines[j].starts_with(&format!("{indent}}}")))
        else {
            continue;
        };
        let length = end - i + 1;
        let above = i.saturating_sub(1);
        let explained = lines[above..=end]
            .iter()
            .any(|l| l.trim_start().starts_with("// Long on purpose:"));
        if length > limit && !explained {
            found.push(format!("{}:{} ({length} lines)", file.display(), i + 1));
        }
    }
    found
}

#[test]
fn a_long_function_says_why_it_is_long() {
    let mut found = Vec::new();
    let mut files = 0;
    for dir in [PHYSICS, LIBRARY] {
        for file in rust_files(&root().join(dir).join("src")) {
            found.extend(unexplained_long_functions(&file, 80));
            files += 1;
        }
    }
    for file in rust_files(&root().join("src")) {
        found.extend(unexplained_long_functions(&file, 80));
        files += 1;
    }
    assert!(files > 50, "only {files} files read");
    assert!(
        found.is_empty(),
        "functions over 80 lines without a `// Long on purpose:` reason:\n{}",
        found.join("\n")
    );
}

#[test]
fn the_long_function_check_can_fail() {
    let dir = tempfile::tempdir().unwrap();
    let body = "    let x = 1;\n".repeat(90);
    let long = dir.path().join("long.rs");
    fs::write(&long, format!("pub fn long() {{\n{body}}}\n")).unwrap();
    assert_eq!(unexplained_long_functions(&long, 80).len(), 1);
    fs::write(
        &long,
        format!("// Long on purpose: a kernel.\npub fn long() {{\n{body}}}\n"),
    )
    .unwrap();
    assert!(unexplained_long_functions(&long, 80).is_empty());
}

/// What only a Blender-tier test may call: the real Blenders, the libraries and files made
/// in them, and the browser.
const NEEDS_INSTALLS: [&str; 9] = [
    "real_blender(",
    "real_blenders(",
    "render_cases(",
    "run_in_blender(",
    "make_library(",
    "view_library(",
    "user_file::",
    "browser()",
    "GLOFFUSE_TEST_BPY",
];

/// The tier a test file names in its doc comment (`//! Tier: fast …` or `//! Tier:
/// blender …`), if it names one.
fn tier_of(text: &str) -> Option<&str> {
    text.lines()
        .take_while(|l| l.starts_with("//!"))
        .find_map(|l| l.strip_prefix("//! Tier: "))
        .and_then(|rest| rest.split([' ', '.']).next())
}

/// Every integration test file names its tier, and a fast one calls nothing that needs what
/// `scripts/test.sh` installs (`--fast` runs the fast files alone, by that line).
#[test]
fn every_test_file_names_its_tier_and_a_fast_one_needs_no_blender() {
    let mut wrong = Vec::new();
    let mut fast = 0;
    for file in fs::read_dir(root().join("tests")).unwrap() {
        let path = file.unwrap().path();
        if path.extension().is_none_or(|e| e != "rs") {
            continue;
        }
        let text = fs::read_to_string(&path).unwrap();
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        match tier_of(&text) {
            Some("blender") => {}
            // This file lists the calls it looks for.
            Some("fast") if name == "architecture.rs" => fast += 1,
            Some("fast") => {
                fast += 1;
                let code: String = text.lines().map(code_of).collect::<Vec<_>>().join("\n");
                for call in NEEDS_INSTALLS.iter().filter(|c| code.contains(**c)) {
                    wrong.push(format!("{name} is fast but calls {call}"));
                }
            }
            other => wrong.push(format!("{name} names no tier ({other:?})")),
        }
    }
    assert!(wrong.is_empty(), "{wrong:#?}");
    assert!(fast > 10, "only {fast} fast test files");
}

#[test]
fn the_tier_check_can_fail() {
    assert_eq!(
        tier_of("//! A test.\n//!\n//! Tier: fast (no Blender).\n"),
        Some("fast")
    );
    assert_eq!(tier_of("//! Tier: blender.\n"), Some("blender"));
    assert_eq!(tier_of("//! A test.\nfn x() {}\n//! Tier: fast\n"), None);
}

/// The module map's rows: the paths in the first cell (a file, or a folder ending in `/`)
/// and the whole row's text.
fn module_map_rows(doc: &str) -> Vec<(Vec<String>, String)> {
    let section = doc
        .split("\n## Module map")
        .nth(1)
        .expect("docs/ARCHITECTURE.md has a \"Module map\" section");
    let section = section.split("\n## ").next().unwrap();
    let mut rows = Vec::new();
    for line in section.lines().filter(|l| l.starts_with("| `")) {
        let first_cell = line.split('|').nth(1).unwrap_or("");
        let paths = first_cell
            .split('`')
            .skip(1)
            .step_by(2)
            .filter(|p| p.starts_with("crates/") || p.starts_with("src/"))
            .map(String::from)
            .collect();
        rows.push((paths, line.to_string()));
    }
    rows
}

/// Whether a row names `file` (relative to the root): by its path, or, in a row of its
/// folder (a folder above it, or a file beside it), by its name in backticks.
fn row_names(paths: &[String], text: &str, file: &str) -> bool {
    let (dir, name) = file.rsplit_once('/').unwrap();
    let stem = name.trim_end_matches(".rs");
    let of_its_folder = paths.iter().any(|p| match p.strip_suffix('/') {
        Some(folder) => dir == folder || dir.starts_with(&format!("{folder}/")),
        None => p.rsplit_once('/').is_some_and(|(d, _)| d == dir),
    });
    paths.iter().any(|p| p == file)
        || of_its_folder
            && (text.contains(&format!("`{name}`")) || text.contains(&format!("`{stem}`")))
}

#[test]
fn the_module_map_names_every_rust_file() {
    let doc = fs::read_to_string(root().join("docs/ARCHITECTURE.md")).unwrap();
    let rows = module_map_rows(&doc);
    let mut missing = Vec::new();
    let mut checked = 0;
    for dir in [PHYSICS, LIBRARY, "."] {
        let src = root().join(dir).join("src");
        for file in rust_files(&src) {
            let relative = file
                .strip_prefix(root())
                .unwrap()
                .to_string_lossy()
                .into_owned();
            if !rows
                .iter()
                .any(|(paths, text)| row_names(paths, text, &relative))
            {
                missing.push(relative);
            }
            checked += 1;
        }
    }
    assert!(checked > 60, "only {checked} files checked");
    assert!(
        missing.is_empty(),
        "docs/ARCHITECTURE.md's module map does not name {missing:#?}"
    );
}

#[test]
fn the_module_map_check_can_fail() {
    let doc = "\n## Module map\n\n| path | what |\n|---|---|\n\
               | `src/cli/` | `args.rs` (clap), `farm/` |\n\
               | `crates/gloffuse/src/verify/image.rs`, `stats.rs` | EXR |\n\n## Next\n";
    let rows = module_map_rows(doc);
    let named = |file: &str| rows.iter().any(|(p, t)| row_names(p, t, file));
    assert!(named("src/cli/args.rs"));
    assert!(named("crates/gloffuse/src/verify/stats.rs"));
    assert!(!named("src/cli/text.rs"));
    assert!(!named("crates/gloffuse/src/verify/plan.rs"));
    assert!(!named("crates/gloffuse/src/audit/stats.rs"));
}

/// `def` lines of a Python file whose function runs over `limit` lines without a
/// `# Long on purpose: why` comment above or inside it. A function ends before the next
/// line of code indented no deeper than its `def`.
fn unexplained_long_python_functions(text: &str, limit: usize) -> Vec<(usize, usize)> {
    let lines: Vec<&str> = text.lines().collect();
    let indent_of = |l: &str| l.len() - l.trim_start().len();
    let mut found = Vec::new();
    for (i, line) in lines.iter().enumerate() {
        let trimmed = line.trim_start();
        if !trimmed.starts_with("def ") {
            continue;
        }
        let indent = indent_of(line);
        let mut end = i;
        for (j, l) in lines.iter().enumerate().skip(i + 1) {
            if l.trim().is_empty() {
                continue;
            }
            if indent_of(l) <= indent && !l.trim_start().starts_with(')') {
                break;
            }
            end = j;
        }
        let length = end - i + 1;
        let explained = lines[i.saturating_sub(1)..=end]
            .iter()
            .any(|l| l.trim_start().starts_with("# Long on purpose:"));
        if length > limit && !explained {
            found.push((i + 1, length));
        }
    }
    found
}

#[test]
fn a_long_python_function_says_why_it_is_long() {
    let package = root().join("blender/gloffuse_blender");
    let mut found = Vec::new();
    let mut checked = 0;
    for entry in fs::read_dir(&package).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "py") {
            let text = fs::read_to_string(&path).unwrap();
            for (line, length) in unexplained_long_python_functions(&text, 80) {
                found.push(format!("{}:{line} ({length} lines)", path.display()));
            }
            checked += 1;
        }
    }
    assert!(checked > 15, "only {checked} Python modules checked");
    assert!(
        found.is_empty(),
        "functions over 80 lines without a `# Long on purpose:` comment saying why: {found:#?}"
    );
}

#[test]
fn the_python_length_check_can_fail() {
    let body: String = (0..90).map(|i| format!("    x = {i}\n")).collect();
    let long = format!("def f():\n{body}\n\ndef g():\n    pass\n");
    assert_eq!(unexplained_long_python_functions(&long, 80), [(1, 91)]);
    let explained = format!("# Long on purpose: a table\n{long}");
    assert!(unexplained_long_python_functions(&explained, 80).is_empty());
    let short = "def f(\n    a,\n):\n    return a\n\nx = 1\n";
    assert_eq!(unexplained_long_python_functions(short, 2), [(1, 4)]);
}
