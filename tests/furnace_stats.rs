//! `furnace::stats::sphere_stats` on synthetic grids whose answers are known independently:
//! a disc of radius R = 0.9 · cell / 2 pixels per cell, each pixel holding a known function
//! of the orthographic view cosine μ = √(1 − (d/R)²) at its centre (or averaged over a
//! supersampled footprint, with fractional alpha and premultiplied RGB at the rim).
//!
//! Oracles: a constant comes back exactly; the disc's mean of μ is ∫₀¹ μ · 2μ dμ = 2/3; a
//! ring [lo, hi) of view cosines holds πR²(hi² − lo²) pixels with mean
//! (2/3)(hi³ − lo³)/(hi² − lo²); independent pixel noise of standard deviation σ gives a
//! standard error σ/√N over the N fully covered pixels.
//!
//! Tier: fast (no Blender; `scripts/test.sh --fast` runs it).

use std::f64::consts::PI;

use gloffuse::verify::image::Rgba;
use gloffuse::verify::stats::{RINGS, SphereStats, sphere_stats};

const CELL: usize = 64;
const RADIUS_FRACTION: f64 = 0.9;
/// Sphere radius in pixels (28.8).
const R: f64 = RADIUS_FRACTION * CELL as f64 / 2.0;
/// `sphere_stats` profiles only pixels whose centre is over 2 px inside the rim.
const INNER_R: f64 = R - 2.0;

/// Tolerance on the disc's mean of μ against 2/3. With pixel-centre sampling the disc
/// holds ≈ πR² ≈ 2600 pixels; a circle's lattice-count discrepancy is O(R^⅔), about 10
/// pixels here, all at the rim where μ < 0.2, so they move the mean by at most about
/// 10 · (2/3) / 2600 ≈ 0.26 %. Measured: −0.075 % (centres), +0.02 % (4×4 supersampled).
const DISC_MEAN_TOLERANCE: f64 = 0.005;
/// Tolerance on a ring's mean against the continuous oracle: the lattice places a few
/// percent more or fewer pixels near either edge of a ring 0.1 wide, moving its mean by a
/// few thousandths (measured ≤ 0.0036).
const RING_MEAN_TOLERANCE: f64 = 0.005;
/// Tolerance on a pixel count against an area, as a fraction of the region's boundary
/// length in pixels (the lattice discrepancy stays well below a tenth of it here; measured
/// ≤ 0.05).
const COUNT_TOLERANCE_PER_BOUNDARY_PIXEL: f64 = 0.1;

/// An image of `columns` × `rows` cells, row 0 at the top, each holding a disc whose pixels
/// (alpha 1 inside, 0 outside at `ss` = 1) carry `value(cell index, μ)` in RGB, scaled by
/// `tint` per channel (tints average to 1). With `ss` > 1 each pixel averages ss × ss
/// subsamples: alpha is the covered fraction and RGB the premultiplied mean.
fn grid(
    columns: usize,
    rows: usize,
    ss: usize,
    tint: [f64; 3],
    mut value: impl FnMut(usize, f64) -> f64,
) -> Rgba {
    let (width, height) = (columns * CELL, rows * CELL);
    let half = CELL as f64 / 2.0;
    let mut pixels = Vec::with_capacity(width * height);
    for y in 0..height {
        for x in 0..width {
            let index = (y / CELL) * columns + x / CELL;
            let (mut sum, mut inside) = (0.0, 0usize);
            for j in 0..ss {
                for i in 0..ss {
                    let dx = (x % CELL) as f64 + (i as f64 + 0.5) / ss as f64 - half;
                    let dy = (y % CELL) as f64 + (j as f64 + 0.5) / ss as f64 - half;
                    let d = (dx * dx + dy * dy).sqrt() / R;
                    if d < 1.0 {
                        sum += value(index, (1.0 - d * d).sqrt());
                        inside += 1;
                    }
                }
            }
            let n = (ss * ss) as f64;
            let v = sum / n;
            pixels.push([
                (v * tint[0]) as f32,
                (v * tint[1]) as f32,
                (v * tint[2]) as f32,
                (inside as f64 / n) as f32,
            ]);
        }
    }
    Rgba {
        width,
        height,
        pixels,
    }
}

