//! How the coat albedo A(μ, r, η) should travel into Blender: the worst absolute error of
//! A over η ∈ [1, 3] (33 indices), r ∈ {0.05, …, 1} and μ ∈ {0.05, …, 1}, all three
//! distributions (height-correlated masking), for
//! - an atlas of K slices, linear between neighbouring slices, spaced evenly in F0, √F0 or
//!   F0^¼;
//! - the split-sum form with Schlick's Fresnel, `E_F ≈ F0 scale + bias` (the classic
//!   real-time approximation), compensated like the exact coat.
//!
//! Run: `cargo run --release --example coat_table_error`

#[path = "shared/xorshift.rs"]
mod xorshift;

use gloffuse::measure::coat::{coat_albedo, fresnel_average};
use gloffuse::measure::fresnel;
use gloffuse::measure::{AlbedoIntegrator, Distribution, Glossy, Masking, Roughness};
use rayon::prelude::*;

const IOR_MAX: f64 = 3.0;

fn main() {
    let q = AlbedoIntegrator::default();
    let tests: Vec<f64> = (0..33)
        .map(|i| 1.0 + (IOR_MAX - 1.0) * i as f64 / 32.0)
        .collect();
    let roughness: Vec<f64> = (1..=20).map(|i| i as f64 / 20.0).collect();
    let mus: Vec<f64> = (1..=20).map(|i| i as f64 / 20.0).collect();
    let f0_max = fresnel::f0(IOR_MAX);
    // Slices even in F0^p: p = 1 (F0), ½ ((η − 1)/(η + 1)), ¼ (Cycles' own table axis).
    let schemes: Vec<(String, f64, Vec<f64>)> = [6usize, 8, 12, 16]
        .iter()
        .flat_map(|&k| {
            [(1.0, "F0"), (0.5, "√F0"), (0.25, "F0^¼")].map(|(p, name)| {
                let slices = (0..k)
                    .map(|i| {
                        let x = i as f64 / (k - 1) as f64;
                        fresnel::ior_from_f0(f0_max * x.powf(1.0 / p))
                    })
                    .collect();
                (format!("{k} slices even in {name}"), p, slices)
            })
        })
        .collect();
    println!("{:<28} {:>12} {:>12}", "encoding", "max |ΔA|", "max |ΔA|/A");
    let mut worst = vec![(0.0f64, 0.0f64); schemes.len() + 2];
    for d in Distribution::ALL {
        let cases: Vec<(f64, f64)> = roughness
            .iter()
            .flat_map(|&r| mus.iter().map(move |&m| (r, m)))
            .collect();
        let results: Vec<Vec<(f64, f64)>> = cases
            .par_iter()
            .map(|&(r, mu)| {
                let g = Glossy::new(d, Masking::HeightCorrelated, Roughness::new(r).unwrap());
                let e_avg = q.average_albedo(&g);
                let a = |eta: f64| {
                    let (e_f, e) = q.fresnel_albedo(&g, mu, eta);
                    coat_albedo(e_f, e, fresnel_average(eta), e_avg)
                };
                let exact: Vec<f64> = tests.iter().map(|&eta| a(eta)).collect();
                let mut errors = Vec::new();
                for (_, p, slices) in &schemes {
                    let values: Vec<f64> = slices.iter().map(|&eta| a(eta)).collect();
                    let key = |eta: f64| fresnel::f0(eta).powf(*p);
                    let keys: Vec<f64> = slices.iter().map(|&eta| key(eta)).collect();
                    let mut worst: (f64, f64) = (0.0, 0.0);
                    for (&eta, &want) in tests.iter().zip(&exact) {
                        let x = key(eta);
                        let i = keys.partition_point(|&k| k <= x).clamp(1, keys.len() - 1);
                        let t = (x - keys[i - 1]) / (keys[i] - keys[i - 1]);
                        let got = values[i - 1] + t * (values[i] - values[i - 1]);
                        let err = (got - want).abs();
                        worst = (
                            worst.0.max(err),
                            worst.1.max(if want > 1e-4 { err / want } else { 0.0 }),
                        );
                    }
                    errors.push(worst);
                }
                // Split-sum with Schlick: E_F ≈ F0 s + b.
                let [s, b, e] = q.directional_moments(&g, mu, &|c| {
                    let k = (1.0 - c).powi(5);
                    [1.0 - k, k, 1.0]
                });
                // Over every index, and over the indices of real coats (1.3 to 2.5).
                let mut w = [(0.0f64, 0.0f64); 2];
                for (&eta, &want) in tests.iter().zip(&exact) {
                    let got = coat_albedo(fresnel::f0(eta) * s + b, e, fresnel_average(eta), e_avg);
                    let err = (got - want).abs();
                    let rel = if want > 1e-4 { err / want } else { 0.0 };
                    for (slot, counts) in w.iter_mut().zip([true, (1.3..=2.5).contains(&eta)]) {
                        if counts {
                            *slot = (slot.0.max(err), slot.1.max(rel));
                        }
                    }
                }
                errors.extend(w);
                errors
            })
            .collect();
        for errors in results {
            for (slot, e) in worst.iter_mut().zip(errors) {
                *slot = (slot.0.max(e.0), slot.1.max(e.1));
            }
        }
    }
    for ((name, _, _), (abs, rel)) in schemes.iter().zip(&worst) {
        println!("{name:<28} {abs:>12.2e} {:>11.2}%", 100.0 * rel);
    }
    for (k, name) in ["split-sum, Schlick F0", "  the same, IOR 1.3 to 2.5"]
        .iter()
        .enumerate()
    {
        let (abs, rel) = worst[schemes.len() + k];
        println!("{name:<28} {abs:>12.2e} {:>11.2}%", 100.0 * rel);
    }
    atlas_as_packed();
}

