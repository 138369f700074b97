//! What a renderer misses reading `gloffuse lut --kind anisotropic`: random anisotropic lobes
//! as Blender's Glossy node makes them (roughness 0.1–1, anisotropy −0.9–0.9, view cosine
//! 0.1–1, any azimuth), looked up the way the table's layout asks (bilinear inside a slice,
//! linear between the two nearest azimuth columns and bitangent rows, from the f32 texels),
//! against the integrator at that exact view. Run:
//! `cargo run --release --example anisotropic_table_error [SIZE]`

use gloffuse::lut::anisotropic::{AZIMUTHS, anisotropic_table};
use gloffuse::measure::anisotropic::view;
use gloffuse::measure::{
    AnisotropicIntegrator, AnisotropicLobe, Anisotropy, Distribution, Masking, Roughness,
};
use gloffuse::progress::Quiet;
use std::f64::consts::FRAC_PI_2;

fn main() {
    let n: usize = std::env::args().nth(1).map_or(16, |s| {
        s.parse().expect("SIZE is a whole number from 2 to 32")
    });
    let exact = AnisotropicIntegrator::default();
    for d in [Distribution::Ggx, Distribution::Beckmann] {
        let table = anisotropic_table(n, d, Masking::HeightCorrelated, &Quiet);
        // A grid axis over [0, 1] with `count` points: the cell and the fraction across it.
        let cell = |x: f64, count: usize| {
            let s = x.clamp(0.0, 1.0) * (count - 1) as f64;
            let k = (s.floor() as usize).min(count - 2);
            (k, s - k as f64)
        };
        let texel =
            |i: usize, k: usize, j: usize, l: usize| f64::from(table.get(k * n + j, l * n + i, 0));
        let mut state = 0x9e37_79b9_7f4a_7c15_u64;
        let mut uniform = move || {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let (mut worst, mut worst_above, mut sum, mut at) = (0.0f64, 0.0f64, 0.0, String::new());
        let samples = 2000;
        for _ in 0..samples {
            let r = 0.1 + 0.9 * uniform();
            let a = -0.9 + 1.8 * uniform();
            let mu = 0.1 + 0.9 * uniform();
            let phi = FRAC_PI_2 * uniform();
            let lobe = AnisotropicLobe::from_glossy_node(
                d,
                Masking::HeightCorrelated,
                Roughness::new(r).expect("in [0, 1]"),
                Anisotropy::new(a).expect("finite"),
            )
            .expect("GGX or Beckmann");
            let e = exact.directional_albedo(&lobe, view(mu, phi));
            let (i, fi) = cell(mu, n);
            let (k, fk) = cell(phi / FRAC_PI_2, AZIMUTHS);
            let (j, fj) = cell(lobe.alpha_x.sqrt(), n);
            let (l, fl) = cell(lobe.alpha_y.sqrt(), n);
            let mut found = 0.0;
            for (di, wi) in [(0, 1.0 - fi), (1, fi)] {
                for (dk, wk) in [(0, 1.0 - fk), (1, fk)] {
                    for (dj, wj) in [(0, 1.0 - fj), (1, fj)] {
                        for (dl, wl) in [(0, 1.0 - fl), (1, fl)] {
                            found += wi * wk * wj * wl * texel(i + di, k + dk, j + dj, l + dl);
                        }
                    }
                }
            }
            let relative = (found / e - 1.0).abs();
            sum += relative;
            if mu >= 0.3 {
                worst_above = worst_above.max(relative);
            }
            if relative > worst {
                worst = relative;
                at = format!("r {r:.2}, anisotropy {a:.2}, N·V {mu:.2}, φ {phi:.2}");
            }
        }
        println!(
            "{d}, size {n}, {AZIMUTHS} azimuths: worst {:.2} % (at {at}); worst for N·V ≥ 0.3 {:.2} %; mean {:.3} %",
            100.0 * worst,
            100.0 * worst_above,
            100.0 * sum / samples as f64
        );
    }
}
