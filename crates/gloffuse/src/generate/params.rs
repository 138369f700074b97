//! The generate job's parameter document: which node groups to build, with their names,
//! descriptions, curves and packed tables. It travels to Python as JSON (see
//! [`super::script`]).

use serde::Serialize;

use super::catalogs::Catalogs;
use crate::error::{Error, Field};
use crate::fit::{Coefficients, ColorSpace, Curve, Target, preset_for_masking};
use crate::measure::anisotropic::AnisotropicAxes;
use crate::measure::dielectric::Side;
use crate::measure::{
    AlbedoIntegrator, AnisotropicIntegrator, BlenderVersion, DielectricIntegrator, DielectricNode,
    Distribution, Engine, GlassForm, Masking, Roughness, coat, grazing_crowded,
};
use crate::progress::Quiet;

/// Which correction a shader group applies.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
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
    /// An anisotropic Glossy (`Gloffuse Anisotropic (GGX)`) with gain 1/E(μ, φ, αx, αy),
    /// φ the view's azimuth from the tangent: every pixel of a furnace sphere is 100 %.
    Anisotropic,
    /// Glass and Refraction BSDFs (`Gloffuse Glass (GGX)`, `Gloffuse Refraction (GGX)`)
    /// with gain 1/E(μ, r, η), η = IOR on a front face and 1/IOR on a back face: every
    /// interface returns all the light that meets it.
    Glass,
}

impl Mode {
    pub const ALL: [Mode; 6] = [
        Mode::Roughness,
        Mode::View,
        Mode::Multiscatter,
        Mode::Layered,
        Mode::Anisotropic,
        Mode::Glass,
    ];