const GREY: [f64; 3] = [1.0, 1.0, 1.0];
/// Exactly representable channel scales averaging to 1: checks that RGB is averaged.
const TINTED: [f64; 3] = [1.25, 1.0, 0.75];

/// Lower and upper view cosine of ring `k`, the lower one raised to the smallest μ a
/// profiled pixel can have.
fn ring_bounds(k: usize) -> (f64, f64) {
    let mu_min = (1.0 - (INNER_R / R).powi(2)).sqrt();
    (
        (k as f64 / RINGS as f64).max(mu_min),
        (k + 1) as f64 / RINGS as f64,
    )
}

/// Circumference in pixels of the circle of view cosine μ.
fn circumference(mu: f64) -> f64 {
    2.0 * PI * R * (1.0 - mu * mu).max(0.0).sqrt()
}

fn stats(img: &Rgba, index: usize, columns: usize) -> SphereStats {
    sphere_stats(img, index, columns, CELL, RADIUS_FRACTION)
}

fn profiled_pixels(s: &SphereStats) -> usize {
    s.rings.iter().map(|r| r.pixels).sum()
}

fn assert_count_near_area(what: &str, count: usize, area: f64, boundary: f64) {
    let tolerance = COUNT_TOLERANCE_PER_BOUNDARY_PIXEL * boundary;
    assert!(
        (count as f64 - area).abs() <= tolerance,
        "{what}: {count} pixels, area {area:.1} ± {tolerance:.1}"
    );
}

#[test]
fn rings_span_the_view_cosines_in_tenths() {
    let s = stats(&grid(1, 1, 1, GREY, |_, _| 0.5), 0, 1);
    assert_eq!(s.rings.len(), RINGS);
    for (k, ring) in s.rings.iter().enumerate() {
        assert_eq!(
            ring.mu,
            (k as f64 / RINGS as f64, (k + 1) as f64 / RINGS as f64)
        );
    }
}

#[test]
fn constant_comes_back_exactly() {
    let c = 0.75;
    for (ss, tint) in [(1, GREY), (1, TINTED), (4, GREY), (4, TINTED)] {
        let what = format!("{ss}×{ss} samples per pixel, tint {tint:?}");
        let s = stats(&grid(1, 1, ss, tint, |_, _| c), 0, 1);
        if ss == 1 {
            assert_eq!(s.mean, c, "{what}");
        } else {
            assert!((s.mean - c).abs() <= 1e-12, "{what}: mean {}", s.mean);
        }
        assert_eq!(s.center, c, "{what}");
        assert!(
            s.standard_error.abs() <= 1e-12,
            "{what}: {}",
            s.standard_error
        );
        for (k, ring) in s.rings.iter().enumerate() {
            if ring.pixels == 0 {
                assert!(
                    ring.mean.is_nan(),
                    "{what}: empty ring {k} has mean {}",
                    ring.mean
                );
            } else {
                assert_eq!(ring.mean, c, "{what}: ring {k}");
            }
        }
        // The disc covers π (0.45)² of the cell.
        let expected = PI * (RADIUS_FRACTION / 2.0).powi(2);
        let tolerance =
            COUNT_TOLERANCE_PER_BOUNDARY_PIXEL * circumference(0.0) / (CELL * CELL) as f64;
        assert!(
            (s.coverage - expected).abs() <= tolerance,
            "{what}: coverage {} vs {expected}",
            s.coverage
        );
    }
}

#[test]
fn mean_of_mu_is_two_thirds() {
    for ss in [1, 4] {
        let s = stats(&grid(1, 1, ss, TINTED, |_, mu| mu), 0, 1);
        let relative = s.mean / (2.0 / 3.0) - 1.0;
        assert!(
            relative.abs() <= DISC_MEAN_TOLERANCE,
            "{ss}×{ss} samples: mean {} is {:+.3} % off 2/3",
            s.mean,
            100.0 * relative
        );
    }
}

