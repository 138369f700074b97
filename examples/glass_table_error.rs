//! What the glass groups miss by reading E(μ, r, η) from their packed tables as
//! `glass_groups.py` does: bilinear in (r, μ) on 16 × 16 grid points, linear between the 12
//! index slices in z = F0^¼, and in 3.0–3.4's two-closure form `E = F(μ) R + max(1e-4,
//! 1 − F(μ)) T` with F exact (the group's Fresnel node) and T leaving read over the cosine
//! above the critical one (`above_critical_coordinate`). Against the integrator, at 4,000
//! pseudo-random points per distribution and form: μ in [0.1, 1], r in [0.1, 1], IOR in
//! [1.1, 2.5], entering and leaving.
//!
//! Run: `cargo run --release --example glass_table_error`

#[path = "shared/xorshift.rs"]
mod xorshift;

use gloffuse::generate::params::GlassTable;
use gloffuse::measure::coat::slice_coordinate;
use gloffuse::measure::{
    BlenderVersion, Dielectric, DielectricIntegrator, DielectricNode, Distribution, Masking,
    Roughness, above_critical_coordinate, fresnel,
};
use rayon::prelude::*;

fn main() {
    let q = DielectricIntegrator::default();
    println!(
        "{:<30} {:>9} {:>16} {:>16} {:>12}",
        "glass (Blender)", "mean", "worst, r ≥ 0.3", "worst, μ ≥ 0.3", "worst"
    );
    for (masking, version) in [
        (Masking::Separable, "3.4"),
        (Masking::HeightCorrelated, "4.5"),
    ] {
        let version: BlenderVersion = version.parse().unwrap();
        for d in [Distribution::Ggx, Distribution::Beckmann] {
            let table = GlassTable::compute(d, masking);
            let n = table.size;
            let z_max = table.z_max;
            let lerp = |a: f64, b: f64, t: f64| a + t * (b - a);
            // Slice k of a packed array at (μ, r), bilinear between grid points.
            let sample = |values: &[f32], k: usize, mu: f64, r: f64| {
                let at = |i: usize, j: usize| values[(i * table.slices + k) * n + j] as f64;
                let (x, y) = (r * (n - 1) as f64, mu * (n - 1) as f64);
                let (j, i) = ((x as usize).min(n - 2), (y as usize).min(n - 2));
                let (tx, ty) = (x - j as f64, y - i as f64);
                lerp(
                    lerp(at(i, j), at(i, j + 1), tx),
                    lerp(at(i + 1, j), at(i + 1, j + 1), tx),
                    ty,
                )
            };
            let read = |values: &[f32], mu: f64, r: f64, ior: f64| {
                let s = slice_coordinate(ior) / z_max * (table.slices - 1) as f64;
                let k = (s as usize).min(table.slices - 2);
                lerp(
                    sample(values, k, mu, r),
                    sample(values, k + 1, mu, r),
                    s - k as f64,
                )
            };
            let mut next = xorshift::uniform();
            let points: Vec<(f64, f64, f64, bool)> = (0..4000)
                .map(|_| {
                    (
                        0.1 + 0.9 * next(),
                        0.1 + 0.9 * next(),
                        1.1 + 1.4 * next(),
                        next() < 0.5,
                    )
                })
                .collect();
            let errors: Vec<(f64, f64, f64)> = points
                .par_iter()
                .map(|&(mu, r, ior, leaving)| {
                    let eta = if leaving { 1.0 / ior } else { ior };
                    let (glass, refraction) = if leaving {
                        (&table.glass_leaving, &table.refraction_leaving)
                    } else {
                        (&table.glass_entering, &table.refraction_entering)
                    };
                    let got = match (glass, &table.reflection) {
                        (Some(glass), _) => read(glass, mu, r, ior),
                        (None, Some(reflection)) => {
                            let f = fresnel::dielectric(mu, eta);
                            let t = match &table.refraction_above_critical {
                                Some(above) if leaving => {
                                    read(above, above_critical_coordinate(mu, ior), r, ior)
                                }
                                _ => read(refraction, mu, r, ior),
                            };
                            f * read(reflection, mu, r, ior) + (1.0 - f).max(1e-4) * t
                        }
                        (None, None) => unreachable!("a glass table has one form"),
                    };
                    let bsdf = Dielectric::new(
                        DielectricNode::Glass,
                        d,
                        Roughness::new(r).unwrap(),
                        version,
                    );
                    let want = q.directional_albedo(&bsdf, mu, eta);
                    ((got / want - 1.0).abs(), mu, r)
                })
                .collect();
            let mean = errors.iter().map(|e| e.0).sum::<f64>() / errors.len() as f64;
            let worst = |keep: &dyn Fn(&(f64, f64, f64)) -> bool| {
                errors
                    .iter()
                    .filter(|e| keep(e))
                    .map(|e| e.0)
                    .fold(0.0, f64::max)
            };
            println!(
                "{:<30} {:>8.3}% {:>15.2}% {:>15.2}% {:>11.2}%",
                format!("{} ({}, {})", d.label(), table.form, masking),
                100.0 * mean,
                100.0 * worst(&|e| e.2 >= 0.3),
                100.0 * worst(&|e| e.1 >= 0.3),
                100.0 * worst(&|_| true)
            );
        }
    }
}
