//! The rule catalogue: for every rule the audit job applies, which Blender versions it
//! applies to, what the flagged node does to the light, and the fix. The job (Python)
//! detects; this table says which rules apply where and words each finding, adding the
//! brightness the integrator predicts where the lobe is known.

use std::collections::HashMap;

use serde::{Deserialize, Serialize};

use crate::measure::{
    AlbedoIntegrator, BlenderVersion, Distribution, Glossy, Roughness, coat::Coat,
};

/// What a flagged node does to a material's brightness.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Effect {
    /// Reflects less than it should: energy single scattering loses.
    Loses,
    /// Reflects more than it receives.
    Creates,
    /// Worth knowing; the furnace judges it.
    Info,
    /// Makes the material impossible to audit as authored.
    Error,
}

impl Effect {
    pub fn key(self) -> &'static str {
        match self {
            Effect::Loses => "loses",
            Effect::Creates => "creates",
            Effect::Info => "info",
            Effect::Error => "error",
        }
    }
}

/// How much a finding counts: only `error` findings fail the check (a judging rule's
/// through the verdict it gives, an `info` rule's by itself); `warning` and `info` are
/// reported.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Severity {
    #[default]
    Error,
    Warning,
    Info,
}

impl Severity {
    pub const ALL: [Severity; 3] = [Severity::Error, Severity::Warning, Severity::Info];

    pub fn key(self) -> &'static str {
        match self {
            Severity::Error => "error",
            Severity::Warning => "warning",
            Severity::Info => "info",
        }
    }

    pub fn from_key(key: &str) -> Option<Severity> {
        Severity::ALL.into_iter().find(|s| s.key() == key)
    }
}

/// One rule of the audit.
#[derive(Clone, Copy, Debug)]
pub struct Rule {
    pub id: &'static str,
    pub effect: Effect,
    /// How much a finding of it counts unless a configuration says otherwise: only an
    /// `error` finding fails the check.
    pub severity: Severity,
    /// The first Blender version it applies to.
    pub from: BlenderVersion,
    /// The first version it no longer applies to (none: every later one).
    pub before: Option<BlenderVersion>,
    /// Why the node was flagged.
    pub why: &'static str,
    /// What to do.
    pub fix: &'static str,
}

const fn v(major: u32, minor: u32) -> BlenderVersion {
    BlenderVersion { major, minor }
}

