//! The microfacet distributions of Blender's Glossy BSDF, each formula once: the normal
//! distribution D, Smith's Λ, G1 and G2 for both masking families, the half-vector
//! sampling density with its inverse CDF, and Heitz's visible-normal sampling of GGX.
//! The albedo integrator, the Glossy BSDF, the LUTs and the classic BRDF set all use these.
//!
//! Names follow the equations (pbrt style). Vectors live in the local shading frame with the
//! normal along +z. The conventions and the Cycles source they come from are in
//! `docs/PHYSICS.md`.

use glam::DVec3;
use std::f64::consts::PI;

use crate::error::{Error, Quantity};

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

    /// The command-line and file spelling: `beckmann`, `ggx`, `ashikhmin-shirley`.
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

impl Distribution {
    /// Smith's Λ as a function of `α² tan²θ`, where for an anisotropic lobe α² is the width
    /// along the direction's azimuth, `(αx² x² + αy² y²)/(x² + y²)` (so one formula serves
    /// both). GGX: the exact `(√(1 + α² tan²θ) − 1)/2`. Beckmann: Walter's rational
    /// approximation, as Cycles uses it, with `a = 1/(α tanθ)`. Ashikhmin–Shirley: 0
    /// (Cycles' version has no masking term; its `max(cosθi, cosθo)` plays that role).
    pub fn lambda_of_alpha2_tan2(self, a2t2: f64) -> f64 {
        match self {
            Distribution::Ggx => ((1.0 + a2t2).sqrt() - 1.0) * 0.5,
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
        Distribution::ALL
            .into_iter()
            .find(|d| d.key() == norm)
            .ok_or_else(|| {
                Error::input(
                    Quantity::Distribution,
                    s,
                    "one of beckmann, ggx, ashikhmin-shirley (case-insensitive; Blender's BECKMANN, GGX, ASHIKHMIN_SHIRLEY also work)",
                )
            })
    }
}

/// How the microfacet masking and shadowing combine (Blender version dependent; see
/// [`super::BlenderVersion::masking`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Masking {
    /// `G2 = G1(ωi) G1(ωo)`: Blender 3.0–3.4.
    Separable,
    /// `G2 = 1 / (1 + Λ(ωi) + Λ(ωo))`: Blender 3.5 and later.
    HeightCorrelated,
}

impl Masking {
    pub const ALL: [Masking; 2] = [Masking::Separable, Masking::HeightCorrelated];

    pub fn key(self) -> &'static str {
        match self {
            Masking::Separable => "separable",
            Masking::HeightCorrelated => "height-correlated",
        }
    }
}

impl Masking {
    /// `G2` from the two directions' Smith Λ: `1/((1 + Λo)(1 + Λi))` or `1/(1 + Λo + Λi)`.
    pub fn g2(self, lambda_o: f64, lambda_i: f64) -> f64 {
        match self {
            Masking::Separable => 1.0 / ((1.0 + lambda_o) * (1.0 + lambda_i)),
            Masking::HeightCorrelated => 1.0 / (1.0 + lambda_o + lambda_i),
        }
    }
}

impl std::fmt::Display for Masking {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.key())
    }
}

/// A Glossy node `Roughness` value, guaranteed finite and in [0, 1] (parse, don't validate).
/// It serialises as the plain number.
#[derive(Clone, Copy, Debug, PartialEq, PartialOrd, serde::Serialize)]
#[serde(transparent)]
pub struct Roughness(f64);

