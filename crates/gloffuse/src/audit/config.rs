//! `gloffuse.toml`: a studio's audit configuration, found upward from each audited file the
//! way ruff finds its own (the nearest one wins, none are merged). It can change a rule's
//! severity (`[severity]`) and waive findings (`[[waiver]]`: rule ids, with optional file
//! globs relative to its folder and material names, and a reason). Any mistake in it (not
//! TOML, an unknown key, rule id or severity, a bad glob, a waiver without a reason) is an
//! error naming the file, the line and what would be right.

use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};

use globset::{GlobBuilder, GlobMatcher};
use serde::Deserialize;
use toml::Spanned;

use super::rules::{Severity, known_ids, rule};
use crate::{Error, Field, Hint};

/// The configuration file's name.
pub const CONFIG_NAME: &str = "gloffuse.toml";

/// The file as written (serde checks the keys; the values are checked below).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawConfig {
    #[serde(default)]
    severity: BTreeMap<String, Spanned<String>>,
    #[serde(default)]
    waiver: Vec<Spanned<RawWaiver>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawWaiver {
    rules: Spanned<Vec<Spanned<String>>>,
    reason: Spanned<String>,
    #[serde(default)]
    files: Vec<Spanned<String>>,
    #[serde(default)]
    materials: Vec<String>,
}

/// Which rules a waiver covers.
#[derive(Clone, Debug, PartialEq)]
pub enum Rules {
    /// `*`: every rule, and a verdict no rule explains (a material measured above 100 %).
    All,
    Ids(Vec<&'static str>),
}

impl Rules {
    pub fn covers(&self, id: &str) -> bool {
        match self {
            Rules::All => true,
            Rules::Ids(ids) => ids.contains(&id),
        }
    }
}

/// One `[[waiver]]` entry.
#[derive(Clone, Debug)]
pub struct ConfigWaiver {
    pub rules: Rules,
    pub reason: String,
    /// The line the entry starts on.
    pub line: usize,
    files: Vec<(String, GlobMatcher)>,
    materials: Vec<String>,
}

impl ConfigWaiver {
    /// Whether it waives rule `id` on `material` (none: a file finding) of a file at
    /// `relative` (its path below the configuration's folder).
    pub fn applies(&self, id: &str, relative: &Path, material: Option<&str>) -> bool {
        self.rules.covers(id) && self.covers_material(relative, material)
    }