    pub fn key(self) -> &'static str {
        match self {
            Mode::Roughness => "roughness",
            Mode::View => "view",
            Mode::Multiscatter => "multiscatter",
            Mode::Layered => "layered",
            Mode::Anisotropic => "anisotropic",
            Mode::Glass => "glass",
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
    /// The index of the last slice: the groups clamp their IOR input to [1, this].
    pub ior_max: f64,
    /// `z = F0^¼` of the last slice (the first is 0).
    pub z_max: f64,
    /// Image rows, bottom first: `values[i * size * slices + k * size + j]`.
    pub values: Vec<f32>,
    /// Beckmann only: `A / E_F` in the layout of `values`, the gain of the single-scattering
    /// Metallic BSDF coat (Blender 5.0+: its Physical Conductor Fresnel with index η and no
    /// extinction is the dielectric one; Cycles compensates only GGX).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gain: Option<Vec<f32>>,
}

impl CoatTable {
    pub fn compute(distribution: Distribution, masking: Masking, size: usize) -> Self {
        let integrator = AlbedoIntegrator::default();
        let axis = Roughness::grid(size);
        let mus: Vec<f64> = axis.iter().map(|mu| mu.get().max(1e-3)).collect();
        let grid = integrator.coat_grid(distribution, masking, &axis, &mus, &Quiet);
        let packed = |at: &dyn Fn(usize, usize, usize) -> f64| {
            let mut values = Vec::with_capacity(size * size * coat::SLICES);
            for i in 0..size {
                for k in 0..coat::SLICES {
                    values.extend((0..size).map(|j| at(k, i, j) as f32));
                }
            }
            values
        };
        let values = packed(&|k, i, j| grid.a(k, i, j));
        let gain =
            (distribution == Distribution::Beckmann).then(|| packed(&|k, i, j| grid.gain(k, i, j)));
        CoatTable {
            size,
            slices: coat::SLICES,
            ior: grid.ior.to_vec(),
            ior_max: coat::IOR_MAX,
            z_max: coat::slice_coordinate(coat::IOR_MAX),
            values,
            gain,
        }
    }
}

/// Grid points per axis of the anisotropic groups' table (N·V, √αx, √αy), and view
/// azimuths: the layout of `lut --kind anisotropic`, whose lookup misses the integrator by
/// 0.1 % on average and at most 2.5 % at grazing views
/// (`cargo run --release --example anisotropic_table_error`).
pub const ANISOTROPIC_TABLE_SIZE: usize = 16;
pub const ANISOTROPIC_AZIMUTHS: usize = 16;

/// `E(μ, φ, αx, αy)` of the anisotropic groups on [`AnisotropicAxes::table`]: `size` grid
/// points on N·V, `√αx` and `√αy` from 0 to 1 and `azimuths` on the view azimuth from the
/// tangent from 0 to π/2.
#[derive(Clone, Debug, Serialize)]
pub struct AnisotropicTable {
    pub size: usize,
    pub azimuths: usize,
    /// `values[((k · size + i) · size + l) · size + j] = E(μ_i, φ_k, rx_j, ry_l)`.
    pub values: Vec<f32>,
}

impl AnisotropicTable {
    pub fn compute(distribution: Distribution, masking: Masking) -> Self {
        let (size, azimuths) = (ANISOTROPIC_TABLE_SIZE, ANISOTROPIC_AZIMUTHS);
        let grid = AnisotropicIntegrator::default()
            .grid(
                distribution,
                masking,
                AnisotropicAxes::table(size, azimuths),
                &Quiet,
            )
            .expect("the table's widths are within [0, 1] and its distribution GGX or Beckmann");
        let mut values = Vec::with_capacity(azimuths * size * size * size);
        for k in 0..azimuths {
            for i in 0..size {
                for l in 0..size {
                    values.extend((0..size).map(|j| grid.e(i, k, j, l) as f32));
                }
            }
        }
        AnisotropicTable {
            size,
            azimuths,
            values,
        }
    }
}

/// `E(μ, r, η)` of the glass groups, in the layout of [`CoatTable`] (slices over the index,
/// column j at r = j/(size − 1)), light entering (η = IOR) and leaving (η = 1/IOR), as the
/// Blenders from `from_version` on within a masking family render them (the
/// height-correlated family's Blender 3.5 still has 3.0–3.4's glass: it gets no glass
/// groups). Row i is at `t = i/(size − 1)` of [`crate::measure::grazing_crowded`] (μ = t^1.5),
/// except in `refraction_leaving`, whose rows are at `s = i/(size − 1)` of
/// [`crate::measure::critical_crowded`] (each slice about its own critical cosine, where
/// that lobe falls steeply). The Refraction node's E is in `refraction_*`. The Glass node's:
/// - one closure (3.6 on): `glass_*`, E itself;
/// - two closures (3.0–3.5): `E = F(μ) R + max(1e-4, 1 − F(μ)) T`, T the refraction
///   lobe's (`refraction_*`) and R the reflection lobe's (`reflection`, the same in every
///   slice), with the Fresnel F at the normal computed in the group: E itself jumps at the
///   critical angle, which a table would blur;
/// - none where the Glass group wraps Blender's own Multiscatter GGX glass
///   ([`GlassGroup::Multiscatter`]).
#[derive(Clone, Debug, Serialize)]
pub struct GlassTable {
    pub size: usize,
    pub slices: usize,
    pub ior: Vec<f64>,
    /// The index of the last slice: the groups clamp their IOR input to [1, this].
    pub ior_max: f64,
    /// `z = F0^¼` of the last slice (the first is 0).
    pub z_max: f64,
    /// `[major, minor]`: the first Blender of the family whose glass this is.
    pub from_version: [u32; 2],
    /// `one-closure` or `two-closures`.
    pub form: &'static str,
    /// How the Glass group keeps the light.
    pub glass_group: GlassGroup,
    /// Image rows, bottom first, each `values[i * size * slices + k * size + j]`.
    pub refraction_entering: Vec<f32>,
    pub refraction_leaving: Vec<f32>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub glass_entering: Option<Vec<f32>>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub glass_leaving: Option<Vec<f32>>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reflection: Option<Vec<f32>>,
    /// For the physical colour model: `E_avg(r, η)` of each node and side, laid out as the
    /// E tables with every row alike (the groups read it as they read E).
    #[serde(flatten, skip_serializing_if = "Option::is_none")]
    pub averages: Option<GlassAverages>,
}

/// How a Glass group keeps the light a rough interface's single bounce loses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum GlassGroup {
    /// Blender's Glass BSDF of colour Color / E, E from the tables.
    Gain,
    /// Blender's own Multiscatter GGX glass, where it is a random walk that keeps all the
    /// light (3.0–3.5): 100 % in the furnace with about a thousandth of the gain's noise in
    /// a rough dense sphere (3.4.1, r 1, IOR 2, 1,024 spp: standard error 0.002 % against
    /// 1.8 %), where the gain multiplies a path's weight by up to 8 at every bounce inside.
    /// Its colour is the walk's: light that bounces k times among the microfacets is tinted
    /// k times.
    Multiscatter,
}

impl GlassGroup {
    /// 3.0–3.5's GGX glass has a random-walk Multiscatter twin; later Multiscatter GGX glass
    /// (a table) and every Beckmann glass lose light the gain restores.
    pub fn of(distribution: Distribution, form: GlassForm) -> Self {
        match (distribution, form) {
            (Distribution::Ggx, GlassForm::TwoClosures) => GlassGroup::Multiscatter,
            _ => GlassGroup::Gain,
        }
    }
}