/// Every rule, in the order the documentation lists them.
pub const RULES: &[Rule] = &[
    Rule {
        id: "glossy-single-scatter",
        effect: Effect::Loses,
        severity: Severity::Error,
        from: v(3, 0),
        before: None,
        why: "a single-scatter glossy lobe (GGX, Beckmann or Ashikhmin–Shirley) loses the light \
              that bounces between microfacets, and Cycles compensates only Multiscatter GGX",
        fix: "use Multiscatter GGX (GGX), or the gloffuse Multiscatter group of the same \
              distribution (Beckmann, Ashikhmin–Shirley); an anisotropic lobe: the gloffuse \
              Anisotropic group",
    },
    Rule {
        id: "anisotropic-multiscatter",
        effect: Effect::Loses,
        severity: Severity::Error,
        // 3.x's Multiscatter GGX is a random walk between microfacets, which conserves an
        // anisotropic lobe too; 4.0 replaced it by the albedo-scaled single scatter.
        from: v(4, 0),
        before: None,
        why: "Cycles compensates an anisotropic Multiscatter GGX lobe with the isotropic table \
              at the geometric-mean roughness, which misses most of its loss (73 % at \
              anisotropy 0.8, roughness 0.7)",
        fix: "use the gloffuse Anisotropic (GGX) group, which restores the light of every view \
              and keeps the highlight's shape",
    },
    Rule {
        id: "metallic-single-scatter",
        effect: Effect::Loses,
        severity: Severity::Error,
        from: v(4, 3),
        before: None,
        why: "a single-scatter Metallic lobe loses the light that bounces between microfacets",
        fix: "set the Metallic BSDF's distribution to Multiscatter GGX",
    },
    Rule {
        id: "glass-single-scatter",
        effect: Effect::Loses,
        severity: Severity::Error,
        from: v(3, 0),
        before: None,
        why: "single-scatter rough glass loses light at every interface (22 % at roughness 0.5, \
              66 % at 1, IOR 1.5)",
        fix: "use the gloffuse Glass group of the same distribution (before 3.6 GGX glass: \
              Multiscatter GGX, which keeps the light there); Multiscatter GGX glass from 3.6 \
              still loses at grazing views",
    },
    Rule {
        id: "refraction-single-scatter",
        effect: Effect::Loses,
        severity: Severity::Error,
        from: v(3, 0),
        before: None,
        why: "the Refraction BSDF has no multiscatter option in any Blender: rough refraction \
              loses light",
        fix: "use the gloffuse Refraction group of the same distribution: it refracts as the \
              node does and returns all the light meeting it, entering and leaving",
    },
    Rule {
        id: "principled-single-scatter",
        effect: Effect::Loses,
        severity: Severity::Error,
        from: v(3, 0),
        before: None,
        why: "Principled BSDF with the GGX distribution is not energy-compensated",
        fix: "set Principled BSDF's distribution to Multiscatter GGX",
    },
    Rule {
        id: "principled-creates-energy",
        effect: Effect::Creates,
        severity: Severity::Error,
        from: v(3, 0),
        before: Some(v(4, 0)),
        why: "Principled BSDF before 4.0 adds its specular layer to an undimmed diffuse base: a \
              white one renders at 106–113 % in the furnace",
        fix: "use the gloffuse Layered group (Base Color, Roughness, IOR), or Blender 4.0 or \
              later, whose Principled BSDF conserves energy",
    },
    Rule {
        id: "mix-fresnel-layering",
        effect: Effect::Loses,
        severity: Severity::Error,
        from: v(3, 0),
        before: None,
        why: "a Mix Shader driven by Fresnel or Layer Weight weights the whole glossy lobe by the \
              smooth Fresnel at the shading normal: the rough coat's darkening is never given \
              back to the base (95 % at roughness 1, IOR 1.5; 90.5 % at IOR 2)",
        fix: "use the gloffuse Layered group of the same distribution, or Principled BSDF in \
              Blender 4.0 or later",
    },
    Rule {
        id: "add-reflecting",
        effect: Effect::Creates,
        severity: Severity::Error,
        from: v(3, 0),
        before: None,
        why: "an Add Shader of two reflecting closures reflects the sum of both: up to twice the \
              light it receives",
        fix: "use a Mix Shader (its factor splits the light between the two); where the Add is \
              the material's whole surface and it renders above 100 %, a fix scales it back to \
              100 % by the brightness measured",
    },
    Rule {
        id: "color-above-one",
        effect: Effect::Creates,
        severity: Severity::Error,
        from: v(3, 0),
        before: None,
        why: "a BSDF colour above 1 reflects more light than arrives",
        fix: "keep every channel of a BSDF colour at or below 1",
    },
    Rule {
        id: "toon-smooth",
        effect: Effect::Creates,
        severity: Severity::Error,
        from: v(3, 0),
        before: None,
        why: "a Toon BSDF with Smooth above 0 is not normalised: it can reflect more than it \
              receives",
        fix: "set Smooth to 0, or use it only where brightness does not matter",
    },
    Rule {
        id: "filter-glossy",
        effect: Effect::Info,
        severity: Severity::Warning,
        from: v(3, 0),
        before: None,
        why: "Filter Glossy raises roughness after Cycles computes its compensation, so rough \
              lobes render darker (the audit renders with it at 0)",
        fix: "set Render ▸ Light Paths ▸ Caustics ▸ Filter Glossy to 0 for final renders",
    },
    Rule {
        id: "load-warning",
        effect: Effect::Info,
        severity: Severity::Warning,
        from: v(3, 0),
        before: None,
        why: "Blender reported an error opening the file and loaded the rest: what it could not \
              read is not audited, a fixed copy lacks it, and the file is not fixed in place",
        fix: "open the file in the Blender that saved it and resolve what the message names",
    },
    Rule {
        id: "missing-texture",
        effect: Effect::Error,
        severity: Severity::Error,
        from: v(3, 0),
        before: None,
        why: "an image the material uses is missing, so Blender renders it magenta",
        fix: "restore the image file, or repath it (File ▸ External Data ▸ Find Missing Files)",
    },
    Rule {
        id: "linked-library",
        effect: Effect::Info,
        severity: Severity::Info,
        from: v(3, 0),
        before: None,
        why: "the material or a group it uses is linked from another .blend (audit that file \
              to fix it); a missing library makes the material an error",
        fix: "audit and fix the library file itself",
    },
    Rule {
        id: "emission",
        effect: Effect::Info,
        severity: Severity::Info,
        from: v(3, 0),
        before: None,
        why: "the material emits light, so its furnace brightness includes what it emits (it is \
              not judged for creating energy)",
        fix: "nothing, if the emission is meant",
    },
    Rule {
        id: "holdout",
        effect: Effect::Info,
        severity: Severity::Info,
        from: v(3, 0),
        before: None,
        why: "a Holdout cuts the material out of the image: where it covers the sphere there is \
              nothing to measure",
        fix: "nothing, if the holdout is meant",
    },
    Rule {
        id: "volume",
        effect: Effect::Info,
        severity: Severity::Info,
        from: v(3, 0),
        before: None,
        why: "the material has a volume, which the furnace renders inside the sphere",
        fix: "nothing, if the volume is meant",
    },
    Rule {
        id: "depends-on-scene",
        effect: Effect::Info,
        severity: Severity::Info,
        from: v(3, 0),
        before: None,
        why: "the material reads what the furnace's sphere cannot know (a mesh's attributes or \
              vertex colours, its object, its place in the world, the camera, the geometry or \
              lights around it): the furnace shows it with the sphere's, which may not be \
              what it meets in its scene",
        fix: "nothing, if that is meant; judge the material on its own object too",
    },
    Rule {
        id: "unknown-node",
        effect: Effect::Info,
        severity: Severity::Warning,
        from: v(3, 0),
        before: None,
        why: "a node the audit does not know (an OSL script, a custom node, a group without a \
              tree): its light is measured by the furnace only",
        fix: "check the node by hand",
    },
    Rule {
        id: "invalid-waiver",
        effect: Effect::Info,
        severity: Severity::Warning,
        from: v(3, 0),
        before: None,
        why: "a `gloffuse_ignore` custom property that gloffuse cannot read: what it cannot \
              read waives nothing",
        fix: "write the property as text, `RULE-ID: reason`, several separated by `;` (`*` for \
              every rule)",
    },
    // The PBR range rules (issue 41): plausible albedos, read off constant colours (an
    // unlinked socket or an RGB node) in sRGB, without a render. Metal: a Principled BSDF
    // with Metallic at or above 0.9, or a Glossy BSDF's colour; non-metal: Metallic at or
    // below 0.1, or a Diffuse BSDF's colour (docs/AUDIT.md, "PBR ranges").
    Rule {
        id: "pbr-albedo-range",
        effect: Effect::Info,
        severity: Severity::Info,
        from: v(3, 0),
        before: None,
        why: "the colour's luminance is outside the range of Unity's Material Validator \
              (Unity's material charts: 50–243 sRGB for non-metals, 186–255 for metals)",
        fix: "bring the colour's luminance into the range, unless the material is meant to be \
              that dark or bright",
    },
    Rule {
        id: "pbr-dark-albedo",
        effect: Effect::Info,
        severity: Severity::Warning,
        from: v(3, 0),
        before: None,
        why: "a channel of the non-metal's colour is below the dark floor of Substance's PBR \
              Validate: 50 sRGB recommended, 30 strict (no real surface is darker than \
              charcoal, about 4 % reflectance)",
        fix: "raise every channel of the colour to 50 sRGB or more (30 at the very least)",
    },
    Rule {
        id: "pbr-metal-reflectance",
        effect: Effect::Info,
        severity: Severity::Warning,
        from: v(3, 0),
        before: None,
        why: "a channel of the metal's colour is below the 60–100 % metal reflectance of \
              Substance's PBR Validate (60 % of 255 sRGB: 153)",
        fix: "raise every channel of the metal's colour to 60 % (153 sRGB) or more, or make \
              the material a non-metal",
    },
];

