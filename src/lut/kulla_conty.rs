//! Kulla–Conty energy compensation (Kulla & Conty 2017, "Revisiting Physically Based
//! Shading at Imageworks") for the Glossy BSDF exactly as Cycles evaluates it.
//!
//! * `E(μ, r) = ∫ f(μ, ωi) cosθi dωi` and `E_avg(r) = 2 ∫₀¹ E(μ) μ dμ` come from the
//!   Cycles-exact quadrature, [`AlbedoIntegrator::directional_albedo`] and
//!   [`AlbedoIntegrator::average_albedo`] (default rules), at the table's pixel centres.
//! * The multiple-scattering lobe is `f_ms(μo, μi) = (1 − E(μo))(1 − E(μi)) / (π (1 − E_avg))`;
//!   its cosine-weighted integral over ωi is `1 − E(μo)` (up to how well the table's E
//!   averages to E_avg), which is what makes `f + f_ms` conserve energy. E at any μ is read
//!   from this column of the E table by linear interpolation between pixel centres,
//!   clamped at the ends — the way a GPU's bilinear, clamp-to-edge fetch reads it.
//!
//! The RGBA table, per texel (row y: `μ = (y + ½)/n`, column x: `r = (x + ½)/n`):
//!
//! * **R, scale** = `∫ (1 − Fc) f cosθi dωi` and **G, bias** = `∫ Fc f cosθi dωi`,
//!   `Fc = (1 − |V·H|)⁵`, f the Cycles BSDF (masking from `--blender-version`), estimated with
//!   N Hammersley samples of Cycles' own importance sampling (GGX: its visible normals, as
//!   in the split-sum table; see [`scale_bias`]). So `R + G → E(μ, r)`, and for GGX with
//!   height-correlated masking (Blender ≥ 3.6) R and G are the split-sum table with
//!   `--g-model height-correlated`. At run time, `F0 · R + G` is the single-scattering
//!   response with Schlick's Fresnel.
//! * **B** = `∫ f_ms(μ, μi) cosθi dωi = (1 − E(μ)) (1 − Ē) / (1 − E_avg)`, in closed form
//!   ([`fms_integral`]; `Ē` is the table's own exact average of E). DESIGN.md integrates it
//!   with the same importance sampling as R and G (`f_ms · 4 · N·L · L·H / (N·H · D)`,
//!   [`fms_sampled`]); that converges to the same number, but far too slowly.
//! * **A** = `E_avg(r)`, the same in every row of a column; with a coloured Fresnel the
//!   multiple-scattering term is `F_avg E_avg / (1 − F_avg (1 − E_avg)) · B`.

use rayon::prelude::*;
use std::f64::consts::PI;

use super::split_sum::{ggx_visible_normal, hammersley};
use super::{Progress, Table};
use crate::microfacet::{AlbedoIntegrator, Distribution, Glossy, Masking};

/// The Kulla–Conty tables of one Glossy BSDF, each row-major with row y at
/// `μ = (y + ½)/size` and column x at `r = (x + ½)/size`.
#[derive(Clone, Debug, PartialEq)]
pub struct KullaConty {
    pub size: usize,
    pub distribution: Distribution,
    pub masking: Masking,
    /// `E(μ_y, r_x)`, Cycles-exact.
    pub e: Vec<f64>,
    /// `E_avg(r_x)`, Cycles-exact (one per column).
    pub e_avg: Vec<f64>,
    /// Channel R: `∫ (1 − Fc) f cos`.
    pub scale: Vec<f64>,
    /// Channel G: `∫ Fc f cos`.
    pub bias: Vec<f64>,
    /// Channel B: `∫ f_ms cos`.
    pub fms: Vec<f64>,
}

impl KullaConty {
    /// The RGBA table as written: R = scale, G = bias, B = ∫ f_ms cos, A = E_avg(r).
    pub fn table(&self) -> Table {
        let n = self.size;
        let mut data = Vec::with_capacity(n * n * 4);
        for y in 0..n {
            for x in 0..n {
                let i = y * n + x;
                data.extend_from_slice(&[
                    self.scale[i] as f32,
                    self.bias[i] as f32,
                    self.fms[i] as f32,
                    self.e_avg[x] as f32,
                ]);
            }
        }
        Table {
            width: n,
            height: n,
            channels: &["R", "G", "B", "A"],
            data,
        }
    }
}