/// `E_avg(r, η)` of the Glass and Refraction nodes, entering and leaving
/// ([`DielectricIntegrator::average_albedo`]), in [`GlassTable`]'s layout; the Glass node's
/// only where its group reads tables ([`GlassGroup::Gain`]).
#[derive(Clone, Debug, Serialize)]
pub struct GlassAverages {
    #[serde(skip_serializing_if = "Option::is_none")]
    pub glass_average_entering: Option<Vec<f32>>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub glass_average_leaving: Option<Vec<f32>>,
    pub refraction_average_entering: Vec<f32>,
    pub refraction_average_leaving: Vec<f32>,
}

/// Grid points per axis (view cosine, r) of each index slice of the glass groups' tables.
pub const GLASS_TABLE_SIZE: usize = 16;

impl GlassTable {
    /// The first Blender of a masking family whose glass the family's table describes.
    fn first_version(masking: Masking) -> BlenderVersion {
        match masking {
            Masking::Separable => BlenderVersion::OLDEST,
            Masking::HeightCorrelated => GlassForm::ONE_CLOSURE_FROM,
        }
    }

    /// Whether the glass groups are built in Blender `version`: in all but 3.5, whose glass
    /// is 3.4's two closures with the height-correlated masking.
    pub fn builds_groups_for(version: BlenderVersion) -> bool {
        version >= Self::first_version(version.masking())
    }

