//! The value parsers, and the help of each value of an enumerated flag.

use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser};

use gloffuse::audit::Verdict;
use gloffuse::fit::{Point, Target, Weighting};
use gloffuse::generate::{ColorModel, Mode};
use gloffuse::lut::{Bits, Format, GModel, Kind, Method};
use gloffuse::measure::brdf::Model;
use gloffuse::measure::{BlenderVersion, Distribution, Engine, Roughness};
use gloffuse::shard::Shard;

/// One value of an enumerated flag: the value, its help, and another spelling it accepts.
pub struct Choice<T: 'static> {
    value: T,
    help: &'static str,
    alias: Option<&'static str>,
}

const fn choice<T>(value: T, help: &'static str) -> Choice<T> {
    Choice {
        value,
        help,
        alias: None,
    }
}

/// A parser for one of `choices`, spelled as `key` names them (the library's spelling, so
/// the command line and the files agree); `--help` lists each with its help.
pub(super) fn one_of<T: Copy + Send + Sync + 'static>(
    choices: &'static [Choice<T>],
    key: fn(T) -> &'static str,
) -> impl TypedValueParser<Value = T> {
    let values = choices.iter().map(move |c| {
        let v = PossibleValue::new(key(c.value)).help(c.help);
        match c.alias {
            Some(a) => v.alias(a),
            None => v,
        }
    });
    PossibleValuesParser::new(values).map(move |name| {
        choices
            .iter()
            .find(|c| key(c.value) == name || c.alias == Some(name.as_str()))
            .map(|c| c.value)
            .expect("clap only passes a listed value")
    })
}

pub(super) const MODES: &[Choice<Mode>] = &[
    choice(
        Mode::Roughness,
        "gain 100/f(r): the sphere's mean is 100 %, its centre darker, its rim brighter",
    ),
    choice(
        Mode::View,
        "gain 1/E(μ, r) with μ = N·I: every pixel of a furnace sphere is 100 %",
    ),
    choice(
        Mode::Multiscatter,
        "Glossy plus a diffuse lobe of colour × (1 − E(μ, r)): every pixel 100 %, highlight unchanged",
    ),
    choice(
        Mode::Layered,
        "a dielectric glossy coat (IOR) over a diffuse base: a white base reflects 100 % at every pixel",
    ),
    choice(
        Mode::Anisotropic,
        "an anisotropic Glossy (GGX; Cycles) with gain 1/E(μ, φ, αx, αy), φ the view's azimuth from the tangent: every pixel 100 %",
    ),
    choice(
        Mode::Glass,
        "Glass and Refraction BSDFs (GGX, Beckmann; Cycles) with gain 1/E(μ, r, η), η = IOR on front faces and 1/IOR on back faces: every interface returns all the light meeting it",
    ),
];

pub(super) const ENGINES: &[Choice<Engine>] = &[
    choice(
        Engine::Cycles,
        "Cycles: each distribution as its Glossy node evaluates it",
    ),
    choice(
        Engine::Eevee,
        "EEVEE (Legacy in 3.x, Next in 4.2+): every distribution renders as its split-sum GGX",
    ),
];

pub(super) const COLOR_MODELS: &[Choice<ColorModel>] = &[
    choice(
        ColorModel::Exact,
        "the surface's albedo is exactly Color at every roughness",
    ),
    choice(
        ColorModel::Physical,
        "the energy of multiple bounces is tinted by Color (Kulla–Conty, as Multiscatter GGX does): rough coloured metals come out darker and more saturated",
    ),
];

pub(super) const TARGETS: &[Choice<Target>] = &[
    choice(
        Target::Mean,
        "E_avg(r): the mean brightness of an evenly lit sphere",
    ),
    choice(
        Target::Center,
        "E(1, r): the brightness at the centre of the sphere (view along the normal)",
    ),
];

pub(super) const WEIGHTINGS: &[Choice<Weighting>] = &[
    choice(
        Weighting::Absolute,
        "minimise the error in brightness points",
    ),
    choice(
        Weighting::Relative,
        "minimise the relative error f/y − 1, i.e. the gain error (right for a gain)",
    ),
];

pub(super) const KINDS: &[Choice<Kind>] = &[
    choice(Kind::SplitSum, "GGX split-sum (R = scale, G = bias)"),
    choice(
        Kind::KullaConty,
        "Kulla–Conty for a Cycles Glossy BSDF (R = scale, G = bias, B = ∫f_ms cos, A = E_avg)",
    ),
    choice(
        Kind::Albedo,
        "Kulla–Conty's albedo tables for a Cycles Glossy BSDF (R = E(μ, r), G = E_avg(r))",
    ),
    choice(
        Kind::Coat,
        "the layered shader's dielectric coat: 12 IOR slices side by side (R = A(μ, r, IOR), G = E(μ, r))",
    ),
    choice(
        Kind::Anisotropic,
        "Cycles' anisotropic GGX or Beckmann lobe: 16 view azimuths × --size bitangent widths of slices at grid points (R = E(μ, φ, αx, αy), G = E_avg(αx, αy))",
    ),
    choice(
        Kind::Glass,
        "Cycles' Glass and Refraction BSDFs: 12 IOR slices side by side, light entering (top row) and leaving (bottom row) (R = E(μ, r, η) of Glass, G = of Refraction)",
    ),
];

