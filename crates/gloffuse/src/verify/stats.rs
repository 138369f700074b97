//! Statistics of one furnace sphere in its grid cell.
//!
//! An orthographic view of a sphere of radius R pixels sees, at distance d from the centre,
//! the view cosine μ = √(1 − (d/R)²); the cosines of the disc have density 2μ, so the
//! coverage-weighted mean Σ RGB / Σ alpha is the sphere's E_avg.
//!
//! A sphere that lets the world through (alpha below 1 where the disc is) is seen as an
//! opaque film would show it: what it reflects plus the white world of strength 1 seen
//! through it, RGB + (1 − alpha) per pixel ([`SphereStats::seen`]).

use serde::Serialize;

use super::image::Rgba;

/// Number of view-cosine rings in a profile.
pub const RINGS: usize = 10;

#[derive(Clone, Debug, Serialize)]
pub struct Ring {
    /// Lower and upper view cosine of the ring.
    pub mu: (f64, f64),
    pub pixels: usize,
    /// Mean brightness (0–1) of the ring's fully covered pixels; NaN if it holds none.
    pub mean: f64,
    /// Estimated standard error of `mean` (from its pixels' spread); NaN with fewer than two.
    pub standard_error: f64,
    /// The same per channel (R, G, B).
    pub mean_rgb: [f64; 3],
}

#[derive(Clone, Debug, Serialize)]
pub struct SphereStats {
    /// Σ RGB / (3 Σ alpha) over the cell: the sphere's mean brightness (0–1).
    pub mean: f64,
    /// Σ R / Σ alpha, Σ G / Σ alpha, Σ B / Σ alpha: the mean per channel.
    pub mean_rgb: [f64; 3],
    /// Estimated standard error of `mean` (from the pixel spread within each ring).
    pub standard_error: f64,
    /// Mean of the pixels with μ ≥ 0.995 (within 10 % of the radius of the centre).
    pub center: f64,
    pub coverage: f64,
    /// Σ alpha over the disc's area π R²: 1 for an opaque sphere, 0 for one the world is
    /// seen through everywhere (clamped to 1: the pixel filter spreads the edge).
    pub opacity: f64,
    /// The grazing-view brightness: over the pixels whose view cosine is below 0.3 (the
    /// outermost ring of the disc and the edge the pixel filter spreads), Σ RGB / Σ alpha
    /// where the sphere covers the ring, the white world where it lets it through (as
    /// [`SphereStats::seen`] weighs the mean).
    pub rim: f64,
    pub rings: Vec<Ring>,
}

impl SphereStats {
    /// The mean as the furnace shows it: the sphere's own light over its opaque part, the
    /// white world (1.0) over the rest of its disc. An opaque sphere's `mean`.
    pub fn seen(&self) -> f64 {
        if self.opacity > 0.0 {
            self.opacity * self.mean + (1.0 - self.opacity)
        } else {
            1.0
        }
    }
}

/// The view cosine below which a pixel counts to the rim: √(1 − 0.954²) = 0.3.
const RIM_MU: f64 = 0.3;

/// The rim as the furnace shows it, from its sums: `rgb` and `alpha` over the pixels whose
/// centre lies beyond the rim's inner circle, `inner` the pixels within it, on a disc of
/// `radius` pixels. An opaque disc's alpha sums to its area π R² (the pixel filter moves
/// alpha but keeps its sum), all of it in the `inner` pixels and the rim's: so the rim's
/// opacity is Σ alpha / (π R² − inner), exact on the pixel lattice.
fn seen_rim(rgb: f64, alpha: f64, radius: f64, inner: usize) -> f64 {
    let area = std::f64::consts::PI * radius * radius - inner as f64;
    let opacity = if area > 0.0 {
        (alpha / area).min(1.0)
    } else {
        1.0
    };
    let own = if alpha > 0.0 { rgb / alpha } else { 0.0 };
    opacity * own + (1.0 - opacity)
}

