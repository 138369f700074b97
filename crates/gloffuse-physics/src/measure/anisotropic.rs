//! The anisotropic Glossy BSDF exactly as Cycles evaluates it for a white colour, and its
//! directional albedo `E(μ, φ, αx, αy)` by quadrature.
//!
//! Cycles stretches the lobe along the shading frame `X, Y, N` it builds from the tangent T
//! (`Y = normalize(N × T)`, `X = Y × N`): width `αx` along X, `αy` along Y. The view's
//! azimuth φ is measured from X. D is the stretched Beckmann or GGX distribution and Λ the
//! isotropic one at the width along the direction's azimuth, `α(ω)² tan²θ = (αx² x² +
//! αy² y²)/z²`. The Glossy node's Roughness r and Anisotropy a map to the widths as in
//! `svm/closure.h` (3.4 to 5.1 alike): `α = r²`, a clamped to [−0.99, 0.99], then
//! `αx = α(1 − a), αy = α/(1 − a)` for a ≥ 0 and `αx = α/(1 + a), αy = α(1 + a)` for
//! a < 0, each width clamped to at most 1 by the BSDF's setup. A negative anisotropy is a
//! positive one with X and Y swapped.
//!
//! The integrator samples the half vector by stretching the unit-width lobe (the slope
//! `(αx ρ cosψ, αy ρ sinψ)` with ρ drawn from the unit distribution, which gives the density
//! `D(h) cosθh`) and cuts each radial line exactly where the reflected direction meets the
//! horizon, so what is left is smooth: Gauss–Legendre along `v`, the square root of the
//! lobe mass within ρ (ρ ∝ v near the peak, so the line has no square-root kink there), and
//! the trapezoid rule (spectrally accurate for a smooth periodic integrand) along ψ.

use glam::DVec3;
use rayon::prelude::*;
use std::f64::consts::{FRAC_PI_2, PI};

use super::albedo::gauss_unit;
use super::microfacet::{Distribution, Masking, Roughness};
use crate::error::{Error, Quantity};

/// The Glossy node's Anisotropy input as Cycles uses it: finite, clamped to [−0.99, 0.99].
#[derive(Clone, Copy, Debug, PartialEq, PartialOrd)]
pub struct Anisotropy(f64);

impl Anisotropy {
    /// Cycles clamps the input to this magnitude.
    pub const MAX: f64 = 0.99;

    /// Any finite number, clamped as Cycles clamps it; NaN and infinities are refused.
    pub fn new(value: f64) -> Result<Self, Error> {
        if value.is_finite() {
            Ok(Anisotropy(value.clamp(-Self::MAX, Self::MAX)))
        } else {
            Err(Error::input(
                Quantity::Anisotropy,
                value,
                "a number from -1 to 1 (Cycles clamps it to ±0.99)",
            ))
        }
    }

    pub fn get(self) -> f64 {
        self.0
    }
}

/// One anisotropic microfacet lobe (GGX or Beckmann) with the masking form of a Blender
/// version.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AnisotropicLobe {
    pub distribution: Distribution,
    pub masking: Masking,
    /// Width along the tangent X, in [0, 1].
    pub alpha_x: f64,
    /// Width along the bitangent Y, in [0, 1].
    pub alpha_y: f64,
}

impl AnisotropicLobe {
    /// A lobe of the given widths; Ashikhmin–Shirley (a different model) and widths outside
    /// [0, 1] (Cycles clamps them there) are refused.
    pub fn new(
        distribution: Distribution,
        masking: Masking,
        alpha_x: f64,
        alpha_y: f64,
    ) -> Result<Self, Error> {
        if distribution == Distribution::AshikhminShirley {
            return Err(Error::input(
                Quantity::Distribution,
                distribution.key(),
                "ggx or beckmann (the anisotropic tables cover the two microfacet distributions)",
            ));
        }
        for alpha in [alpha_x, alpha_y] {
            if !(alpha.is_finite() && (0.0..=1.0).contains(&alpha)) {
                return Err(Error::input(
                    Quantity::Roughness,
                    alpha,
                    "a lobe width α from 0 to 1 (Cycles clamps wider lobes to 1)",
                ));
            }
        }
        Ok(AnisotropicLobe {
            distribution,
            masking,
            alpha_x,
            alpha_y,
        })
    }