/// The rules gloffuse reports itself, from what the job read (no detector in the job).
pub const REPORTED_BY_GLOFFUSE: &[&str] = &["invalid-waiver"];

/// Every rule id, comma-separated: what a wrong id is told.
pub fn known_ids() -> String {
    RULES.iter().map(|r| r.id).collect::<Vec<_>>().join(", ")
}

/// The rule `id`, if the catalogue has it.
pub fn rule(id: &str) -> Option<&'static Rule> {
    RULES.iter().find(|r| r.id == id)
}

impl Rule {
    /// Whether the rule applies in Blender `version`.
    pub fn applies(&self, version: BlenderVersion) -> bool {
        self.from <= version && self.before.is_none_or(|b| version < b)
    }

    /// The versions it applies to, in words: "3.0 and later", "3.0 to 3.x".
    pub fn versions(&self) -> String {
        match self.before {
            None => format!("{} and later", self.from),
            Some(b) if b.minor == 0 => format!("{} to {}.x", self.from, b.major - 1),
            Some(b) => format!("{} up to (not including) {b}", self.from),
        }
    }
}

/// The catalogue as the job's parameter document carries it: each rule's id and version range.
#[derive(Clone, Debug, Serialize)]
pub struct RuleRange {
    pub id: &'static str,
    pub from: [u32; 2],
    pub before: Option<[u32; 2]>,
}

