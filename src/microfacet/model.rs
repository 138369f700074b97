//! The Glossy BSDF exactly as Cycles evaluates it for a white colour (Fresnel = 1).
//!
//! Names follow the equations (pbrt style): `d` is the normal distribution D(h),
//! `lambda` is Smith's Λ(ω), `g2` the masking–shadowing term, `eval_cos` is f(ωo, ωi) cosθi.
//! Vectors live in the local shading frame with the normal along +z.

use glam::DVec3;
use std::f64::consts::PI;

use crate::Error;

/// The three single-scattering distributions of Blender's Glossy BSDF.
#[derive(
    Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize, serde::Deserialize,
)]
#[serde(rename_all = "kebab-case")]
pub enum Distribution {
    Beckmann,
    Ggx,
    AshikhminShirley,
}

impl Distribution {
    pub const ALL: [Distribution; 3] = [
        Distribution::Beckmann,
        Distribution::Ggx,
        Distribution::AshikhminShirley,
    ];

    /// The CLI / file spelling: `beckmann`, `ggx`, `ashikhmin-shirley`.
    pub fn key(self) -> &'static str {
        match self {
            Distribution::Beckmann => "beckmann",
            Distribution::Ggx => "ggx",
            Distribution::AshikhminShirley => "ashikhmin-shirley",
        }
    }

    /// Blender's enum spelling for `ShaderNodeBsdfGlossy.distribution`.
    pub fn blender_enum(self) -> &'static str {
        match self {
            Distribution::Beckmann => "BECKMANN",
            Distribution::Ggx => "GGX",
            Distribution::AshikhminShirley => "ASHIKHMIN_SHIRLEY",
        }
    }

    /// The human label used in node-group names: `Beckmann`, `GGX`, `Ashikhmin-Shirley`.
    pub fn label(self) -> &'static str {
        match self {
            Distribution::Beckmann => "Beckmann",
            Distribution::Ggx => "GGX",
            Distribution::AshikhminShirley => "Ashikhmin-Shirley",
        }
    }
}

impl std::fmt::Display for Distribution {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.key())
    }
}

impl std::str::FromStr for Distribution {
    type Err = Error;

    /// Case-insensitive; `-` and `_` are interchangeable, so Blender's `ASHIKHMIN_SHIRLEY` works.
    fn from_str(s: &str) -> Result<Self, Error> {
        let norm = s.trim().to_ascii_lowercase().replace('_', "-");
        match norm.as_str() {
            "beckmann" => Ok(Distribution::Beckmann),
            "ggx" => Ok(Distribution::Ggx),
            "ashikhmin-shirley" => Ok(Distribution::AshikhminShirley),
            _ => Err(Error::input(
                "distribution",
                s,
                "one of beckmann, ggx, ashikhmin-shirley (case-insensitive; Blender's BECKMANN, GGX, ASHIKHMIN_SHIRLEY also work)",
            )),
        }
    }
}

/// How the microfacet masking and shadowing combine (Blender version dependent).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Masking {
    /// `G2 = G1(ωi) G1(ωo)`: Blender 3.x.
    Separable,
    /// `G2 = 1 / (1 + Λ(ωi) + Λ(ωo))`: Blender 4.0 and later.
    HeightCorrelated,
}

impl Masking {
    pub fn key(self) -> &'static str {
        match self {
            Masking::Separable => "separable",
            Masking::HeightCorrelated => "height-correlated",
        }
    }
}

impl std::fmt::Display for Masking {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.key())
    }
}

impl std::str::FromStr for Masking {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self, Error> {
        match s.trim().to_ascii_lowercase().replace('_', "-").as_str() {
            "separable" => Ok(Masking::Separable),
            "height-correlated" => Ok(Masking::HeightCorrelated),
            _ => Err(Error::input(
                "masking",
                s,
                "separable (Blender 3.x) or height-correlated (Blender 4.0+)",
            )),
        }
    }
}

/// A Glossy node `Roughness` value, guaranteed finite and in [0, 1] (parse, don't validate).
#[derive(Clone, Copy, Debug, PartialEq, PartialOrd)]
pub struct Roughness(f64);

impl Roughness {
    /// Build from a number; refuses NaN, infinities and values outside [0, 1].
    pub fn new(value: f64) -> Result<Self, Error> {
        if value.is_finite() && (0.0..=1.0).contains(&value) {
            Ok(Roughness(value))
        } else {
            Err(Error::input(
                "roughness",
                &value.to_string(),
                "a number from 0 to 1 (Blender clamps the Roughness socket to [0, 1])",
            ))
        }
    }

    pub fn get(self) -> f64 {
        self.0
    }

    /// Blender's mapping from the node's Roughness to the microfacet width: `alpha = r²`.
    pub fn alpha(self) -> f64 {
        self.0 * self.0
    }
}

