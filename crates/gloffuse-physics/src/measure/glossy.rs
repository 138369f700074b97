//! The Glossy BSDF exactly as Cycles evaluates and samples it for a white colour
//! (Fresnel = 1): a [`Microfacet`] lobe with the masking family of a Blender version.

use glam::DVec3;
use std::f64::consts::PI;

use super::microfacet::{Distribution, Masking, Microfacet, Polar, Roughness};

/// One Glossy BSDF configuration: a lobe and a masking form.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Glossy {
    pub microfacet: Microfacet,
    pub masking: Masking,
}

/// One half-vector sample of Cycles' sampler (see [`Glossy::half_vector_sample`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HalfVectorSample {
    /// `ωo·h` as the sampler uses it (the cosine a Fresnel term would take).
    pub o_dot_h: f64,
    /// `f cosθi / pdf`, with the pdf of h per solid angle mapped to ωi; 0 below the horizon.
    pub weight: f64,
}

impl Glossy {
    pub fn new(distribution: Distribution, masking: Masking, roughness: Roughness) -> Self {
        Glossy {
            microfacet: Microfacet::new(distribution, roughness),
            masking,
        }
    }

    pub fn distribution(&self) -> Distribution {
        self.microfacet.distribution
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
        let m = self.microfacet;
        match m.distribution {
            Distribution::Beckmann | Distribution::Ggx => {
                m.d(h.z) * m.g2(self.masking, cos_o, cos_i) / (4.0 * cos_o)
            }
            Distribution::AshikhminShirley => {
                let n = m.ashikhmin_shirley_exponent();
                cos_i * (n + 1.0) / (8.0 * PI) * h.z.powf(n) / (h.dot(wi) * cos_i.max(cos_o))
            }
        }
    }

    /// The sample Cycles' sampler makes from half vector h (polar angle `h`, azimuth with
    /// cosine `cos_phi` from the view's plane) for the view cosine `mu` (`sin_o = √(1 − μ²)`),
    /// where h is drawn with density [`Microfacet::pdf_h`].
    ///
    /// Microfacet: the reflection about h, weight `G2 (ωo·h) / (μ cosθh)`.
    /// Ashikhmin–Shirley: weight `cosθi / max(cosθi, μ)` — and Cycles' sampler, when h faces
    /// away from the viewer (ωo·h < 0), flips h *after* taking ωo·h, which sends the sample to
    /// `−ωo − 2(ωo·h)h` instead of discarding it. Those samples add energy at oblique views
    /// (a rough sphere's mean rises from 0.215 to 0.240 at r = 1, as Blender renders it);
    /// gloffuse reproduces what Cycles renders, quirk included.
    #[inline]
    pub fn half_vector_sample(
        &self,
        mu: f64,
        sin_o: f64,
        h: Polar,
        cos_phi: f64,
    ) -> HalfVectorSample {
        let o_dot_h = sin_o * h.sin * cos_phi + mu * h.cos;
        match self.microfacet.distribution {
            Distribution::Beckmann | Distribution::Ggx => {
                let cos_i = 2.0 * o_dot_h * h.cos - mu;
                let weight = if cos_i <= 0.0 {
                    0.0
                } else {
                    self.microfacet.g2(self.masking, mu, cos_i) * o_dot_h / (mu * h.cos)
                };
                HalfVectorSample { o_dot_h, weight }
            }
            Distribution::AshikhminShirley => {
                let o_dot_h = o_dot_h.abs();
                let cos_i = 2.0 * o_dot_h * h.cos - mu;
                let weight = if cos_i <= 0.0 {
                    0.0
                } else {
                    cos_i / cos_i.max(mu)
                };
                HalfVectorSample { o_dot_h, weight }
            }
        }
    }

    /// The weight `f cosθi / pdf = G2(μ, μi) / G1(μ) = G2 (1 + Λ(μ))` of a half vector
    /// drawn from GGX's visible normals ([`Microfacet::sample_visible_normal`]) whose
    /// reflection has cosine `cos_i`; 0 below the horizon.
    pub fn visible_normal_weight(&self, mu: f64, cos_i: f64) -> f64 {
        if cos_i <= 0.0 {
            return 0.0;
        }
        self.microfacet.g2(self.masking, mu, cos_i) * (1.0 + self.microfacet.lambda(mu))
    }
}
