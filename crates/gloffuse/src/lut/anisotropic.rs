//! The anisotropic albedo table for real-time renderers: `E(μ, φ, αx, αy)` of Cycles'
//! anisotropic GGX or Beckmann lobe, and its hemispherical average, from the same
//! [`AnisotropicIntegrator::grid`] that `gloffuse` checks against Blender's renders.
//!
//! Layout: an atlas of [`AZIMUTHS`] × n slices, each `n × n`. Slice (k, l) sits at column
//! k, row l; within it texel (x, y) holds `rx = (x + ½)/n` and `N·V = (y + ½)/n` (pixel
//! centres, so a renderer filters bilinearly inside a slice). Column k is the view azimuth
//! from the tangent `φ_k = k/(AZIMUTHS − 1) · π/2` (grid points, for a linear blend
//! between two columns; fold any azimuth into [0, π/2] by the lobe's mirror symmetries),
//! row l the bitangent's `ry = (l + ½)/n`. The widths are `αx = rx²`, `αy = ry²` (like
//! the Roughness input: `α = r²`). R = E, G = E_avg(αx, αy).

use super::Table;
use crate::measure::anisotropic::{AnisotropicAxes, AnisotropicIntegrator};
use crate::measure::{Distribution, Masking, Roughness};
use crate::progress::Progress;
use std::f64::consts::FRAC_PI_2;

/// View azimuths per table: a column of slices for each.
pub const AZIMUTHS: usize = 8;

/// The largest `--size`: 32 makes 8 × 32 slices of 32² texels (262,144 albedos, about a
/// minute on two cores).
pub const MAX_SIZE: u32 = 32;

/// The view azimuths of the columns, in order: `k/(AZIMUTHS − 1) · π/2`.
pub fn azimuths() -> Vec<f64> {
    (0..AZIMUTHS)
        .map(|k| FRAC_PI_2 * k as f64 / (AZIMUTHS - 1) as f64)
        .collect()
}

/// The anisotropic atlas of `distribution` (GGX or Beckmann, checked by the caller) with
/// `masking`, `size` texels per slice side; `progress` steps once per row of slices.
pub fn anisotropic_table(
    size: usize,
    distribution: Distribution,
    masking: Masking,
    progress: &dyn Progress,
) -> Table {
    let centres: Vec<f64> = Roughness::pixel_centres(size)
        .iter()
        .map(|r| r.get())
        .collect();
    let axes = AnisotropicAxes {
        mu: centres.clone(),
        phi: azimuths(),
        rx: centres.clone(),
        ry: centres,
    };
    let grid = AnisotropicIntegrator::default()
        .grid(distribution, masking, axes, progress)
        .expect("pixel centres are widths within [0, 1] and the caller checked the distribution");
    let mut data = Vec::with_capacity(size * size * AZIMUTHS * size * 2);
    for l in 0..size {
        for i in 0..size {
            for k in 0..AZIMUTHS {
                for j in 0..size {
                    data.extend_from_slice(&[grid.e(i, k, j, l) as f32, grid.e_avg(j, l) as f32]);
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
