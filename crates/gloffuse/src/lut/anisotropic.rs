//! The anisotropic albedo table for real-time renderers: `E(μ, φ, αx, αy)` of Cycles'
//! anisotropic GGX or Beckmann lobe, and its hemispherical average, from the same
//! [`AnisotropicIntegrator::grid`] that `gloffuse` checks against Blender's renders.
//!
//! Layout: an atlas of [`AZIMUTHS`] × n slices, each `n × n`. Slice (k, l) sits at column
//! k, row l; within it texel (x, y) holds `rx = x/(n − 1)` and `N·V = y/(n − 1)` (grid
//! points, so both ends are exact: one width is often clamped to 1, where E is steep; the
//! N·V = 0 row is taken at 1e-3 and a width of 0 at [`MIN_WIDTH_ROOT`]). Column k is the view azimuth from the tangent
//! `φ_k = k/(AZIMUTHS − 1) · π/2` (fold any azimuth into [0, π/2] by the lobe's mirror
//! symmetries), row l the bitangent's `ry = l/(n − 1)`. The widths are `αx = rx²`,
//! `αy = ry²` (like the Roughness input: `α = r²`). R = E, G = E_avg(αx, αy). A renderer
//! samples a slice at `u = (rx (n − 1) + ½)/n` (bilinear inside the slice) and blends the
//! two nearest columns and rows itself; `cargo run --release --example
//! anisotropic_table_error` measures what that lookup misses.

use super::Table;
use crate::measure::anisotropic::{AnisotropicAxes, AnisotropicIntegrator};
use crate::measure::{Distribution, Masking};
use crate::progress::Progress;
use std::f64::consts::FRAC_PI_2;

/// View azimuths per table: a column of slices for each. Near grazing, a view along the
/// narrow axis changes E steeply with φ: 8 columns miss it by 4.6 %, 16 by 2.6 %.
pub const AZIMUTHS: usize = 16;

/// The largest `--size`: 32 makes 16 × 32 slices of 32² texels (524,288 albedos, about
/// two minutes on two cores).
pub const MAX_SIZE: u32 = 32;

/// The table's N·V, rx and ry axes: `n` grid points from 0 to 1.
pub fn grid_points(n: usize) -> Vec<f64> {
    (0..n).map(|i| i as f64 / (n.max(2) - 1) as f64).collect()
}

/// The smallest `√α` the table is computed at. A lobe with `αx αy ≤ 1e-7` is a mirror to
/// Cycles (albedo 1), so at an exact 0 one width would switch a rough lobe to a mirror; at
/// 0.01 (α = 1e-4) the row holds the needle-thin lobe's own albedo, which the next row
/// blends with.
pub const MIN_WIDTH_ROOT: f64 = 0.01;

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
    let points = grid_points(size);
    let axes = AnisotropicAxes {
        mu: points.iter().map(|&mu| mu.max(1e-3)).collect(),
        phi: azimuths(),
        rx: points.iter().map(|&r| r.max(MIN_WIDTH_ROOT)).collect(),
        ry: points.iter().map(|&r| r.max(MIN_WIDTH_ROOT)).collect(),
    };
    let grid = AnisotropicIntegrator::default()
        .grid(distribution, masking, axes, progress)
        .expect("grid points are widths within [0, 1] and the caller checked the distribution");
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
