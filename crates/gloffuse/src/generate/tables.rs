//! The packed tables the node groups read, computed from `measure` for one distribution
//! and masking family: E(μ, r) of the view modes ([`AlbedoTable`]), the layered coat's
//! ([`CoatTable`]), the anisotropic lobe's ([`AnisotropicTable`]) and the glass groups'
//! ([`GlassTable`]), with the sizes they are packed at.

use serde::Serialize;

use super::vocabulary::ColorModel;
use crate::measure::anisotropic::AnisotropicAxes;
use crate::measure::dielectric::Side;
use crate::measure::{
    AlbedoIntegrator, AnisotropicIntegrator, BlenderVersion, DielectricIntegrator, DielectricNode,
    Distribution, GlassForm, Masking, Roughness, coat, grazing_crowded,
};

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
        let grid = integrator.coat_grid(distribution, masking, &axis, &mus, &|| {});
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
                &|| {},
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
        let grid = integrator.grid(distribution, from, &mus, &axis, &|| {});
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
        let grid = integrator.grid(distribution, masking, &Roughness::grid(size), &mus, &|| {});
        AlbedoTable {
            width: size,
            height: size,
            values: grid.e.into_iter().map(|e| e as f32).collect(),
            average: grid.e_avg.into_iter().map(|e| e as f32).collect(),
        }
    }
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
