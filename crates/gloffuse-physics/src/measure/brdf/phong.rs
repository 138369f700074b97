//! The energy-normalised modified Phong BRDF (Lafortune & Willems 1994).

use glam::DVec3;
use std::f64::consts::PI;

use super::{Brdf, mirror, reflectance};
use crate::error::{Error, Quantity};

/// `f = ρs (n + 2)/(2π) cosⁿα`, α the angle between ωi and the mirror direction of ωo,
/// and 0 where cosα ≤ 0 (Lafortune & Willems 1994).
///
/// `cosα = ωi · mirror(ωo) = ωo · mirror(ωi)`, so it is reciprocal. The factor (n + 2)/(2π)
/// normalises `∫ cosⁿα cosθi dωi` at normal incidence, so `E(1) = ρs` exactly for every n.
/// At other views the lobe tilts and part of it (and its cosine weight) falls below the
/// horizon: `ρs μ ≤ E(μ) ≤ ρs`, with `E → ρs μ` as n → ∞ (see tests/brdf_models.rs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ModifiedPhong {
    rho_s: f64,
    n: f64,
}

impl ModifiedPhong {
    /// ρs in [0, 1], exponent n finite and ≥ 0.
    pub fn new(rho_s: f64, n: f64) -> Result<Self, Error> {
        if !(n.is_finite() && n >= 0.0) {
            return Err(Error::input(
                Quantity::ModelParameter("Phong exponent n"),
                n,
                "a finite number ≥ 0",
            ));
        }
        Ok(ModifiedPhong {
            rho_s: reflectance("Phong specular reflectance rho_s", rho_s)?,
            n,
        })
    }

    pub fn rho_s(&self) -> f64 {
        self.rho_s
    }

    pub fn exponent(&self) -> f64 {
        self.n
    }

    /// cosα between ωi and the mirror direction of ωo.
    pub fn cos_alpha(wo: DVec3, wi: DVec3) -> f64 {
        wi.dot(mirror(wo))
    }

    /// The sampling lobe `(n + 1)/(2π) cosⁿα` around the mirror direction (unit mass over
    /// the hemisphere cosα > 0).
    pub fn lobe_pdf(&self, cos_alpha: f64) -> f64 {
        if cos_alpha <= 0.0 {
            0.0
        } else {
            (self.n + 1.0) / (2.0 * PI) * cos_alpha.powf(self.n)
        }
    }
}

impl Brdf for ModifiedPhong {
    fn eval(&self, wo: DVec3, wi: DVec3) -> f64 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        let c = Self::cos_alpha(wo, wi);
        if c <= 0.0 {
            0.0
        } else {
            self.rho_s * (self.n + 2.0) / (2.0 * PI) * c.powf(self.n)
        }
    }

    /// `cosα = u₀^{1/(n+1)}`, `φ = 2π u₁` around the mirror direction (the inverse CDF of
    /// [`Self::lobe_pdf`]); draws below the horizon return `None`.
    fn sample(&self, wo: DVec3, u: [f64; 2]) -> Option<(DVec3, f64)> {
        if wo.z <= 0.0 || u[0] <= 0.0 {
            return None;
        }
        let r = mirror(wo);
        let ln_cos = u[0].ln() / (self.n + 1.0);
        let cos_a = ln_cos.exp();
        // sin²α = 1 − e^{2 ln cosα}, accurate when the lobe is narrow.
        let sin_a = (-(2.0 * ln_cos).exp_m1()).max(0.0).sqrt();
        let (t, b) = r.any_orthonormal_pair();
        let (s, c) = (2.0 * PI * u[1]).sin_cos();
        let wi = (sin_a * c * t + sin_a * s * b + cos_a * r).normalize();
        (wi.z > 0.0).then(|| (wi, self.lobe_pdf(cos_a)))
    }

    fn pdf(&self, wo: DVec3, wi: DVec3) -> f64 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            0.0
        } else {
            self.lobe_pdf(Self::cos_alpha(wo, wi))
        }
    }
}