    /// The table of `distribution` for a masking family: 3.0–3.4's glass (separable) or
    /// 3.6 and later's (height-correlated); with the averages the physical colour model
    /// needs if `color_model` is physical.
    pub fn compute(distribution: Distribution, masking: Masking, color_model: ColorModel) -> Self {
        let from = Self::first_version(masking);
        let size = GLASS_TABLE_SIZE;
        let axis = Roughness::grid(size);
        let mus: Vec<f64> = axis
            .iter()
            .map(|t| grazing_crowded(t.get()).max(1e-3))
            .collect();
        let integrator = DielectricIntegrator::default();
        let grid = integrator.grid(distribution, from, &mus, &axis, &Quiet);
        let packed = |at: &dyn Fn(usize, usize, usize) -> f64| {
            let mut values = Vec::with_capacity(size * size * coat::SLICES);
            for i in 0..size {
                for k in 0..coat::SLICES {
                    values.extend((0..size).map(|j| at(k, i, j) as f32));
                }
            }
            values
        };
        let e = |node, side| packed(&|k, i, j| grid.e(node, side, k, i, j));
        let one_closure = GlassForm::of(from) == GlassForm::OneClosure;
        let glass_group = GlassGroup::of(distribution, GlassForm::of(from));
        let gain = glass_group == GlassGroup::Gain;
        let leaving = integrator.refraction_leaving(distribution, from, &axis, &axis);
        GlassTable {
            size,
            slices: coat::SLICES,
            ior: grid.ior.to_vec(),
            ior_max: coat::IOR_MAX,
            z_max: coat::slice_coordinate(coat::IOR_MAX),
            from_version: [from.major, from.minor],
            form: if one_closure {
                "one-closure"
            } else {
                "two-closures"
            },
            glass_group,
            refraction_entering: e(DielectricNode::Refraction, Side::Entering),
            refraction_leaving: packed(&|k, i, j| leaving[i][k][j]),
            glass_entering: one_closure.then(|| e(DielectricNode::Glass, Side::Entering)),
            glass_leaving: one_closure.then(|| e(DielectricNode::Glass, Side::Leaving)),
            reflection: (!one_closure && gain).then(|| packed(&|_, i, j| grid.reflection(i, j))),
            averages: (color_model == ColorModel::Physical).then(|| {
                let average = |node, side| {
                    let values = integrator.average_grid(distribution, from, node, side, &axis);
                    packed(&|k, _, j| values[k][j])
                };
                GlassAverages {
                    glass_average_entering: gain
                        .then(|| average(DielectricNode::Glass, Side::Entering)),
                    glass_average_leaving: gain
                        .then(|| average(DielectricNode::Glass, Side::Leaving)),
                    refraction_average_entering: average(
                        DielectricNode::Refraction,
                        Side::Entering,
                    ),
                    refraction_average_leaving: average(DielectricNode::Refraction, Side::Leaving),
                }
            }),
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
    /// Name of the packed float image holding `coat_table.gain` (layered Beckmann only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub coat_gain_image: Option<String>,
    /// Name of the packed float image holding `anisotropic_table` (anisotropic mode, where
    /// this family's Blenders render the lobe).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub anisotropic_image: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub anisotropic_table: Option<AnisotropicTable>,
    /// The prefix of the packed float images holding `glass_table`'s four tables (glass
    /// mode): `<prefix> glass entering`, … .
    #[serde(skip_serializing_if = "Option::is_none")]
    pub glass_image: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub glass_table: Option<GlassTable>,
}

/// One distribution's node groups, as the Python side builds them. The script picks the
/// family of the Blender it runs in (see [`GenerateParams::height_correlated_from`]).
#[derive(Clone, Debug, Serialize)]
pub struct GroupSpec {
    /// Written as Blender's enum for the Glossy node's distribution (`GGX`, …).
    #[serde(serialize_with = "as_blender_enum")]
    pub distribution: Distribution,
    /// The engine the groups are calibrated for (it is in their names, and it decides
    /// which normal the view-dependent groups read the view cosine at).
    pub engine: Engine,
    pub correction_group: String,
    pub shader_group: String,
    /// The helper group the view-dependent groups take the shading normal and view
    /// cosine from (only when a per-pixel mode asks for them): see [`normal_group_name`].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub normal_group: Option<String>,
    /// The view and multiscatter groups (only when a mode asks for them).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub view: Option<ViewNames>,
    /// `Gloffuse Layered (…)` (layered mode only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub layered_group: Option<String>,
    /// `Gloffuse Anisotropic (GGX | Beckmann)` (anisotropic mode; a script builds it only
    /// in the Blenders whose family carries its table: not Beckmann in 3.0–3.4).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub anisotropic_group: Option<String>,
    /// `Gloffuse Glass (GGX)` and `Gloffuse Refraction (GGX)` (glass mode; a script builds
    /// them only in the Blenders whose family's table is theirs: not in 3.5).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub glass_group: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub refraction_group: Option<String>,
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
            Mode::Anisotropic => self.anisotropic_group.as_deref(),
            Mode::Glass => self.glass_group.as_deref(),
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
        names.extend(self.anisotropic_group.iter().cloned());
        names.extend(self.glass_group.iter().cloned());
        names.extend(self.refraction_group.iter().cloned());
        names
    }
}

/// Where the curves come from.
#[derive(Clone, Copy, Debug)]
pub enum Curves<'a> {
    /// One coefficients file (or preset) for every family, calibrated for the engine its
    /// entries name; `name` is what it was loaded by.
    Pinned {
        coefficients: &'a Coefficients,
        name: &'a str,
    },
    /// For each engine, each family's own preset (Cycles: `blender-3` for separable,
    /// `blender-4` for height-correlated masking; EEVEE: `eevee`, one family).
    Presets(&'a [Engine]),
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

/// `Gloffuse Shading Normal` (EEVEE: `Gloffuse EEVEE Shading Normal`): the public name of
/// the helper group that finds the normal a glossy BSDF shades with and the view cosine
/// there. Cycles raises a bump normal whose mirror reflection would dip below the surface;
/// EEVEE shades with the bump normal as it is, its view cosine clamped at 0.
pub fn normal_group_name(engine: Engine) -> String {
    format!("Gloffuse{} Shading Normal", engine_infix(engine))
}

/// ` EEVEE` in the names of the groups calibrated for EEVEE; nothing for Cycles.
fn engine_infix(engine: Engine) -> &'static str {
    match engine {
        Engine::Cycles => "",
        Engine::Eevee => " EEVEE",
    }
}

/// `Brightness Correction (GGX)` (EEVEE: `Brightness Correction EEVEE (GGX)`): the public
/// name of the gain group.
pub fn correction_group_name(engine: Engine, d: Distribution) -> String {
    format!(
        "Brightness Correction{} ({})",
        engine_infix(engine),
        d.label()
    )
}

/// `Gloffuse Layered (GGX)`: the public name of the glossy-over-diffuse group.
pub fn layered_group_name(d: Distribution) -> String {
    format!("Gloffuse Layered ({})", d.label())
}

/// `Gloffuse Anisotropic (GGX)`: the public name of the anisotropic glossy group.
pub fn anisotropic_group_name(d: Distribution) -> String {
    format!("Gloffuse Anisotropic ({})", d.label())
}

/// `Gloffuse Glass (GGX)`: the public name of the glass group.
pub fn glass_group_name(d: Distribution) -> String {
    format!("Gloffuse Glass ({})", d.label())
}

/// `Gloffuse Refraction (GGX)`: the public name of the refraction group.
pub fn refraction_group_name(d: Distribution) -> String {
    format!("Gloffuse Refraction ({})", d.label())
}

/// `Gloffuse Multiscatter (GGX)`: the public name of the Glossy + lost-energy group.
pub fn multiscatter_group_name(engine: Engine, d: Distribution) -> String {
    format!(
        "Gloffuse{} Multiscatter ({})",
        engine_infix(engine),
        d.label()
    )
}

/// `Gloffuse (GGX)` (EEVEE: `Gloffuse EEVEE (GGX)`): the public name of the corrected
/// shader group.
pub fn shader_group_name(engine: Engine, d: Distribution) -> String {
    format!("Gloffuse{} ({})", engine_infix(engine), d.label())
}

impl GenerateParams {
    /// The groups for every distribution the curves hold, for each masking family in
    /// `families` (EEVEE: its one model), with the view-dependent groups `modes` ask for.
    pub fn new(
        curves: Curves,
        families: &[Masking],
        modes: &[Mode],
        color_model: ColorModel,
    ) -> Result<Self, Error> {
        let engines = match curves {
            Curves::Pinned { coefficients, .. } => vec![coefficients.engine()],
            Curves::Presets(engines) => engines.to_vec(),
        };
        if engines.contains(&Engine::Eevee) && modes.contains(&Mode::Layered) {
            return Err(Error::input(
                Field::Mode,
                Mode::Layered.key(),
                "roughness, view or multiscatter for EEVEE: the layered groups are calibrated \
                 for Cycles, and in EEVEE's furnace their rings miss 2 % (docs/EEVEE.md)",
            ));
        }
        if engines.contains(&Engine::Eevee) && modes.contains(&Mode::Anisotropic) {
            return Err(Error::input(
                Field::Mode,
                Mode::Anisotropic.key(),
                "roughness, view or multiscatter for EEVEE: EEVEE renders an anisotropic \
                 Glossy as an isotropic one, so the anisotropic groups are built for Cycles only",
            ));
        }
        if engines.contains(&Engine::Eevee) && modes.contains(&Mode::Glass) {
            return Err(Error::input(
                Field::Mode,
                Mode::Glass.key(),
                "roughness, view or multiscatter for EEVEE: the glass groups restore the \
                 energy of Cycles' Glass and Refraction BSDFs, which EEVEE does not render",
            ));
        }
        let mut groups = Vec::new();
        for engine in engines {
            let mut loaded = Vec::new();
            for masking in engine_families(engine, families) {
                let (coefficients, name) = match curves {
                    Curves::Pinned { coefficients, name } => {
                        (coefficients.clone(), name.to_string())
                    }
                    Curves::Presets(_) => {
                        let name = preset_for_masking(engine, masking);
                        (Coefficients::load(name)?, name.to_string())
                    }
                };
                loaded.push((masking, coefficients, name));
            }
            let distributions: Vec<Distribution> = loaded
                .first()
                .map(|(_, c, _)| c.distributions.keys().copied().collect())
                .unwrap_or_default();
            groups.extend(
                distributions
                    .into_iter()
                    .map(|d| group_spec(engine, d, &loaded, modes, color_model)),
            );
        }
        let first = BlenderVersion::HEIGHT_CORRELATED_FROM;
        Ok(GenerateParams {
            gloffuse_version: env!("CARGO_PKG_VERSION"),
            height_correlated_from: [first.major, first.minor],
            color_model,
            catalogs: Catalogs::default(),
            asset_author: ASSET_AUTHOR,
            asset_license: ASSET_LICENSE,
            asset_copyright: ASSET_COPYRIGHT,
            previews: false,
            groups,
        })
    }