/// The atlas as `generate` packs it (`coat::SLICES` slices, `ATLAS` × `ATLAS` per slice,
/// grid points at i/(n − 1)), read as the layered group reads it: bilinear in (r, μ), linear between
/// slices in z = F0^¼. Worst |ΔA| at 2000 pseudo-random (μ, r, η), μ ≥ 0.05.
fn atlas_as_packed() {
    use gloffuse::measure::coat::{SLICES, slice_coordinate};
    const ATLAS: usize = 64;
    let q = AlbedoIntegrator::default();
    let axis: Vec<Roughness> = Roughness::grid(ATLAS);
    let mus: Vec<f64> = axis.iter().map(|m| m.get().max(1e-3)).collect();
    let z_max = slice_coordinate(IOR_MAX);
    for d in Distribution::ALL {
        let grid = q.coat_grid(d, Masking::HeightCorrelated, &axis, &mus, &|| {});
        let lerp = |a: f64, b: f64, t: f64| a + t * (b - a);
        let sample = |k: usize, mu: f64, r: f64| {
            let (x, y) = (r * (ATLAS - 1) as f64, mu * (ATLAS - 1) as f64);
            let (j, i) = ((x as usize).min(ATLAS - 2), (y as usize).min(ATLAS - 2));
            let (tx, ty) = (x - j as f64, y - i as f64);
            lerp(
                lerp(grid.a(k, i, j), grid.a(k, i, j + 1), tx),
                lerp(grid.a(k, i + 1, j), grid.a(k, i + 1, j + 1), tx),
                ty,
            )
        };
        let mut next = xorshift::uniform();
        let points: Vec<(f64, f64, f64)> = (0..2000)
            .map(|_| (0.05 + 0.95 * next(), next(), 1.0 + 2.0 * next()))
            .collect();
        let worst = points
            .par_iter()
            .map(|&(mu, r, eta)| {
                let s = slice_coordinate(eta) / z_max * (SLICES - 1) as f64;
                let k = (s as usize).min(SLICES - 2);
                let got = lerp(sample(k, mu, r), sample(k + 1, mu, r), s - k as f64);
                let g = Glossy::new(d, Masking::HeightCorrelated, Roughness::new(r).unwrap());
                (got - q.coat(&g, mu, eta)).abs()
            })
            .reduce(|| 0.0, f64::max);
        println!("atlas {ATLAS}×{ATLAS}×{SLICES}, {d:<18} max |ΔA| {worst:.2e}");
    }
}
