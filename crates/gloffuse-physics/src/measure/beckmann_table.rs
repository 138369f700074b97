//! Cycles 3.0–3.4's Beckmann sampler on the CPU: it draws a visible normal's slope along
//! the view from a table instead of the exact inverse CDF, so what a Beckmann lobe returns
//! on average in those Blenders is the sample weight integrated over the random numbers
//! through that table (docs/PHYSICS.md §15). Read at v3.4.0 (`scene/shader.cpp`, the
//! table; `closure/bsdf_microfacet.h`, `microfacet_beckmann_sample_slopes`; v3.5.0 draws
//! the slope by Newton's method instead):
//!
//! - for α = 1 and 256 stretched view cosines c = i/255, the marginal density of the slope x
//!   along the view, `(c − x √(1 − c²))⁺ e^(−x²)`, is summed over 512 slopes even in
//!   [−6, 6] into a running sum (each slope's value added at that slope), normalised to 1;
//! - at 256 random numbers `U = 1e-7 + 0.9999998 m/255` the slope is where the running sum
//!   reaches U, linear between the two slopes about it;
//! - a lookup reads the table bilinearly at (u · 255, c · 255), clamped to the table; the
//!   slope across the view is drawn exactly (an inverse error function), and a view within
//!   1e-5 of the normal samples the whole lobe exactly.

use std::sync::OnceLock;

/// Rows (view cosines) and columns (random numbers) of the table.
pub const SIZE: usize = 256;
/// Slopes summed per row.
const SLOPES: usize = 512;
/// The slopes' range, ±.
const SLOPE_MAX: f64 = 6.0;
/// At or above this stretched view cosine Cycles samples the lobe exactly.
pub const EXACT_FROM: f64 = 0.99999;

/// The table's row coordinate for an isotropic lobe of width `alpha` and the view cosine
/// `mu`: the cosine of the view stretched by α, `μ / √(μ² + α² (1 − μ²))`.
pub fn stretched_cosine(mu: f64, alpha: f64) -> f64 {
    mu / (mu * mu + alpha * alpha * (1.0 - mu * mu)).sqrt()
}

/// The table: `values[row * SIZE + column]`, the slope for view cosine `row / 255` and
/// random number about `column / 255`.
pub struct SlopeTable {
    values: Vec<f64>,
}

impl SlopeTable {
    /// The table Cycles 3.0–3.4 build at start-up (built once).
    pub fn cycles() -> &'static SlopeTable {
        static TABLE: OnceLock<SlopeTable> = OnceLock::new();
        TABLE.get_or_init(SlopeTable::build)
    }

    fn build() -> SlopeTable {
        let slope = |k: usize| -SLOPE_MAX + 2.0 * SLOPE_MAX * k as f64 / (SLOPES - 1) as f64;
        let mut values = Vec::with_capacity(SIZE * SIZE);
        for row in 0..SIZE {
            let cos = row as f64 / (SIZE - 1) as f64;
            let sin = (1.0 - cos * cos).max(0.0).sqrt();
            let mut cdf = vec![0.0; SLOPES];
            for k in 1..SLOPES {
                let x = slope(k);
                cdf[k] = cdf[k - 1] + (cos - x * sin).max(0.0) * (-x * x).exp();
            }
            let total = cdf[SLOPES - 1];
            cdf.iter_mut().for_each(|c| *c /= total);
            let mut k = 0;
            for column in 0..SIZE {
                let u = 1e-7 + 0.9999998 * column as f64 / (SIZE - 1) as f64;
                while cdf[k] <= u {
                    k += 1;
                }
                let t = (cdf[k] - u) / (cdf[k] - cdf[k - 1]);
                values.push(t * slope(k - 1) + (1.0 - t) * slope(k));
            }
        }
        SlopeTable { values }
    }

    /// The slope along the view for random number `u` and stretched view cosine `cos`, read
    /// as Cycles reads it.
    pub fn slope(&self, u: f64, cos: f64) -> f64 {
        let (row, t) = cell(cos);
        let read = |row: usize| {
            let (column, s) = cell(u);
            let at = |c: usize| self.values[row * SIZE + c];
            (1.0 - s) * at(column) + s * at((column + 1).min(SIZE - 1))
        };
        (1.0 - t) * read(row) + t * read((row + 1).min(SIZE - 1))
    }
}

/// The index and fraction of `x` in [0, 1] on the table's axis of `SIZE` points.
fn cell(x: f64) -> (usize, f64) {
    let x = x.clamp(0.0, 1.0) * (SIZE - 1) as f64;
    let index = (x as usize).min(SIZE - 1);
    (index, x - index as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The exact CDF of the slope along the view for α = 1 at view cosine c: `∫ (c − x s)⁺
    /// e^(−x²) dx` from −9 up to x over the same integral up to cot θ (s = sin θ), each by
    /// 400 Gauss nodes: a second method, not the table's running sum.
    fn exact_cdf(x: f64, c: f64) -> f64 {
        let s = (1.0 - c * c).sqrt();
        let nodes = crate::measure::albedo::gauss_unit(400);
        let integral = |to: f64| -> f64 {
            let from = -9.0;
            nodes
                .iter()
                .map(|&(t, w)| {
                    let x = from + (to - from) * t;
                    w * (to - from) * (c - x * s).max(0.0) * (-x * x).exp()
                })
                .sum()
        };
        integral(x.min(c / s)) / integral(c / s)
    }

    /// Where the table is fine (rows of an oblique view, random numbers away from the ends)
    /// its slope is where the exact CDF reaches the random number, within the 512 slopes'
    /// spacing; at the ends it cannot be (the slopes stop at ±6, the CDF is clamped).
    #[test]
    fn the_table_inverts_the_exact_cdf() {
        let t = SlopeTable::cycles();
        let spacing = 2.0 * SLOPE_MAX / (SLOPES - 1) as f64;
        for row in [32, 128, 200, 250] {
            let c = row as f64 / (SIZE - 1) as f64;
            for column in [13, 64, 128, 192, 240] {
                let u = column as f64 / (SIZE - 1) as f64;
                let x = t.slope(u, c);
                let at = exact_cdf(x, c);
                // The CDF's slope there bounds how far a slope error moves it.
                let (lo, hi) = (exact_cdf(x - spacing, c), exact_cdf(x + spacing, c));
                assert!(
                    (lo..=hi).contains(&u),
                    "row {row}, column {column}: slope {x}, CDF {at} not about {u} ({lo}..{hi})"
                );
            }
        }
    }

    /// A lookup between grid points is bilinear: halfway between two rows and two columns it
    /// is the mean of the four values.
    #[test]
    fn a_lookup_is_bilinear() {
        let t = SlopeTable::cycles();
        let (i, j) = (100, 37);
        let v = |r: usize, c: usize| t.values[r * SIZE + c];
        let want = (v(i, j) + v(i + 1, j) + v(i, j + 1) + v(i + 1, j + 1)) / 4.0;
        let got = t.slope(
            (j as f64 + 0.5) / (SIZE - 1) as f64,
            (i as f64 + 0.5) / (SIZE - 1) as f64,
        );
        assert!((got - want).abs() < 1e-12, "{got} vs {want}");
    }
}