pub fn ranges() -> Vec<RuleRange> {
    RULES
        .iter()
        .map(|r| RuleRange {
            id: r.id,
            from: [r.from.major, r.from.minor],
            before: r.before.map(|b| [b.major, b.minor]),
        })
        .collect()
}

/// The brightness the integrator predicts for a flagged lobe, from what the job read off its
/// node (`detail`): a white single-scatter glossy lobe's E_avg, or the hand-made Mix
/// Shader's mean over a white base; none where a value is linked or the lobe is not
/// modelled. Results are kept, as a library repeats the same few lobes.
pub struct Predictor {
    version: BlenderVersion,
    integrator: AlbedoIntegrator,
    known: HashMap<String, Option<f64>>,
}

impl Predictor {
    pub fn new(version: BlenderVersion) -> Self {
        Predictor {
            version,
            integrator: AlbedoIntegrator::default(),
            known: HashMap::new(),
        }
    }

    pub fn predict(&mut self, rule: &str, detail: &serde_json::Value) -> Option<f64> {
        let key = format!("{rule} {detail}");
        if let Some(known) = self.known.get(&key) {
            return *known;
        }
        let value = self.compute(rule, detail);
        self.known.insert(key, value);
        value
    }

    fn compute(&self, rule: &str, detail: &serde_json::Value) -> Option<f64> {
        let distribution: Distribution = detail["distribution"].as_str()?.parse().ok()?;
        let roughness = Roughness::new(detail["roughness"].as_f64()?).ok()?;
        // An anisotropic lobe (or one whose anisotropy is linked) is not the tabulated one.
        if detail
            .get("anisotropy")
            .is_some_and(|a| a.as_f64() != Some(0.0))
        {
            return None;
        }
        let glossy = Glossy::new(distribution, self.version.masking(), roughness);
        match rule {
            "glossy-single-scatter" => Some(self.integrator.average_albedo(&glossy)),
            "mix-fresnel-layering" => {
                let ior = detail["ior"].as_f64()?;
                (1.0..=3.0)
                    .contains(&ior)
                    .then(|| Coat::new(&self.integrator, glossy, ior).hand_mix_average([1.0; 3])[0])
            }
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_rule_is_listed_once_and_words_its_versions() {
        for (i, r) in RULES.iter().enumerate() {
            assert!(RULES[..i].iter().all(|o| o.id != r.id), "{} twice", r.id);
        }
        let p = rule("principled-creates-energy").unwrap();
        assert_eq!(p.versions(), "3.0 to 3.x");
        assert!(p.applies(v(3, 4)) && p.applies(v(3, 6)) && !p.applies(v(4, 0)));
        let m = rule("metallic-single-scatter").unwrap();
        assert!(!m.applies(v(4, 2)) && m.applies(v(4, 3)) && m.applies(v(5, 0)));
        assert_eq!(m.versions(), "4.3 and later");
    }

    /// docs/AUDIT.md lists every rule, with the effect, versions and severity the catalogue
    /// gives it.
    #[test]
    fn the_documentation_lists_every_rule_as_the_catalogue_has_it() {
        let doc = include_str!("../../../../docs/AUDIT.md");
        let section = doc.split("\n## Rules\n").nth(1).expect("a Rules section");
        let section = section.split("\n## ").next().unwrap_or(section);
        let rows: Vec<Vec<&str>> = section
            .lines()
            .filter(|l| l.starts_with("| `"))
            .map(|l| l.split('|').map(str::trim).collect())
            .collect();
        assert_eq!(rows.len(), RULES.len(), "one row per rule");
        for (row, rule) in rows.iter().zip(RULES) {
            assert_eq!(row[1], format!("`{}`", rule.id), "in the catalogue's order");
            assert_eq!(row[2], rule.effect.key(), "{}", rule.id);
            assert_eq!(row[3], rule.versions(), "{}", rule.id);
            assert_eq!(row[4], rule.severity.key(), "{}", rule.id);
        }
    }

    /// The quoted strings that follow each of `openings` in `text`.
    fn quoted_after<'a>(text: &'a str, openings: &[&str]) -> Vec<&'a str> {
        let mut found = Vec::new();
        for opening in openings {
            for (i, _) in text.match_indices(opening) {
                let rest = &text[i + opening.len()..];
                found.extend(rest.split('"').next());
            }
        }
        found
    }

