//! The split-sum LUT (Karis 2013, "Real Shading in Unreal Engine 4"; the classic "BRDF
//! generator"; `docs/PHYSICS.md` §10), vectorised.
//!
//! # The integral
//!
//! For texel (x, y) of an n × n table, at pixel centres: roughness `r = (x + ½)/n`,
//! `N·V = (y + ½)/n`, `V = (√(1 − N·V²), 0, N·V)`, `N = +z`, `α = r²`, `L = reflect(−V, H)`,
//! `G_Vis = G · V·H / (N·H · N·V)`, `Fc = (1 − V·H)⁵`:
//!
//! `scale = E[(1 − Fc) G_Vis · 1(N·L > 0)]`, `bias = E[Fc G_Vis · 1(N·L > 0)]`, H ~ D(H) N·H.
//!
//! G is [`GModel::Ue4`] (separable Schlick-GGX, `G1(x) = x/(x(1 − k) + k)`, `k = α/2`) or
//! [`GModel::HeightCorrelated`] (Smith GGX, `G2 = 1/(1 + Λ(V) + Λ(L))`).
//!
//! # Two estimators of it ([`Sampling`])
//!
//! * [`Sampling::Classic`] is the textbook estimator to the letter: Hammersley points
//!   `(u, v) = (i/N, radical_inverse₂(i))`, `φ = 2πu`,
//!   `cos θh = √((1 − v)/(1 + (α² − 1) v))`, and the sums above divided by N (samples with
//!   `N·L ≤ 0` still count). Its weight `G_Vis` grows like `tan θh / α` towards grazing
//!   views, so at 1024 samples it is off by up to 1e-2 near `N·V = 0` (measured:
//!   `cargo bench --bench lut`).
//! * [`Sampling::VisibleNormals`] (the default) estimates the same integral by sampling H
//!   from GGX's distribution of visible normals (Heitz 2018, "Sampling the GGX Distribution
//!   of Visible Normals") with centred Hammersley points on its disk, `ρ² = (i + ½)/N`,
//!   `φ = 2π radical_inverse₂(i)`. The pdf is `G1(V) max(0, V·H) D(H) / N·V` with Smith's
//!   `G1(V) = 1/(1 + Λ(V))`, so each sample's weight becomes `G / G1(V)` — bounded by about
//!   1 — instead of `G_Vis`. With 2048 samples the 512² table is within 1e-3 of the
//!   converged values everywhere (measured max ≈ 7e-4); with 1024 within about 1.3e-3.
//!
//! # Speed
//!
//! Each row runs every texel through an f32 kernel with eight explicit accumulator lanes
//! (flushed to f64 every 512 samples). The lanes fix the order of the sum, so the result is
//! bit-identical whether the kernel runs as SSE2 or AVX2 code (chosen at run time; no FMA)
//! and for any thread count. Rows run in parallel (rayon).

use glam::DVec3;
use rayon::prelude::*;
use std::f64::consts::PI;

use super::{GModel, Sampling};
use crate::measure::{Distribution, Masking, Microfacet};
use crate::progress::Progress;

/// Lanes of the inner kernels (one AVX register of f32).
const LANES: usize = 8;
/// Chunks of [`LANES`] samples summed in f32 before the lanes are added to the f64 totals.
const CHUNKS_PER_FLUSH: usize = 64;

/// The Van der Corput radical inverse in base 2 of `i`: its bits mirrored about the point.
pub fn radical_inverse_base2(i: u32) -> f64 {
    f64::from(i.reverse_bits()) / 4_294_967_296.0
}

/// Hammersley point `i` of `n`: `(i/n, radical_inverse₂(i))`.
pub fn hammersley(i: u32, n: u32) -> (f64, f64) {
    (f64::from(i) / f64::from(n), radical_inverse_base2(i))
}

/// The GGX lobe of width `alpha`.
fn ggx(alpha: f64) -> Microfacet {
    Microfacet {
        distribution: Distribution::Ggx,
        alpha,
    }
}

/// The masking–shadowing term `G(V, L)` of a split-sum model, in f64.
pub fn g(g_model: GModel, alpha: f64, nov: f64, nol: f64) -> f64 {
    match g_model {
        GModel::Ue4 => {
            let k = alpha / 2.0;
            let g1 = |x: f64| x / (x * (1.0 - k) + k);
            g1(nov) * g1(nol)
        }
        GModel::HeightCorrelated => ggx(alpha).g2(Masking::HeightCorrelated, nov, nol),
    }
}