/// The half vector's polar angle `(cos θh, sin θh)` for CDF value `v` of the sampling
/// density (the inverse CDFs of Cycles' samplers).
pub fn sample_polar(glossy: &Glossy, v: f64) -> (f64, f64) {
    let a2 = glossy.alpha * glossy.alpha;
    let from_tan2 = |t2: f64| {
        let c2 = 1.0 / (1.0 + t2);
        (c2.sqrt(), (t2 * c2).sqrt())
    };
    match glossy.distribution {
        // tan²θ = α² v/(1 − v)
        Distribution::Ggx => super::split_sum::ggx_polar(glossy.alpha, v),
        // tan²θ = −α² ln(1 − v)
        Distribution::Beckmann => from_tan2(-a2 * (-v).ln_1p()),
        // cosθ = (1 − v)^(1/(n + 1))
        Distribution::AshikhminShirley => {
            let n = glossy.ashikhmin_shirley_exponent();
            let log_cos = (-v).ln_1p() / (n + 1.0);
            (log_cos.exp(), (-(2.0 * log_cos).exp_m1()).max(0.0).sqrt())
        }
    }
}

/// The sampling density of the half vector per unit solid angle at `cos θh`:
/// `D(h) cosθh` for the microfacet models, `(n + 1)/(2π) cosⁿθh` for Ashikhmin–Shirley.
pub fn pdf_h(glossy: &Glossy, cos_h: f64) -> f64 {
    match glossy.distribution {
        Distribution::Ggx | Distribution::Beckmann => glossy.d(cos_h) * cos_h,
        Distribution::AshikhminShirley => {
            let n = glossy.ashikhmin_shirley_exponent();
            (n + 1.0) / (2.0 * PI) * cos_h.powf(n)
        }
    }
}

/// Reads a column of E (values at μ = (y + ½)/n) at any μ: linear between pixel centres,
/// clamped to the first and last value outside them.
pub fn interpolate(column: &[f64], mu: f64) -> f64 {
    let n = column.len();
    let t = mu * n as f64 - 0.5;
    if t <= 0.0 {
        return column[0];
    }
    let i = t.floor() as usize;
    if i + 1 >= n {
        return column[n - 1];
    }
    let f = t - i as f64;
    column[i] * (1.0 - f) + column[i + 1] * f
}

/// `1 − E` clamped at 0 (E can exceed 1 by a hair where a quadrature or Beckmann's rational
/// Λ makes it so): the energy a white lobe misses, never negative.
fn missing(e: f64) -> f64 {
    (1.0 - e).max(0.0)
}

/// `Ē = 2 ∫₀¹ E(μ) μ dμ` of the column as [`interpolate`] reads it (with `E` clamped to 1),
/// exactly: constant ends, Simpson's rule on each linear piece (exact for its quadratic
/// integrand).
pub fn column_average(column: &[f64]) -> f64 {
    let n = column.len();
    let e = |i: usize| 1.0 - missing(column[i]);
    let mu = |i: usize| (i as f64 + 0.5) / n as f64;
    let mut total = e(0) * mu(0) * mu(0) + e(n - 1) * (1.0 - mu(n - 1) * mu(n - 1));
    for i in 0..n.saturating_sub(1) {
        let (m0, m1) = (mu(i), mu(i + 1));
        let mid = 0.5 * (m0 + m1);
        let f = |m: f64, v: f64| 2.0 * m * v;
        let (f0, f1, fm) = (
            f(m0, e(i)),
            f(m1, e(i + 1)),
            f(mid, 0.5 * (e(i) + e(i + 1))),
        );
        total += (m1 - m0) / 6.0 * (f0 + 4.0 * fm + f1);
    }
    total
}

