//! The split-sum LUT (Karis 2013, "Real Shading in Unreal Engine 4"; the classic "BRDF
//! generator"; `docs/PHYSICS.md` §10): deterministic quadrature, vectorised.
//!
//! An n × n table of two channels, **R = scale, G = bias**, in the layout of every
//! whole-table kind ([`super`]); at run time `specular = F0 · scale + bias`.
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
//! # Two methods ([`Estimate`])
//!
//! * [`Estimate::Quadrature`] (the default; [`Rule::default`]) integrates it by
//!   deterministic Gauss–Legendre quadrature over the half vector, no samples. Written as a
//!   density, the integrand is GGX's distribution of visible normals (Heitz 2018) times the
//!   weight `G/G1(V)`, which is smooth except where `N·L` crosses 0. So the domain is cut
//!   exactly there: along each azimuth φ of H, L meets the horizon at
//!   `tan θh = T(φ) = (vx cos φ + √(vx² cos² φ + vz²))/vz` (independent of α). Three pieces:
//!   - **azimuth**: φ ∈ [0, π] (the y-mirror doubles it), split at π/2, where `T` changes
//!     over `|cos φ| ~ N·V/vx` — sharply at grazing views; [`Rule::azimuth`] nodes per
//!     side, which Gauss–Legendre crowds towards the cut.
//!   - **pole** (`tan θh ≤ min(T, 0.3)`): the visible-normal density in the stretched
//!     normal n (`tan θn = tan θh / α`, the lobe's own width), with `e = tan(θn/2)` so that
//!     every node is rational arithmetic; [`Rule::pole`] nodes.
//!   - **tail** (`0.3 < tan θh < T`): `u = ln tan θh`, where GGX's heavy tail is smooth and
//!     where the height-correlated weight's change within `N·L ~ N·V` near the horizon is
//!     smooth too; [`Rule::tail`] nodes. These nodes depend on `N·V` only, so each row
//!     makes them once for all its texels, and a texel adds only `D(α)` and `G(α)`.
//!
//!   Measured on the 512² table (`cargo bench --bench lut`): within 2.2e-5 of converged
//!   values for both G models, against a fine rule of the same quadrature (64 nodes per
//!   piece, itself within 2e-6 of the f64 visible-normal estimator with 2²⁰ samples) and,
//!   for height-correlated G, against `AlbedoIntegrator` (within 1.8e-5).
//! * [`Estimate::Classic`] is the textbook estimator to the letter: Hammersley points
//!   `(u, v) = (i/N, radical_inverse₂(i))`, `φ = 2πu`,
//!   `cos θh = √((1 − v)/(1 + (α² − 1) v))`, and the sums above divided by N (samples with
//!   `N·L ≤ 0` still count). Its weight `G_Vis` grows like `tan θh / α` towards grazing
//!   views, so at 1024 samples it is off by up to 1e-2 near `N·V = 0` (measured:
//!   `cargo bench --bench lut`).
//!
//! [`split_sum_texel_sampled`] is a third, slow estimator in plain f64 that shares no
//! integration code with the quadrature (only the masking formula [`g`]): the classic
//! estimator, or GGX's visible normals sampled with centred
//! Hammersley points on Heitz's disk (pdf `G1(V) max(0, V·H) D(H) / N·V`, weight
//! `G/G1(V)`). The tests and the bench use it as the independent reference.
//!
//! # Speed
//!
//! Each row runs every texel through f32 kernels with eight explicit accumulator lanes
//! (flushed to f64 per azimuth, per 512 tail nodes, every 512 classic samples). The
//! lanes fix the order of the sum, so the result is bit-identical whether the kernel runs as
//! SSE2 or AVX2 code (chosen at run time; no FMA) and for any thread count. Rows run in
//! parallel (rayon). The f32 kernels stay within 2e-7 of the same rule in f64
//! ([`split_sum_texel_quadrature`]).

use glam::DVec3;
use rayon::prelude::*;
use std::f64::consts::{FRAC_PI_2, PI};

use super::{Bsdf, GModel, KindFacts, LutOptions, Method, Spec, Table};
use crate::error::{Error, Field, Hint};
use crate::measure::albedo::gauss_unit;
use crate::measure::{Distribution, Masking, Microfacet};
use crate::progress::Progress;