/// Sums eight lanes into f64.
fn lanes_sum(a: &[f32; LANES]) -> f64 {
    a.iter().map(|&x| f64::from(x)).sum()
}

// ---------------------------------------------------------------------------------------
// Visible-normal sampling

/// The disk points of the visible-normal sampler (they do not depend on the texel): with
/// `t1 = ρ cos φ` (the out-of-plane coordinate), `t2 = ρ sin φ`, `q = √(1 − t1²)` and
/// `q2 = 1 − t1²` (t1 itself is not needed). Padded to a multiple of [`LANES`] with
/// `q = q2 = t2 = 0`, which yields `H = (0, 1, 0)`, so `N·L = −N·V < 0`: no contribution.
struct Disk {
    t2: Vec<f32>,
    q: Vec<f32>,
    q2: Vec<f32>,
}

impl Disk {
    fn new(samples: u32) -> Self {
        let padded = (samples as usize).div_ceil(LANES) * LANES;
        let mut d = Disk {
            t2: vec![0.0; padded],
            q: vec![0.0; padded],
            q2: vec![0.0; padded],
        };
        for i in 0..samples {
            let (t1, t2) = disk_point(i, samples);
            let k = i as usize;
            d.t2[k] = t2 as f32;
            d.q2[k] = (1.0 - t1 * t1) as f32;
            d.q[k] = (1.0 - t1 * t1).max(0.0).sqrt() as f32;
        }
        d
    }
}

/// Disk point `i` of `n`: `ρ² = (i + ½)/n` (centred), `φ = 2π radical_inverse₂(i)`.
pub fn disk_point(i: u32, n: u32) -> (f64, f64) {
    let rho = ((f64::from(i) + 0.5) / f64::from(n)).sqrt();
    let phi = 2.0 * PI * radical_inverse_base2(i);
    (rho * phi.cos(), rho * phi.sin())
}

/// Per-texel constants of the visible-normal kernel.
#[derive(Clone, Copy)]
struct VisiblePixel {
    alpha: f32,
    alpha2: f32,
    one_minus_alpha2: f32,
    /// V.x and N·V
    vx: f32,
    nov: f32,
    /// `V_h = normalize(α V.x, 0, N·V) = (a, 0, b)`; the disk frame is `T1 = (0, 1, 0)`,
    /// `T2 = (−b, 0, a)`.
    a: f32,
    b: f32,
    /// `s = (1 + V_h.z)/2`, the warp of the disk towards the visible half.
    s: f32,
    /// ue4: `k = α/2`; height-correlated: `α²`.
    k: f32,
    /// ue4: `G1(V)/G1_Smith(V)`; height-correlated: `2(1 + Λ(V))`.
    c: f32,
    /// height-correlated: `1 + 2Λ(V)`.
    lv: f32,
}

impl VisiblePixel {
    fn new(g_model: GModel, alpha: f64, nov: f64) -> Self {
        let vx = (1.0 - nov * nov).sqrt();
        let (ax, az) = (alpha * vx, nov);
        let len = (ax * ax + az * az).sqrt();
        let (a, b) = (ax / len, az / len);
        let lambda_v = ggx(alpha).lambda(nov);
        let (k, c, lv) = match g_model {
            GModel::Ue4 => {
                let k = alpha / 2.0;
                (k, nov / (nov * (1.0 - k) + k) * (1.0 + lambda_v), 0.0)
            }
            GModel::HeightCorrelated => {
                (alpha * alpha, 2.0 * (1.0 + lambda_v), 1.0 + 2.0 * lambda_v)
            }
        };
        VisiblePixel {
            alpha: alpha as f32,
            alpha2: (alpha * alpha) as f32,
            one_minus_alpha2: (1.0 - alpha * alpha) as f32,
            vx: vx as f32,
            nov: nov as f32,
            a: a as f32,
            b: b as f32,
            s: (0.5 * (1.0 + b)) as f32,
            k: k as f32,
            c: c as f32,
            lv: lv as f32,
        }
    }
}

