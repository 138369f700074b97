//! Independent oracles shared by the integration tests.
#![allow(dead_code)]

use glam::DVec3;
use gloffuse::microfacet::Glossy;
use std::f64::consts::{FRAC_PI_2, PI};

/// Brute-force `E(μ)`: a plain midpoint rule over the half vector with the map
/// `tan θh = α tan(πx/2)`, over the full azimuth, evaluating the public
/// `Glossy::eval_cos` (so it shares nothing with the integrator but the BSDF itself).
pub fn brute_force_albedo(glossy: &Glossy, mu: f64, nx: usize, nphi: usize) -> f64 {
    let wo = DVec3::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu);
    let a = glossy.alpha.max(1e-4);
    let mut sum = 0.0;
    for ix in 0..nx {
        let x = (ix as f64 + 0.5) / nx as f64;
        let t = (FRAC_PI_2 * x).tan();
        let theta = (a * t).atan();
        // dθ/dx = α (π/2) sec²(πx/2) / (1 + α² tan²(πx/2))
        let dtheta = a * FRAC_PI_2 * (1.0 + t * t) / (1.0 + a * a * t * t);
        let (st, ct) = theta.sin_cos();
        let mut ring = 0.0;
        for ip in 0..nphi {
            let phi = 2.0 * PI * (ip as f64 + 0.5) / nphi as f64;
            let h = DVec3::new(st * phi.cos(), st * phi.sin(), ct);
            let od = wo.dot(h);
            if od <= 0.0 {
                continue;
            }
            let wi = 2.0 * od * h - wo;
            ring += glossy.eval_cos(wo, wi) * 4.0 * od;
        }
        sum += ring * st * dtheta;
    }
    sum * (2.0 * PI / nphi as f64) / nx as f64
}