/// The split-sum table: its facts for `lut` (see the module's doc for its layout).
pub const KIND: KindFacts = KindFacts {
    key: "split-sum",
    default_size: 512,
    size_limit: None,
    bsdf,
    channels: &["R: scale", "G: bias"],
    steps_per_size: 1,
    slice_iors: None,
    slice_azimuths: None,
    compute: table,
};

/// Hammersley samples per texel of the classic estimator when none are asked for.
const CLASSIC_SAMPLES: u32 = 2048;

/// The split-sum table: GGX, no Blender version, and samples only for the classic method.
fn bsdf(args: &LutOptions) -> Result<Bsdf, Error> {
    if let Some(d) = args.distribution.filter(|&d| d != Distribution::Ggx) {
        return Err(Error::input(
            Field::Distribution,
            d.key(),
            Hint::new(
                "ggx or nothing: the split-sum table is GGX by definition (use {} kulla-conty for Cycles' Beckmann or Ashikhmin-Shirley)",
                [Field::Kind],
            ),
        ));
    }
    if let Some(v) = args.blender_version {
        return Err(Error::input(
            Field::BlenderVersion,
            v,
            Hint::new(
                "nothing with {} split-sum (choose its masking with {}; {} applies to kulla-conty)",
                [Field::Kind, Field::GModel, Field::BlenderVersion],
            ),
        ));
    }
    let estimate = match args.method.unwrap_or(Method::Quadrature) {
        Method::Quadrature => {
            if let Some(n) = args.samples {
                return Err(Error::input(
                    Field::Samples,
                    n,
                    Hint::new(
                        "nothing with {} split-sum's default {} quadrature (it is deterministic quadrature, not sampled; {} applies to {} classic)",
                        [Field::Kind, Field::Method, Field::Samples, Field::Method],
                    ),
                ));
            }
            Estimate::Quadrature(Rule::default())
        }
        Method::Classic => Estimate::Classic {
            samples: args.samples.unwrap_or(CLASSIC_SAMPLES),
        },
    };
    Ok(Bsdf::SplitSum {
        g_model: args.g_model.unwrap_or(GModel::Ue4),
        estimate,
    })
}

/// The two-channel table of a split-sum request.
fn table(spec: &Spec, progress: &dyn Progress) -> Table {
    let Bsdf::SplitSum { g_model, estimate } = spec.bsdf else {
        unreachable!("only split-sum's own request is its GGX");
    };
    Table {
        width: spec.size,
        height: spec.size,
        channels: &["R", "G"],
        data: split_sum(spec.size, g_model, estimate, progress),
    }
}

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

/// Disk point `i` of `n` for visible-normal sampling: `ρ² = (i + ½)/n` (centred),
/// `φ = 2π radical_inverse₂(i)`.
pub fn disk_point(i: u32, n: u32) -> (f64, f64) {
    let rho = ((f64::from(i) + 0.5) / f64::from(n)).sqrt();
    let phi = 2.0 * PI * radical_inverse_base2(i);
    (rho * phi.cos(), rho * phi.sin())
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
// Quadrature

/// Node counts of the split-sum quadrature ([`Rule::default`] meets 5e-5; see the module
/// doc).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Rule {
    /// Gauss–Legendre nodes in azimuth, on each side of φ = π/2.
    pub azimuth: usize,
    /// Nodes along the pole piece (stretched normals with `tan θh ≤ TAIL_START`).
    pub pole: usize,
    /// Nodes along the tail piece (`ln tan θh` from `ln TAIL_START` to the horizon of L).
    pub tail: usize,
}

impl Default for Rule {
    fn default() -> Self {
        Rule {
            azimuth: 12,
            pole: 24,
            tail: 16,
        }
    }
}

/// `tan θh` where the pole piece ends and the tail piece begins.
const TAIL_START: f64 = 0.3;

/// `e = tan(θ/2)` of an angle with tangent `t ≥ 0`.
fn half_tan(t: f64) -> f64 {
    t / (1.0 + (1.0 + t * t).sqrt())
}

/// One azimuth node of a row: `cos φ`, its weight (both sides of the y-mirror counted), and
/// `T = tan θh` where L meets the horizon.
struct Azimuth {
    cos: f64,
    weight: f64,
    horizon: f64,
}

