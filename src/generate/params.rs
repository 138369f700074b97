//! The generate job's parameter document: which node groups to build, with their names,
//! descriptions, curves and packed tables. It travels to Python as JSON (see
//! [`super::script`]).

use serde::Serialize;

use super::catalogs::Catalogs;
use crate::Error;
use crate::fit::{Coefficients, ColorSpace, Curve, Target, preset_for_masking};
use crate::measure::{AlbedoIntegrator, BlenderVersion, Distribution, Masking, Roughness, coat};
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
    /// A dielectric glossy coat over a diffuse base (`Gloffuse Layered (…)`): the coat
    /// reflects A(μ, r, IOR), the base gets the rest.
    Layered,
}

impl Mode {
    pub const ALL: [Mode; 4] = [
        Mode::Roughness,
        Mode::View,
        Mode::Multiscatter,
        Mode::Layered,
    ];

    pub fn key(self) -> &'static str {
        match self {
            Mode::Roughness => "roughness",
            Mode::View => "view",
            Mode::Multiscatter => "multiscatter",
            Mode::Layered => "layered",
        }
    }

    /// Does this mode's shader group read the view cosine (so that every pixel, not only
    /// the sphere's mean, is judged)?
    pub fn per_pixel(self) -> bool {
        self != Mode::Roughness
    }
}

/// What a coloured correction keeps (`--color-model`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum ColorModel {
    /// The surface's albedo is exactly `Color`, whatever the roughness.
    Exact,
    /// The energy multiple bounces add is tinted by the colour, as Kulla and Conty (and
    /// Blender's Multiscatter GGX) compute it: `Fms = F·E_avg / (1 − F(1 − E_avg))`, so a rough
    /// coloured metal renders darker and more saturated than `Color`.
    Physical,
}

impl ColorModel {
    pub const ALL: [ColorModel; 2] = [ColorModel::Exact, ColorModel::Physical];

    pub fn key(self) -> &'static str {
        match self {
            ColorModel::Exact => "exact",
            ColorModel::Physical => "physical",
        }
    }
}

/// Side of the E(μ, r) table packed into the .blend for the view and multiscatter modes:
/// bilinear interpolation of 96 × 96 samples stays within 0.33 % of E for μ ≥ 0.05
/// (`cargo run --release --example view_table_error`).
pub const VIEW_TABLE_SIZE: usize = 96;

/// Side of each index slice of the coat table packed for the layered groups: with
/// [`coat::SLICES`] slices, bilinear in (r, μ) and linear between slices, A stays within
/// 5.7e-3 of the integrator (`cargo run --release --example coat_table_error`).
pub const COAT_TABLE_SIZE: usize = 64;

/// The coat albedo `A(μ, r, η)` of the layered groups as one image: [`coat::SLICES`] slices
/// side by side, slice k for index `ior[k]` (even in `z = F0^¼`), each `size` × `size` with
/// row i at μ = i/(size − 1) and column j at r = j/(size − 1).
#[derive(Clone, Debug, Serialize)]
pub struct CoatTable {
    pub size: usize,
    pub slices: usize,
    pub ior: Vec<f64>,
    /// `z = F0^¼` of the last slice (the first is 0).
    pub z_max: f64,
    /// Image rows, bottom first: `values[i * size * slices + k * size + j]`.
    pub values: Vec<f32>,
}

impl CoatTable {
    pub fn compute(distribution: Distribution, masking: Masking, size: usize) -> Self {
        let integrator = AlbedoIntegrator::default();
        let axis = Roughness::grid(size);
        let mus: Vec<f64> = axis.iter().map(|mu| mu.get().max(1e-3)).collect();
        let grid = integrator.coat_grid(distribution, masking, &axis, &mus, &Quiet);
        let mut values = Vec::with_capacity(size * size * coat::SLICES);
        for i in 0..size {
            for k in 0..coat::SLICES {
                values.extend((0..size).map(|j| grid.a(k, i, j) as f32));
            }
        }
        CoatTable {
            size,
            slices: coat::SLICES,
            ior: grid.ior.to_vec(),
            z_max: coat::slice_coordinate(coat::IOR_MAX),
            values,
        }
    }
}

/// E(μ, r) on a grid (row i is μ = i/(height − 1), column j is r = j/(width − 1)) and
/// E_avg(r) per column.
#[derive(Clone, Debug, Serialize)]
pub struct AlbedoTable {
    pub width: usize,
    pub height: usize,
    /// Row-major; f32 because Blender stores image pixels as 32-bit floats.
    pub values: Vec<f32>,
    /// `E_avg(r_j)`, one per column (the physical colour model needs it).
    pub average: Vec<f32>,
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
        AlbedoTable {
            width: size,
            height: size,
            values: grid.e.into_iter().map(|e| e as f32).collect(),
            average: grid.e_avg.into_iter().map(|e| e as f32).collect(),
        }
    }
}