#[test]
fn centre_of_mu_is_one() {
    let s = stats(&grid(1, 1, 1, GREY, |_, mu| mu), 0, 1);
    // The centre is d ≤ R/10, i.e. μ ≥ √0.99 ≈ 0.99499.
    assert!(
        (0.99499..=1.0).contains(&s.center) && (1.0 - s.center) <= 0.005,
        "centre {}",
        s.center
    );
}

#[test]
fn ring_profile_of_mu() {
    for ss in [1, 4] {
        let s = stats(&grid(1, 1, ss, GREY, |_, mu| mu), 0, 1);
        let mut total = 0;
        for (k, ring) in s.rings.iter().enumerate() {
            let what = format!("{ss}×{ss} samples, ring {k} {:?}", ring.mu);
            let (lo, hi) = ring_bounds(k);
            if lo >= hi {
                // Below the smallest profiled μ (≈ 0.366): no pixel.
                assert_eq!(ring.pixels, 0, "{what}");
                assert!(ring.mean.is_nan(), "{what}");
                continue;
            }
            total += ring.pixels;
            let mid = (ring.mu.0 + ring.mu.1) / 2.0;
            assert!(
                (ring.mean - mid).abs() <= 0.5 / RINGS as f64,
                "{what}: mean {} outside the ring",
                ring.mean
            );
            let oracle = 2.0 / 3.0 * (hi.powi(3) - lo.powi(3)) / (hi * hi - lo * lo);
            assert!(
                (ring.mean - oracle).abs() <= RING_MEAN_TOLERANCE,
                "{what}: mean {} vs {oracle}",
                ring.mean
            );
            assert_count_near_area(
                &what,
                ring.pixels,
                PI * R * R * (hi * hi - lo * lo),
                circumference(lo) + circumference(hi),
            );
        }
        assert_count_near_area(
            "all profiled pixels",
            total,
            PI * INNER_R * INNER_R,
            2.0 * PI * INNER_R,
        );
    }
}

/// SplitMix64: a seeded stream of uniform numbers in [0, 1).
struct SplitMix(u64);