/// Statistics of cell `index` in a grid of `columns` cells of `cell` pixels, where the
/// sphere's diameter is `radius_fraction` of the cell.
// Long on purpose: one numeric pass; a single pixel loop feeds every sum the summary reads.
pub fn sphere_stats(
    img: &Rgba,
    index: usize,
    columns: usize,
    cell: usize,
    radius_fraction: f64,
) -> SphereStats {
    let (col, row) = (index % columns, index / columns);
    let (x0, y0) = (col * cell, row * cell);
    let centre = cell as f64 / 2.0;
    let radius = radius_fraction * cell as f64 / 2.0;
    let (mut sum_rgb, mut sum_a) = (0.0f64, 0.0f64);
    let mut sum_channel = [0.0f64; 3];
    let (mut centre_sum, mut centre_n) = (0.0f64, 0usize);
    let mut ring_sum = [0.0f64; RINGS];
    let mut ring_channel = [[0.0f64; 3]; RINGS];
    let mut ring_sq = [0.0f64; RINGS];
    let mut ring_n = [0usize; RINGS];
    let (mut rim_rgb, mut rim_a, mut inner) = (0.0f64, 0.0f64, 0usize);
    let rim_d = (1.0 - RIM_MU * RIM_MU).sqrt();
    for y in y0..(y0 + cell).min(img.height) {
        for x in x0..(x0 + cell).min(img.width) {
            let p = img.pixels[y * img.width + x];
            let rgb = (p[0] as f64 + p[1] as f64 + p[2] as f64) / 3.0;
            sum_rgb += rgb;
            sum_a += p[3] as f64;
            for (c, sum) in sum_channel.iter_mut().enumerate() {
                *sum += p[c] as f64;
            }
            let dx = (x - x0) as f64 + 0.5 - centre;
            let dy = (y - y0) as f64 + 0.5 - centre;
            let d = (dx * dx + dy * dy).sqrt() / radius;
            if d >= rim_d {
                rim_rgb += rgb;
                rim_a += p[3] as f64;
            } else {
                inner += 1;
            }
            // Only pixels whose filter footprint lies inside the disc count as fully
            // covered; what alpha leaves is the white world seen through the sphere.
            if d * radius < radius - 2.0 {
                let v = rgb + (1.0 - p[3] as f64);
                let mu = (1.0 - d * d).sqrt();
                let k = ((mu * RINGS as f64) as usize).min(RINGS - 1);
                ring_sum[k] += v;
                ring_sq[k] += v * v;
                ring_n[k] += 1;
                for (c, sum) in ring_channel[k].iter_mut().enumerate() {
                    *sum += p[c] as f64 + (1.0 - p[3] as f64);
                }
                if d <= 0.1 {
                    centre_sum += v;
                    centre_n += 1;
                }
            }
        }
    }
    let mean = if sum_a > 0.0 {
        sum_rgb / sum_a
    } else {
        f64::NAN
    };
    // Pixel noise is independent between pixels; within a ring all pixels share (nearly)
    // one expected value, so the ring's sample variance estimates each pixel's variance.
    let mut var_sum = 0.0;
    let mut n_total = 0usize;
    let rings = (0..RINGS)
        .map(|k| {
            let n = ring_n[k];
            let m = if n > 0 {
                ring_sum[k] / n as f64
            } else {
                f64::NAN
            };
            let mut standard_error = f64::NAN;
            if n > 1 {
                let var = (ring_sq[k] - n as f64 * m * m) / (n as f64 - 1.0);
                var_sum += var.max(0.0) * n as f64;
                standard_error = (var.max(0.0) / n as f64).sqrt();
            }
            n_total += n;
            Ring {
                mu: (k as f64 / RINGS as f64, (k + 1) as f64 / RINGS as f64),
                pixels: n,
                mean: m,
                standard_error,
                mean_rgb: ring_channel[k].map(|sum| sum / n as f64),
            }
        })
        .collect();
    let standard_error = if n_total > 0 {
        var_sum.sqrt() / n_total as f64
    } else {
        f64::NAN
    };
    SphereStats {
        mean,
        mean_rgb: sum_channel.map(|sum| sum / sum_a),
        standard_error,
        center: if centre_n > 0 {
            centre_sum / centre_n as f64
        } else {
            f64::NAN
        },
        coverage: sum_a / (cell * cell) as f64,
        opacity: (sum_a / (std::f64::consts::PI * radius * radius)).min(1.0),
        rim: seen_rim(rim_rgb, rim_a, radius, inner),
        rings,
    }
}
