//! The anisotropic albedo table for real-time renderers: `E(μ, φ, αx, αy)` of Cycles'
//! anisotropic GGX or Beckmann lobe, and its hemispherical average, from the same
//! [`AnisotropicIntegrator::grid`] that `gloffuse` checks against Blender's renders.
//!
//! Layout: an atlas of [`AZIMUTHS`] × n slices, each `n × n`. Slice (k, l) sits at column
//! k, row l; within it texel (x, y) holds `rx = x/(n − 1)` and `N·V = y/(n − 1)` (grid
//! points, so both ends are exact; see [`AnisotropicAxes::table`]). Column k is the view
//! azimuth from the tangent `φ_k = k/(AZIMUTHS − 1) · π/2` (fold any azimuth into [0, π/2] by the lobe's mirror
//! symmetries), row l the bitangent's `ry = l/(n − 1)`. The widths are `αx = rx²`,
//! `αy = ry²` (like the Roughness input: `α = r²`). R = E, G = E_avg(αx, αy). A renderer
//! samples a slice at `u = (rx (n − 1) + ½)/n` (bilinear inside the slice) and blends the
//! two nearest columns and rows itself; `cargo run --release --example
//! anisotropic_table_error` measures what that lookup misses.

use super::{Bsdf, KindFacts, LutOptions, SizeLimit, Spec, Table, blender_bsdf, microfacet_only};
use crate::error::{Error, Field, Hint};
use crate::measure::anisotropic::{AnisotropicAxes, AnisotropicIntegrator};
use crate::measure::{Distribution, Masking};
use crate::progress::Progress;

/// The anisotropic table: its facts for `lut` (see the module's doc for its layout).
pub const KIND: KindFacts = KindFacts {
    key: "anisotropic",
    default_size: 16,
    size_limit: Some(SizeLimit {
        min: 2,
        max: MAX_SIZE,
        why: || {
            format!(
                "its atlas holds {AZIMUTHS} × size slices of size² albedos, each a 9,216-point quadrature"
            )
        },
    }),
    bsdf,
    channels: &[
        "R: E(N·V, φ of the slice's column, αx = rx², αy = ry² of the slice's row)",
        "G: E_avg(αx, αy)",
    ],
    steps_per_size: 2,
    slice_iors: None,
    slice_azimuths: Some(azimuths),
    compute: |spec: &Spec, progress| {
        let bsdf = spec.blender();
        anisotropic_table(
            spec.size,
            bsdf.distribution,
            bsdf.blender_version.masking(),
            progress,
        )
    },
};

/// GGX or Beckmann, as a Blender version that renders the lobe renders it.
fn bsdf(args: &LutOptions) -> Result<Bsdf, Error> {
    let bsdf = blender_bsdf(args, None)?;
    let (distribution, blender_version) = (bsdf.distribution, bsdf.blender_version);
    microfacet_only(
        distribution,
        args.kind,
        "the table covers the two microfacet distributions",
    )?;
    if !blender_version.renders_anisotropic(distribution) {
        return Err(Error::input(
            Field::BlenderVersion,
            blender_version,
            Hint::new(
                "3.5 or later with {} beckmann {} anisotropic (Blender 3.0–3.4 sample an isotropic lobe for anisotropic Beckmann, so they do not render the lobe this table describes; GGX is right in every version)",
                [Field::Distribution, Field::Kind],
            ),
        ));
    }
    Ok(Bsdf::Blender(bsdf))
}

/// View azimuths per table: a column of slices for each. Near grazing, a view along the
/// narrow axis changes E steeply with φ: 8 columns miss it by 4.6 %, 16 by 2.6 %.
pub const AZIMUTHS: usize = 16;

/// The largest `--size`: 32 makes 16 × 32 slices of 32² texels (524,288 albedos, about
/// two minutes on two cores).
pub const MAX_SIZE: u32 = 32;

/// The view azimuths of the columns, in order: `k/(AZIMUTHS − 1) · π/2`.
pub fn azimuths() -> Vec<f64> {
    AnisotropicAxes::table(2, AZIMUTHS).phi
}

/// The anisotropic atlas of `distribution` (GGX or Beckmann, checked by the caller) with
/// `masking`, `size` texels per slice side; `progress` steps twice per row of slices (its averages,
/// then its E).
pub fn anisotropic_table(
    size: usize,
    distribution: Distribution,
    masking: Masking,
    progress: &dyn Progress,
) -> Table {
    let axes = AnisotropicAxes::table(size, AZIMUTHS);
    let integrator = AnisotropicIntegrator::default();
    let e_avg = integrator
        .average_grid(distribution, masking, &axes.rx, &axes.ry, &|| {
            progress.step()
        })
        .expect("grid points are widths within [0, 1] and the caller checked the distribution");
    let grid = integrator
        .grid(distribution, masking, axes, &|| progress.step())
        .expect("grid points are widths within [0, 1] and the caller checked the distribution");
    let mut data = Vec::with_capacity(size * size * AZIMUTHS * size * 2);
    for l in 0..size {
        for i in 0..size {
            for k in 0..AZIMUTHS {
                for j in 0..size {
                    data.extend_from_slice(&[
                        grid.e(i, k, j, l) as f32,
                        e_avg[l * size + j] as f32,
                    ]);
                }
            }
        }
    }
    Table {
        width: size * AZIMUTHS,
        height: size * size,
        channels: &["R", "G"],
        data,
    }
}
