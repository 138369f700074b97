//! Directional albedo `E(μ, r)` and its hemispherical average `E_avg(r)` by deterministic,
//! importance-mapped Gauss–Legendre quadrature over the microfacet normal h.
//!
//! Why quadrature and not Monte Carlo: the integrand is smooth once (1) θh is mapped through
//! the inverse CDF of the distribution's own lobe (so narrow lobes at small roughness cost
//! nothing extra) and (2) the φh range is cut exactly where the reflected direction crosses
//! the horizon (`cos φ = −cot θo · cot 2θh`). What is left converges geometrically, so a few
//! hundred evaluations per (μ, r) reach 1e-5, where QMC with visible-normal sampling needs
//! far more (see `docs/RESULTS.md` for the measured comparison).

use gauss_quad::legendre::GaussLegendre;
use rayon::prelude::*;
use std::f64::consts::{FRAC_PI_2, PI};
use std::num::NonZeroUsize;

use super::glossy::Glossy;
use super::microfacet::{Distribution, Masking, Polar, Roughness};

/// Numbers of quadrature nodes; [`Quadrature::default`] meets the 2e-4 accuracy goal.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Quadrature {
    /// Nodes along θh in each of its two intervals.
    pub theta: usize,
    /// Nodes along φh.
    pub phi: usize,
    /// Nodes along μ for the hemispherical average.
    pub mu: usize,
}

impl Default for Quadrature {
    fn default() -> Self {
        Quadrature {
            theta: 24,
            phi: 8,
            mu: 24,
        }
    }
}

/// Precomputed quadrature rules; build once, evaluate many times (it is `Sync`).
pub struct AlbedoIntegrator {
    theta_rule: Vec<(f64, f64)>,
    phi_rule: Vec<(f64, f64)>,
    mu_rule: Vec<(f64, f64)>,
}

impl Default for AlbedoIntegrator {
    fn default() -> Self {
        Self::new(Quadrature::default())
    }
}

/// Gauss–Legendre nodes and weights on [0, 1].
pub fn gauss_unit(n: usize) -> Vec<(f64, f64)> {
    let n = NonZeroUsize::new(n.max(1)).expect("max(1) is non-zero");
    GaussLegendre::new(n)
        .as_node_weight_pairs()
        .iter()
        .map(|&(x, w)| (0.5 * (x + 1.0), 0.5 * w))
        .collect()
}

/// Gauss–Legendre after the substitution x = 3t² − 2t³, whose zero slope at both ends
/// tames the square-root behaviour of the integrand where the φ range starts to shrink.
fn smoothstep_unit(n: usize) -> Vec<(f64, f64)> {
    gauss_unit(n)
        .into_iter()
        .map(|(t, w)| (t * t * (3.0 - 2.0 * t), w * 6.0 * t * (1.0 - t)))
        .collect()
}

impl AlbedoIntegrator {
    pub fn new(q: Quadrature) -> Self {
        AlbedoIntegrator {
            theta_rule: smoothstep_unit(q.theta),
            phi_rule: gauss_unit(q.phi),
            mu_rule: gauss_unit(q.mu),
        }
    }

    /// Where the integrand has a kink or an edge, as constants k of `ωo·h = k / cosθh`
    /// (the reflected cosine is `cosθi = 2 (ωo·h) cosθh − μ`): the horizon (k = μ/2), the
    /// onset of shadowing for the microfacet models (cosθi ≈ α, Λ(ωi) grows once
    /// α tanθi ≳ 1), and for Ashikhmin–Shirley the kink of `max(cosθi, μ)` (k = μ) and the
    /// same two for its flipped samples (negative k).
    fn events(glossy: &Glossy, mu: f64) -> Vec<f64> {
        match glossy.distribution() {
            Distribution::Beckmann | Distribution::Ggx => {
                vec![0.5 * mu, 0.5 * (glossy.microfacet.alpha + mu)]
            }
            Distribution::AshikhminShirley => vec![0.5 * mu, mu, -0.5 * mu, -mu],
        }
    }