/// `(Σ (1 − Fc) w, Σ Fc w)` over the disk for one texel, `w = G/G1_Smith(V)` where
/// `N·L > 0`.
///
/// Heitz's sampler in this frame: `t2' = (1 − s) q + s t2`, `w = √(1 − t1² − t2'²)`,
/// `N_h = t1 T1 + t2' T2 + w V_h`, `H = normalize(α N_h.x, α N_h.y, max(0, N_h.z))`.
/// ue4: `w = c · N·L / (N·L(1 − k) + k)`;
/// height-correlated: `w = 2(1 + Λ(V)) N·L / ((1 + 2Λ(V)) N·L + √(α² + N·L²(1 − α²)))`.
/// (Both are evaluated multiplied through by `|H|²`, which saves a division per sample.)
#[inline(always)]
fn visible_kernel<const HC: bool>(d: &Disk, p: VisiblePixel) -> (f64, f64) {
    let (mut total_scale, mut total_bias) = (0.0, 0.0);
    let blocks =
        d.t2.chunks(LANES * CHUNKS_PER_FLUSH)
            .zip(d.q.chunks(LANES * CHUNKS_PER_FLUSH))
            .zip(d.q2.chunks(LANES * CHUNKS_PER_FLUSH));
    for ((t2b, qb), q2b) in blocks {
        let mut scale = [0.0f32; LANES];
        let mut bias = [0.0f32; LANES];
        let chunks = t2b
            .as_chunks::<LANES>()
            .0
            .iter()
            .zip(qb.as_chunks::<LANES>().0)
            .zip(q2b.as_chunks::<LANES>().0);
        for ((t2, q), q2) in chunks {
            for l in 0..LANES {
                let t2 = (1.0 - p.s) * q[l] + p.s * t2[l];
                let w = (q2[l] - t2 * t2).max(0.0).sqrt();
                // N_h without the α stretch; |N_h| = 1, so |(α N_h.x, α N_h.y, N_h.z)|² is
                // α² + (1 − α²) N_h.z² and t1 (the out-of-plane part) drops out.
                let nx = p.alpha * (p.a * w - p.b * t2);
                let nz = (p.a * t2 + p.b * w).max(0.0);
                let l2 = p.alpha2 + p.one_minus_alpha2 * nz * nz;
                // With H = (nx, ·, nz)/√l2: V·H = dot/√l2 and N·L = (2 dot nz − N·V l2)/l2.
                let dot = p.vx * nx + p.nov * nz;
                let nol_l2 = 2.0 * dot * nz - p.nov * l2;
                let sl = l2.sqrt();
                // weight = c N·L / den: both forms are homogeneous in l2, so the one
                // division 1/(√l2 den) gives the weight and 1/√l2 for V·H.
                let den = if HC {
                    p.lv * nol_l2 + (p.k * l2 * l2 + nol_l2 * nol_l2 * (1.0 - p.k)).sqrt()
                } else {
                    nol_l2 * (1.0 - p.k) + p.k * l2
                };
                let rcp = 1.0 / (sl * den);
                let (weight, voh) = if nol_l2 > 0.0 {
                    (p.c * nol_l2 * sl * rcp, dot * den * rcp)
                } else {
                    (0.0, 1.0)
                };
                let m = 1.0 - voh;
                let m2 = m * m;
                let fw = m2 * m2 * m * weight;
                scale[l] += weight - fw;
                bias[l] += fw;
            }
        }
        total_scale += lanes_sum(&scale);
        total_bias += lanes_sum(&bias);
    }
    (total_scale, total_bias)
}

// ---------------------------------------------------------------------------------------
// Classic sampling

/// Half vectors of one column for the classic estimator: `H.x` and `H.z` (`H.y` never
/// enters, because V lies in the xz-plane), padded with `H = 0`, which gives
/// `N·L = −N·V < 0`.
struct Column {
    hx: Vec<f32>,
    hz: Vec<f32>,
}

impl Column {
    fn new(alpha: f64, samples: u32) -> Self {
        let padded = (samples as usize).div_ceil(LANES) * LANES;
        let mut hx = vec![0.0f32; padded];
        let mut hz = vec![0.0f32; padded];
        for i in 0..samples {
            let (u, v) = hammersley(i, samples);
            let h = ggx(alpha).sample_polar(v);
            hx[i as usize] = (h.sin * (2.0 * PI * u).cos()) as f32;
            hz[i as usize] = h.cos as f32;
        }
        Column { hx, hz }
    }
}