/// One tail node of a row (α-independent): the half vector's `cos²θh`, `N·L`, `V·H`, the
/// Fresnel factor, and the weight `w_u w_φ V·H sin²θh cosθh / N·V` (times `D G` per texel).
struct TailNode {
    cos2: f64,
    nol: f64,
    voh: f64,
    weight: f64,
}

/// What the quadrature of one row (one `N·V`) shares across its texels.
struct RowRule {
    nov: f64,
    vx: f64,
    azimuths: Vec<Azimuth>,
    /// Gauss–Legendre on [0, 1] for the pole piece.
    pole: Vec<(f64, f64)>,
    tail: Vec<TailNode>,
}

impl RowRule {
    /// The integral over H in (θh, φ), φ ∈ [0, π] (the y-mirror gives the other half).
    /// L meets the horizon at `tan θh = T(φ) = (vx cos φ + √(vx² cos² φ + vz²))/vz`, which
    /// changes over `|cos φ| ~ vz/vx` around φ = π/2 — sharply at grazing views — so φ is
    /// split there, and Gauss–Legendre crowds each side's nodes towards the cut. (Without
    /// the cut, grazing texels in `tests/lut.rs` miss their 5e-5 bound.)
    fn new(nov: f64, rule: Rule) -> Self {
        let vx = (1.0 - nov * nov).sqrt();
        let azimuth_rule = gauss_unit(rule.azimuth);
        let tail_rule = gauss_unit(rule.tail);
        let mut azimuths = Vec::with_capacity(2 * rule.azimuth);
        let mut tail = Vec::new();
        for side in [-1.0, 1.0] {
            for &(x, w) in &azimuth_rule {
                let phi = FRAC_PI_2 * (1.0 + side * x);
                // ×2 for the mirror half φ ∈ [−π, 0].
                let weight = 2.0 * w * FRAC_PI_2;
                let cos = phi.cos();
                let horizon = (vx * cos + (vx * vx * cos * cos + nov * nov).sqrt()) / nov;
                azimuths.push(Azimuth {
                    cos,
                    weight,
                    horizon,
                });
                if horizon <= TAIL_START {
                    continue;
                }
                // The tail in u = ln tan θh: smooth up to the horizon of L, even where G's
                // masking of L changes within N·L ~ N·V at grazing views.
                let (u0, u1) = (TAIL_START.ln(), horizon.ln());
                for &(y, wu) in &tail_rule {
                    let t = (u0 + (u1 - u0) * y).exp();
                    let cos_h = 1.0 / (1.0 + t * t).sqrt();
                    let sin_h = t * cos_h;
                    let voh = vx * sin_h * cos + nov * cos_h;
                    let nol = 2.0 * voh * cos_h - nov;
                    if nol <= 0.0 || voh <= 0.0 {
                        continue;
                    }
                    tail.push(TailNode {
                        cos2: cos_h * cos_h,
                        nol,
                        voh,
                        // dω = sinθh dθh dφ, dθh = sinθh cosθh du
                        weight: wu * (u1 - u0) * weight * voh * sin_h * sin_h * cos_h / nov,
                    });
                }
            }
        }
        RowRule {
            nov,
            vx,
            azimuths,
            pole: gauss_unit(rule.pole),
            tail,
        }
    }
}

/// Per-texel constants of both pieces.
struct Texel {
    alpha: f64,
    /// `V_h = normalize(α vx, 0, vz) = (a, 0, b)`.
    a: f64,
    b: f64,
    /// `1/(π (1 + V_h.z)/2)`: the visible-normal density's normalisation.
    norm: f64,
}

impl Texel {
    fn new(row: &RowRule, alpha: f64) -> Self {
        let (ax, az) = (alpha * row.vx, row.nov);
        let len = (ax * ax + az * az).sqrt();
        let b = az / len;
        Texel {
            alpha,
            a: ax / len,
            b,
            norm: 2.0 / (PI * (1.0 + b)),
        }
    }

    /// The pole piece's end for one azimuth: `e = tan(θn/2)` of the stretched normal with
    /// `tan θn = min(T, TAIL_START)/α`.
    fn pole_end(&self, az: &Azimuth) -> f64 {
        half_tan(az.horizon.min(TAIL_START) / self.alpha)
    }
}

