//! The versioned coefficients file: one correction curve per distribution, with what it was
//! fitted to and where the numbers came from. Built-in presets ship in `presets/`.

use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;

use super::curve::{Curve, MAX_DEGREE, Point, Residuals, Variable, Weighting, fit_polynomial};
use crate::Error;
use crate::measure::{
    AlbedoIntegrator, BlenderVersion, Distribution, Engine, Masking, Quadrature, Roughness,
};
use crate::output::write_output;

pub const FORMAT: &str = "gloffuse-coefficients";
pub const FORMAT_VERSION: u32 = 1;

/// Built-in presets: name, file contents, one-line summary.
pub const PRESETS: [(&str, &str, &str); 4] = [
    (
        "seed",
        include_str!("../../../../presets/seed.json"),
        "the original hand-made two-point cubics (display-referred; kept for comparison)",
    ),
    (
        "blender-3",
        include_str!("../../../../presets/blender-3.json"),
        "linear-space fits to E_avg for Blender 3.0–3.4 (separable masking)",
    ),
    (
        "blender-4",
        include_str!("../../../../presets/blender-4.json"),
        "linear-space fits to E_avg for Blender 3.5 and later (height-correlated masking)",
    ),
    (
        "eevee",
        include_str!("../../../../presets/eevee.json"),
        "linear-space fits to E_avg for EEVEE (every distribution renders as its split-sum GGX)",
    ),
];

/// The preset fitted for what `engine` renders in `version`: `blender-3` or `blender-4`
/// (Cycles, by masking family) or `eevee`.
pub fn preset_for(engine: Engine, version: BlenderVersion) -> &'static str {
    preset_for_masking(engine, version.masking())
}

/// The preset fitted for what `engine` renders where Cycles uses `masking`.
pub fn preset_for_masking(engine: Engine, masking: Masking) -> &'static str {
    match (engine, masking) {
        (Engine::Cycles, Masking::Separable) => "blender-3",
        (Engine::Cycles, Masking::HeightCorrelated) => "blender-4",
        (Engine::Eevee, _) => "eevee",
    }
}

/// What brightness the curve reproduces.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Target {
    /// E_avg(r): the mean brightness of an evenly lit sphere.
    Mean,
    /// E(1, r): the brightness at the centre of the sphere (view along the normal).
    Center,
}

impl Target {
    pub const ALL: [Target; 2] = [Target::Mean, Target::Center];

    pub fn key(self) -> &'static str {
        match self {
            Target::Mean => "mean",
            Target::Center => "center",
        }
    }
}

/// Whether the percentages are linear (what a shader gain acts on) or display-encoded.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ColorSpace {
    Linear,
    /// sRGB-encoded brightness read off a screen: not valid as a linear gain.
    Display,
}

/// What a curve was fitted to.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Source {
    /// gloffuse's quadrature of the BSDF Cycles evaluates.
    Integrator,
    /// Rendered furnace spheres (`gloffuse refresh`).
    Blender,
    /// Brightness points given by hand (`gloffuse fit --point`).
    Points,
}

impl Source {
    pub fn key(self) -> &'static str {
        match self {
            Source::Integrator => "integrator",
            Source::Blender => "blender",
            Source::Points => "points",
        }
    }
}

/// Where a curve's numbers came from.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Provenance {
    pub source: Source,
    /// The Blender version measured, or whose masking the integrator modelled.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub blender_version: Option<String>,
    /// Samples per pixel (Blender) or the quadrature used (integrator).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub samples: Option<String>,
    /// Render resolution per sphere (Blender measurements).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub resolution: Option<u32>,
    /// Number of (roughness, brightness) points fitted (set by [`Coefficients::fit`]).
    pub points: usize,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub date: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub note: Option<String>,
}

