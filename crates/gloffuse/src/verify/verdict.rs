//! The verdict of a verify run, as data: what was rendered, what came out, what was
//! expected, whether each sphere passes, and notes for the reader. `super::judge` makes it;
//! `crate::report` renders it (and puts the notes into words).

use serde::{Serialize, Serializer};

use super::plan::Block;
use super::render::RenderInfo;
use super::stats::SphereStats;
use crate::fit::Coefficients;
use crate::generate::{ColorModel, Mode};
use crate::measure::{BlenderVersion, Distribution, Engine, Masking, Roughness};

/// Rings with fewer fully covered pixels than this are too noisy to judge flatness by (at
/// 64 px per sphere, the outermost ring, μ ∈ [0.3, 0.4), holds 72 pixels: at 32 spp its
/// mean scatters by ±2 % in multiscatter mode, while at 512 spp every ring is within 0.3 %).
pub const MIN_RING_PIXELS: usize = 150;

/// The thresholds a corrected sphere is judged by (each mode's and engine's defaults:
/// [`super::ModeSpec::defaults`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Judging {
    /// Allowed |mean − 100 %| of a corrected sphere, in percent.
    pub tolerance_percent: f64,
    /// In the view modes: allowed |ring mean − 100 %| of every view-cosine ring with at
    /// least [`MIN_RING_PIXELS`] pixels, in percent.
    pub ring_tolerance_percent: f64,
}

impl Default for Judging {
    fn default() -> Self {
        super::spec(Mode::Roughness).cycles.judging
    }
}

/// One distribution at one roughness: the plain Glossy sphere and the corrected one (layered
/// mode: at one index of refraction, the hand-made Mix Shader and the layered group).
#[derive(Clone, Debug, Serialize)]
pub struct Row {
    /// The plan's row this judges ([`super::plan::PlanRow::id`]): it holds the cells.
    pub id: usize,
    pub distribution: Distribution,
    pub roughness: Roughness,
    /// The coat's index of refraction (layered mode) or the lobe's anisotropy (anisotropic
    /// mode), as the field `ior` or `anisotropy`.
    #[serde(flatten)]
    pub block: Option<Block>,
    pub uncorrected: SphereStats,
    pub corrected: SphereStats,
    /// What the colour model promises the corrected sphere's mean is, per channel: the
    /// colour itself (exact), or the colour with multiple bounces tinted (physical).
    pub target: [f64; 3],
    /// The uncorrected sphere's mean relative to the colour (1 for a white sphere that lost
    /// nothing), the channels averaged.
    pub uncorrected_brightness: f64,
    /// The corrected sphere's mean relative to `target`, the channels averaged: 1 is right.
    pub brightness: f64,
    /// The worst channel's |mean / target − 1|.
    pub deviation: f64,
    /// What the integrator predicts for the uncorrected sphere: E_avg(r) of the BSDF the
    /// engine renders (0–1); in layered mode the Mix Shader's mean relative to `target`;
    /// in glass mode none (a solid sphere's light crosses its surfaces many times).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub predicted_uncorrected: Option<f64>,
    /// In an EEVEE sweep: what Cycles renders for the uncorrected sphere in this Blender
    /// (the integrator's E_avg(r) for its distribution and masking).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub cycles_uncorrected: Option<f64>,
    /// What the coefficients should give relative to `target` (gain(r) · E_avg(r) for a
    /// white sphere; 1 in the view modes, unless the groups are another engine's).
    pub predicted_corrected: f64,
    /// What the colour model promises each view-cosine ring of the corrected sphere (in the
    /// order of its rings), per channel: for a pixel-exact correction, every pixel's target.
    pub ring_targets: Vec<[f64; 3]>,
    /// Largest |ring mean / ring target − 1| of the corrected sphere over its view-cosine
    /// rings and channels.
    pub worst_ring: f64,
    /// Every channel's |mean / target − 1| ≤ tolerance (and, in the view modes, every ring
    /// within the ring tolerance).
    pub pass: bool,
    /// It fails, but each failing mean (the sphere's, its worst ring's) is off by no more
    /// than three of its standard errors beyond the tolerance: more samples may pass it.
    pub within_noise: bool,
}

/// `GGX`, or in layered mode `GGX, IOR 1.5`: the name of a row's series.
fn series_name(name: &str, block: Option<Block>) -> String {
    match block {
        Some(b) => format!("{name}, {}", b.label()),
        None => name.to_string(),
    }
}

impl Row {
    /// The distribution, and the block's index or anisotropy: `GGX, IOR 1.5`.
    pub fn series(&self) -> String {
        series_name(self.distribution.label(), self.block)
    }
}