/// `(scale, bias)` of one texel by the quadrature, in plain f64 with [`Microfacet`] and [`g`]:
/// the reference the f32 kernels are checked against.
pub fn split_sum_texel_quadrature(r: f64, nov: f64, g_model: GModel, rule: Rule) -> (f64, f64) {
    let row = RowRule::new(nov, rule);
    texel_f64(&row, g_model, r * r)
}

fn texel_f64(row: &RowRule, g_model: GModel, alpha: f64) -> (f64, f64) {
    let lobe = ggx(alpha);
    let p = Texel::new(row, alpha);
    let (nov, vx) = (row.nov, row.vx);
    let g1v = lobe.g1(nov);
    let (mut scale, mut bias) = (0.0, 0.0);
    let mut add = |w: f64, voh: f64| {
        let fc = (1.0 - voh).powi(5);
        scale += (1.0 - fc) * w;
        bias += fc * w;
    };
    // Pole piece: stretched normals n = (sinθn cosφ, ·, cosθn) with e = tan(θn/2), weighted
    // by the visible-normal density (n·V_h)/(π(1 + V_h.z)/2) and the weight G/G1(V).
    for az in &row.azimuths {
        let e1 = p.pole_end(az);
        for &(y, wy) in &row.pole {
            let e = e1 * y;
            let d = 1.0 + e * e;
            let (st, ct) = (2.0 * e / d, (1.0 - e * e) / d);
            let h = DVec3::new(alpha * st * az.cos, 0.0, ct);
            let l2 = alpha * alpha * st * st + ct * ct;
            let voh = (vx * h.x + nov * h.z) / l2.sqrt();
            let nol = 2.0 * voh * ct / l2.sqrt() - nov;
            if nol <= 0.0 {
                continue;
            }
            let nv = p.a * st * az.cos + p.b * ct;
            // dω_n = sinθn dθn dφ, dθn = 2 de/(1 + e²)
            let w = wy * e1 * az.weight * p.norm * nv * st * 2.0 / d;
            add(w * g(g_model, alpha, nov, nol) / g1v, voh);
        }
    }
    // Tail piece: G V·H D / N·V dω_h.
    for t in &row.tail {
        let w = t.weight * lobe.d(t.cos2.sqrt()) * g(g_model, alpha, nov, t.nol);
        add(w, t.voh);
    }
    (scale, bias)
}

/// The tail nodes as f32 lanes: `cos²θh`, `N·L`, the Fresnel factor and the weight (padded
/// with weight 0).
struct TailLanes {
    cos2: Vec<f32>,
    nol: Vec<f32>,
    fc: Vec<f32>,
    weight: Vec<f32>,
}

impl TailLanes {
    fn new(tail: &[TailNode]) -> Self {
        let padded = tail.len().div_ceil(LANES) * LANES;
        let mut lanes = TailLanes {
            cos2: vec![1.0; padded],
            nol: vec![1.0; padded],
            fc: vec![0.0; padded],
            weight: vec![0.0; padded],
        };
        for (i, t) in tail.iter().enumerate() {
            lanes.cos2[i] = t.cos2 as f32;
            lanes.nol[i] = t.nol as f32;
            lanes.fc[i] = (1.0 - t.voh).powi(5) as f32;
            lanes.weight[i] = t.weight as f32;
        }
        lanes
    }
}

/// A row ready for the f32 kernels.
struct QuadratureRow {
    rule: RowRule,
    /// The pole rule's nodes and weights, padded to [`LANES`] with weight 0.
    pole_y: Vec<f32>,
    pole_w: Vec<f32>,
    tail: TailLanes,
}

impl QuadratureRow {
    fn new(nov: f64, rule: Rule) -> Self {
        let rule = RowRule::new(nov, rule);
        let padded = rule.pole.len().div_ceil(LANES) * LANES;
        let mut pole_y = vec![0.5; padded];
        let mut pole_w = vec![0.0; padded];
        for (i, &(y, w)) in rule.pole.iter().enumerate() {
            pole_y[i] = y as f32;
            pole_w[i] = w as f32;
        }
        let tail = TailLanes::new(&rule.tail);
        QuadratureRow {
            rule,
            pole_y,
            pole_w,
            tail,
        }
    }
}