    /// The lobe Cycles builds from a Glossy node's Roughness and Anisotropy (see the module
    /// notes for the mapping).
    pub fn from_glossy_node(
        distribution: Distribution,
        masking: Masking,
        roughness: Roughness,
        anisotropy: Anisotropy,
    ) -> Result<Self, Error> {
        let (alpha, a) = (roughness.alpha(), anisotropy.get());
        let (alpha_x, alpha_y) = if a < 0.0 {
            (alpha / (1.0 + a), alpha * (1.0 + a))
        } else {
            (alpha * (1.0 - a), alpha / (1.0 - a))
        };
        Self::new(distribution, masking, alpha_x.min(1.0), alpha_y.min(1.0))
    }

    /// Smith's Λ of direction `w` (local frame, unit, `w.z > 0`).
    pub fn lambda(&self, w: DVec3) -> f64 {
        let a2t2 = ((self.alpha_x * w.x).powi(2) + (self.alpha_y * w.y).powi(2)) / (w.z * w.z);
        self.distribution.lambda_of_alpha2_tan2(a2t2)
    }

    /// The stretched distribution `D(h)` (local frame, unit h).
    pub fn d(&self, h: DVec3) -> f64 {
        if h.z <= 0.0 {
            return 0.0;
        }
        let (sx, sy) = (h.x / (self.alpha_x * h.z), h.y / (self.alpha_y * h.z));
        let slope2 = sx * sx + sy * sy;
        let norm = PI * self.alpha_x * self.alpha_y * h.z.powi(4);
        match self.distribution {
            Distribution::Beckmann => (-slope2).exp() / norm,
            _ => 1.0 / (norm * (1.0 + slope2).powi(2)),
        }
    }

    /// `G2(ωo, ωi)` in the version's masking form.
    fn g2(&self, wo: DVec3, wi: DVec3) -> f64 {
        self.masking.g2(self.lambda(wo), self.lambda(wi))
    }

    /// `f(ωo, ωi) cosθi = D G2 / (4 cosθo)` for reflection: the albedo's integrand.
    pub fn eval_cos(&self, wo: DVec3, wi: DVec3) -> f64 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        let h = (wo + wi).normalize();
        self.d(h) * self.g2(wo, wi) / (4.0 * wo.z)
    }

    /// Cycles treats a lobe with `αx αy ≤ 1e-7` as a perfect mirror (albedo 1).
    fn is_mirror(&self) -> bool {
        self.alpha_x * self.alpha_y <= 1e-7
    }
}

/// The view direction with cosine `mu` to the normal and azimuth `phi` from the tangent X.
pub fn view(mu: f64, phi: f64) -> DVec3 {
    let sin = (1.0 - mu * mu).max(0.0).sqrt();
    DVec3::new(sin * phi.cos(), sin * phi.sin(), mu)
}

/// The direction `w` (world space) in the shading frame Cycles builds from the normal and
/// tangent: `Y = normalize(N × T)`, `X = Y × N`; returns `(w·X, w·Y, w·N)`.
pub fn local_direction(normal: DVec3, tangent: DVec3, w: DVec3) -> DVec3 {
    let y = normal.cross(tangent).normalize();
    let x = y.cross(normal);
    DVec3::new(w.dot(x), w.dot(y), w.dot(normal))
}

/// Numbers of quadrature nodes for [`AnisotropicIntegrator`]; the default meets 2e-4.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct AnisotropicQuadrature {
    /// Gauss–Legendre nodes along each of a radial line's two pieces.
    pub radial: usize,
    /// Gauss–Legendre nodes along each half of the circle of slope directions ψ.
    pub azimuth: usize,
}