    /// Every group name the script builds, in build order: each spec's groups, after the
    /// normal helper it is the first to use.
    pub fn group_names(&self) -> Vec<String> {
        let mut names: Vec<String> = Vec::new();
        for spec in &self.groups {
            if let Some(normal) = &spec.normal_group
                && !names.contains(normal)
            {
                names.push(normal.clone());
            }
            names.extend(spec.group_names());
        }
        names
    }
}

/// The masking families an engine's groups carry: each of Cycles' `families` as that
/// engine renders it, once (EEVEE's one model serves every Blender version).
fn engine_families(engine: Engine, families: &[Masking]) -> Vec<Masking> {
    let mut rendered: Vec<Masking> = families.iter().map(|&m| engine.masking(m)).collect();
    rendered.dedup();
    rendered
}

/// One distribution's groups for one engine: names, and per family the curve and the tables
/// of the BSDF that engine renders.
fn group_spec(
    engine: Engine,
    d: Distribution,
    loaded: &[(Masking, Coefficients, String)],
    modes: &[Mode],
    color_model: ColorModel,
) -> GroupSpec {
    let wants = |m: Mode| modes.contains(&m);
    // Every per-pixel group reads the shading normal; all but the anisotropic one E(μ, r).
    let normal = modes.iter().any(|m| m.per_pixel());
    let views = modes
        .iter()
        .any(|m| m.per_pixel() && !matches!(m, Mode::Anisotropic | Mode::Glass));
    let layered = wants(Mode::Layered);
    // Anisotropic GGX and Beckmann (Ashikhmin–Shirley's anisotropic lobe is another model).
    let anisotropic = wants(Mode::Anisotropic) && d != Distribution::AshikhminShirley;
    // Blender's Glass and Refraction BSDFs have GGX and Beckmann.
    let glass = wants(Mode::Glass) && d != Distribution::AshikhminShirley;
    let infix = engine_infix(engine);
    GroupSpec {
        distribution: d,
        engine,
        correction_group: correction_group_name(engine, d),
        shader_group: shader_group_name(engine, d),
        normal_group: normal.then(|| normal_group_name(engine)),
        layered_group: layered.then(|| layered_group_name(d)),
        anisotropic_group: anisotropic.then(|| anisotropic_group_name(d)),
        glass_group: glass.then(|| glass_group_name(d)),
        refraction_group: glass.then(|| refraction_group_name(d)),
        view: (wants(Mode::View) || wants(Mode::Multiscatter)).then(|| ViewNames {
            correction_group: wants(Mode::View)
                .then(|| format!("Brightness Correction{infix} View ({})", d.label())),
            shader_group: wants(Mode::View)
                .then(|| format!("Gloffuse{infix} View ({})", d.label())),
            multiscatter_group: wants(Mode::Multiscatter)
                .then(|| multiscatter_group_name(engine, d)),
        }),
        families: loaded
            .iter()
            .filter_map(|(masking, c, name)| {
                let e = c.distributions.get(&d)?;
                // EEVEE renders every distribution as its GGX: the tables are that BSDF's.
                let (model, model_masking) = engine.model(d, *masking);
                let rendered_anisotropic = anisotropic && family_renders_anisotropic(*masking, d);
                Some(FamilySpec {
                    masking: *masking,
                    coefficients_source: format!("{name} ({})", c.name),
                    description: describe(engine, d, e, name),
                    curve: e.curve.clone(),
                    image: views.then(|| {
                        format!("Gloffuse E(mu, r) ({}, {})", model.label(), model_masking)
                    }),
                    table: views
                        .then(|| AlbedoTable::compute(model, model_masking, VIEW_TABLE_SIZE)),
                    coat_image: layered
                        .then(|| format!("Gloffuse coat A ({}, {})", d.label(), masking)),
                    coat_table: layered.then(|| CoatTable::compute(d, *masking, COAT_TABLE_SIZE)),
                    coat_gain_image: (layered && d == Distribution::Beckmann)
                        .then(|| format!("Gloffuse coat gain ({}, {})", d.label(), masking)),
                    anisotropic_image: rendered_anisotropic.then(|| {
                        format!("Gloffuse E(mu, phi, ax, ay) ({}, {})", d.label(), masking)
                    }),
                    anisotropic_table: rendered_anisotropic
                        .then(|| AnisotropicTable::compute(d, *masking)),
                    glass_image: glass
                        .then(|| format!("Gloffuse E(mu, r, eta) ({}, {})", d.label(), masking)),
                    glass_table: glass.then(|| GlassTable::compute(d, *masking, color_model)),
                })
            })
            .collect(),
    }
}

/// Whether the Blenders of a masking family render the anisotropic lobe of `d` (not
/// Beckmann in 3.0–3.4, the separable family): where they do not, the family carries no
/// table and the script builds no anisotropic group for `d`.
fn family_renders_anisotropic(masking: Masking, d: Distribution) -> bool {
    let first = match masking {
        Masking::Separable => BlenderVersion::OLDEST,
        Masking::HeightCorrelated => BlenderVersion::HEIGHT_CORRELATED_FROM,
    };
    first.renders_anisotropic(d)
}

/// The description of a distribution's groups: what the curve restores, where it comes
/// from, and what the other engine makes of it.
fn describe(
    engine: Engine,
    d: Distribution,
    e: &crate::fit::coefficients::Entry,
    source: &str,
) -> String {
    let what = match engine {
        Engine::Cycles => format!("a white {} Glossy BSDF", d.label()),
        Engine::Eevee => format!(
            "a white {} Glossy BSDF in EEVEE (which renders it as GGX)",
            d.label()
        ),
    };
    format!(
        "Restores {what} to 100 % brightness under even light: gain = 100 / f(r), fitted to the sphere's {} brightness ({} masking{}). Coefficients: {}. {}",
        match e.target {
            Target::Mean => "mean",
            Target::Center => "centre",
        },
        e.masking,
        match e.color_space {
            ColorSpace::Linear => "",
            ColorSpace::Display => "; display-referred percentages, not a true linear gain",
        },
        source,
        in_the_other_engine(engine, d, e.masking),
    )
}

/// The roughness values of the EEVEE measurements quoted in the Cycles groups' descriptions.
const EEVEE_ROUGHNESS: [f64; 4] = [0.25, 0.5, 0.75, 1.0];

/// The Blender each Cycles family's EEVEE figures were measured in (separable, then
/// height-correlated).
const EEVEE_MEASURED_IN: [&str; 2] = ["3.4.1 (EEVEE Legacy)", "4.5.15 (EEVEE Next)"];

/// A white sphere with the Cycles group of `d` and `masking`'s preset, rendered in EEVEE
/// (`verify --engine eevee --coefficients blender-3|blender-4 -r 0.25,0.5,0.75,1`, 1 spp,
/// 64 px), in percent at [`EEVEE_ROUGHNESS`]; `tests/eevee_e2e.rs` re-renders them.
pub fn in_eevee(d: Distribution, masking: Masking) -> [f64; 4] {
    match (masking, d) {
        (Masking::Separable, Distribution::Beckmann) => [98.8, 90.6, 74.1, 57.4],
        (Masking::Separable, Distribution::Ggx) => [99.9, 100.0, 100.0, 100.0],
        (Masking::Separable, Distribution::AshikhminShirley) => [104.4, 112.1, 118.8, 156.9],
        (Masking::HeightCorrelated, Distribution::Beckmann) => [98.0, 89.6, 73.2, 56.3],
        (Masking::HeightCorrelated, Distribution::Ggx) => [99.0, 98.6, 96.9, 91.4],
        (Masking::HeightCorrelated, Distribution::AshikhminShirley) => [103.4, 110.8, 117.6, 155.7],
    }
}

/// What a group does in the engine it is not calibrated for, as measured (docs/RESULTS.md, "EEVEE").
fn in_the_other_engine(engine: Engine, d: Distribution, masking: Masking) -> String {
    match engine {
        Engine::Eevee => "In Cycles use the groups without EEVEE in their names.".into(),
        Engine::Cycles => {
            let measured = in_eevee(d, masking)
                .iter()
                .map(|p| format!("{p} %"))
                .collect::<Vec<_>>()
                .join(", ");
            format!(
                "In EEVEE a white sphere with this group renders at {measured} of the light at roughness {} (measured in Blender {}); use the EEVEE groups there.",
                EEVEE_ROUGHNESS.map(|r| r.to_string()).join(", "),
                EEVEE_MEASURED_IN[usize::from(masking == Masking::HeightCorrelated)]
            )
        }
    }
}
fn as_blender_enum<S: serde::Serializer>(d: &Distribution, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_str(d.blender_enum())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::measure::{Dielectric, critical_cosine};

    /// The physical colour model's tables carry E_avg of each node and side, every row
    /// alike, at each slice's index and column's roughness; the exact model's carry none.
    #[test]
    fn physical_glass_tables_carry_the_averages() {
        let q = DielectricIntegrator::default();
        let n = GLASS_TABLE_SIZE;
        let exact = GlassTable::compute(
            Distribution::Beckmann,
            Masking::HeightCorrelated,
            ColorModel::Exact,
        );
        assert!(exact.averages.is_none());
        let table = GlassTable::compute(
            Distribution::Beckmann,
            Masking::HeightCorrelated,
            ColorModel::Physical,
        );
        let averages = table.averages.as_ref().unwrap();
        for (values, node, side) in [
            (
                averages.glass_average_entering.as_ref().unwrap(),
                DielectricNode::Glass,
                Side::Entering,
            ),
            (
                averages.glass_average_leaving.as_ref().unwrap(),
                DielectricNode::Glass,
                Side::Leaving,
            ),
            (
                &averages.refraction_average_entering,
                DielectricNode::Refraction,
                Side::Entering,
            ),
            (
                &averages.refraction_average_leaving,
                DielectricNode::Refraction,
                Side::Leaving,
            ),
        ] {
            for (k, j) in [(0, 3), (5, 15), (11, 8)] {
                let r = Roughness::new(j as f64 / (n - 1) as f64).unwrap();
                let bsdf =
                    Dielectric::new(node, Distribution::Beckmann, r, GlassForm::ONE_CLOSURE_FROM);
                let want = q.average_albedo(&bsdf, side.eta(table.ior[k])) as f32;
                for i in [0, 7, n - 1] {
                    let got = values[(i * table.slices + k) * n + j];
                    assert_eq!(
                        got, want,
                        "{node:?} {side:?} row {i}, slice {k}, column {j}"
                    );
                }
            }
        }
    }

    /// 3.0–3.4's GGX Glass group wraps the random-walk Multiscatter GGX glass, so its table
    /// carries nothing for the Glass node; Beckmann's, and 3.6 on, carry the Glass node's E.
    #[test]
    fn only_three_x_ggx_glass_wraps_multiscatter() {
        for (d, masking, wraps) in [
            (Distribution::Ggx, Masking::Separable, true),
            (Distribution::Beckmann, Masking::Separable, false),
            (Distribution::Ggx, Masking::HeightCorrelated, false),
        ] {
            let t = GlassTable::compute(d, masking, ColorModel::Physical);
            let what = format!("{d:?} {masking:?}");
            let averages = t.averages.as_ref().unwrap();
            assert_eq!(t.glass_group == GlassGroup::Multiscatter, wraps, "{what}");
            let glass_node = t.glass_entering.is_some() || t.reflection.is_some();
            assert_eq!(glass_node, !wraps, "{what}");
            assert_eq!(averages.glass_average_leaving.is_some(), !wraps, "{what}");
            assert_eq!(
                averages.refraction_average_leaving.len(),
                t.refraction_leaving.len()
            );
        }
    }

    /// Each table's texels are the integrator's E at their row's view cosine: μ = t^1.5 in
    /// every table but the leaving Refraction one, whose rows crowd about each slice's
    /// critical cosine (at it halfway up, at 0 and 1 in the first and last rows). Checked
    /// against the axes' closed forms, not the axis functions the table is built with.
    #[test]
    fn the_rows_crowd_at_grazing_and_at_the_critical_angle() {
        let q = DielectricIntegrator::default();
        let n = GLASS_TABLE_SIZE;
        for (masking, version) in [
            (Masking::Separable, BlenderVersion::OLDEST),
            (Masking::HeightCorrelated, GlassForm::ONE_CLOSURE_FROM),
        ] {
            let table = GlassTable::compute(Distribution::Ggx, masking, ColorModel::Exact);
            let cases = [
                (&table.refraction_leaving, DielectricNode::Refraction, true),
                (
                    &table.refraction_entering,
                    DielectricNode::Refraction,
                    false,
                ),
            ]
            .into_iter()
            .chain(
                table
                    .glass_leaving
                    .as_ref()
                    .map(|v| (v, DielectricNode::Glass, true)),
            );
            for ((values, node, leaving), (i, k, j)) in cases.flat_map(|c| {
                [
                    (c, (0, 6, 2)),
                    (c, (3, 11, 15)),
                    (c, (9, 4, 8)),
                    (c, (15, 7, 1)),
                ]
            }) {
                let (ior, x) = (table.ior[k], i as f64 / (n - 1) as f64);
                let c = critical_cosine(ior);
                let mu = match (node, leaving) {
                    (DielectricNode::Refraction, true) if x >= 0.5 => {
                        c + (1.0 - c) * (2.0 * x - 1.0).powi(2)
                    }
                    (DielectricNode::Refraction, true) => c * (1.0 - (1.0 - 2.0 * x).powi(2)),
                    _ => x * x.sqrt(),
                };
                let r = Roughness::new(j as f64 / (n - 1) as f64).unwrap();
                let lobe = Dielectric::new(node, Distribution::Ggx, r, version);
                let eta = if leaving { 1.0 / ior } else { ior };
                let want = q.directional_albedo(&lobe, mu.max(1e-3), eta) as f32;
                let got = values[(i * table.slices + k) * n + j];
                assert!(
                    (got - want).abs() < 1e-6,
                    "{masking:?} {node:?} leaving {leaving} ({i}, {k}, {j}): {got} vs {want}"
                );
            }
        }
    }
}