pub(super) const G_MODELS: &[Choice<GModel>] = &[
    choice(
        GModel::Ue4,
        "separable Schlick-GGX with k = α/2 (Karis' UE4 table)",
    ),
    choice(
        GModel::HeightCorrelated,
        "Smith GGX height-correlated, G2 = 1/(1 + Λ(V) + Λ(L)) (Cycles 3.5+, Filament)",
    ),
];

pub(super) const METHODS: &[Choice<Method>] = &[
    choice(
        Method::Quadrature,
        "deterministic Gauss–Legendre quadrature cut at the horizon of L: within 5e-5",
    ),
    choice(
        Method::Classic,
        "the textbook (UE4) estimator to the letter: H ~ D·N·H; up to 1e-2 off near grazing at 1024",
    ),
];

pub(super) const FORMATS: &[Choice<Format>] = &[
    choice(Format::Exr, "OpenEXR, ZIP-compressed scan lines"),
    choice(Format::Dds, "DirectDraw Surface with a DX10 header"),
    Choice {
        value: Format::Ktx,
        help: "KTX 2.0 (not KTX 1)",
        alias: Some("ktx"),
    },
];

pub(super) const BITS: &[Choice<Bits>] = &[
    choice(
        Bits::Half,
        "IEEE half floats (what GPUs sample fastest; rounding error ≤ 2.5e-4 below 1)",
    ),
    choice(
        Bits::Float,
        "IEEE single floats (exactly the computed values)",
    ),
];

pub(super) fn parse_distribution(s: &str) -> Result<Distribution, String> {
    s.parse()
        .map_err(|e: gloffuse::measure::Error| e.to_string())
}

pub(super) fn parse_model(s: &str) -> Result<Model, String> {
    s.parse()
        .map_err(|e: gloffuse::measure::Error| e.to_string())
}

pub(super) fn parse_ior(s: &str) -> Result<f64, String> {
    let max = gloffuse::measure::coat::IOR_MAX;
    match s.trim().parse::<f64>() {
        Ok(n) if (1.0..=max).contains(&n) => Ok(n),
        _ => Err(format!(
            "'{s}' is not an index of refraction from 1 to {max} (e.g. 1.5, glass)"
        )),
    }
}

pub(super) fn parse_roughness(s: &str) -> Result<Roughness, String> {
    s.parse()
        .map_err(|e: gloffuse::measure::Error| e.to_string())
}

pub(super) fn parse_version(s: &str) -> Result<BlenderVersion, String> {
    s.parse()
        .map_err(|e: gloffuse::measure::Error| e.to_string())
}

pub(super) fn parse_point(s: &str) -> Result<Point, String> {
    s.parse().map_err(|e: gloffuse::Error| e.to_string())
}

pub(super) fn parse_mu(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 && v <= 1.0 => Ok(v),
        _ => Err(format!(
            "invalid view cosine '{s}': expected a number in (0, 1], e.g. 1 or 0.5"
        )),
    }
}

pub(super) fn parse_color(s: &str) -> Result<[f64; 3], String> {
    let bad = || {
        format!(
            "invalid colour '{s}': expected R,G,B, three numbers from 0 to 1, e.g. 0.95,0.64,0.54"
        )
    };
    let values: Vec<f64> = s
        .split(',')
        .map(|v| v.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| bad())?;
    match values.as_slice() {
        &[r, g, b] if values.iter().all(|v| (0.0..=1.0).contains(v)) => Ok([r, g, b]),
        _ => Err(bad()),
    }
}

pub(super) fn parse_tolerance(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 && v <= 100.0 => Ok(v),
        _ => Err(format!(
            "invalid tolerance '{s}': expected a percentage above 0 and at most 100, e.g. 1"
        )),
    }
}

pub(super) fn parse_shard(s: &str) -> Result<Shard, String> {
    s.parse::<Shard>()
        .map_err(|e| e.render(|_| "shard".to_string()))
}

pub(super) fn parse_verdict(s: &str) -> Result<Verdict, String> {
    Verdict::ALL
        .into_iter()
        .find(|v| v.key() == s.trim())
        .ok_or_else(|| format!("invalid verdict '{s}': expected ok, loses, creates or error"))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `--mode` offers every mode the library has, each once and in its order, so a new mode
    /// cannot be verified or generated without a choice and its help.
    #[test]
    fn the_mode_choices_are_every_mode() {
        let offered: Vec<Mode> = MODES.iter().map(|c| c.value).collect();
        assert_eq!(offered, Mode::ALL);
        assert!(MODES.iter().all(|c| !c.help.is_empty()));
    }
}