    /// ∫₀^π weight dφ for one polar angle, in pieces cut at every event's azimuth, for each
    /// of the `N` factors `factors(ωo·h)` the sample weight is multiplied by.
    fn azimuth_integral<const N: usize>(
        &self,
        glossy: &Glossy,
        mu: f64,
        sin_o: f64,
        h: Polar,
        events: &[f64],
        factors: &impl Fn(f64) -> [f64; N],
    ) -> [f64; N] {
        // ωo·h = A cos φ + B with A = sinθo sinθh, B = μ cosθh.
        let (a, b) = (sin_o * h.sin, mu * h.cos);
        let mut cuts = vec![0.0, PI];
        if a > 0.0 {
            for &k in events {
                let c = (k / h.cos - b) / a;
                if c > -1.0 && c < 1.0 {
                    cuts.push(c.acos());
                }
            }
        }
        cuts.sort_by(f64::total_cmp);
        let mut total = [0.0; N];
        for pair in cuts.windows(2) {
            let (lo, hi) = (pair[0], pair[1]);
            if hi <= lo {
                continue;
            }
            let mut sum = [0.0; N];
            for &(x, w) in &self.phi_rule {
                let cos_phi = (lo + (hi - lo) * x).cos();
                let sample = glossy.half_vector_sample(mu, sin_o, h, cos_phi);
                let f = factors(sample.o_dot_h);
                for k in 0..N {
                    sum[k] += w * (f[k] * sample.weight);
                }
            }
            for k in 0..N {
                total[k] += sum[k] * (hi - lo);
            }
        }
        total
    }

    /// Directional albedo `E(μ) = ∫ f(ωo, ωi) cosθi dωi` for view cosine `mu` ∈ (0, 1], as
    /// Cycles renders it. Roughness 0 is Cycles' perfect mirror: exactly 1.
    pub fn directional_albedo(&self, glossy: &Glossy, mu: f64) -> f64 {
        self.directional_moments(glossy, mu, &|_| [1.0])[0]
    }

    /// `∫ f(ωo, ωi) cosθi · factor_k(ωo·h) dωi` for each of the `N` factors at once (one pass
    /// over the half vectors): with a factor of 1 the albedo, with a Fresnel term the albedo
    /// of a Fresnel-weighted lobe, with Schlick's weights the split-sum scale and bias. At
    /// roughness 0 (the mirror, h = n) it is `factor(μ)`.
    pub fn directional_moments<const N: usize>(
        &self,
        glossy: &Glossy,
        mu: f64,
        factors: &impl Fn(f64) -> [f64; N],
    ) -> [f64; N] {
        let lobe = glossy.microfacet;
        if lobe.alpha <= 0.0 {
            return factors(mu.clamp(0.0, 1.0));
        }
        let mu = mu.clamp(1e-9, 1.0);
        let sin_o = (1.0 - mu * mu).max(0.0).sqrt();
        let theta_o = mu.acos();
        let events = Self::events(glossy, mu);
        // An event's azimuth enters or leaves [0, π] where k − μcos²θh = ±sinθo sinθh cosθh,
        // i.e. where cos(2θh ∓ θo) = 2k − μ: there the φ-integral has a square-root kink,
        // so θh is cut there too.
        let theta_end = match lobe.distribution {
            // Beyond θb = (π/2 + θo)/2 every reflected direction is below the horizon.
            Distribution::Beckmann | Distribution::Ggx => 0.5 * (FRAC_PI_2 + theta_o),
            Distribution::AshikhminShirley => FRAC_PI_2,
        };
        let mut cuts = vec![0.0, theta_end];
        for &k in &events {
            let c = 2.0 * k - mu;
            if c.abs() <= 1.0 {
                let base = c.acos();
                for t in [base - theta_o, base + theta_o, -base + theta_o] {
                    let t = 0.5 * t;
                    if t > 1e-12 && t < theta_end - 1e-12 {
                        cuts.push(t);
                    }
                }
            }
        }
        cuts.sort_by(f64::total_cmp);
        cuts.dedup_by(|x, y| (*x - *y).abs() < 1e-12);

        let mut total = [0.0; N];
        for pair in cuts.windows(2) {
            let (t0, t1) = (pair[0], pair[1]);
            let azimuth = |h: Polar| self.azimuth_integral(glossy, mu, sin_o, h, &events, factors);
            // GGX's heavy tail (D → α²/π at grazing) spans decades of tanθh away from the
            // peak; Beckmann's and Ashikhmin–Shirley's tails vanish too fast for that.
            let heavy_tail = lobe.distribution == Distribution::Ggx;
            if t0 == 0.0 || !heavy_tail {
                // Integrate in lobe mass s (inverse CDF): smooth across the lobe's peak.
                let (s_hi, s_lo) = (lobe.survival(t0), lobe.survival(t1));
                if s_hi <= s_lo {
                    continue;
                }
                let mut piece = [0.0; N];
                for &(x, w) in &self.theta_rule {
                    let az = azimuth(lobe.polar_from_survival(s_lo + (s_hi - s_lo) * x));
                    for k in 0..N {
                        piece[k] += w * az[k];
                    }
                }
                for k in 0..N {
                    total[k] += piece[k] * (s_hi - s_lo);
                }
            } else {
                // In the heavy tail, integrate in ln tanθh, where the integrand is smooth.
                let (w0, w1) = (t0.tan().ln(), t1.tan().ln());
                let mut piece = [0.0; N];
                for &(x, w) in &self.theta_rule {
                    let h = Polar::from_tan2((2.0 * (w0 + (w1 - w0) * x)).exp());
                    let az = azimuth(h);
                    for k in 0..N {
                        piece[k] += w * az[k] * lobe.density(h) * h.sin * h.cos;
                    }
                }
                for k in 0..N {
                    total[k] += piece[k] * (w1 - w0);
                }
            }
        }
        // (1/2π) ∫∫ over the full circle = (1/π) ∫ over [0, π] by symmetry in φ.
        total.map(|t| t / PI)
    }