/// One distribution's correction curve.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Entry {
    pub curve: Curve,
    /// Polynomial degree in r.
    pub degree: usize,
    pub target: Target,
    pub color_space: ColorSpace,
    pub masking: Masking,
    /// The engine whose Glossy the curve corrects (absent in files: Cycles).
    #[serde(default, skip_serializing_if = "Engine::is_cycles")]
    pub engine: Engine,
    pub weighting: Weighting,
    pub residuals: Residuals,
    pub provenance: Provenance,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Coefficients {
    pub format: String,
    pub format_version: u32,
    pub name: String,
    pub description: String,
    pub distributions: BTreeMap<Distribution, Entry>,
}

impl Coefficients {
    /// Loads a preset by name, or else a file by path.
    pub fn load(preset_or_path: &str) -> Result<Self, Error> {
        if let Some((_, text, _)) = PRESETS.iter().find(|(n, _, _)| *n == preset_or_path) {
            return Self::parse(text, preset_or_path);
        }
        let path = Path::new(preset_or_path);
        if !path.exists() {
            let names: Vec<&str> = PRESETS.iter().map(|p| p.0).collect();
            return Err(Error::Coefficients {
                source_name: preset_or_path.to_string(),
                message: format!("no such preset or file (presets: {})", names.join(", ")),
            });
        }
        let text = std::fs::read_to_string(path).map_err(|source| Error::Read {
            path: path.to_path_buf(),
            source,
        })?;
        Self::parse(&text, preset_or_path)
    }

    /// Parses and validates a coefficients document; `source_name` names it in errors.
    pub fn parse(text: &str, source_name: &str) -> Result<Self, Error> {
        let fail = |message: String| Error::Coefficients {
            source_name: source_name.to_string(),
            message,
        };
        let value: serde_json::Value =
            serde_json::from_str(text).map_err(|e| fail(format!("not valid JSON: {e}")))?;
        match value.get("format").and_then(|f| f.as_str()) {
            Some(FORMAT) => {}
            _ => {
                return Err(fail(format!(
                    "not a coefficients file (\"format\" must be \"{FORMAT}\")"
                )));
            }
        }
        match value.get("format_version").and_then(|v| v.as_u64()) {
            Some(v) if v == FORMAT_VERSION as u64 => {}
            Some(v) => {
                return Err(fail(format!(
                    "format_version {v} is not supported; this gloffuse reads format_version {FORMAT_VERSION}"
                )));
            }
            None => {
                return Err(fail(match value.get("format_version") {
                    None => "missing \"format_version\"".into(),
                    Some(v) => {
                        format!("\"format_version\" is {v}; expected the number {FORMAT_VERSION}")
                    }
                }));
            }
        }
        let c: Coefficients =
            serde_json::from_value(value).map_err(|e| fail(format!("malformed: {e}")))?;
        c.validate().map_err(fail)?;
        Ok(c)
    }

