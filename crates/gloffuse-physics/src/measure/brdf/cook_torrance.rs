//! Cook & Torrance (1982) with a Beckmann distribution and Schlick's Fresnel.

use glam::DVec3;
use std::f64::consts::PI;

use super::{Brdf, half_vector, reflect_about, reflectance, spherical, width};
use crate::Error;
use crate::measure::microfacet::{Distribution, Masking, Microfacet};

/// The masking–shadowing term G of [`CookTorrance`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Shadowing {
    /// Torrance–Sparrow's V-cavity, as in Cook & Torrance (1982):
    /// `G = min(1, 2(n·h)(n·ωo)/(ωo·h), 2(n·h)(n·ωi)/(ωi·h))`.
    VCavity,
    /// Separable Smith for Beckmann, `G = G1(ωo) G1(ωi)`, with Walter et al.'s (2007, eq. 27)
    /// rational approximation of G1 (the one Cycles uses: [`Microfacet::g1`]).
    Smith,
}

/// `f = D G F / (4 cosθi cosθo)` with the Beckmann
/// `D(h) = exp(−tan²θh/α²) / (π α² cos⁴θh)` and Schlick's `F = f0 + (1 − f0)(1 − h·ωi)⁵`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CookTorrance {
    f0: f64,
    beckmann: Microfacet,
    shadowing: Shadowing,
}

impl CookTorrance {
    /// f0 in [0, 1]; α finite and > 0. Uses the V-cavity G (see [`Self::with_shadowing`]).
    pub fn new(f0: f64, alpha: f64) -> Result<Self, Error> {
        Ok(CookTorrance {
            f0: reflectance("Cook-Torrance Fresnel f0", f0)?,
            beckmann: Microfacet {
                distribution: Distribution::Beckmann,
                alpha: width("Cook-Torrance alpha", alpha)?,
            },
            shadowing: Shadowing::VCavity,
        })
    }

    pub fn with_shadowing(self, shadowing: Shadowing) -> Self {
        CookTorrance { shadowing, ..self }
    }

    pub fn f0(&self) -> f64 {
        self.f0
    }

    pub fn alpha(&self) -> f64 {
        self.beckmann.alpha
    }

    pub fn shadowing(&self) -> Shadowing {
        self.shadowing
    }

    /// Beckmann `D(h)` from `cos_h = h·n` ([`Microfacet::d`]).
    pub fn d(&self, cos_h: f64) -> f64 {
        self.beckmann.d(cos_h)
    }

    /// Masking–shadowing G(ωo, ωi) for the half vector h.
    pub fn g(&self, wo: DVec3, wi: DVec3, h: DVec3) -> f64 {
        match self.shadowing {
            Shadowing::VCavity => {
                let masking = 2.0 * h.z * wo.z / wo.dot(h);
                let shadowing = 2.0 * h.z * wi.z / wi.dot(h);
                masking.min(shadowing).min(1.0)
            }
            Shadowing::Smith => self.beckmann.g2(Masking::Separable, wo.z, wi.z),
        }
    }

    /// Schlick's Fresnel `F = f0 + (1 − f0)(1 − cosθd)⁵`.
    pub fn fresnel(&self, cos_d: f64) -> f64 {
        self.f0 + (1.0 - self.f0) * (1.0 - cos_d).max(0.0).powi(5)
    }
}

impl Brdf for CookTorrance {
    fn eval(&self, wo: DVec3, wi: DVec3) -> f64 {
        let Some(h) = half_vector(wo, wi) else {
            return 0.0;
        };
        self.d(h.z) * self.g(wo, wi, h) * self.fresnel(h.dot(wi)) / (4.0 * wi.z * wo.z)
    }

    /// h from `D(h) cosθh` ([`Microfacet::sample_polar`]: `tan²θh = −α² ln(1 − u₀)`),
    /// `φh = 2π u₁` (Walter et al. 2007, eqs. 28–29), then reflect ωo about h.
    fn sample(&self, wo: DVec3, u: [f64; 2]) -> Option<(DVec3, f64)> {
        let polar = self.beckmann.sample_polar(u[0]);
        if polar.cos <= 0.0 {
            return None;
        }
        let h = spherical(polar.cos, polar.sin, 2.0 * PI * u[1]);
        reflect_about(wo, h, self.beckmann.pdf_h(polar.cos))
    }

    fn pdf(&self, wo: DVec3, wi: DVec3) -> f64 {
        match half_vector(wo, wi) {
            Some(h) => self.beckmann.pdf_h(h.z) / (4.0 * wo.dot(h)),
            None => 0.0,
        }
    }
}