    /// The rule ids the Python job reports and replaces are the catalogue's, and every
    /// catalogue rule is reported by it: the two sides agree without a Blender.
    #[test]
    fn the_python_detectors_report_exactly_the_catalogues_rules() {
        let py = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../blender/gloffuse_blender/"
        );
        let read = |name: &str| std::fs::read_to_string(format!("{py}{name}")).unwrap();
        let (rules, job, twin) = (
            read("audit_rules.py"),
            read("audit_job.py"),
            read("audit_twin.py"),
        );
        let openings = [
            "finding(\"",
            "\"rule\": \"",
            "rule_microfacet_single_scatter(\"",
        ];
        let mut reported = quoted_after(&rules, &openings);
        reported.extend(quoted_after(&job, &openings));
        for id in &reported {
            assert!(
                rule(id).is_some(),
                "the job reports {id}, which the catalogue lacks"
            );
        }
        for r in RULES
            .iter()
            .filter(|r| !REPORTED_BY_GLOFFUSE.contains(&r.id))
        {
            assert!(
                reported.contains(&r.id),
                "no detector in the job reports {}",
                r.id
            );
        }
        let replaced = twin
            .split("REPLACEMENTS = {")
            .nth(1)
            .expect("audit_twin's table");
        let replaced = replaced.split('}').next().unwrap();
        let keys = quoted_after(replaced, &["\n    \""]);
        assert!(keys.len() >= 5, "{keys:?}");
        for id in keys {
            assert!(
                rule(id).is_some(),
                "audit_twin replaces {id}, which the catalogue lacks"
            );
        }
        assert_eq!(quoted_after("x finding(\"a-b\", y)", &openings), ["a-b"]);
    }

    #[test]
    fn a_white_ggx_lobe_at_roughness_1_keeps_41_percent() {
        // The measured furnace mean in Blender 4.5 and 5.0 is 0.409 (64 px, 32 spp).
        let mut p = Predictor::new(v(4, 5));
        let detail = serde_json::json!({"distribution": "GGX", "roughness": 1.0});
        let e = p.predict("glossy-single-scatter", &detail).unwrap();
        assert!((e - 0.409).abs() < 0.003, "{e}");
        let linked = serde_json::json!({"distribution": "GGX", "roughness": null});
        assert_eq!(p.predict("glossy-single-scatter", &linked), None);
        let aniso = serde_json::json!({"distribution": "GGX", "roughness": 0.5, "anisotropy": 0.8});
        assert_eq!(p.predict("glossy-single-scatter", &aniso), None);
    }
}