/// Per-texel constants of the classic kernel.
#[derive(Clone, Copy)]
struct ClassicPixel {
    vx: f32,
    nov: f32,
    /// ue4: `k = α/2`; height-correlated: `α²`.
    k: f32,
    /// ue4: `G1(V)/N·V`; height-correlated: `2/N·V`.
    c: f32,
    /// height-correlated: `1 + 2Λ(V)`.
    lv: f32,
}

impl ClassicPixel {
    fn new(g_model: GModel, alpha: f64, nov: f64) -> Self {
        let vx = (1.0 - nov * nov).sqrt() as f32;
        match g_model {
            GModel::Ue4 => {
                let k = alpha / 2.0;
                ClassicPixel {
                    vx,
                    nov: nov as f32,
                    k: k as f32,
                    c: (1.0 / (nov * (1.0 - k) + k)) as f32,
                    lv: 0.0,
                }
            }
            GModel::HeightCorrelated => ClassicPixel {
                vx,
                nov: nov as f32,
                k: (alpha * alpha) as f32,
                c: (2.0 / nov) as f32,
                lv: (1.0 + 2.0 * ggx(alpha).lambda(nov)) as f32,
            },
        }
    }
}

/// `(Σ (1 − Fc) G_Vis, Σ Fc G_Vis)` over a column's half vectors for one texel.
///
/// ue4: `G_Vis = c · N·L V·H / ((N·L(1 − k) + k) N·H)`;
/// height-correlated (`2Λ(L) N·L = √(α² + N·L²(1 − α²)) − N·L`):
/// `G_Vis = 2 N·L V·H / (N·H N·V ((1 + 2Λ(V)) N·L + √(α² + N·L²(1 − α²))))`.
#[inline(always)]
fn classic_kernel<const HC: bool>(col: &Column, p: ClassicPixel) -> (f64, f64) {
    let (mut total_scale, mut total_bias) = (0.0, 0.0);
    let blocks = col
        .hx
        .chunks(LANES * CHUNKS_PER_FLUSH)
        .zip(col.hz.chunks(LANES * CHUNKS_PER_FLUSH));
    for (hxb, hzb) in blocks {
        let mut scale = [0.0f32; LANES];
        let mut bias = [0.0f32; LANES];
        let chunks = hxb
            .as_chunks::<LANES>()
            .0
            .iter()
            .zip(hzb.as_chunks::<LANES>().0);
        for (hx, hz) in chunks {
            for l in 0..LANES {
                let (hx, hz) = (hx[l], hz[l]);
                let voh = p.vx * hx + p.nov * hz;
                let nol = 2.0 * voh * hz - p.nov;
                let g_vis = if HC {
                    let root = (p.k + nol * nol * (1.0 - p.k)).sqrt();
                    p.c * nol * voh / (hz * (p.lv * nol + root))
                } else {
                    p.c * nol * voh / ((nol * (1.0 - p.k) + p.k) * hz)
                };
                let g_vis = if nol > 0.0 { g_vis } else { 0.0 };
                let m = 1.0 - voh;
                let m2 = m * m;
                let fw = m2 * m2 * m * g_vis;
                scale[l] += g_vis - fw;
                bias[l] += fw;
            }
        }
        total_scale += lanes_sum(&scale);
        total_bias += lanes_sum(&bias);
    }
    (total_scale, total_bias)
}

// ---------------------------------------------------------------------------------------
// Rows, compiled twice

/// What one row needs: either the shared disk (visible normals) or every column's half
/// vectors (classic).
enum Points {
    Visible(Disk),
    Classic(Vec<Column>),
}

/// All texels of row `y` (sums, not yet divided by N). A plain loop, not a closure: a
/// closure would be compiled without the caller's `target_feature`.
#[inline(always)]
fn row_body<const HC: bool>(
    points: &Points,
    g_model: GModel,
    y: usize,
    size: usize,
) -> Vec<(f64, f64)> {
    let n = size as f64;
    let nov = (y as f64 + 0.5) / n;
    let mut out = Vec::with_capacity(size);
    for x in 0..size {
        let r = (x as f64 + 0.5) / n;
        let alpha = r * r;
        out.push(match points {
            Points::Visible(d) => visible_kernel::<HC>(d, VisiblePixel::new(g_model, alpha, nov)),
            Points::Classic(cols) => {
                classic_kernel::<HC>(&cols[x], ClassicPixel::new(g_model, alpha, nov))
            }
        });
    }
    out
}