    /// The invariants a curve must keep for its gain to be usable on [0, 1].
    fn validate(&self) -> Result<(), String> {
        if self.distributions.is_empty() {
            return Err("holds no distributions".into());
        }
        let engine = self.engine();
        if let Some((d, e)) = self.distributions.iter().find(|(_, e)| e.engine != engine) {
            return Err(format!(
                "{d}: \"engine\" is \"{}\", but the other curves are for \"{}\" (a file holds one engine's curves)",
                e.engine.key(),
                engine.key()
            ));
        }
        for (d, e) in &self.distributions {
            let c = &e.curve;
            let all = c.numerator.iter().chain(&c.denominator);
            if let Some(bad) = all.clone().find(|x| !x.is_finite()) {
                return Err(format!("{d}: coefficient {bad} is not a finite number"));
            }
            if c.numerator.is_empty() || c.denominator.is_empty() {
                return Err(format!(
                    "{d}: numerator and denominator need at least one coefficient"
                ));
            }
            if c.degree_in_r() > MAX_DEGREE {
                return Err(format!(
                    "{d}: degree {} is above the maximum {MAX_DEGREE}",
                    c.degree_in_r()
                ));
            }
            if c.denominator[0] != 1.0 || c.numerator[0] != 100.0 {
                return Err(format!(
                    "{d}: f(0) must be 100 with a leading denominator of 1 (numerator starts with {}, denominator with {})",
                    c.numerator[0], c.denominator[0]
                ));
            }
            if c.variable == Variable::Roughness
                && (c.numerator.get(1).copied().unwrap_or(0.0) != 0.0
                    || c.denominator.get(1).copied().unwrap_or(0.0) != 0.0)
            {
                return Err(format!("{d}: the r¹ coefficient must be 0 (f'(0) = 0)"));
            }
            for i in 0..=1000 {
                let r = i as f64 / 1000.0;
                let f = c.percent(r);
                if f.is_nan() || f <= 0.0 || !f.is_finite() {
                    // Short even for absurd coefficients (1e308 prints as 309 digits).
                    let f = if f.abs() < 1e9 {
                        f.to_string()
                    } else {
                        format!("{f:.3e}")
                    };
                    return Err(format!(
                        "{d}: f({r}) = {f}: the curve must stay above 0 on roughness [0, 1] (the gain 100/f would blow up)"
                    ));
                }
            }
            if e.degree > MAX_DEGREE
                || (c.variable == Variable::Roughness && e.degree != c.degree_in_r())
            {
                return Err(format!(
                    "{d}: \"degree\" is {}, but the curve has degree {} in r (at most {MAX_DEGREE})",
                    e.degree,
                    c.degree_in_r()
                ));
            }
        }
        Ok(())
    }

    /// The engine every curve corrects (a file holds one engine's curves).
    pub fn engine(&self) -> Engine {
        self.distributions
            .values()
            .next()
            .map_or(Engine::Cycles, |e| e.engine)
    }

    pub fn to_json(&self) -> String {
        let mut s = serde_json::to_string_pretty(self).expect("coefficients serialise");
        s.push('\n');
        s
    }

    /// Writes the file to `path` atomically, after validating exactly the text written
    /// (a curve reaching 0 on [0, 1] is refused, and nothing is written).
    pub fn write(&self, path: &Path) -> Result<(), Error> {
        let text = self.to_json();
        Self::parse(&text, &path.display().to_string())?;
        write_output(path, text.as_bytes())
    }

    /// A preset or file by name, or else the preset for what `engine` renders in
    /// `version`; returns the coefficients and the name they were loaded by.
    pub fn load_or_preset(
        name: Option<&str>,
        engine: Engine,
        version: BlenderVersion,
    ) -> Result<(Self, String), Error> {
        let name = name.unwrap_or_else(|| preset_for(engine, version));
        Ok((Self::load(name)?, name.to_string()))
    }

    /// The one way to build a coefficients file: fits every distribution's points with
    /// `spec` (a polynomial in r, pinned to f(0) = 100 and f'(0) = 0).
    pub fn fit(
        name: String,
        description: String,
        spec: &FitSpec,
        points: impl IntoIterator<Item = (Distribution, Vec<Point>)>,
    ) -> Result<Self, Error> {
        let mut distributions = BTreeMap::new();
        for (d, points) in points {
            let fit = fit_polynomial(&points, Variable::Roughness, spec.degree, spec.weighting)?;
            distributions.insert(
                d,
                Entry {
                    curve: fit.curve,
                    degree: spec.degree,
                    target: spec.target,
                    color_space: ColorSpace::Linear,
                    masking: spec.masking,
                    engine: spec.engine,
                    weighting: spec.weighting,
                    residuals: fit.residuals,
                    provenance: Provenance {
                        points: points.len(),
                        ..spec.provenance.clone()
                    },
                },
            );
        }
        Ok(Coefficients {
            format: FORMAT.into(),
            format_version: FORMAT_VERSION,
            name,
            description,
            distributions,
        })
    }