impl std::str::FromStr for Roughness {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self, Error> {
        let v: f64 = s
            .trim()
            .parse()
            .map_err(|_| Error::input("roughness", s, "a number from 0 to 1, for example 0.5"))?;
        Roughness::new(v)
    }
}

/// One Glossy BSDF configuration: a distribution, a masking form and a width `alpha`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Glossy {
    pub distribution: Distribution,
    pub masking: Masking,
    pub alpha: f64,
}

impl Glossy {
    pub fn new(distribution: Distribution, masking: Masking, roughness: Roughness) -> Self {
        Glossy {
            distribution,
            masking,
            alpha: roughness.alpha(),
        }
    }

    /// Ashikhmin–Shirley exponent as Cycles derives it from alpha: `n = 2/α² − 2`,
    /// with α clamped to [1e-4, 1] first.
    pub fn ashikhmin_shirley_exponent(&self) -> f64 {
        let a = self.alpha.clamp(1e-4, 1.0);
        2.0 / (a * a) - 2.0
    }

    /// Normal distribution D(h) for a microfacet normal with cosine `cos_h` to the normal.
    /// Beckmann: `exp(−tan²θ/α²) / (π α² cos⁴θ)`; GGX: `α² / (π (1 + (α² − 1) cos²θ)²)`.
    /// For Ashikhmin–Shirley this is the normalised lobe `(n + 2)/(2π) cosⁿθ`
    /// (only used by tests; the BSDF itself is evaluated in [`Glossy::eval_cos`]).
    pub fn d(&self, cos_h: f64) -> f64 {
        if cos_h <= 0.0 {
            return 0.0;
        }
        let a2 = self.alpha * self.alpha;
        let c2 = cos_h * cos_h;
        match self.distribution {
            Distribution::Beckmann => {
                let tan2 = (1.0 - c2) / c2;
                (-tan2 / a2).exp() / (PI * a2 * c2 * c2)
            }
            Distribution::Ggx => {
                let t = 1.0 + (a2 - 1.0) * c2;
                a2 / (PI * t * t)
            }
            Distribution::AshikhminShirley => {
                let n = self.ashikhmin_shirley_exponent();
                (n + 2.0) / (2.0 * PI) * cos_h.powf(n)
            }
        }
    }

    /// Smith's Λ for a direction with cosine `cos_t` to the normal.
    /// GGX: the exact `(√(1 + α² tan²θ) − 1)/2`. Beckmann: Walter's rational approximation,
    /// as Cycles uses it, with `a = 1/(α tanθ)`.
    pub fn lambda(&self, cos_t: f64) -> f64 {
        let c2 = cos_t * cos_t;
        let tan2 = ((1.0 - c2) / c2).max(0.0);
        let a2t2 = self.alpha * self.alpha * tan2;
        match self.distribution {
            Distribution::Ggx => ((1.0 + a2t2).sqrt() - 1.0) * 0.5,
            // Cycles' Ashikhmin–Shirley has no masking term: its max(cosθi, cosθo) plays that role.
            Distribution::AshikhminShirley => 0.0,
            Distribution::Beckmann => {
                // a ≥ 1.6 ⇔ α² tan²θ ≤ 1/1.6² = 0.390625
                if a2t2 < 0.39 {
                    0.0
                } else {
                    let a = 1.0 / a2t2.sqrt();
                    ((0.396 * a - 1.259) * a + 1.0) / ((2.181 * a + 3.535) * a)
                }
            }
        }
    }

    /// Masking–shadowing `G2(ωo, ωi)` from the cosines of the two directions.
    pub fn g2(&self, cos_o: f64, cos_i: f64) -> f64 {
        let (lo, li) = (self.lambda(cos_o), self.lambda(cos_i));
        match self.masking {
            Masking::Separable => 1.0 / ((1.0 + lo) * (1.0 + li)),
            Masking::HeightCorrelated => 1.0 / (1.0 + lo + li),
        }
    }

    /// `f(ωo, ωi) cosθi` for reflection, the quantity whose integral over ωi is the albedo.
    /// Microfacet: `D G2 / (4 cosθo)`. Ashikhmin–Shirley (Cycles, Fresnel omitted):
    /// `cosθi (n + 1)/(8π) (h·n)ⁿ / ((h·ωi) max(cosθi, cosθo))`.
    pub fn eval_cos(&self, wo: DVec3, wi: DVec3) -> f64 {
        let (cos_o, cos_i) = (wo.z, wi.z);
        if cos_o <= 0.0 || cos_i <= 0.0 {
            return 0.0;
        }
        let h = (wo + wi).normalize();
        match self.distribution {
            Distribution::Beckmann | Distribution::Ggx => {
                self.d(h.z) * self.g2(cos_o, cos_i) / (4.0 * cos_o)
            }
            Distribution::AshikhminShirley => {
                let n = self.ashikhmin_shirley_exponent();
                cos_i * (n + 1.0) / (8.0 * PI) * h.z.powf(n) / (h.dot(wi) * cos_i.max(cos_o))
            }
        }
    }
}