    /// Whether its files and materials hold `material` of the file at `relative` (a file
    /// finding is held only by an entry that names no materials).
    pub fn covers_material(&self, relative: &Path, material: Option<&str>) -> bool {
        let file = self.files.is_empty() || self.files.iter().any(|(_, g)| g.is_match(relative));
        let material = match material {
            None => self.materials.is_empty(),
            Some(name) => self.materials.is_empty() || self.materials.iter().any(|m| m == name),
        };
        file && material
    }
}

/// A `gloffuse.toml`, read and checked.
#[derive(Clone, Debug)]
pub struct Config {
    pub path: PathBuf,
    pub severity: HashMap<&'static str, Severity>,
    pub waivers: Vec<ConfigWaiver>,
}

impl Config {
    /// The folder its globs are relative to.
    pub fn folder(&self) -> &Path {
        self.path.parent().unwrap_or(Path::new(""))
    }
}

/// The line (from 1) of byte `offset` in `text`.
fn line_of(text: &str, offset: usize) -> usize {
    text.as_bytes()[..offset.min(text.len())]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
        + 1
}

/// The error of `path` at `line`: what is there, and what would be right.
fn bad(path: &Path, line: usize, what: impl std::fmt::Display, right: impl Into<Hint>) -> Error {
    Error::input(
        Field::AuditConfig,
        format!("{}, line {line}: {what}", path.display()),
        right,
    )
}

/// Reads and checks the configuration at `path`.
pub fn read_config(path: &Path) -> Result<Config, Error> {
    let text = std::fs::read_to_string(path).map_err(|source| Error::Read {
        path: path.to_path_buf(),
        source,
    })?;
    parse_config(path, &text)
}

/// The configuration `text`, read from `path` (named in its errors).
pub fn parse_config(path: &Path, text: &str) -> Result<Config, Error> {
    let raw: RawConfig = toml::from_str(text).map_err(|e| {
        let line = e.span().map_or(1, |s| line_of(text, s.start));
        let message = e.message().trim().to_string();
        bad(
            path,
            line,
            message,
            "TOML with only a [severity] table (RULE-ID = \"error\" | \"warning\" | \"info\") \
             and [[waiver]] entries (rules, reason, and optionally files and materials)",
        )
    })?;
    let mut severity = HashMap::new();
    for (id, level) in &raw.severity {
        let line = line_of(text, level.span().start);
        let known = rule(id).ok_or_else(|| {
            bad(
                path,
                line,
                format!("unknown rule `{id}` in [severity]"),
                format!("a rule id: {}", known_ids()),
            )
        })?;
        let value = Severity::from_key(level.get_ref()).ok_or_else(|| {
            bad(
                path,
                line,
                format!("severity `{}` for {id}", level.get_ref()),
                "\"error\", \"warning\" or \"info\"",
            )
        })?;
        severity.insert(known.id, value);
    }
    let waivers = raw
        .waiver
        .iter()
        .map(|w| checked_waiver(path, text, w))
        .collect::<Result<_, _>>()?;
    Ok(Config {
        path: path.to_path_buf(),
        severity,
        waivers,
    })
}

fn checked_waiver(path: &Path, text: &str, w: &Spanned<RawWaiver>) -> Result<ConfigWaiver, Error> {
    let line = line_of(text, w.span().start);
    let w = w.get_ref();
    let at = |span: std::ops::Range<usize>| line_of(text, span.start);
    let mut ids = Vec::new();
    let mut all = false;
    for id in w.rules.get_ref() {
        match id.get_ref().as_str() {
            "*" => all = true,
            other => ids.push(
                rule(other)
                    .ok_or_else(|| {
                        bad(
                            path,
                            at(id.span()),
                            format!("unknown rule `{other}` in a [[waiver]]"),
                            format!("`*` or a rule id: {}", known_ids()),
                        )
                    })?
                    .id,
            ),
        }
    }
    if w.rules.get_ref().is_empty() {
        return Err(bad(
            path,
            at(w.rules.span()),
            "a [[waiver]] with no rules",
            "rules = [\"RULE-ID\", …], or [\"*\"] for every rule",
        ));
    }
    if w.reason.get_ref().trim().is_empty() {
        return Err(bad(
            path,
            at(w.reason.span()),
            "a [[waiver]] with an empty reason",
            "reason = \"why the finding is accepted\"",
        ));
    }
    let files = w
        .files
        .iter()
        .map(|pattern| {
            // `*` stays within one folder, as ruff and git read it: `props/*.blend` does not
            // match `props/old/x.blend`, `props/**/*.blend` does.
            GlobBuilder::new(pattern.get_ref())
                .literal_separator(true)
                .build()
                .map(|g| (pattern.get_ref().clone(), g.compile_matcher()))
                .map_err(|e| {
                    bad(
                        path,
                        at(pattern.span()),
                        format!("glob `{}`: {}", pattern.get_ref(), e.kind()),
                        "a glob relative to the configuration's folder, such as \
                         \"props/**/*.blend\" (`*` within a folder, `**` across folders)",
                    )
                })
        })
        .collect::<Result<_, _>>()?;
    Ok(ConfigWaiver {
        rules: if all { Rules::All } else { Rules::Ids(ids) },
        reason: w.reason.get_ref().trim().to_string(),
        line,
        files,
        materials: w.materials.clone(),
    })
}

/// The configurations that hold each audited file: the nearest `gloffuse.toml` in its
/// folder or above, each read once.
#[derive(Debug, Default)]
pub struct Configs {
    by_folder: HashMap<PathBuf, Option<usize>>,
    pub read: Vec<Config>,
}

impl Configs {
    /// The configuration of `file` (none: no `gloffuse.toml` holds it). A configuration
    /// that cannot be read or is wrong is an error.
    pub fn for_file(&mut self, file: &Path) -> Result<Option<&Config>, Error> {
        let absolute = std::path::absolute(file).unwrap_or_else(|_| file.to_path_buf());
        let mut walked = Vec::new();
        let mut found = None;
        for folder in absolute.ancestors().skip(1) {
            if let Some(known) = self.by_folder.get(folder) {
                found = *known;
                break;
            }
            walked.push(folder.to_path_buf());
            let candidate = folder.join(CONFIG_NAME);
            if candidate.is_file() {
                self.read.push(read_config(&candidate)?);
                found = Some(self.read.len() - 1);
                break;
            }
        }
        for folder in walked {
            self.by_folder.insert(folder, found);
        }
        Ok(found.map(|i| &self.read[i]))
    }
}

/// `file`'s path below `config`'s folder (as its globs match it).
pub fn relative_to(config: &Config, file: &Path) -> PathBuf {
    let absolute = std::path::absolute(file).unwrap_or_else(|_| file.to_path_buf());
    absolute
        .strip_prefix(config.folder())
        .map(Path::to_path_buf)
        .unwrap_or(absolute)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<Config, String> {
        parse_config(Path::new("/studio/gloffuse.toml"), text).map_err(|e| e.to_string())
    }

    #[test]
    fn a_configuration_sets_severities_and_waivers() {
        let c = parse(
            "[severity]\nglossy-single-scatter = \"warning\"\n\n[[waiver]]\nrules = \
             [\"color-above-one\"]\nreason = \"a light panel\"\nfiles = [\"props/*.blend\"]\n\
             materials = [\"Panel\"]\n\n[[waiver]]\nrules = [\"*\"]\nreason = \"legacy\"\n",
        )
        .unwrap();
        assert_eq!(c.severity["glossy-single-scatter"], Severity::Warning);
        assert_eq!(c.waivers.len(), 2);
        let w = &c.waivers[0];
        assert_eq!(w.line, 4);
        assert!(w.applies("color-above-one", Path::new("props/a.blend"), Some("Panel")));
        assert!(!w.applies(
            "color-above-one",
            Path::new("props/old/a.blend"),
            Some("Panel")
        ));
        assert!(!w.applies("color-above-one", Path::new("props/a.blend"), Some("Other")));
        assert!(!w.applies("color-above-one", Path::new("props/a.blend"), None));
        assert!(!w.applies("toon-smooth", Path::new("props/a.blend"), Some("Panel")));
        assert_eq!(c.waivers[1].rules, Rules::All);
        assert_eq!(c.waivers[1].line, 10);
        assert!(c.waivers[1].applies("toon-smooth", Path::new("x.blend"), None));
        assert!(parse("").unwrap().waivers.is_empty());
    }

    /// Every mistake names the file, the line and what would be right.
    #[test]
    fn a_bad_configuration_is_an_error_naming_its_line() {
        for (text, line, words) in [
            (
                "[severity]\nglossy = \"warning\"\n",
                2,
                "a rule id: glossy-single-scatter",
            ),
            (
                "[severity]\ntoon-smooth = \"fatal\"\n",
                2,
                "\"error\", \"warning\" or \"info\"",
            ),
            ("colour = 1\n", 1, "unknown field"),
            (
                "[[waiver]]\nrules = [\"*\"]\nreason = \"x\"\nmaterial = [\"a\"]\n",
                4,
                "materials",
            ),
            ("[[waiver]]\nrules = [\"*\"]\n", 1, "reason"),
            (
                "[[waiver]]\nrules = [\"*\"]\nreason = \"  \"\n",
                3,
                "empty reason",
            ),
            ("[[waiver]]\nrules = []\nreason = \"x\"\n", 2, "no rules"),
            (
                "[[waiver]]\n\nrules = [\"*\", \"nope\"]\nreason = \"x\"\n",
                3,
                "unknown rule `nope`",
            ),
            (
                "[[waiver]]\nrules = [\"*\"]\nreason = \"x\"\nfiles = [\"a/[b\"]\n",
                4,
                "glob `a/[b`",
            ),
            ("[severity\n", 1, "TOML"),
            ("[[waiver]]\nrules = \"*\"\nreason = \"x\"\n", 2, "sequence"),
        ] {
            let message = parse(text).unwrap_err();
            assert!(
                message.contains(&format!("/studio/gloffuse.toml, line {line}"))
                    && message.contains(words),
                "{text:?}: {message}"
            );
        }
    }

    #[test]
    fn the_nearest_configuration_wins() {
        let dir = tempfile::tempdir().unwrap();
        let root = dir.path();
        std::fs::create_dir_all(root.join("a/b/c")).unwrap();
        std::fs::create_dir_all(root.join("d")).unwrap();
        std::fs::write(
            root.join("gloffuse.toml"),
            "[severity]\ntoon-smooth = \"info\"\n",
        )
        .unwrap();
        std::fs::write(root.join("a/b/gloffuse.toml"), "").unwrap();
        // A folder named like the file is no configuration.
        std::fs::create_dir_all(root.join("d/gloffuse.toml")).unwrap();
        let mut configs = Configs::default();
        let near = configs
            .for_file(&root.join("a/b/c/x.blend"))
            .unwrap()
            .unwrap();
        assert_eq!(near.path, root.join("a/b/gloffuse.toml"));
        assert!(near.severity.is_empty(), "the nearest one alone counts");
        let top = configs.for_file(&root.join("d/y.blend")).unwrap().unwrap();
        assert_eq!(top.path, root.join("gloffuse.toml"));
        assert_eq!(
            relative_to(&configs.read[1].clone(), &root.join("d/y.blend")),
            Path::new("d/y.blend")
        );
        assert_eq!(configs.read.len(), 2, "each read once");
        configs.for_file(&root.join("a/b/z.blend")).unwrap();
        assert_eq!(configs.read.len(), 2);
        std::fs::write(root.join("a/gloffuse.toml"), "nope").unwrap();
        let mut fresh = Configs::default();
        let message = fresh
            .for_file(&root.join("a/q.blend"))
            .unwrap_err()
            .to_string();
        assert!(message.contains("a/gloffuse.toml, line 1"), "{message}");
    }

    /// The example in docs/AUDIT.md is a configuration this reads.
    #[test]
    fn the_documented_example_reads() {
        let doc = include_str!("../../../../docs/AUDIT.md");
        let example = doc.split("```toml\n").nth(1).expect("a toml example");
        let example = example.split("```").next().unwrap();
        let c = parse(example).unwrap();
        assert_eq!(c.severity["toon-smooth"], Severity::Warning);
        assert_eq!(c.waivers.len(), 1);
        assert!(c.waivers[0].applies(
            "glossy-single-scatter",
            Path::new("props/cars/a.blend"),
            Some("Brushed steel")
        ));
    }
}
