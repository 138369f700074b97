//! The generate job's parameter document: which node groups to build, with their names,
//! descriptions, curves and packed tables. It travels to Python as JSON (see
//! [`super::script`]).

use serde::Serialize;

use crate::fit::{Coefficients, ColorSpace, Curve, Target};
use crate::measure::{AlbedoIntegrator, Distribution, Masking, Roughness};
use crate::progress::Quiet;

/// Which correction a shader group applies.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Mode {
    /// Gain 100/f(r): the sphere's mean is 100 %, its centre darker, its rim brighter.
    Roughness,
    /// Gain 1/E(μ, r) with μ = N·I: every pixel of a furnace sphere is 100 %.
    View,
    /// Glossy plus a diffuse lobe of colour × (1 − E(μ, r)): every pixel 100 %, highlight unchanged.
    Multiscatter,
}

impl Mode {
    pub const ALL: [Mode; 3] = [Mode::Roughness, Mode::View, Mode::Multiscatter];

    pub fn key(self) -> &'static str {
        match self {
            Mode::Roughness => "roughness",
            Mode::View => "view",
            Mode::Multiscatter => "multiscatter",
        }
    }
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
        // μ = 0 is a limit; the bottom row uses a grazing view instead.
        let mus: Vec<f64> = Roughness::grid(size)
            .iter()
            .map(|mu| mu.get().max(1e-3))
            .collect();
        let grid = integrator.grid(distribution, masking, &Roughness::grid(size), &mus, &Quiet);
        let values = grid.e.into_iter().map(|e| e as f32).collect();
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
    /// Written as Blender's enum for the Glossy node's distribution (`GGX`, …).
    #[serde(serialize_with = "as_blender_enum")]
    pub distribution: Distribution,
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
                distribution: d,
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

    /// Adds the view and multiscatter groups, with E(μ, r) for `masking` from the integrator.
    pub fn with_view(mut self, masking: Masking) -> Self {
        for g in &mut self.groups {
            let d = g.distribution;
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

fn as_blender_enum<S: serde::Serializer>(d: &Distribution, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_str(d.blender_enum())
}
