//! The diffuse term of Ashikhmin & Shirley's (2000) anisotropic Phong BRDF, eq. 5.

use glam::DVec3;
use std::f64::consts::PI;

use super::{Brdf, cosine_pdf, reflectance, sample_cosine};
use crate::Error;

/// The Fresnel-blend diffuse lobe
/// `f = (28 Rd / 23π)(1 − Rs)(1 − (1 − cosθi/2)⁵)(1 − (1 − cosθo/2)⁵)`.
///
/// The constant makes its albedo `E(μ) = Rd (1 − Rs)(1 − (1 − μ/2)⁵)`, since
/// `2π ∫₀¹ (1 − (1 − c/2)⁵) c dc = 23π/28`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FresnelBlendDiffuse {
    rd: f64,
    rs: f64,
}

impl FresnelBlendDiffuse {
    /// Rd (diffuse reflectance) and Rs (specular reflectance at normal incidence), both in
    /// [0, 1].
    pub fn new(rd: f64, rs: f64) -> Result<Self, Error> {
        Ok(FresnelBlendDiffuse {
            rd: reflectance("Fresnel-blend diffuse reflectance Rd", rd)?,
            rs: reflectance("Fresnel-blend specular reflectance Rs", rs)?,
        })
    }

    pub fn rd(&self) -> f64 {
        self.rd
    }

    pub fn rs(&self) -> f64 {
        self.rs
    }

    /// The per-direction factor `1 − (1 − cosθ/2)⁵`.
    pub fn falloff(cos_t: f64) -> f64 {
        1.0 - (1.0 - 0.5 * cos_t).powi(5)
    }
}

impl Brdf for FresnelBlendDiffuse {
    fn eval(&self, wo: DVec3, wi: DVec3) -> f64 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        28.0 * self.rd / (23.0 * PI) * (1.0 - self.rs) * Self::falloff(wi.z) * Self::falloff(wo.z)
    }

    /// Cosine sampling.
    fn sample(&self, wo: DVec3, u: [f64; 2]) -> Option<(DVec3, f64)> {
        if wo.z <= 0.0 {
            return None;
        }
        sample_cosine(u)
    }

    fn pdf(&self, wo: DVec3, wi: DVec3) -> f64 {
        cosine_pdf(wo, wi)
    }
}
