//! Independent oracles: brute-force integrals that share nothing with the integrator but
//! the BSDF itself.

use glam::DVec3;
use gloffuse::measure::{AnisotropicLobe, Glossy};
use std::f64::consts::{FRAC_PI_2, PI};

/// Brute-force `E(μ)`: a plain midpoint rule over the half vector with the map
/// `tan θh = α tan(πx/2)`, over the full azimuth, evaluating the public
/// `Glossy::eval_cos` (so it shares nothing with the integrator but the BSDF itself).
/// Ashikhmin–Shirley is integrated as Cycles samples it (see `cycles_ashikhmin_shirley`).
pub fn brute_force_albedo(glossy: &Glossy, mu: f64, nx: usize, nphi: usize) -> f64 {
    brute_force_weighted(glossy, mu, nx, nphi, &|_| 1.0)
}

/// [`brute_force_albedo`] with every direction weighted by `weight(ωo·h)` (a Fresnel term
/// at the microfacet: for Ashikhmin–Shirley, at |ωo·h| of Cycles' sampled h).
pub fn brute_force_weighted(
    glossy: &Glossy,
    mu: f64,
    nx: usize,
    nphi: usize,
    weight: &dyn Fn(f64) -> f64,
) -> f64 {
    if glossy.distribution() == gloffuse::measure::Distribution::AshikhminShirley {
        return cycles_ashikhmin_shirley(glossy, mu, nx, nphi, weight);
    }
    let wo = DVec3::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu);
    over_half_vectors(glossy.microfacet.alpha, wo, nx, nphi, &|wi, od| {
        glossy.eval_cos(wo, wi) * weight(od)
    })
}

/// Brute-force anisotropic `E(ωo)`: the same rule over the half vector, α the geometric
/// mean width, evaluating the public `AnisotropicLobe::eval_cos` (D and G2; the
/// anisotropic integrator samples the stretched lobe instead and never evaluates D).
pub fn brute_force_anisotropic(lobe: &AnisotropicLobe, wo: DVec3, nx: usize, nphi: usize) -> f64 {
    let alpha = (lobe.alpha_x * lobe.alpha_y).sqrt();
    over_half_vectors(alpha, wo, nx, nphi, &|wi, _| lobe.eval_cos(wo, wi))
}

/// The midpoint rule both brute forces share: over the half vector h with the map
/// `tan θh = α tan(πx/2)` and the full azimuth, `∫ f(ωi, ωo·h) · 4 (ωo·h) dh` with ωi the
/// mirror of ωo about h (`4 (ωo·h)` is the Jacobian from h to ωi); h facing away from ωo
/// adds nothing.
fn over_half_vectors(
    alpha: f64,
    wo: DVec3,
    nx: usize,
    nphi: usize,
    f: &dyn Fn(DVec3, f64) -> f64,
) -> f64 {
    let a = alpha.max(1e-4);
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
            ring += f(wi, od) * 4.0 * od;
        }
        sum += ring * st * dtheta;
    }
    sum * (2.0 * PI / nphi as f64) / nx as f64
}

/// Cycles' Ashikhmin–Shirley estimator, integrated by brute force, following Cycles'
/// `bsdf_ashikhmin_shirley_sample`/`_eval` step by step: h drawn with density
/// `(n+1)/(2π) cosⁿθh`; the sampler takes d = ωo·h, flips h if d < 0, and builds the light
/// direction `−ωo + 2 d h_flipped` (not a unit vector for flipped samples); eval and pdf both
/// use H = normalize(ωo + ωi) and |H·ωo|: eval = cosθi (n+1)/(8π) (N·H)ⁿ / (|H·ωo| max(cosθi, μ)),
/// pdf = (n+1)/(8π) (N·H)ⁿ / |H·ωo|; a zero pdf discards the sample.
pub fn cycles_ashikhmin_shirley(
    glossy: &Glossy,
    mu: f64,
    nx: usize,
    nphi: usize,
    weight: &dyn Fn(f64) -> f64,
) -> f64 {
    let wo = DVec3::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu);
    let n = glossy.microfacet.ashikhmin_shirley_exponent();
    let norm = (n + 1.0) / (8.0 * PI);
    let a = glossy.microfacet.alpha.max(1e-4);
    let mut sum = 0.0;
    for ix in 0..nx {
        let x = (ix as f64 + 0.5) / nx as f64;
        let t = (FRAC_PI_2 * x).tan();
        let theta = (a * t).atan();
        let dtheta = a * FRAC_PI_2 * (1.0 + t * t) / (1.0 + a * a * t * t);
        let (st, ct) = theta.sin_cos();
        let density = (n + 1.0) / (2.0 * PI) * ct.powf(n) * st * dtheta;
        let mut ring = 0.0;
        for ip in 0..nphi {
            let phi = 2.0 * PI * (ip as f64 + 0.5) / nphi as f64;
            let h = DVec3::new(st * phi.cos(), st * phi.sin(), ct);
            let d = wo.dot(h);
            let flipped = if d < 0.0 { -h } else { h };
            let wi = -wo + 2.0 * d * flipped;
            if wi.z <= 0.0 {
                continue;
            }
            let hh = (wo + wi).normalize();
            let h_dot_view = hh.dot(wo).abs();
            let lobe = hh.z.powf(n);
            let pdf = norm * lobe / h_dot_view;
            if pdf > 0.0 {
                let eval = wi.z * norm * lobe / (h_dot_view * wi.z.max(mu));
                ring += eval / pdf * weight(d.abs());
            }
        }
        sum += ring * density;
    }
    sum * (2.0 * PI / nphi as f64) / nx as f64
}
