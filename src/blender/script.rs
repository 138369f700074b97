//! Generated Python: a header holding one JSON parameter document, then the embedded
//! `blender_scripts/groups_lib.py`, then a main (`generate_main.py` or `furnace_main.py`).
//!
//! The parameter document is encoded by serde_json twice: once as JSON, then as a JSON
//! string literal, which is also a valid Python string literal. No user text is ever
//! pasted into code, so names, descriptions and paths cannot become code.

use serde::Serialize;

use crate::coefficients::{Coefficients, ColorSpace, Target};
use crate::fit::Curve;
use crate::microfacet::{AlbedoIntegrator, Distribution, Glossy, Masking};

pub const GROUPS_LIB: &str = include_str!("../../blender_scripts/groups_lib.py");
pub const GENERATE_MAIN: &str = include_str!("../../blender_scripts/generate_main.py");
pub const FURNACE_MAIN: &str = include_str!("../../blender_scripts/furnace_main.py");

/// Which correction a shader group applies.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, clap::ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum Mode {
    /// Gain 100/f(r): the sphere's mean is 100 %, its centre darker, its rim brighter.
    Roughness,
    /// Gain 1/E(μ, r) with μ = N·I: every pixel of a furnace sphere is 100 %.
    View,
    /// Glossy plus a diffuse lobe of colour × (1 − E(μ, r)): every pixel 100 %, highlight unchanged.
    Multiscatter,
}

/// Side of the E(μ, r) table packed into the .blend for the view and multiscatter modes:
/// bilinear interpolation of 96 × 96 samples stays within 0.33 % of E for μ ≥ 0.05
/// (`cargo run --release --example view_table_error`).
pub const VIEW_TABLE_SIZE: usize = 96;

/// E(μ, r) on a grid: row i is μ = i/(height − 1), column j is r = j/(width − 1).
#[derive(Clone, Debug, Serialize)]
pub struct AlbedoTable {
    pub width: usize,
    pub height: usize,
    /// Row-major; f32 because Blender stores image pixels as 32-bit floats.
    pub values: Vec<f32>,
}

impl AlbedoTable {
    pub fn compute(distribution: Distribution, masking: Masking, size: usize) -> Self {
        let integrator = AlbedoIntegrator::default();
        let rs: Vec<f64> = (0..size).map(|j| j as f64 / (size - 1) as f64).collect();
        // μ = 0 is a limit; the bottom row uses a grazing view instead.
        let mus: Vec<f64> = (0..size)
            .map(|i| (i as f64 / (size - 1) as f64).max(1e-3))
            .collect();
        let make = |r: f64| Glossy {
            distribution,
            masking,
            alpha: r * r,
        };
        let values = integrator
            .table(make, &mus, &rs)
            .into_iter()
            .map(|e| e as f32)
            .collect();
        AlbedoTable {
            width: size,
            height: size,
            values,
        }
    }
}

/// The view-dependent groups of one distribution and the table they sample.
#[derive(Clone, Debug, Serialize)]
pub struct ViewSpec {
    pub correction_group: String,
    pub shader_group: String,
    pub multiscatter_group: String,
    /// Name of the packed float image holding the table.
    pub image: String,
    pub table: AlbedoTable,
}

/// One distribution's node groups, as the Python side builds them.
#[derive(Clone, Debug, Serialize)]
pub struct GroupSpec {
    /// Blender's enum for the Glossy node's distribution.
    pub distribution: &'static str,
    pub correction_group: String,
    pub shader_group: String,
    pub description: String,
    pub curve: Curve,
    /// The view and multiscatter groups (only when a mode asks for them).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub view: Option<ViewSpec>,
}

impl GroupSpec {
    /// The shader group a furnace sphere of this mode is shaded with.
    pub fn shader_for(&self, mode: Mode) -> Option<&str> {
        match mode {
            Mode::Roughness => Some(&self.shader_group),
            Mode::View => self.view.as_ref().map(|v| v.shader_group.as_str()),
            Mode::Multiscatter => self.view.as_ref().map(|v| v.multiscatter_group.as_str()),
        }
    }
}

/// The parameter document of the generate job.
#[derive(Clone, Debug, Serialize)]
pub struct GenerateParams {
    pub gloffuse_version: &'static str,
    pub coefficients_source: String,
    pub groups: Vec<GroupSpec>,
}

/// `Brightness Correction (GGX)`: the public name of the gain group.
pub fn correction_group_name(d: Distribution) -> String {
    format!("Brightness Correction ({})", d.label())
}

/// `Gloffuse (GGX)`: the public name of the corrected shader group.
pub fn shader_group_name(d: Distribution) -> String {
    format!("Gloffuse ({})", d.label())
}

impl GenerateParams {
    /// The groups for every distribution in `coefficients`; `source` names where the
    /// coefficients came from (a preset name or a file path) for the descriptions.
    pub fn new(coefficients: &Coefficients, source: &str) -> Self {
        let groups = coefficients
            .distributions
            .iter()
            .map(|(&d, e)| GroupSpec {
                distribution: d.blender_enum(),
                correction_group: correction_group_name(d),
                shader_group: shader_group_name(d),
                description: format!(
                    "Restores a white {} Glossy BSDF to 100 % brightness under even light: gain = 100 / f(r), fitted to the sphere's {} brightness ({} masking{}). Coefficients: {}.",
                    d.label(),
                    match e.target {
                        Target::Mean => "mean",
                        Target::Center => "centre",
                    },
                    e.masking,
                    match e.color_space {
                        ColorSpace::Linear => "",
                        ColorSpace::Display => "; display-referred percentages, not a true linear gain",
                    },
                    source
                ),
                curve: e.curve.clone(),
                view: None,
            })
            .collect();
        GenerateParams {
            gloffuse_version: env!("CARGO_PKG_VERSION"),
            coefficients_source: format!("{source} ({})", coefficients.name),
            groups,
        }
    }
}

impl GenerateParams {
    /// Adds the view and multiscatter groups, with E(μ, r) for `masking` from the integrator.
    pub fn with_view(mut self, masking: Masking) -> Self {
        for g in &mut self.groups {
            let d = Distribution::ALL
                .into_iter()
                .find(|d| d.blender_enum() == g.distribution)
                .expect("specs are built from distributions");
            g.view = Some(ViewSpec {
                correction_group: format!("Brightness Correction View ({})", d.label()),
                shader_group: format!("Gloffuse View ({})", d.label()),
                multiscatter_group: format!("Gloffuse Multiscatter ({})", d.label()),
                image: format!("Gloffuse E(mu, r) ({}, {})", d.label(), masking),
                table: AlbedoTable::compute(d, masking, VIEW_TABLE_SIZE),
            });
        }
        self
    }
}

/// The full script: header with the parameter literal, the groups library, then `main`.
pub fn assemble(params: &impl Serialize, main: &str) -> String {
    let document = serde_json::to_string(params).expect("parameters serialise");
    let literal = serde_json::to_string(&document).expect("a string serialises");
    let mut s = format!(
        "# Generated by gloffuse {}: brightness-correction node groups for Blender's glossy BSDFs.\n\
         # Run it in Blender's Text Editor, or: blender -b --factory-startup -noaudio --python THIS.py -- --save OUT.blend\n\
         GLOFFUSE_PARAMS = {literal}\n",
        env!("CARGO_PKG_VERSION")
    );
    for part in [GROUPS_LIB, main] {
        s.push_str(part);
        if !part.ends_with('\n') {
            s.push('\n');
        }
    }
    s
}