impl Default for AnisotropicQuadrature {
    fn default() -> Self {
        AnisotropicQuadrature {
            radial: 24,
            azimuth: 96,
        }
    }
}

/// Precomputed rules; build once, evaluate many times (it is `Sync`).
pub struct AnisotropicIntegrator {
    radial: Vec<(f64, f64)>,
    /// Fractions of a half circle, crowded at both ends.
    azimuth: Vec<(f64, f64)>,
}

impl Default for AnisotropicIntegrator {
    fn default() -> Self {
        Self::new(AnisotropicQuadrature::default())
    }
}

impl AnisotropicIntegrator {
    pub fn new(q: AnisotropicQuadrature) -> Self {
        let smoothstep = |(t, w): (f64, f64)| (t * t * (3.0 - 2.0 * t), w * 6.0 * t * (1.0 - t));
        AnisotropicIntegrator {
            radial: gauss_unit(q.radial),
            azimuth: gauss_unit(q.azimuth).into_iter().map(smoothstep).collect(),
        }
    }

    /// Directional albedo `E = ∫ f(ωo, ωi) cosθi dωi` of `lobe` for the view `wo` (local
    /// frame, unit; views below 1e-4 of grazing are taken at that cosine).
    pub fn directional_albedo(&self, lobe: &AnisotropicLobe, wo: DVec3) -> f64 {
        if lobe.is_mirror() {
            return 1.0;
        }
        let mu = wo.z.max(1e-4);
        let wo = DVec3::new(wo.x, wo.y, mu).normalize();
        let mu = wo.z;
        // Where the slope direction is square to the view (k = 0 below), the horizon cut
        // jumps from near the peak to far out over an angle of about μ: each half circle
        // starts and ends there, and its nodes crowd at its ends.
        let psi0 = (-lobe.alpha_x * wo.x).atan2(lobe.alpha_y * wo.y);
        let lambda_o = lobe.lambda(wo);
        let mut total = 0.0;
        for (half, &(x, weight)) in [0.0, PI]
            .iter()
            .flat_map(|half| self.azimuth.iter().map(move |node| (half, node)))
        {
            let (sin_psi, cos_psi) = (psi0 + half + PI * x).sin_cos();
            // h ∝ (−ρ m, 1) with m the stretched slope direction.
            let m = (lobe.alpha_x * cos_psi, lobe.alpha_y * sin_psi);
            let m2 = m.0 * m.0 + m.1 * m.1;
            let k = m.0 * wo.x + m.1 * wo.y;
            // cosθi = 2 (ωo·h) cosθh − μ = 2(μ − ρk)/(1 + ρ² m²) − μ vanishes at ρ_h, the
            // positive root, written without cancellation: ρ_h = μ / (√(k² + μ²m²) + k).
            let rho_h = mu / ((k * k + mu * mu * m2).sqrt() + k);
            // f cosθi / pdf of the half vector at slope ρ along this line.
            let weight_at = |rho: f64| {
                let h = DVec3::new(-rho * m.0, -rho * m.1, 1.0).normalize();
                let o_dot_h = wo.dot(h);
                let wi = 2.0 * o_dot_h * h - wo;
                if wi.z <= 0.0 || o_dot_h <= 0.0 {
                    return 0.0;
                }
                let g2 = lobe.masking.g2(lambda_o, lobe.lambda(wi));
                g2 * o_dot_h / (mu * h.z)
            };
            // Up to the unit lobe's width, in v = √mass (ρ ∝ v near the peak, so no
            // square-root kink there; dmass = 2v dv).
            let v_1 = unit_cdf(lobe.distribution, rho_h.min(1.0).powi(2)).sqrt();
            let mut line = 0.0;
            for &(x, w) in &self.radial {
                let v = v_1 * x;
                line += w * 2.0 * v * v_1 * weight_at(unit_slope2(lobe.distribution, v * v).sqrt());
            }
            // Beyond it, in ln ρ: at grazing views GGX's heavy tail carries large weights
            // over decades of slope (Beckmann's mass is gone by ρ = 6).
            let rho_end = match lobe.distribution {
                Distribution::Beckmann => rho_h.min(6.0),
                _ => rho_h,
            };
            if rho_end > 1.0 {
                let span = rho_end.ln();
                for &(x, w) in &self.radial {
                    let rho = (span * x).exp();
                    line += w * span * rho * unit_density(lobe.distribution, rho) * weight_at(rho);
                }
            }
            total += weight * line;
        }
        // (1/2π) ∫ dψ over two half circles of π each.
        0.5 * total
    }
}