/// Per-texel f32 constants of the quadrature kernels.
#[derive(Clone, Copy)]
struct QuadraturePixel {
    alpha: f32,
    alpha2: f32,
    vx: f32,
    nov: f32,
    a: f32,
    b: f32,
    /// ue4: `k = α/2`; height-correlated: `α²`.
    k: f32,
    /// height-correlated: `1 + 2Λ(V)`.
    lv: f32,
    /// The masking weight's factor in the pole piece (ue4: `G1(V)/G1_Smith(V)`;
    /// height-correlated: `2(1 + Λ(V))`) and in the tail (ue4: `G1(V)`; height-correlated: 2).
    c_pole: f64,
    c_tail: f64,
}

impl QuadraturePixel {
    fn new(g_model: GModel, p: &Texel, nov: f64, vx: f64) -> Self {
        let alpha = p.alpha;
        let lambda_v = ggx(alpha).lambda(nov);
        let (k, lv, c_pole, c_tail) = match g_model {
            GModel::Ue4 => {
                let k = alpha / 2.0;
                let g1 = nov / (nov * (1.0 - k) + k);
                (k, 0.0, g1 * (1.0 + lambda_v), g1)
            }
            GModel::HeightCorrelated => (
                alpha * alpha,
                1.0 + 2.0 * lambda_v,
                2.0 * (1.0 + lambda_v),
                2.0,
            ),
        };
        QuadraturePixel {
            alpha: alpha as f32,
            alpha2: (alpha * alpha) as f32,
            vx: vx as f32,
            nov: nov as f32,
            a: p.a as f32,
            b: p.b as f32,
            k: k as f32,
            lv: lv as f32,
            c_pole,
            c_tail,
        }
    }

    /// The denominator of `G(N·L)` (up to the factor `c`) for `N·L = nol/l`, made
    /// homogeneous in `l` so that `G = nol / den`: ue4 `nol (1 − k) + k l`, height-correlated
    /// `(1 + 2Λ(V)) nol + √(α² l² + nol² (1 − α²))`.
    #[inline(always)]
    fn masking_den<const HC: bool>(&self, nol: f32, l: f32) -> f32 {
        if HC {
            self.lv * nol + (self.k * l * l + nol * nol * (1.0 - self.k)).sqrt()
        } else {
            nol * (1.0 - self.k) + self.k * l
        }
    }
}

