//! Ward's (1992) anisotropic Gaussian lobe, with Walter's (2005) sampling.

use glam::DVec3;
use std::f64::consts::PI;

use super::{Brdf, half_vector, reflect_about, reflectance, spherical, width};
use crate::Error;

/// `f = ρs / (4π αx αy √(cosθi cosθo)) · exp(−((h·x/αx)² + (h·y/αy)²) / (h·n)²)`
/// (Ward 1992), h the (unnormalised) half vector, x the tangent.
///
/// Reciprocal exactly: h and √(cosθi cosθo) are symmetric in ωi, ωo. Not energy-conserving
/// in the other direction: its albedo tends to ρs cosθo for narrow lobes, and stays below
/// ρs for every width and view tested (α ∈ [0.05, 2], μ ∈ [0.02, 1]; tests/brdf_models.rs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ward {
    rho_s: f64,
    alpha_x: f64,
    alpha_y: f64,
}

impl Ward {
    /// ρs in [0, 1]; αx, αy finite and > 0.
    pub fn new(rho_s: f64, alpha_x: f64, alpha_y: f64) -> Result<Self, Error> {
        Ok(Ward {
            rho_s: reflectance("Ward specular reflectance rho_s", rho_s)?,
            alpha_x: width("Ward alpha_x", alpha_x)?,
            alpha_y: width("Ward alpha_y", alpha_y)?,
        })
    }

    pub fn rho_s(&self) -> f64 {
        self.rho_s
    }

    pub fn alpha_x(&self) -> f64 {
        self.alpha_x
    }

    pub fn alpha_y(&self) -> f64 {
        self.alpha_y
    }

    /// The exponent `((h·x/αx)² + (h·y/αy)²) / (h·n)²` = `tan²θh (cos²φh/αx² + sin²φh/αy²)`;
    /// h need not be normalised.
    pub fn exponent(&self, h: DVec3) -> f64 {
        let (x, y) = (h.x / self.alpha_x, h.y / self.alpha_y);
        (x * x + y * y) / (h.z * h.z)
    }

    /// Walter's half-vector density `exp(−exponent) / (π αx αy cos³θh)` (Walter 2005):
    /// the anisotropic Beckmann D times cosθh, unit mass over the hemisphere.
    pub fn pdf_h(&self, h: DVec3) -> f64 {
        if h.z <= 0.0 {
            return 0.0;
        }
        (-self.exponent(h)).exp() / (PI * self.alpha_x * self.alpha_y * h.z.powi(3))
    }
}

impl Brdf for Ward {
    fn eval(&self, wo: DVec3, wi: DVec3) -> f64 {
        let (cos_o, cos_i) = (wo.z, wi.z);
        if cos_o <= 0.0 || cos_i <= 0.0 {
            return 0.0;
        }
        let h = wo + wi;
        self.rho_s * (-self.exponent(h)).exp()
            / (4.0 * PI * self.alpha_x * self.alpha_y * (cos_i * cos_o).sqrt())
    }

    /// Walter (2005): `φh = atan2(αy sin 2πu₁, αx cos 2πu₁)`,
    /// `tan²θh = −ln(1 − u₀) / (cos²φh/αx² + sin²φh/αy²)`, then reflect ωo about h.
    fn sample(&self, wo: DVec3, u: [f64; 2]) -> Option<(DVec3, f64)> {
        let (s, c) = (2.0 * PI * u[1]).sin_cos();
        let phi = (self.alpha_y * s).atan2(self.alpha_x * c);
        let (sp, cp) = phi.sin_cos();
        let a = (cp / self.alpha_x).powi(2) + (sp / self.alpha_y).powi(2);
        let tan2 = -(-u[0]).ln_1p() / a;
        if !tan2.is_finite() {
            return None;
        }
        let cos2 = 1.0 / (1.0 + tan2);
        let h = spherical(cos2.sqrt(), (tan2 * cos2).sqrt(), phi);
        reflect_about(wo, h, self.pdf_h(h))
    }

    fn pdf(&self, wo: DVec3, wi: DVec3) -> f64 {
        match half_vector(wo, wi) {
            Some(h) => self.pdf_h(h) / (4.0 * wo.dot(h)),
            None => 0.0,
        }
    }
}
