//! Classic analytic BRDFs (`docs/PHYSICS.md` §11): Lambert, the normalised
//! modified Phong, Ward's anisotropic lobe, Cook–Torrance and the Ashikhmin–Shirley
//! Fresnel-blend diffuse term — each with its importance sampler, the sampler's pdf, and the
//! directional albedo they imply.
//!
//! Everything lives in the local shading frame: normal +z, tangent +x (Ward's αx runs along
//! x). Directions are unit vectors pointing away from the surface. `eval` is f(ωo, ωi) itself,
//! not f cosθi, and is 0 when either direction is at or below the horizon. Sampling is
//! deterministic: the caller passes the two uniform numbers `u ∈ [0, 1)²`.

mod cook_torrance;
mod fresnel_blend;
mod lambert;
mod phong;
mod ward;

pub use cook_torrance::{CookTorrance, Shadowing};
pub use fresnel_blend::FresnelBlendDiffuse;
pub use lambert::Lambert;
pub use phong::ModifiedPhong;
pub use ward::Ward;

use glam::DVec3;
use std::f64::consts::PI;

use crate::error::{Error, Quantity};

/// A reflection-only BRDF in the local shading frame, with a sampler and its pdf.
pub trait Brdf {
    /// f(ωo, ωi) in 1/sr; 0 when either cosine is ≤ 0. Helmholtz-reciprocal:
    /// `eval(wo, wi) == eval(wi, wo)`.
    fn eval(&self, wo: DVec3, wi: DVec3) -> f64;

    /// Draws ωi for a given ωo from `u ∈ [0, 1)²`: `Some((wi, pdf))` with the pdf in solid
    /// angle, or `None` when the draw lands at or below the horizon (where f = 0), so a
    /// lobe that reaches below the horizon loses that part of its mass.
    fn sample(&self, wo: DVec3, u: [f64; 2]) -> Option<(DVec3, f64)>;

    /// The solid-angle density with which [`Brdf::sample`] returns `wi`; 0 where it never
    /// does (below the horizon). `∫ pdf dωi` over the sphere is therefore the probability
    /// that `sample` returns `Some`: 1 for the cosine samplers, ≤ 1 for the lobes.
    fn pdf(&self, wo: DVec3, wi: DVec3) -> f64;

    /// Directional albedo `E(μ) = ∫ f(ωo, ωi) cosθi dωi` for `ωo = (√(1 − μ²), 0, μ)`
    /// (in the xz-plane, which matters only for Ward's anisotropic lobe).
    ///
    /// `E = ∫₀¹∫₀¹ w(u) du` with the sample weight `w = f cosθi / pdf` (0 for a `None`
    /// draw), estimated deterministically through [`Brdf::sample`] on an `n × n` grid: the
    /// midpoint rule in `(t, u₁)` with `u₀ = 3t² − 2t³`, weights `6t(1 − t)` normalised to
    /// sum to 1. The graded `u₀` (every sampler here maps it to the polar angle) smooths the
    /// square-root and logarithmic behaviour of `w` at `u₀ → 0, 1`; the weights are
    /// normalised so a constant weight (Lambert) is integrated exactly. What is left is the
    /// jump of `w` where draws cross the horizon.
    ///
    /// Measured against closed forms and a 2000 × 4000 brute-force quadrature over the
    /// hemisphere (`white_furnace_two_methods` in tests/brdf_models.rs; white Lambert,
    /// Fresnel blend, Phong n ≤ 200, Ward α ≥ 0.1, Cook–Torrance α ∈ [0.1, 1.5], μ ∈ {0.1,
    /// 0.5, 1}): max |error| 2.3e-3 at n = 32, 1.8e-4 at n = 64, 2.2e-5 at n = 128,
    /// 9e-6 at n = 256 and 5e-6 at n = 512, where the largest gap is the reference's own
    /// error (Phong n = 200 at μ = 1, exactly 1: quadrature 1 + 5e-6, sampler 1 − 2e-7).
    fn albedo(&self, mu: f64, n: usize) -> f64 {
        let n = n.max(1);
        let wo = DVec3::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu);
        let step = 1.0 / n as f64;
        let rows: Vec<(f64, f64)> = (0..n)
            .map(|i| {
                let t = (i as f64 + 0.5) * step;
                (t * t * (3.0 - 2.0 * t), t * (1.0 - t))
            })
            .collect();
        let row_sum: f64 = rows.iter().map(|&(_, w)| w).sum();
        let mut total = 0.0;
        for &(u0, row_weight) in &rows {
            let mut row = 0.0;
            for j in 0..n {
                let u = [u0, (j as f64 + 0.5) * step];
                if let Some((wi, pdf)) = self.sample(wo, u)
                    && pdf > 0.0
                {
                    row += self.eval(wo, wi) * wi.z / pdf;
                }
            }
            total += row * row_weight;
        }
        total * step / row_sum
    }
}