impl AnisotropicIntegrator {
    /// Hemispherical average `E_avg = (1/π) ∫ E(ωo) cosθo dωo`: the mean brightness of an
    /// evenly lit sphere seen by an orthographic camera whose tangents turn every way. By the
    /// lobe's mirror symmetries one quadrant of view azimuths is enough.
    pub fn average_albedo(&self, lobe: &AnisotropicLobe) -> f64 {
        if lobe.is_mirror() {
            return 1.0;
        }
        let mus = gauss_unit(AVERAGE_NODES);
        let phis = gauss_unit(AVERAGE_NODES / 2);
        let mut total = 0.0;
        for &(mu, wm) in &mus {
            for &(x, wp) in &phis {
                total +=
                    2.0 * mu * wm * wp * self.directional_albedo(lobe, view(mu, FRAC_PI_2 * x));
            }
        }
        total
    }

    /// The mean brightness of an evenly lit unit sphere seen by an orthographic camera
    /// looking down −Z, its tangent the constant world X everywhere (verify's anisotropic
    /// spheres): `(1/π) ∫∫ E μ dμ dβ` over the disk, β the angle about the view axis. Unlike
    /// [`Self::average_albedo`], whose tangents turn every way, here the view's azimuth
    /// from the tangent depends on where on the disk a pixel is. The disk's mirror
    /// symmetries in x and y (which mirror the azimuth, and the lobe is mirror symmetric)
    /// leave one quadrant of β.
    pub fn constant_tangent_sphere_mean(&self, lobe: &AnisotropicLobe) -> f64 {
        if lobe.is_mirror() {
            return 1.0;
        }
        let mus = gauss_unit(AVERAGE_NODES);
        let betas = gauss_unit(AVERAGE_NODES);
        let mut total = 0.0;
        for &(mu, wm) in &mus {
            let rho = (1.0 - mu * mu).sqrt();
            for &(x, wb) in &betas {
                let beta = FRAC_PI_2 * x;
                let normal = DVec3::new(rho * beta.cos(), rho * beta.sin(), mu);
                let wo = local_direction(normal, DVec3::X, DVec3::Z);
                total += 2.0 * mu * wm * wb * self.directional_albedo(lobe, wo);
            }
        }
        total
    }