impl SplitMix {
    fn uniform(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Zero mean, standard deviation `sigma` (uniform on ±σ√3).
    fn noise(&mut self, sigma: f64) -> f64 {
        sigma * 3f64.sqrt() * (2.0 * self.uniform() - 1.0)
    }
}

#[test]
fn standard_error_of_independent_noise() {
    let (c, sigma) = (0.5, 0.05);
    for seed in [1, 2, 3] {
        let mut rng = SplitMix(seed);
        let s = stats(&grid(1, 1, 1, GREY, |_, _| c + rng.noise(sigma)), 0, 1);
        let n = profiled_pixels(&s);
        assert_count_near_area(
            "profiled pixels",
            n,
            PI * INNER_R * INNER_R,
            2.0 * PI * INNER_R,
        );
        let expected = sigma / (n as f64).sqrt();
        assert!(
            (s.standard_error / expected - 1.0).abs() <= 0.2,
            "seed {seed}: standard error {} vs σ/√N = {expected} (N = {n})",
            s.standard_error
        );
        // And the mean is c within four of its own standard errors (over the whole disc).
        assert!(
            (s.mean - c).abs() <= 4.0 * sigma / (PI * R * R).sqrt(),
            "seed {seed}: mean {}",
            s.mean
        );
    }
}

/// Noise on a shaded sphere (value μ + noise): the ring split keeps the shading out of the
/// noise estimate, up to the spread of μ within a ring (≤ 0.1 wide, variance ≲ 0.1²/12).
#[test]
fn standard_error_of_noise_on_shading() {
    let sigma = 0.05;
    let mut rng = SplitMix(7);
    let s = stats(&grid(1, 1, 1, GREY, |_, mu| mu + rng.noise(sigma)), 0, 1);
    let n = profiled_pixels(&s) as f64;
    let within_ring = 0.1f64.powi(2) / 12.0;
    let (low, high) = (
        sigma / n.sqrt(),
        (sigma * sigma + within_ring).sqrt() / n.sqrt(),
    );
    assert!(
        (0.8 * low..=1.2 * high).contains(&s.standard_error),
        "standard error {} not in [{low}, {high}] ± 20 %",
        s.standard_error
    );
}

#[test]
fn cells_are_indexed_row_major_from_the_top() {
    // Two columns, one row.
    let constants = [0.25, 0.625];
    let img = grid(2, 1, 1, TINTED, |i, _| constants[i]);
    for (i, &c) in constants.iter().enumerate() {
        let s = stats(&img, i, 2);
        assert_eq!((s.mean, s.center), (c, c), "cell {i} of 2 × 1");
    }

    // Three columns, two rows: index = row · 3 + column, row 0 the top CELL pixel rows.
    let constant = |i: usize| 0.125 * (i + 1) as f64;
    let img = grid(3, 2, 4, GREY, |i, _| constant(i));
    // The builder puts cell 3 (column 0, row 1) in the second band of CELL pixel rows.
    let centre_of_cell_3 = (CELL + CELL / 2) * img.width + CELL / 2;
    assert_eq!(img.pixels[centre_of_cell_3][0] as f64, constant(3));
    let first = stats(&img, 0, 3);
    for i in 0..6 {
        let s = stats(&img, i, 3);
        let c = constant(i);
        assert!(
            (s.mean - c).abs() <= 1e-12,
            "cell {i} of 3 × 2: mean {}",
            s.mean
        );
        assert_eq!(s.center, c, "cell {i} of 3 × 2");
        // Every cell sees the same disc, and nothing of its neighbours.
        assert_eq!(s.coverage, first.coverage, "cell {i} of 3 × 2");
        assert_eq!(profiled_pixels(&s), profiled_pixels(&first), "cell {i}");
    }
}

/// The rim is the grazing views, μ < 0.3: for a disc holding μ, the mean of μ over that
/// ring with density 2μ, ∫₀^0.3 2μ² dμ / ∫₀^0.3 2μ dμ = 0.2 (the ring is about 1.3 px wide
/// at this size, so the lattice moves it by a few hundredths; measured below 0.01 at 4×4
/// samples).
#[test]
fn rim_of_mu_is_a_fifth() {
    let s = stats(&grid(1, 1, 4, TINTED, |_, mu| mu), 0, 1);
    assert!((s.rim - 0.2).abs() < 0.02, "rim {}", s.rim);
    assert!((s.opacity - 1.0).abs() < 0.01, "opacity {}", s.opacity);
}

/// A sphere the world is half seen through (alpha 0.5, premultiplied RGB of a 0.4
/// surface) shows 0.5 · 0.4 + 0.5 · 1 = 0.7 everywhere: in its mean as seen, its rings and
/// its rim; its opacity is 0.5. One the world is wholly seen through shows the world, 1.
#[test]
fn a_half_transparent_sphere_shows_the_world_through_it() {
    for (alpha, seen) in [(0.5f32, 0.7), (0.0, 1.0)] {
        let mut img = grid(1, 1, 4, GREY, |_, _| 0.4);
        for p in &mut img.pixels {
            *p = [p[0] * alpha, p[1] * alpha, p[2] * alpha, p[3] * alpha];
        }
        let s = stats(&img, 0, 1);
        assert!(
            (s.opacity - f64::from(alpha)).abs() < 0.01,
            "opacity {}",
            s.opacity
        );
        assert!(
            (s.seen() - seen).abs() < 0.005,
            "alpha {alpha}: seen {}",
            s.seen()
        );
        assert!((s.rim - seen).abs() < 0.02, "alpha {alpha}: rim {}", s.rim);
        for ring in s.rings.iter().filter(|r| r.pixels > 0) {
            assert!(
                (ring.mean - seen).abs() < 1e-4,
                "alpha {alpha}: ring {}",
                ring.mean
            );
        }
    }
}