/// `(scale, bias)` of one texel by the quadrature in f32 lanes, summed in f64 per azimuth
/// and per tail block. Same nodes and formulas as [`texel_f64`].
#[inline(always)]
// Long on purpose: one hot loop nest whose f32 lanes must vectorise, kept node by node beside texel_f64.
fn quadrature_kernel<const HC: bool>(
    row: &QuadratureRow,
    g_model: GModel,
    alpha: f64,
) -> (f64, f64) {
    let texel = Texel::new(&row.rule, alpha);
    let p = QuadraturePixel::new(g_model, &texel, row.rule.nov, row.rule.vx);
    let (mut total_scale, mut total_bias) = (0.0, 0.0);
    let ys = row.pole_y.as_chunks::<LANES>().0;
    let ws = row.pole_w.as_chunks::<LANES>().0;
    for az in &row.rule.azimuths {
        let e1_64 = texel.pole_end(az);
        let e1 = e1_64 as f32;
        let cos_phi = az.cos as f32;
        let mut scale = [0.0f32; LANES];
        let mut bias = [0.0f32; LANES];
        for (y, wy) in ys.iter().zip(ws) {
            for l in 0..LANES {
                // Everything below is homogeneous in the unnormalised (sinθn, cosθn) =
                // (2e, 1 − e²), whose length is d = 1 + e², so one division per node does.
                let e = e1 * y[l];
                let e2 = e * e;
                let d = 1.0 + e2;
                let st = 2.0 * e;
                let ct = 1.0 - e2;
                let sx = st * cos_phi;
                // H ∝ (α sx, ·, ct); l2 = |H|² d²; dot = V·H |H| d; nol_l2 = N·L l2.
                let l2 = p.alpha2 * st * st + ct * ct;
                let dot = p.vx * p.alpha * sx + p.nov * ct;
                let nol_l2 = 2.0 * dot * ct - p.nov * l2;
                let voh = dot / l2.sqrt();
                // n·V_h d
                let nv = p.a * sx + p.b * ct;
                // n·V_h sinθn /(1 + e²) × G/G1(V) (the 2 of dθn and c are applied per azimuth)
                let w = if nol_l2 > 0.0 {
                    wy[l] * nv * st * nol_l2 / (p.masking_den::<HC>(nol_l2, l2) * d * d * d)
                } else {
                    0.0
                };
                let m = 1.0 - voh;
                let m2 = m * m;
                let fw = m2 * m2 * m * w;
                scale[l] += w - fw;
                bias[l] += fw;
            }
        }
        // dθn = 2 de/(1 + e²); the visible-normal density's normalisation.
        let f = 2.0 * e1_64 * az.weight * texel.norm * p.c_pole;
        total_scale += lanes_sum(&scale) * f;
        total_bias += lanes_sum(&bias) * f;
    }
    let t = &row.tail;
    let blocks = t
        .cos2
        .chunks(LANES * CHUNKS_PER_FLUSH)
        .zip(t.nol.chunks(LANES * CHUNKS_PER_FLUSH))
        .zip(t.fc.chunks(LANES * CHUNKS_PER_FLUSH))
        .zip(t.weight.chunks(LANES * CHUNKS_PER_FLUSH));
    let mut tail_scale = 0.0;
    let mut tail_bias = 0.0;
    for (((c2b, nolb), fcb), wb) in blocks {
        let mut scale = [0.0f32; LANES];
        let mut bias = [0.0f32; LANES];
        let chunks = c2b
            .as_chunks::<LANES>()
            .0
            .iter()
            .zip(nolb.as_chunks::<LANES>().0)
            .zip(fcb.as_chunks::<LANES>().0)
            .zip(wb.as_chunks::<LANES>().0);
        for (((c2, nol), fc), w) in chunks {
            for l in 0..LANES {
                // GGX D without its constant α²/π
                let d = 1.0 + (p.alpha2 - 1.0) * c2[l];
                let term = w[l] * nol[l] / (p.masking_den::<HC>(nol[l], 1.0) * d * d);
                let fw = term * fc[l];
                scale[l] += term - fw;
                bias[l] += fw;
            }
        }
        tail_scale += lanes_sum(&scale);
        tail_bias += lanes_sum(&bias);
    }
    let f = alpha * alpha / PI * p.c_tail;
    (total_scale + tail_scale * f, total_bias + tail_bias * f)
}

// ---------------------------------------------------------------------------------------
// Classic sampling

/// Half vectors of one column for the classic estimator: `H.x` and `H.z` (`H.y` never
/// enters, because V lies in the xz-plane), padded with `H = 0`, which gives
/// `N·L = −N·V < 0`.
struct Column {
    hx: Vec<f32>,
    hz: Vec<f32>,
    samples: f64,
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
        Column {
            hx,
            hz,
            samples: f64::from(samples),
        }
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

/// How the table is computed: the quadrature (the default) or the classic estimator with
/// N Hammersley samples per texel.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Estimate {
    Quadrature(Rule),
    Classic { samples: u32 },
}

/// What the rows share: the classic estimator's half vectors per column (the quadrature's
/// nodes are made per row).
enum Shared {
    Quadrature(Rule),
    Classic(Vec<Column>),
}

/// All texels of row `y`. A plain loop, not a closure: a closure would be compiled without
/// the caller's `target_feature`.
#[inline(always)]
fn row_body<const HC: bool>(
    shared: &Shared,
    g_model: GModel,
    y: usize,
    size: usize,
) -> Vec<(f64, f64)> {
    let n = size as f64;
    let nov = (y as f64 + 0.5) / n;
    let mut out = Vec::with_capacity(size);
    match shared {
        Shared::Quadrature(rule) => {
            let row = QuadratureRow::new(nov, *rule);
            for x in 0..size {
                let r = (x as f64 + 0.5) / n;
                out.push(quadrature_kernel::<HC>(&row, g_model, r * r));
            }
        }
        Shared::Classic(cols) => {
            for (x, col) in cols.iter().enumerate() {
                let r = (x as f64 + 0.5) / n;
                let (s, b) = classic_kernel::<HC>(col, ClassicPixel::new(g_model, r * r, nov));
                out.push((s / col.samples, b / col.samples));
            }
        }
    }
    out
}