/// Channel B in closed form: `∫ f_ms(μ, μi) cosθi dωi = (1 − E(μ)) (1 − Ē) / (1 − E_avg)`,
/// with `f_ms = (1 − E(μ))(1 − E(μi)) / (π (1 − E_avg))`, E read from the column (see
/// [`interpolate`], clamped to 1) and `Ē` its exact average ([`column_average`]). Zero where
/// `1 − E_avg ≤ 1e-12` (a mirror loses nothing).
pub fn fms_integral(mu: f64, e_column: &[f64], e_bar: f64, e_avg: f64) -> f64 {
    if 1.0 - e_avg > 1e-12 {
        missing(interpolate(e_column, mu)) * missing(e_bar) / (1.0 - e_avg)
    } else {
        0.0
    }
}

/// DESIGN.md's estimator of channel B, kept for comparison: the f_ms lobe integrated with
/// the distribution's own half-vector sampling, `(1/N) Σ f_ms · 4 N·L V·H / pdf(h)` over
/// the samples with `V·H > 0` and `N·L > 0` (`pdf(h) = D N·H` for the microfacet models).
/// It converges to [`fms_integral`], but slowly: a narrow lobe's samples rarely reach the
/// broad f_ms lobe (measured on a 32² GGX table at 4096 samples: off by up to 0.07;
/// Beckmann 0.08, Ashikhmin–Shirley 0.36), so the table uses the closed form.
pub fn fms_sampled(glossy: &Glossy, mu: f64, samples: u32, e_column: &[f64], e_avg: f64) -> f64 {
    if 1.0 - e_avg <= 1e-12 {
        return 0.0;
    }
    let sin_o = (1.0 - mu * mu).max(0.0).sqrt();
    let k = missing(interpolate(e_column, mu)) / (PI * (1.0 - e_avg));
    let mut fms = 0.0;
    for i in 0..samples {
        let (u, v) = hammersley(i, samples);
        let (cos_h, sin_h) = sample_polar(glossy, v);
        let o_dot_h = sin_o * sin_h * (2.0 * PI * u).cos() + mu * cos_h;
        let cos_i = 2.0 * o_dot_h * cos_h - mu;
        if o_dot_h > 0.0 && cos_i > 0.0 {
            let f_ms = k * missing(interpolate(e_column, cos_i));
            fms += f_ms * cos_i * 4.0 * o_dot_h / pdf_h(glossy, cos_h);
        }
    }
    fms / f64::from(samples)
}

/// One texel's `(scale, bias)`: `(1/N) Σ (1 − Fc) w` and `(1/N) Σ Fc w` with Cycles' sample
/// weight w, for view cosine `mu`.
///
/// GGX samples its visible normals (Heitz 2018, the same centred Hammersley disk as the
/// split-sum table), weight `G2(μ, μi) / G1(μ) = G2 (1 + Λ(μ))`. Beckmann and
/// Ashikhmin–Shirley sample `D cosθh` / `(n + 1)/(2π) cosⁿθh` at Hammersley points
/// `(u, v)`, `φ = 2πu`, with Cycles' weights `G2 V·H / (N·H μ)` and `cosθi / max(cosθi, μ)`
/// (Ashikhmin–Shirley flips a back-facing h after taking V·H, as Cycles does).
pub fn scale_bias(glossy: &Glossy, mu: f64, samples: u32) -> (f64, f64) {
    let sin_o = (1.0 - mu * mu).max(0.0).sqrt();
    let v = [sin_o, 0.0, mu];
    let (mut scale, mut bias) = (0.0, 0.0);
    for i in 0..samples {
        let (w, voh) = match glossy.distribution {
            Distribution::Ggx => {
                let h = ggx_visible_normal(glossy.alpha, v, i, samples);
                let voh = v[0] * h[0] + v[2] * h[2];
                let cos_i = 2.0 * voh * h[2] - mu;
                if cos_i > 0.0 {
                    (glossy.g2(mu, cos_i) * (1.0 + glossy.lambda(mu)), voh)
                } else {
                    (0.0, voh)
                }
            }
            Distribution::Beckmann => {
                let (u, v) = hammersley(i, samples);
                let (cos_h, sin_h) = sample_polar(glossy, v);
                let voh = sin_o * sin_h * (2.0 * PI * u).cos() + mu * cos_h;
                let cos_i = 2.0 * voh * cos_h - mu;
                if cos_i > 0.0 {
                    (glossy.g2(mu, cos_i) * voh / (mu * cos_h), voh)
                } else {
                    (0.0, voh)
                }
            }
            Distribution::AshikhminShirley => {
                let (u, v) = hammersley(i, samples);
                let (cos_h, sin_h) = sample_polar(glossy, v);
                let voh = (sin_o * sin_h * (2.0 * PI * u).cos() + mu * cos_h).abs();
                let cos_i = 2.0 * voh * cos_h - mu;
                if cos_i > 0.0 {
                    (cos_i / cos_i.max(mu), voh)
                } else {
                    (0.0, voh)
                }
            }
        };
        if w > 0.0 {
            let fc = (1.0 - voh).powi(5);
            scale += (1.0 - fc) * w;
            bias += fc * w;
        }
    }
    let n = f64::from(samples);
    (scale / n, bias / n)
}