/// The grid size [`model_albedo`] uses: `ALBEDO_GRID²` draws per estimate.
pub const ALBEDO_GRID: usize = 512;

/// The models the CLI can name (serialised by their Rust names: `CookTorrance`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize)]
pub enum Model {
    Lambert,
    Phong,
    Ward,
    CookTorrance,
    FresnelBlend,
}

impl Model {
    pub const ALL: [Model; 5] = [
        Model::Lambert,
        Model::Phong,
        Model::Ward,
        Model::CookTorrance,
        Model::FresnelBlend,
    ];

    /// The CLI spelling: `lambert`, `phong`, `ward`, `cook-torrance`, `fresnel-blend`.
    pub fn key(self) -> &'static str {
        match self {
            Model::Lambert => "lambert",
            Model::Phong => "phong",
            Model::Ward => "ward",
            Model::CookTorrance => "cook-torrance",
            Model::FresnelBlend => "fresnel-blend",
        }
    }

    /// Builds the model from the parameters it uses (see [`ModelParams`]), validated.
    pub fn brdf(self, p: &ModelParams) -> Result<Box<dyn Brdf + Send + Sync>, Error> {
        Ok(match self {
            Model::Lambert => Box::new(Lambert::new(p.rho)?),
            Model::Phong => Box::new(ModifiedPhong::new(p.rho, p.exponent)?),
            Model::Ward => Box::new(Ward::new(p.rho, p.alpha_x, p.alpha_y)?),
            Model::CookTorrance => Box::new(CookTorrance::new(p.rho, p.alpha_x)?),
            Model::FresnelBlend => Box::new(FresnelBlendDiffuse::new(p.rho, p.rs)?),
        })
    }
}

impl std::fmt::Display for Model {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.key())
    }
}

impl std::str::FromStr for Model {
    type Err = Error;

    /// Case-insensitive; `-` and `_` are interchangeable.
    fn from_str(s: &str) -> Result<Self, Error> {
        let norm = s.trim().to_ascii_lowercase().replace('_', "-");
        Model::ALL
            .into_iter()
            .find(|m| m.key() == norm)
            .ok_or_else(|| {
                Error::input(
                    Quantity::Model,
                    s,
                    "one of lambert, phong, ward, cook-torrance, fresnel-blend (case-insensitive)",
                )
            })
    }
}

/// Parameters for [`model_albedo`]; each model reads only the ones it needs.
///
/// | model           | reads                                   |
/// |-----------------|-----------------------------------------|
/// | `lambert`       | `rho` = ρ                               |
/// | `phong`         | `rho` = ρs, `exponent` = n              |
/// | `ward`          | `rho` = ρs, `alpha_x`, `alpha_y`        |
/// | `cook-torrance` | `rho` = f0, `alpha_x` = α (isotropic)   |
/// | `fresnel-blend` | `rho` = Rd, `rs` = Rs                   |
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ModelParams {
    /// Reflectance ρ, ρs, f0 or Rd, in [0, 1]. Default 1 (a white furnace).
    pub rho: f64,
    /// Fresnel-blend's specular reflectance at normal incidence Rs, in [0, 1]. Default 0.04.
    pub rs: f64,
    /// Modified Phong exponent n ≥ 0. Default 32.
    pub exponent: f64,
    /// Ward's αx (along the tangent) and Cook–Torrance's α, > 0. Default 0.3.
    pub alpha_x: f64,
    /// Ward's αy (along the bitangent), > 0. Default 0.3.
    pub alpha_y: f64,
}

impl Default for ModelParams {
    fn default() -> Self {
        ModelParams {
            rho: 1.0,
            rs: 0.04,
            exponent: 32.0,
            alpha_x: 0.3,
            alpha_y: 0.3,
        }
    }
}

