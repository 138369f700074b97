//! The verify report: what was rendered, what came out, what was expected, and the verdict.

use serde::Serialize;

use super::stats::SphereStats;
use crate::microfacet::Distribution;

/// One distribution at one roughness: the plain Glossy sphere and the corrected one.
#[derive(Clone, Debug, Serialize)]
pub struct Row {
    pub distribution: Distribution,
    pub roughness: f64,
    pub uncorrected: SphereStats,
    pub corrected: SphereStats,
    /// The integrator's E_avg(r) for this Blender's masking (0–1).
    pub predicted_uncorrected: f64,
    /// gain(r) · E_avg(r): what the coefficients should give (0–1).
    pub predicted_corrected: f64,
    /// Largest |ring mean − 1| of the corrected sphere over its view-cosine rings.
    pub worst_ring: f64,
    /// |corrected mean − 1| ≤ tolerance (and, in the view modes, every ring within the ring
    /// tolerance).
    pub pass: bool,
}

/// Blender's Multiscatter GGX at one roughness (the energy-conserving peer).
#[derive(Clone, Debug, Serialize)]
pub struct ReferenceSphere {
    pub roughness: f64,
    pub stats: SphereStats,
}

#[derive(Clone, Debug, Serialize)]
pub struct RenderInfo {
    pub blender_version: String,
    pub blender_program: String,
    pub masking: String,
    pub cell: u32,
    pub samples: u32,
    pub seed: u32,
    pub width: usize,
    pub height: usize,
    pub render_seconds: f64,
    pub log: String,
    pub command: String,
}

#[derive(Clone, Debug, Serialize)]
pub struct VerifyReport {
    pub coefficients: String,
    pub mode: crate::blender::script::Mode,
    /// Allowed |ring mean − 100 %| in the view modes, in percent.
    pub ring_tolerance_percent: f64,
    pub render: RenderInfo,
    /// Allowed |mean − 100 %| of a corrected sphere, in percent.
    pub tolerance_percent: f64,
    pub rows: Vec<Row>,
    pub reference: Vec<ReferenceSphere>,
    /// Explanations for the reader (display-referred coefficients, masking mismatch, …).
    pub notes: Vec<String>,
    pub pass: bool,
}
