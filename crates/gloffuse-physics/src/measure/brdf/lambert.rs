//! The Lambertian BRDF `f = ρ/π`.

use glam::DVec3;
use std::f64::consts::PI;

use super::{Brdf, cosine_pdf, reflectance, sample_cosine};
use crate::Error;

/// Ideal diffuse reflection: `f = ρ/π`, albedo ρ at every view angle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lambert {
    rho: f64,
}

impl Lambert {
    /// ρ must be in [0, 1].
    ///
    /// ```
    /// use gloffuse_physics::measure::brdf::{Brdf, Lambert};
    /// assert!((Lambert::new(0.5).unwrap().albedo(0.2, 4) - 0.5).abs() < 1e-12);
    /// assert!(Lambert::new(1.5).is_err());
    /// ```
    pub fn new(rho: f64) -> Result<Self, Error> {
        Ok(Lambert {
            rho: reflectance("Lambert reflectance rho", rho)?,
        })
    }

    pub fn rho(&self) -> f64 {
        self.rho
    }
}

impl Brdf for Lambert {
    fn eval(&self, wo: DVec3, wi: DVec3) -> f64 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            0.0
        } else {
            self.rho / PI
        }
    }

    /// Cosine sampling: the weight f cosθi / pdf is ρ for every draw.
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