/// Directional albedo `E(μ)` of `model` with `params` at view cosine `mu` ∈ (0, 1],
/// by [`Brdf::albedo`] on an [`ALBEDO_GRID`]² grid.
///
/// ```
/// use gloffuse_physics::measure::brdf::{model_albedo, Model, ModelParams};
/// let p = ModelParams { rho: 0.5, ..ModelParams::default() };
/// let e = model_albedo("Lambert".parse().unwrap(), &p, 0.3).unwrap();
/// assert!((e - 0.5).abs() < 1e-12);
/// assert!(model_albedo(Model::Lambert, &p, 0.0).is_err());
/// ```
pub fn model_albedo(model: Model, params: &ModelParams, mu: f64) -> Result<f64, Error> {
    if !(mu > 0.0 && mu <= 1.0) {
        return Err(Error::input(Quantity::ViewCosine, mu, "a number in (0, 1]"));
    }
    Ok(model.brdf(params)?.albedo(mu, ALBEDO_GRID))
}

/// Hemispherical average `E_avg = 2∫E(μ)μdμ` of `model` with `params`, by a 16-point
/// midpoint rule in μ² over [`model_albedo`].
pub fn model_average_albedo(model: Model, params: &ModelParams) -> Result<f64, Error> {
    let n = 16;
    (0..n)
        .map(|i| {
            let mu = ((i as f64 + 0.5) / n as f64).sqrt();
            model_albedo(model, params, mu).map(|e| e / n as f64)
        })
        .sum()
}

/// A reflectance: finite, in [0, 1].
fn reflectance(what: &'static str, value: f64) -> Result<f64, Error> {
    if (0.0..=1.0).contains(&value) {
        Ok(value)
    } else {
        Err(Error::input(
            Quantity::ModelParameter(what),
            value,
            "a number from 0 to 1",
        ))
    }
}

/// A lobe width α: finite and > 0.
fn width(what: &'static str, value: f64) -> Result<f64, Error> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(Error::input(
            Quantity::ModelParameter(what),
            value,
            "a finite number > 0",
        ))
    }
}

/// The mirror direction of ω about the normal: `(−x, −y, z)`.
fn mirror(w: DVec3) -> DVec3 {
    DVec3::new(-w.x, -w.y, w.z)
}

/// Cosine-weighted hemisphere sampling (Malley's method, polar map): `cosθ = √(1 − u₀)`,
/// `φ = 2π u₁`, pdf `cosθ / π`. `None` for a grazing draw (cosθ = 0).
fn sample_cosine(u: [f64; 2]) -> Option<(DVec3, f64)> {
    let z = (1.0 - u[0]).max(0.0).sqrt();
    if z <= 0.0 {
        return None;
    }
    let r = u[0].max(0.0).sqrt();
    let (s, c) = (2.0 * PI * u[1]).sin_cos();
    Some((DVec3::new(r * c, r * s, z), z / PI))
}

/// The pdf of [`sample_cosine`]: `cosθi / π` above the horizon, else 0 (and 0 for ωo below).
fn cosine_pdf(wo: DVec3, wi: DVec3) -> f64 {
    if wo.z <= 0.0 || wi.z <= 0.0 {
        0.0
    } else {
        wi.z / PI
    }
}

/// A unit vector from its cosine and sine of polar angle and its azimuth.
fn spherical(cos_t: f64, sin_t: f64, phi: f64) -> DVec3 {
    let (s, c) = phi.sin_cos();
    DVec3::new(sin_t * c, sin_t * s, cos_t)
}

/// Reflects ωo about the microfacet normal h: `ωi = 2 (ωo·h) h − ωo`, as a draw of a
/// half-vector sampler with half-vector density `pdf_h`; the solid-angle pdf of ωi is
/// `pdf_h / (4 ωo·h)` (Walter et al. 2007, eq. 14). `None` when h faces away from ωo or ωi
/// lands at or below the horizon.
fn reflect_about(wo: DVec3, h: DVec3, pdf_h: f64) -> Option<(DVec3, f64)> {
    let o_h = wo.dot(h);
    if wo.z <= 0.0 || o_h <= 0.0 {
        return None;
    }
    let wi = 2.0 * o_h * h - wo;
    (wi.z > 0.0 && pdf_h > 0.0).then(|| (wi, pdf_h / (4.0 * o_h)))
}

/// The half vector of a reflection pair above the horizon, or `None` if either is below.
fn half_vector(wo: DVec3, wi: DVec3) -> Option<DVec3> {
    (wo.z > 0.0 && wi.z > 0.0).then(|| (wo + wi).normalize())
}