    /// `E(μ_i, φ_k, αx = rx_j², αy = ry_l²)` on a grid: the one table builder for the LUT
    /// and the Blender groups. Slices of one `ry` run in parallel and `step` is called once
    /// per slice; every entry is computed independently, so the table is identical for any
    /// thread count. On square axes (`rx` = `ry`, azimuths mirrored about π/4) half the
    /// entries come from the other half by [`swapped`]: turning the frame a quarter turn
    /// swaps the widths and takes the view's azimuth φ to π/2 − φ.
    pub fn grid(
        &self,
        distribution: Distribution,
        masking: Masking,
        axes: AnisotropicAxes,
        step: &(dyn Fn() + Sync),
    ) -> Result<AnisotropicGrid, Error> {
        let lobes = lobe_rows(distribution, masking, &axes.rx, &axes.ry)?;
        let square = axes.is_square();
        let slices: Vec<Vec<f64>> = lobes
            .par_iter()
            .enumerate()
            .map(|(l, row)| {
                // On square axes, slice l computes the widths rx_j ≤ ry_l only.
                let row = if square { &row[..=l] } else { &row[..] };
                let mut e = Vec::with_capacity(row.len() * axes.phi.len() * axes.mu.len());
                for &mu in &axes.mu {
                    for &phi in &axes.phi {
                        e.extend(
                            row.iter()
                                .map(|lobe| self.directional_albedo(lobe, view(mu, phi))),
                        );
                    }
                }
                step();
                e
            })
            .collect();
        let (n_mu, n_phi, n_rx) = (axes.mu.len(), axes.phi.len(), axes.rx.len());
        let computed = |i: usize, k: usize, j: usize, l: usize| {
            let width = if square { l + 1 } else { n_rx };
            slices[l][(i * n_phi + k) * width + j]
        };
        let mut e = Vec::with_capacity(axes.ry.len() * n_mu * n_phi * n_rx);
        for l in 0..axes.ry.len() {
            for i in 0..n_mu {
                for k in 0..n_phi {
                    e.extend((0..n_rx).map(|j| {
                        if square && j > l {
                            let (k, j, l) = swapped(k, j, l, n_phi);
                            computed(i, k, j, l)
                        } else {
                            computed(i, k, j, l)
                        }
                    }));
                }
            }
        }
        Ok(AnisotropicGrid { axes, e })
    }

    /// `E_avg(rx_j², ry_l²)` per pair of widths, `[l · |rx| + j]`: the hemispherical average
    /// of [`Self::average_albedo`] (symmetric in the two widths). Rows of one `ry` run in
    /// parallel and `step` is called once per row.
    pub fn average_grid(
        &self,
        distribution: Distribution,
        masking: Masking,
        rx: &[f64],
        ry: &[f64],
        step: &(dyn Fn() + Sync),
    ) -> Result<Vec<f64>, Error> {
        let lobes = lobe_rows(distribution, masking, rx, ry)?;
        let rows: Vec<Vec<f64>> = lobes
            .par_iter()
            .map(|row| {
                let averages = row.iter().map(|lobe| self.average_albedo(lobe)).collect();
                step();
                averages
            })
            .collect();
        Ok(rows.concat())
    }
}

/// The lobes of a grid: `rows[l][j]` has `αx = rx_j²`, `αy = ry_l²`.
fn lobe_rows(
    distribution: Distribution,
    masking: Masking,
    rx: &[f64],
    ry: &[f64],
) -> Result<Vec<Vec<AnisotropicLobe>>, Error> {
    ry.iter()
        .map(|&ry| {
            rx.iter()
                .map(|&rx| AnisotropicLobe::new(distribution, masking, rx * rx, ry * ry))
                .collect()
        })
        .collect()
}

/// The grid entry (azimuth k, widths j, l) that equals entry (k, l, j) with the widths
/// swapped: a quarter turn of the frame takes φ_k to π/2 − φ_k = φ_{n−1−k} on mirrored
/// azimuths.
fn swapped(k: usize, j: usize, l: usize, azimuths: usize) -> (usize, usize, usize) {
    (azimuths - 1 - k, l, j)
}

/// Hemispherical averages use this many Gauss nodes along μ (half as many along φ).
const AVERAGE_NODES: usize = 16;

/// The sample points of an anisotropic table: view cosines, view azimuths from the tangent
/// (in [0, π/2], which covers every azimuth by the lobe's mirror symmetries), and the
/// square roots of the two widths (like the Roughness input, `α = r²`).
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct AnisotropicAxes {
    pub mu: Vec<f64>,
    pub phi: Vec<f64>,
    pub rx: Vec<f64>,
    pub ry: Vec<f64>,
}

impl AnisotropicAxes {
    /// Whether the two width axes are the same and the azimuths mirror about π/4 (φ_k +
    /// φ_{n−1−k} = π/2): then [`AnisotropicIntegrator::grid`] computes half the table.
    pub fn is_square(&self) -> bool {
        let n = self.phi.len();
        self.rx == self.ry
            && (0..n).all(|k| (self.phi[k] + self.phi[n - 1 - k] - FRAC_PI_2).abs() < 1e-12)
    }