impl Roughness {
    /// Build from a number; refuses NaN, infinities and values outside [0, 1].
    pub fn new(value: f64) -> Result<Self, Error> {
        if value.is_finite() && (0.0..=1.0).contains(&value) {
            Ok(Roughness(value))
        } else {
            Err(Error::input(
                Quantity::Roughness,
                value,
                "a number from 0 to 1 (the Glossy node's Roughness range)",
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

    /// `n ≥ 2` values from 0 to 1 inclusive: `j/(n − 1)`.
    pub fn grid(n: usize) -> Vec<Roughness> {
        let last = n.max(2) - 1;
        (0..=last)
            .map(|j| Roughness(j as f64 / last as f64))
            .collect()
    }

    /// The `n` pixel centres of a table over [0, 1]: `(j + ½)/n`.
    pub fn pixel_centres(n: usize) -> Vec<Roughness> {
        (0..n)
            .map(|j| Roughness((j as f64 + 0.5) / n as f64))
            .collect()
    }
}

impl std::fmt::Display for Roughness {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        self.0.fmt(f)
    }
}

impl std::str::FromStr for Roughness {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self, Error> {
        let v: f64 = s.trim().parse().map_err(|_| {
            Error::input(
                Quantity::Roughness,
                s,
                "a number from 0 to 1, for example 0.5",
            )
        })?;
        Roughness::new(v)
    }
}

/// A polar angle as cosine and sine (kept separate for precision near 0 and π/2).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Polar {
    pub cos: f64,
    pub sin: f64,
}

impl Polar {
    pub fn from_tan2(tan2: f64) -> Self {
        if tan2.is_infinite() {
            return Polar { cos: 0.0, sin: 1.0 };
        }
        let cos2 = 1.0 / (1.0 + tan2);
        Polar {
            cos: cos2.sqrt(),
            sin: (tan2 * cos2).sqrt(),
        }
    }

    /// The polar angle with `ln cosθ = log_cos`, accurate when θ is tiny.
    fn from_log_cos(log_cos: f64) -> Self {
        Polar {
            cos: log_cos.exp(),
            sin: (-(2.0 * log_cos).exp_m1()).max(0.0).sqrt(),
        }
    }
}

/// One isotropic microfacet lobe: a distribution and its width `alpha`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Microfacet {
    pub distribution: Distribution,
    pub alpha: f64,
}

impl Microfacet {
    pub fn new(distribution: Distribution, roughness: Roughness) -> Self {
        Microfacet {
            distribution,
            alpha: roughness.alpha(),
        }
    }

    /// Ashikhmin–Shirley exponent as Cycles derives it from alpha: `n = 2/α² − 2`,
    /// with α clamped to [1e-4, 1] first.
    pub fn ashikhmin_shirley_exponent(self) -> f64 {
        let a = self.alpha.clamp(1e-4, 1.0);
        2.0 / (a * a) - 2.0
    }