/// Blender's Multiscatter GGX at one roughness (the energy-conserving peer; layered mode:
/// Principled BSDF at one index of refraction).
#[derive(Clone, Debug, Serialize)]
pub struct ReferenceSphere {
    pub roughness: Roughness,
    #[serde(flatten)]
    pub block: Option<Block>,
    /// Where the sphere is in the plan's cells.
    #[serde(skip)]
    pub cell: usize,
    pub stats: SphereStats,
    /// Its mean relative to what the colour model promises a GGX sphere (layered mode: a
    /// layered GGX coat), channels averaged.
    pub brightness: f64,
}

impl ReferenceSphere {
    /// `Multiscatter GGX`, or in layered mode `Principled BSDF, IOR 1.5`.
    pub fn series(&self, mode: Mode) -> String {
        series_name(super::spec(mode).reference, self.block)
    }
}

#[derive(Clone, Debug, Serialize)]
pub struct VerifyReport {
    pub coefficients: String,
    /// The engine that rendered the sweep.
    pub engine: Engine,
    /// The engine the coefficients (and so the corrected spheres' groups) are calibrated for.
    pub groups_engine: Engine,
    /// EEVEE: a white Diffuse sphere's mean relative to the colour (how bright the engine's
    /// lighting is; the corrections cannot do better).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lighting: Option<f64>,
    pub mode: Mode,
    /// The spheres' colour, and what the corrections promise for it.
    pub color: [f64; 3],
    pub color_model: ColorModel,
    /// Allowed |ring mean − 100 %| in the view modes, in percent.
    pub ring_tolerance_percent: f64,
    pub render: RenderInfo,
    /// Allowed |mean − 100 %| of a corrected sphere, in percent.
    pub tolerance_percent: f64,
    pub rows: Vec<Row>,
    pub reference: Vec<ReferenceSphere>,
    /// Explanations for the reader (display-referred coefficients, masking mismatch, …), as
    /// data: `crate::report::verify::notes` puts them into words.
    pub notes: Vec<Note>,
    pub pass: bool,
}

/// Something the reader of a verdict should know, as data (the renderers word it).
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "kebab-case")]
pub enum Note {
    /// How bright a white Diffuse sphere renders in `engine` (EEVEE): no sphere can come out
    /// brighter.
    Lighting { engine: Engine, brightness: f64 },
    /// The coefficients correct `groups_engine`'s Glossy, but `engine` rendered the sweep;
    /// the preset `suggested` holds `engine`'s own groups.
    ForeignGroups {
        coefficients: String,
        groups_engine: Engine,
        engine: Engine,
        suggested: &'static str,
    },
    /// A distribution's curve was fitted for `fitted` masking, but `blender` uses `masking`;
    /// the preset `suggested` suits it.
    MaskingMismatch {
        distribution: Distribution,
        fitted: Masking,
        #[serde(serialize_with = "as_text")]
        blender: BlenderVersion,
        masking: Masking,
        suggested: &'static str,
    },
    /// The coefficients are display-referred, so their gain misses; the worst failing sphere
    /// on each side of 100 %.
    DisplayReferred {
        coefficients: String,
        #[serde(skip_serializing_if = "Option::is_none")]
        under: Option<WorstSphere>,
        #[serde(skip_serializing_if = "Option::is_none")]
        over: Option<WorstSphere>,
    },
    /// `count` of the `failing` spheres fail within their noise (`Row::within_noise`),
    /// rendered with `samples` per pixel.
    WithinNoise {
        count: usize,
        failing: usize,
        samples: u32,
    },
}

impl Note {
    /// The preset the note suggests instead of the coefficients used, if any.
    pub fn suggested_preset(&self) -> Option<&'static str> {
        match self {
            Note::ForeignGroups { suggested, .. } | Note::MaskingMismatch { suggested, .. } => {
                Some(suggested)
            }
            _ => None,
        }
    }
}

/// The worst failing sphere on one side of 100 %, and how many failed on that side.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct WorstSphere {
    /// Failing spheres on this side.
    pub count: usize,
    pub distribution: Distribution,
    pub roughness: Roughness,
    /// Its corrected mean relative to the target.
    pub brightness: f64,
    /// The coefficients' gain at its roughness.
    pub gain: f64,
    /// The gain it needs: 1 / E_avg(r).
    pub needed_gain: f64,
}

/// A value as its `Display` text (`"4.5"` for a Blender version).
fn as_text<T: std::fmt::Display, S: Serializer>(value: &T, s: S) -> Result<S::Ok, S::Error> {
    s.collect_str(value)
}

/// What a verify sweep checks: the coefficients (and the name they were loaded by), the
/// distributions and roughness values rendered, and the correction mode.
pub struct Sweep<'a> {
    pub coefficients: &'a Coefficients,
    pub source: &'a str,
    pub distributions: &'a [Distribution],
    pub roughness: &'a [Roughness],
    /// Layered mode: the indices of refraction; anisotropic mode: the anisotropies (else
    /// empty).
    pub blocks: &'a [Block],
    pub mode: Mode,
    /// The spheres' colour and what a correction promises for it.
    pub color: [f64; 3],
    pub color_model: ColorModel,
}