    /// The axes of a table to interpolate in (the LUT and the Blender groups): `n` grid
    /// points from 0 to 1 on N·V, `√αx` and `√αy`, and `azimuths` from 0 to π/2. Grid
    /// points, not pixel centres, so both ends are exact: one width is often clamped to 1,
    /// where E is steep. N·V = 0 is taken at 1e-3 (a limit), and a width of 0 at √α = 0.01:
    /// a lobe with `αx αy ≤ 1e-7` is a mirror to Cycles, so at an exact 0 one width would
    /// switch the needle-thin lobe to a mirror.
    pub fn table(n: usize, azimuths: usize) -> Self {
        let points = |count: usize, low: f64| -> Vec<f64> {
            (0..count)
                .map(|i| (i as f64 / (count.max(2) - 1) as f64).max(low))
                .collect()
        };
        AnisotropicAxes {
            mu: points(n, 1e-3),
            phi: points(azimuths, 0.0)
                .iter()
                .map(|t| t * FRAC_PI_2)
                .collect(),
            rx: points(n, 0.01),
            ry: points(n, 0.01),
        }
    }
}

/// `E` on [`AnisotropicAxes`], from [`AnisotropicIntegrator::grid`].
#[derive(Clone, Debug, PartialEq)]
pub struct AnisotropicGrid {
    pub axes: AnisotropicAxes,
    /// `e[((l · |μ| + i) · |φ| + k) · |rx| + j] = E(μ_i, φ_k, rx_j, ry_l)`.
    pub e: Vec<f64>,
}

impl AnisotropicGrid {
    /// `E(μ_i, φ_k, rx_j, ry_l)`.
    pub fn e(&self, i: usize, k: usize, j: usize, l: usize) -> f64 {
        let a = &self.axes;
        self.e[((l * a.mu.len() + i) * a.phi.len() + k) * a.rx.len() + j]
    }
}

/// The unit-width lobe's mass within slope ρ (given ρ²): GGX `ρ²/(1 + ρ²)`, Beckmann
/// `1 − exp(−ρ²)`.
fn unit_cdf(distribution: Distribution, rho2: f64) -> f64 {
    match distribution {
        Distribution::Beckmann => -(-rho2).exp_m1(),
        _ if rho2.is_infinite() => 1.0,
        _ => rho2 / (1.0 + rho2),
    }
}

/// The unit-width lobe's mass per unit slope: GGX `2ρ/(1 + ρ²)²`, Beckmann `2ρ exp(−ρ²)`.
fn unit_density(distribution: Distribution, rho: f64) -> f64 {
    match distribution {
        Distribution::Beckmann => 2.0 * rho * (-rho * rho).exp(),
        _ => 2.0 * rho / (1.0 + rho * rho).powi(2),
    }
}

/// The inverse of [`unit_cdf`]: ρ² for the lobe mass `c`.
fn unit_slope2(distribution: Distribution, c: f64) -> f64 {
    match distribution {
        Distribution::Beckmann => -(-c).ln_1p(),
        _ => c / (1.0 - c),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_node_mapping_follows_cycles() {
        let lobe = |r: f64, a: f64| {
            AnisotropicLobe::from_glossy_node(
                Distribution::Ggx,
                Masking::HeightCorrelated,
                Roughness::new(r).unwrap(),
                Anisotropy::new(a).unwrap(),
            )
            .unwrap()
        };
        let l = lobe(0.5, 0.5);
        assert!((l.alpha_x - 0.125).abs() < 1e-15 && (l.alpha_y - 0.5).abs() < 1e-15);
        let l = lobe(0.5, -0.5);
        assert!((l.alpha_x - 0.5).abs() < 1e-15 && (l.alpha_y - 0.125).abs() < 1e-15);
        // Clamped: anisotropy to 0.99, widths to 1.
        let l = lobe(1.0, 5.0);
        assert!((l.alpha_x - 0.01).abs() < 1e-15 && l.alpha_y == 1.0);
    }
}