/// `E(μ_y, r_x)` (one column per roughness) and `E_avg(r_x)`, Cycles-exact quadrature,
/// columns in parallel.
fn albedo_columns(
    size: usize,
    distribution: Distribution,
    masking: Masking,
    progress: Progress,
) -> Vec<(Glossy, Vec<f64>, f64)> {
    let integrator = AlbedoIntegrator::default();
    let n = size as f64;
    (0..size)
        .into_par_iter()
        .map(|x| {
            let r = (x as f64 + 0.5) / n;
            let glossy = Glossy {
                distribution,
                masking,
                alpha: r * r,
            };
            let e = (0..size)
                .map(|y| integrator.directional_albedo(&glossy, (y as f64 + 0.5) / n))
                .collect();
            let e_avg = integrator.average_albedo(&glossy);
            progress();
            (glossy, e, e_avg)
        })
        .collect()
}

/// The albedo table: R = `E(μ_y, r_x)`, G = `E_avg(r_x)`; `progress` is called once per
/// column.
pub fn albedo_table(
    size: usize,
    distribution: Distribution,
    masking: Masking,
    progress: Progress,
) -> Table {
    let columns = albedo_columns(size, distribution, masking, progress);
    let mut data = Vec::with_capacity(size * size * 2);
    for y in 0..size {
        for (_, e, e_avg) in &columns {
            data.extend_from_slice(&[e[y] as f32, *e_avg as f32]);
        }
    }
    Table {
        width: size,
        height: size,
        channels: &["R", "G"],
        data,
    }
}

/// Computes the Kulla–Conty tables for `distribution` with `masking`, `size × size`
/// texels, `samples` Hammersley points per texel (columns in parallel); `progress` is
/// called twice per column (albedo, then scale/bias).
pub fn kulla_conty(
    size: usize,
    samples: u32,
    distribution: Distribution,
    masking: Masking,
    progress: Progress,
) -> KullaConty {
    let n = size as f64;
    let columns: Vec<_> = albedo_columns(size, distribution, masking, progress)
        .into_par_iter()
        .map(|(glossy, e, e_avg)| {
            let e_bar = column_average(&e);
            let texels: Vec<_> = (0..size)
                .map(|y| {
                    let mu = (y as f64 + 0.5) / n;
                    let (s, b) = scale_bias(&glossy, mu, samples);
                    (s, b, fms_integral(mu, &e, e_bar, e_avg))
                })
                .collect();
            progress();
            (e, e_avg, texels)
        })
        .collect();
    let mut kc = KullaConty {
        size,
        distribution,
        masking,
        e: vec![0.0; size * size],
        e_avg: vec![0.0; size],
        scale: vec![0.0; size * size],
        bias: vec![0.0; size * size],
        fms: vec![0.0; size * size],
    };
    for (x, (e, e_avg, texels)) in columns.into_iter().enumerate() {
        kc.e_avg[x] = e_avg;
        for y in 0..size {
            let i = y * size + x;
            kc.e[i] = e[y];
            (kc.scale[i], kc.bias[i], kc.fms[i]) = texels[y];
        }
    }
    kc
}