    /// Measures E_avg (or E(1, r)) with the integrator for what `engine` renders in
    /// `version` on a 201-point roughness grid and fits every distribution.
    pub fn from_integrator(
        engine: Engine,
        version: BlenderVersion,
        degree: usize,
        target: Target,
        weighting: Weighting,
        date: Option<String>,
    ) -> Result<Self, Error> {
        let quadrature = Quadrature::default();
        let integrator = AlbedoIntegrator::new(quadrature);
        let rs = Roughness::grid(INTEGRATOR_POINTS);
        let mus: &[f64] = match target {
            Target::Mean => &[],
            Target::Center => &[1.0],
        };
        // The masking of the curve's model (every distribution's, for one engine).
        let masking = engine.masking(version.masking());
        let spec = FitSpec {
            degree,
            weighting,
            target,
            masking,
            engine,
            provenance: Provenance {
                source: Source::Integrator,
                blender_version: engine.is_cycles().then(|| version.to_string()),
                samples: Some(format!(
                    "Gauss-Legendre quadrature {}x{} per E(mu), {} mu nodes",
                    quadrature.theta, quadrature.phi, quadrature.mu
                )),
                resolution: None,
                points: 0,
                date,
                note: None,
            },
        };
        let points = Distribution::ALL.map(|d| {
            let (model, masking) = engine.model(d, version.masking());
            let grid = integrator.grid(model, masking, &rs, mus, &|| {});
            let values = match target {
                Target::Mean => grid.e_avg,
                Target::Center => grid.e,
            };
            let points = rs
                .iter()
                .zip(values)
                .map(|(r, e)| Point {
                    roughness: r.get(),
                    percent: 100.0 * e,
                })
                .collect();
            (d, points)
        });
        let target_text = match target {
            Target::Mean => "mean, E_avg",
            Target::Center => "centre, E(1, r)",
        };
        let description = match engine {
            Engine::Cycles => format!(
                "Linear-space brightness of a white glossy furnace sphere ({target_text}) from gloffuse's integrator, {masking} masking (Blender {version}); gain = 100 / f(r)."
            ),
            Engine::Eevee => format!(
                "Linear-space brightness of a white glossy furnace sphere in EEVEE ({target_text}) from gloffuse's integrator: EEVEE renders every distribution as GGX with separable masking (its split-sum table); gain = 100 / f(r)."
            ),
        };
        Self::fit(
            preset_for(engine, version).into(),
            description,
            &spec,
            points,
        )
    }
}

/// How many roughness values [`Coefficients::from_integrator`] fits: r = 0, 0.005, …, 1.
pub const INTEGRATOR_POINTS: usize = 201;

/// The degree of a fit to the integrator: the lowest that keeps every distribution's gain
/// within 0.1 % of 1/E_avg (measured; see docs/RESULTS.md, "Coefficients: why degree 6").
pub const INTEGRATOR_DEGREE: usize = 6;

/// How [`Coefficients::fit`] fits every distribution, and what the file records about it.
#[derive(Clone, Debug, PartialEq)]
pub struct FitSpec {
    /// Polynomial degree in r.
    pub degree: usize,
    pub weighting: Weighting,
    pub target: Target,
    /// The masking family the points were measured with.
    pub masking: Masking,
    /// The engine whose Glossy the points were measured in.
    pub engine: Engine,
    /// Where the points came from (`points` is filled in per distribution).
    pub provenance: Provenance,
}

/// Today's date (UTC, YYYY-MM-DD), or `SOURCE_DATE_EPOCH`'s when set, for reproducible files.
pub fn today() -> String {
    let now = std::env::var("SOURCE_DATE_EPOCH")
        .ok()
        .and_then(|s| s.parse::<u64>().ok())
        .map(|s| std::time::UNIX_EPOCH + std::time::Duration::from_secs(s))
        .unwrap_or_else(std::time::SystemTime::now);
    humantime::format_rfc3339(now).to_string()[..10].to_string()
}
