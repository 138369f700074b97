//! What the glass groups miss by reading E(μ, r, η) from their packed tables as
//! `glass_groups.py` does: bilinear in (r, t = √μ) on 16 × 16 grid points, linear between
//! the 12 index slices in z = F0^¼, and in 3.0–3.4's two-closure Glass `E = F(μ) R +
//! max(1e-4, 1 − F(μ)) T` with F exact (the group's Fresnel node) and T leaving read over the
//! cosine above the critical one (`above_critical_coordinate`). Against the integrator, at
//! 4,000 pseudo-random points per node, distribution and form: μ in [0, 1] (the rim, μ <
//! 0.1, apart), r in [0.1, 1], IOR in [1.1, 2.5], entering and leaving. The Refraction
//! node's points count where it returns at least 5 % (leaving past the critical angle it
//! returns almost nothing, and a relative error there says nothing about a render).
//!
//! Run: `cargo run --release --example glass_table_error`

#[path = "shared/xorshift.rs"]
mod xorshift;

use gloffuse::generate::ColorModel;
use gloffuse::generate::tables::{GlassGroup, GlassTable};
use gloffuse::measure::coat::slice_coordinate;
use gloffuse::measure::{
    BlenderVersion, Dielectric, DielectricIntegrator, DielectricNode, Distribution, Masking,
    Roughness, critical_crowded_coordinate, fresnel, grazing_crowded_coordinate,
};
use rayon::prelude::*;

fn main() {
    let q = DielectricIntegrator::default();
    println!(
        "{:<36} {:>9} {:>16} {:>16} {:>16} {:>12}",
        "node (Blender)", "mean", "worst, r ≥ 0.3", "worst, μ ≥ 0.3", "rim, μ < 0.1", "worst"
    );
    for (masking, version) in [
        (Masking::Separable, "3.4"),
        (Masking::HeightCorrelated, "4.5"),
    ] {
        let version: BlenderVersion = version.parse().unwrap();
        for d in [Distribution::Ggx, Distribution::Beckmann] {
            let table = GlassTable::compute(d, masking, ColorModel::Exact);
            let n = table.size;
            let z_max = table.z_max;
            let lerp = |a: f64, b: f64, t: f64| a + t * (b - a);
            // Slice k of a packed array at (row coordinate, r), bilinear between grid points.
            let sample = |values: &[f32], k: usize, row: f64, r: f64| {
                let at = |i: usize, j: usize| values[(i * table.slices + k) * n + j] as f64;
                let (x, y) = (r * (n - 1) as f64, row * (n - 1) as f64);
                let (j, i) = ((x as usize).min(n - 2), (y as usize).min(n - 2));
                let (tx, ty) = (x - j as f64, y - i as f64);
                lerp(
                    lerp(at(i, j), at(i, j + 1), tx),
                    lerp(at(i + 1, j), at(i + 1, j + 1), tx),
                    ty,
                )
            };
            let read = |values: &[f32], row: f64, r: f64, ior: f64| {
                let s = slice_coordinate(ior) / z_max * (table.slices - 1) as f64;
                let k = (s as usize).min(table.slices - 2);
                lerp(
                    sample(values, k, row, r),
                    sample(values, k + 1, row, r),
                    s - k as f64,
                )
            };
            for node in [DielectricNode::Glass, DielectricNode::Refraction] {
                let label = format!("{:?} {} ({}, {})", node, d.label(), table.form, masking);
                if node == DielectricNode::Glass && table.glass_group == GlassGroup::Multiscatter {
                    println!("{label:<36} no table: Blender's own Multiscatter GGX glass");
                    continue;
                }
                let mut next = xorshift::uniform();
                let points: Vec<(f64, f64, f64, bool)> = (0..4000)
                    .map(|_| (next(), 0.1 + 0.9 * next(), 1.1 + 1.4 * next(), next() < 0.5))
                    .collect();
                let errors: Vec<(f64, f64, f64)> = points
                    .par_iter()
                    .filter_map(|&(mu, r, ior, leaving)| {
                        let eta = if leaving { 1.0 / ior } else { ior };
                        let row = grazing_crowded_coordinate(mu);
                        // The refraction lobe: leaving, over the cosine about the critical one.
                        let refraction = if leaving {
                            read(
                                &table.refraction_leaving,
                                critical_crowded_coordinate(mu, ior),
                                r,
                                ior,
                            )
                        } else {
                            read(&table.refraction_entering, row, r, ior)
                        };
                        let glass = if leaving {
                            &table.glass_leaving
                        } else {
                            &table.glass_entering
                        };
                        let got = match (node, glass, &table.reflection) {
                            (DielectricNode::Refraction, _, _) => refraction,
                            (_, Some(glass), _) => read(glass, row, r, ior),
                            (_, None, Some(reflection)) => {
                                let f = fresnel::dielectric(mu, eta);
                                f * read(reflection, row, r, ior) + (1.0 - f).max(1e-4) * refraction
                            }
                            (_, None, None) => unreachable!("a glass table has one form"),
                        };
                        let bsdf = Dielectric::new(node, d, Roughness::new(r).unwrap(), version);
                        let want = q.directional_albedo(&bsdf, mu, eta);
                        (want >= 0.05).then(|| ((got / want - 1.0).abs(), mu, r))
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
                    "{:<36} {:>8.3}% {:>15.2}% {:>15.2}% {:>15.2}% {:>11.2}%",
                    label,
                    100.0 * mean,
                    100.0 * worst(&|e| e.2 >= 0.3),
                    100.0 * worst(&|e| e.1 >= 0.3),
                    100.0 * worst(&|e| e.1 < 0.1),
                    100.0 * worst(&|_| true)
                );
            }
        }
    }
}