/// The names of the view-dependent groups of one distribution; a name is there when a
/// mode asks for its group.
#[derive(Clone, Debug, Serialize)]
pub struct ViewNames {
    #[serde(skip_serializing_if = "Option::is_none")]
    pub correction_group: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub shader_group: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub multiscatter_group: Option<String>,
}

/// What one masking family (one Blender version range) builds for a distribution: the
/// curve, its description, and the packed E(μ, r) table of the view modes.
#[derive(Clone, Debug, Serialize)]
pub struct FamilySpec {
    pub masking: Masking,
    /// The preset or file the curve comes from, for the descriptions.
    pub coefficients_source: String,
    pub description: String,
    pub curve: Curve,
    /// Name of the packed float image holding `table` (view modes only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub image: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub table: Option<AlbedoTable>,
    /// Name of the packed float image holding `coat_table` (layered mode only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub coat_image: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub coat_table: Option<CoatTable>,
}

/// One distribution's node groups, as the Python side builds them. The script picks the
/// family of the Blender it runs in (see [`GenerateParams::height_correlated_from`]).
#[derive(Clone, Debug, Serialize)]
pub struct GroupSpec {
    /// Written as Blender's enum for the Glossy node's distribution (`GGX`, …).
    #[serde(serialize_with = "as_blender_enum")]
    pub distribution: Distribution,
    pub correction_group: String,
    pub shader_group: String,
    /// The view and multiscatter groups (only when a mode asks for them).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub view: Option<ViewNames>,
    /// `Gloffuse Layered (…)` (layered mode only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub layered_group: Option<String>,
    pub families: Vec<FamilySpec>,
}

impl GroupSpec {
    /// The shader group a furnace sphere of this mode is shaded with.
    pub fn shader_for(&self, mode: Mode) -> Option<&str> {
        let view = self.view.as_ref();
        match mode {
            Mode::Roughness => Some(&self.shader_group),
            Mode::View => view.and_then(|v| v.shader_group.as_deref()),
            Mode::Multiscatter => view.and_then(|v| v.multiscatter_group.as_deref()),
            Mode::Layered => self.layered_group.as_deref(),
        }
    }

    /// Every group name this spec builds, in build order.
    pub fn group_names(&self) -> Vec<String> {
        let mut names = vec![self.correction_group.clone(), self.shader_group.clone()];
        if let Some(v) = &self.view {
            let view = [&v.correction_group, &v.shader_group, &v.multiscatter_group];
            names.extend(view.into_iter().flatten().cloned());
        }
        names.extend(self.layered_group.iter().cloned());
        names
    }
}

/// Where the curves come from.
#[derive(Clone, Copy, Debug)]
pub enum Curves<'a> {
    /// One coefficients file (or preset) for every family; `name` is what it was loaded by.
    Pinned {
        coefficients: &'a Coefficients,
        name: &'a str,
    },
    /// Each family's own preset (`blender-3` for separable, `blender-4` for
    /// height-correlated masking).
    Presets,
}

/// The parameter document of the generate job.
#[derive(Clone, Debug, Serialize)]
pub struct GenerateParams {
    pub gloffuse_version: &'static str,
    /// The first Blender version whose Cycles uses height-correlated masking: the script
    /// builds the separable family in older versions, the height-correlated one from this
    /// version on (or the only family it carries).
    pub height_correlated_from: [u32; 2],
    pub color_model: ColorModel,
    /// The helper group every view-dependent group uses for the normal the BSDF shades
    /// with (only when a view mode is asked for).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub normal_group: Option<String>,
    /// The asset catalogs the groups are assigned to.
    pub catalogs: Catalogs,
    /// The assets' author; their licence and copyright (Blender 3.6+ stores those two).
    pub asset_author: &'static str,
    pub asset_license: &'static str,
    pub asset_copyright: &'static str,
    /// Render a preview of every group (the generate job sets it for a .blend).
    pub previews: bool,
    pub groups: Vec<GroupSpec>,
}

/// The licence of the assets gloffuse generates (Blender's extension rules ask for CC0 or
/// a compatible licence for bundled assets).
pub const ASSET_LICENSE: &str = "CC0-1.0";
pub const ASSET_AUTHOR: &str = "gloffuse";
pub const ASSET_COPYRIGHT: &str = "Generated by gloffuse; dedicated to the public domain (CC0 1.0)";