    /// Hemispherical average `E_avg = 2 ∫₀¹ E(μ) μ dμ`: the mean brightness of an evenly lit
    /// sphere seen by an orthographic camera (view cosines have density 2μ on its disc).
    pub fn average_albedo(&self, glossy: &Glossy) -> f64 {
        if glossy.microfacet.alpha <= 0.0 {
            return 1.0;
        }
        self.hemispherical_average(|mu| self.directional_albedo(glossy, mu))
    }

    /// `2 ∫₀¹ f(μ) μ dμ` on the integrator's μ rule: the mean of a view-dependent albedo
    /// `f` over an orthographic sphere.
    pub fn hemispherical_average(&self, f: impl Fn(f64) -> f64) -> f64 {
        self.mu_rule
            .iter()
            .map(|&(mu, w)| 2.0 * w * mu * f(mu))
            .sum()
    }

    /// `E(μ_i, r_j)` and `E_avg(r_j)` of one distribution and masking on a grid: the one
    /// table builder (the CSV, the packed view table, the LUTs and the fits all use it).
    /// Columns (one per roughness) run in parallel and `step` is called once per column;
    /// every entry is computed independently, so the table is identical for any thread
    /// count.
    pub fn grid(
        &self,
        distribution: Distribution,
        masking: Masking,
        roughness: &[Roughness],
        mu: &[f64],
        step: &(dyn Fn() + Sync),
    ) -> AlbedoGrid {
        let columns: Vec<(Vec<f64>, f64)> = roughness
            .par_iter()
            .map(|&r| {
                let glossy = Glossy::new(distribution, masking, r);
                let e = mu
                    .iter()
                    .map(|&mu| self.directional_albedo(&glossy, mu))
                    .collect();
                let e_avg = self.average_albedo(&glossy);
                step();
                (e, e_avg)
            })
            .collect();
        let width = roughness.len();
        let mut e = vec![0.0; mu.len() * width];
        for (j, (column, _)) in columns.iter().enumerate() {
            for (i, &v) in column.iter().enumerate() {
                e[i * width + j] = v;
            }
        }
        AlbedoGrid {
            roughness: roughness.to_vec(),
            mu: mu.to_vec(),
            e,
            e_avg: columns.into_iter().map(|(_, avg)| avg).collect(),
        }
    }
}

/// `E(μ, r)` on a grid and `E_avg(r)` per roughness, from [`AlbedoIntegrator::grid`].
#[derive(Clone, Debug, PartialEq)]
pub struct AlbedoGrid {
    pub roughness: Vec<Roughness>,
    pub mu: Vec<f64>,
    /// Row-major, one row per μ: `e[i * roughness.len() + j] = E(μ_i, r_j)`.
    pub e: Vec<f64>,
    /// `E_avg(r_j)`.
    pub e_avg: Vec<f64>,
}

impl AlbedoGrid {
    /// `E(μ_i, r_j)`.
    pub fn e(&self, i: usize, j: usize) -> f64 {
        self.e[i * self.roughness.len() + j]
    }

    /// Column `j`: `E(μ_i, r_j)` for every μ.
    pub fn column(&self, j: usize) -> Vec<f64> {
        (0..self.mu.len()).map(|i| self.e(i, j)).collect()
    }

    /// As CSV: a header, then one line per (μ, r), μ-major, every number as Rust prints
    /// it (shortest round-trip form).
    pub fn csv(&self) -> String {
        use std::fmt::Write as _;
        let mut csv = String::from("roughness,mu,albedo,average_albedo\n");
        for (i, mu) in self.mu.iter().enumerate() {
            for (j, r) in self.roughness.iter().enumerate() {
                let _ = writeln!(csv, "{r},{mu},{},{}", self.e(i, j), self.e_avg[j]);
            }
        }
        csv
    }
}