    /// Normal distribution D(h) for a microfacet normal with cosine `cos_h` to the normal.
    /// Beckmann: `exp(−tan²θ/α²) / (π α² cos⁴θ)`; GGX: `α² / (π (1 + (α² − 1) cos²θ)²)`.
    /// Ashikhmin–Shirley: the normalised lobe `(n + 2)/(2π) cosⁿθ` (Cycles evaluates that
    /// BSDF without a D; see [`super::Glossy::eval_cos`]).
    pub fn d(self, cos_h: f64) -> f64 {
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
    pub fn lambda(self, cos_t: f64) -> f64 {
        let c2 = cos_t * cos_t;
        let tan2 = ((1.0 - c2) / c2).max(0.0);
        self.distribution
            .lambda_of_alpha2_tan2(self.alpha * self.alpha * tan2)
    }

    /// Smith's masking `G1(ω) = 1 / (1 + Λ(ω))`.
    pub fn g1(self, cos_t: f64) -> f64 {
        1.0 / (1.0 + self.lambda(cos_t))
    }

    /// Masking–shadowing `G2(ωo, ωi)` from the cosines of the two directions.
    pub fn g2(self, masking: Masking, cos_o: f64, cos_i: f64) -> f64 {
        masking.g2(self.lambda(cos_o), self.lambda(cos_i))
    }

    /// The density with which Cycles samples the half vector, per unit solid angle:
    /// `D(h) cosθh` for the microfacet models, `(n + 1)/(2π) cosⁿθh` for Ashikhmin–Shirley.
    pub fn pdf_h(self, cos_h: f64) -> f64 {
        match self.distribution {
            Distribution::Ggx | Distribution::Beckmann => self.d(cos_h) * cos_h,
            Distribution::AshikhminShirley => {
                let n = self.ashikhmin_shirley_exponent();
                (n + 1.0) / (2.0 * PI) * cos_h.powf(n)
            }
        }
    }

    /// Lobe mass beyond polar angle θ: `S(θ) = 1 − CDF(θ)` of [`Self::pdf_h`].
    pub fn survival(self, theta: f64) -> f64 {
        let a2 = self.alpha * self.alpha;
        match self.distribution {
            Distribution::Ggx => {
                let t2 = theta.tan().powi(2);
                a2 / (a2 + t2)
            }
            Distribution::Beckmann => (-theta.tan().powi(2) / a2).exp(),
            Distribution::AshikhminShirley => {
                let n = self.ashikhmin_shirley_exponent();
                theta.cos().powf(n + 1.0)
            }
        }
    }

    /// `−dS/dθh`: the sampling density per unit polar angle.
    pub fn density(self, h: Polar) -> f64 {
        let a2 = self.alpha * self.alpha;
        let t = h.sin / h.cos;
        let t2 = t * t;
        match self.distribution {
            Distribution::Ggx => 2.0 * a2 * t * (1.0 + t2) / ((a2 + t2) * (a2 + t2)),
            Distribution::Beckmann => (-t2 / a2).exp() * 2.0 * t * (1.0 + t2) / a2,
            Distribution::AshikhminShirley => {
                let n = self.ashikhmin_shirley_exponent();
                (n + 1.0) * h.cos.powf(n) * h.sin
            }
        }
    }

    /// The inverse CDF: the polar angle with lobe mass `s` beyond it (`S(θ) = s`).
    /// GGX `tan²θ = α² (1 − s)/s`, Beckmann `tan²θ = −α² ln s`,
    /// Ashikhmin–Shirley `cosθ = s^(1/(n + 1))`.
    pub fn polar_from_survival(self, s: f64) -> Polar {
        let a2 = self.alpha * self.alpha;
        match self.distribution {
            Distribution::Ggx => Polar::from_tan2(a2 * (1.0 - s) / s),
            Distribution::Beckmann => Polar::from_tan2(-a2 * s.ln()),
            Distribution::AshikhminShirley => {
                let n = self.ashikhmin_shirley_exponent();
                Polar::from_log_cos(s.ln() / (n + 1.0))
            }
        }
    }

    /// Importance sampling of the half vector's polar angle for a uniform number `v`
    /// (the CDF value): [`Self::polar_from_survival`] of `1 − v`.
    pub fn sample_polar(self, v: f64) -> Polar {
        self.polar_from_survival(1.0 - v)
    }

    /// Heitz's (2018) sample of GGX's visible normals for the view `v` (unit, `v.z > 0`),
    /// from a point `(t1, t2)` of the unit disk: the half vector h, with density
    /// `G1(v) max(0, v·h) D(h) / v.z`. (GGX only: it is GGX's stretch-invariance.)
    pub fn sample_visible_normal(self, v: DVec3, (t1, t2): (f64, f64)) -> DVec3 {
        let alpha = self.alpha;
        let stretched = DVec3::new(alpha * v.x, alpha * v.y, v.z);
        let vh = stretched / stretched.length();
        let lensq = vh.x * vh.x + vh.y * vh.y;
        let t1_axis = if lensq > 0.0 {
            DVec3::new(-vh.y, vh.x, 0.0) / lensq.sqrt()
        } else {
            DVec3::X
        };
        let t2_axis = vh.cross(t1_axis);
        let s = 0.5 * (1.0 + vh.z);
        let t2 = (1.0 - s) * (1.0 - t1 * t1).sqrt() + s * t2;
        let w = (1.0 - t1 * t1 - t2 * t2).max(0.0).sqrt();
        let nh = t1 * t1_axis + t2 * t2_axis + w * vh;
        let h = DVec3::new(alpha * nh.x, alpha * nh.y, nh.z.max(0.0));
        h / h.length()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn g1_is_walters_rational_form_for_beckmann() {
        // Walter et al. (2007), eq. 27: G1 = (3.535a + 2.181a²)/(1 + 2.276a + 2.577a²) for
        // a < 1.6, the same function as 1/(1 + Λ) with Cycles' Λ.
        let m = Microfacet {
            distribution: Distribution::Beckmann,
            alpha: 0.7,
        };
        for cos in [0.05, 0.2, 0.4, 0.6] {
            let cos: f64 = cos;
            let tan = (1.0 - cos * cos).sqrt() / cos;
            let a = 1.0 / (m.alpha * tan);
            assert!(a < 1.6);
            let walter = (3.535 * a + 2.181 * a * a) / (1.0 + 2.276 * a + 2.577 * a * a);
            assert!((m.g1(cos) - walter).abs() < 1e-12, "{cos}");
        }
    }

    #[test]
    fn the_inverse_cdf_inverts_the_survival() {
        for distribution in Distribution::ALL {
            for alpha in [0.01, 0.3, 1.0] {
                let m = Microfacet {
                    distribution,
                    alpha,
                };
                for s in [1e-6, 0.1, 0.5, 0.9, 1.0 - 1e-9] {
                    let h = m.polar_from_survival(s);
                    let back = m.survival(h.sin.atan2(h.cos));
                    assert!(
                        (back / s - 1.0).abs() < 1e-6,
                        "{distribution} α {alpha} s {s}: {back}"
                    );
                }
            }
        }
    }

    #[test]
    fn grids_span_the_unit_interval() {
        let g: Vec<f64> = Roughness::grid(5).iter().map(|r| r.get()).collect();
        assert_eq!(g, [0.0, 0.25, 0.5, 0.75, 1.0]);
        let c: Vec<f64> = Roughness::pixel_centres(4)
            .iter()
            .map(|r| r.get())
            .collect();
        assert_eq!(c, [0.125, 0.375, 0.625, 0.875]);
    }
}