/// The public name of the helper group that finds the normal a glossy BSDF shades with.
pub const NORMAL_GROUP: &str = "Gloffuse Shading Normal";

/// `Brightness Correction (GGX)`: the public name of the gain group.
pub fn correction_group_name(d: Distribution) -> String {
    format!("Brightness Correction ({})", d.label())
}

/// `Gloffuse Layered (GGX)`: the public name of the glossy-over-diffuse group.
pub fn layered_group_name(d: Distribution) -> String {
    format!("Gloffuse Layered ({})", d.label())
}

/// `Gloffuse (GGX)`: the public name of the corrected shader group.
pub fn shader_group_name(d: Distribution) -> String {
    format!("Gloffuse ({})", d.label())
}

impl GenerateParams {
    /// The groups for every distribution the curves hold, for each masking family in
    /// `families`, with the view-dependent groups `modes` ask for.
    pub fn new(
        curves: Curves,
        families: &[Masking],
        modes: &[Mode],
        color_model: ColorModel,
    ) -> Result<Self, Error> {
        let mut loaded = Vec::new();
        for &masking in families {
            let (coefficients, name) = match curves {
                Curves::Pinned { coefficients, name } => (coefficients.clone(), name.to_string()),
                Curves::Presets => {
                    let name = preset_for_masking(masking);
                    (Coefficients::load(name)?, name.to_string())
                }
            };
            loaded.push((masking, coefficients, name));
        }
        let wants = |m: Mode| modes.contains(&m);
        // Every per-pixel group reads E(μ, r) and the shading normal.
        let views = modes.iter().any(|m| m.per_pixel());
        let layered = wants(Mode::Layered);
        let distributions: Vec<Distribution> = loaded
            .first()
            .map(|(_, c, _)| c.distributions.keys().copied().collect())
            .unwrap_or_default();
        let groups = distributions
            .into_iter()
            .map(|d| GroupSpec {
                distribution: d,
                correction_group: correction_group_name(d),
                shader_group: shader_group_name(d),
                layered_group: layered.then(|| layered_group_name(d)),
                view: (wants(Mode::View) || wants(Mode::Multiscatter)).then(|| ViewNames {
                    correction_group: wants(Mode::View)
                        .then(|| format!("Brightness Correction View ({})", d.label())),
                    shader_group: wants(Mode::View)
                        .then(|| format!("Gloffuse View ({})", d.label())),
                    multiscatter_group: wants(Mode::Multiscatter)
                        .then(|| format!("Gloffuse Multiscatter ({})", d.label())),
                }),
                families: loaded
                    .iter()
                    .filter_map(|(masking, c, name)| {
                        let e = c.distributions.get(&d)?;
                        Some(FamilySpec {
                            masking: *masking,
                            coefficients_source: format!("{name} ({})", c.name),
                            description: describe(d, e, name),
                            curve: e.curve.clone(),
                            image: views
                                .then(|| format!("Gloffuse E(mu, r) ({}, {})", d.label(), masking)),
                            table: views
                                .then(|| AlbedoTable::compute(d, *masking, VIEW_TABLE_SIZE)),
                            coat_image: layered
                                .then(|| format!("Gloffuse coat A ({}, {})", d.label(), masking)),
                            coat_table: layered
                                .then(|| CoatTable::compute(d, *masking, COAT_TABLE_SIZE)),
                        })
                    })
                    .collect(),
            })
            .collect();
        let first = BlenderVersion::HEIGHT_CORRELATED_FROM;
        Ok(GenerateParams {
            gloffuse_version: env!("CARGO_PKG_VERSION"),
            height_correlated_from: [first.major, first.minor],
            color_model,
            normal_group: views.then(|| NORMAL_GROUP.to_string()),
            catalogs: Catalogs::default(),
            asset_author: ASSET_AUTHOR,
            asset_license: ASSET_LICENSE,
            asset_copyright: ASSET_COPYRIGHT,
            previews: false,
            groups,
        })
    }

    /// Every group name the script builds, in build order.
    pub fn group_names(&self) -> Vec<String> {
        let groups = self.groups.iter().flat_map(GroupSpec::group_names);
        self.normal_group.iter().cloned().chain(groups).collect()
    }
}

/// The description of a distribution's groups: what the curve restores and where it comes
/// from.
fn describe(d: Distribution, e: &crate::fit::coefficients::Entry, source: &str) -> String {
    format!(
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
    )
}

fn as_blender_enum<S: serde::Serializer>(d: &Distribution, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_str(d.blender_enum())
}