/// [`row_body`] with AVX2 enabled (eight f32 lanes per instruction). No FMA: the
/// arithmetic, and so the result, is the same as the baseline build's.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn row_avx2<const HC: bool>(
    shared: &Shared,
    g_model: GModel,
    y: usize,
    size: usize,
) -> Vec<(f64, f64)> {
    row_body::<HC>(shared, g_model, y, size)
}

fn row<const HC: bool>(shared: &Shared, g_model: GModel, y: usize, size: usize) -> Vec<(f64, f64)> {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU supports AVX2, checked just above.
        return unsafe { row_avx2::<HC>(shared, g_model, y, size) };
    }
    row_body::<HC>(shared, g_model, y, size)
}

/// The split-sum table, row-major (row y = `N·V` index), two interleaved channels per texel:
/// `[scale, bias]`. `size ≥ 1` (and `samples ≥ 1`); `progress` steps once per row. Every
/// texel is computed on its own, so the table is bit-identical for any thread count.
pub fn split_sum(
    size: usize,
    g_model: GModel,
    estimate: Estimate,
    progress: &dyn Progress,
) -> Vec<f32> {
    let n = size as f64;
    let shared = match estimate {
        Estimate::Quadrature(rule) => Shared::Quadrature(rule),
        Estimate::Classic { samples } => Shared::Classic(
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
                GModel::Ue4 => row::<false>(&shared, g_model, y, size),
                GModel::HeightCorrelated => row::<true>(&shared, g_model, y, size),
            };
            progress.step();
            row
        })
        .collect();
    rows.into_iter()
        .flatten()
        .flat_map(|(s, b)| [s as f32, b as f32])
        .collect()
}

/// The estimators of [`split_sum_texel_sampled`]: the classic one (H ~ D·N·H, Hammersley
/// points) or GGX's visible normals (Heitz 2018, centred Hammersley points on the disk).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Sampler {
    Classic,
    VisibleNormals,
}

/// One texel estimated in plain f64, sample by sample, from the textbook formulas (with the
/// full 3-vectors, no shortcuts): `(scale, bias)` at roughness `r` and `N·V = nov`. Slow;
/// it shares only [`g`] with the quadrature: a cross-check of the classic kernel and, with
/// visible normals and many samples, an independent reference for the quadrature.
pub fn split_sum_texel_sampled(
    r: f64,
    nov: f64,
    samples: u32,
    g_model: GModel,
    sampler: Sampler,
) -> (f64, f64) {
    let alpha = r * r;
    let lobe = ggx(alpha);
    let v = DVec3::new((1.0 - nov * nov).sqrt(), 0.0, nov);
    let g1_smith_v = lobe.g1(nov);
    let (mut scale, mut bias) = (0.0, 0.0);
    for i in 0..samples {
        let h = match sampler {
            Sampler::Classic => {
                let (u1, u2) = hammersley(i, samples);
                let polar = lobe.sample_polar(u2);
                let phi = 2.0 * PI * u1;
                DVec3::new(polar.sin * phi.cos(), polar.sin * phi.sin(), polar.cos)
            }
            Sampler::VisibleNormals => lobe.sample_visible_normal(v, disk_point(i, samples)),
        };
        let voh = v.dot(h);
        let nol = 2.0 * voh * h.z - v.z;
        let noh = h.z;
        if nol > 0.0 {
            let g = g(g_model, alpha, nov, nol);
            let w = match sampler {
                // G_Vis = G V·H / (N·H N·V)
                Sampler::Classic => g * voh / (noh * nov),
                // f cos / pdf = G / G1_Smith(V)
                Sampler::VisibleNormals => g / g1_smith_v,
            };
            let fc = (1.0 - voh).powi(5);
            scale += (1.0 - fc) * w;
            bias += fc * w;
        }
    }
    (scale / f64::from(samples), bias / f64::from(samples))
}