/// [`row_body`] with AVX2 enabled (eight f32 lanes per instruction). No FMA: the
/// arithmetic, and so the result, is the same as the baseline build's.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn row_avx2<const HC: bool>(
    points: &Points,
    g_model: GModel,
    y: usize,
    size: usize,
) -> Vec<(f64, f64)> {
    row_body::<HC>(points, g_model, y, size)
}

fn row<const HC: bool>(points: &Points, g_model: GModel, y: usize, size: usize) -> Vec<(f64, f64)> {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU supports AVX2, checked just above.
        return unsafe { row_avx2::<HC>(points, g_model, y, size) };
    }
    row_body::<HC>(points, g_model, y, size)
}

/// The split-sum table, row-major (row y = `N·V` index), two interleaved channels per texel:
/// `[scale, bias]`. `size ≥ 1`, `samples ≥ 1`; `progress` steps once per row.
pub fn split_sum(
    size: usize,
    samples: u32,
    g_model: GModel,
    sampling: Sampling,
    progress: &dyn Progress,
) -> Vec<f32> {
    let n = size as f64;
    let points = match sampling {
        Sampling::VisibleNormals => Points::Visible(Disk::new(samples)),
        Sampling::Classic => Points::Classic(
            (0..size)
                .into_par_iter()
                .map(|x| {
                    let r = (x as f64 + 0.5) / n;
                    Column::new(r * r, samples)
                })
                .collect(),
        ),
    };
    let rows: Vec<Vec<(f64, f64)>> = (0..size)
        .into_par_iter()
        .map(|y| {
            let row = match g_model {
                GModel::Ue4 => row::<false>(&points, g_model, y, size),
                GModel::HeightCorrelated => row::<true>(&points, g_model, y, size),
            };
            progress.step();
            row
        })
        .collect();
    let inv = 1.0 / f64::from(samples);
    rows.into_iter()
        .flatten()
        .flat_map(|(s, b)| [(s * inv) as f32, (b * inv) as f32])
        .collect()
}

/// One texel computed in plain f64, sample by sample, from the textbook formulas (with the
/// full 3-vectors, no shortcuts): `(scale, bias)` at roughness `r` and `N·V = nov`. Slow;
/// a cross-check of the vectorised kernels and a reference with many samples.
pub fn split_sum_texel_f64(
    r: f64,
    nov: f64,
    samples: u32,
    g_model: GModel,
    sampling: Sampling,
) -> (f64, f64) {
    let alpha = r * r;
    let lobe = ggx(alpha);
    let v = DVec3::new((1.0 - nov * nov).sqrt(), 0.0, nov);
    let g1_smith_v = lobe.g1(nov);
    let (mut scale, mut bias) = (0.0, 0.0);
    for i in 0..samples {
        let h = match sampling {
            Sampling::Classic => {
                let (u1, u2) = hammersley(i, samples);
                let polar = lobe.sample_polar(u2);
                let phi = 2.0 * PI * u1;
                DVec3::new(polar.sin * phi.cos(), polar.sin * phi.sin(), polar.cos)
            }
            Sampling::VisibleNormals => lobe.sample_visible_normal(v, disk_point(i, samples)),
        };
        let voh = v.dot(h);
        let nol = 2.0 * voh * h.z - v.z;
        let noh = h.z;
        if nol > 0.0 {
            let g = g(g_model, alpha, nov, nol);
            let w = match sampling {
                // G_Vis = G V·H / (N·H N·V)
                Sampling::Classic => g * voh / (noh * nov),
                // f cos / pdf = G / G1_Smith(V)
                Sampling::VisibleNormals => g / g1_smith_v,
            };
            let fc = (1.0 - voh).powi(5);
            scale += (1.0 - fc) * w;
            bias += fc * w;
        }
    }
    (scale / f64::from(samples), bias / f64::from(samples))
}
