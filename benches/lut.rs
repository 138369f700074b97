//! The 512 × 512 split-sum LUT by its default quadrature: time (criterion) and the measured
//! max |error| against converged references, printed once before timing:
//!
//! * the same quadrature with a fine rule (64 nodes per piece), over every texel;
//! * the fine rule in plain f64 on a subset of texels (every 8th texel, every other texel of
//!   the three most grazing rows and of the two smoothest columns), itself checked against
//!   the plain-f64 visible-normal estimator with 2²⁰ samples (it shares only the masking
//!   formula) on every 8th
//!   texel of that subset;
//! * for height-correlated G, `scale + bias` against the Cycles-exact albedo quadrature
//!   (`AlbedoIntegrator`, fine rules), which shares no code with the LUT.
//!
//! Goal: ≤ 1 s on the 2-core machine with max |error| ≤ 5e-5.
//! Also printed, for the time–error frontier: other rule sizes, the classic estimator at
//! 1024 and 2048 samples (the textbook recipe verbatim), and the 64 × 64 Kulla–Conty GGX
//! table.

use criterion::{Criterion, criterion_group, criterion_main};
use gloffuse::lut::split_sum::{
    Estimate, Rule, Sampler, split_sum, split_sum_texel_quadrature, split_sum_texel_sampled,
};
use gloffuse::lut::{GModel, kulla_conty};
use gloffuse::measure::{AlbedoIntegrator, Distribution, Glossy, Masking, Quadrature, Roughness};
use gloffuse::progress::Quiet;
use rayon::prelude::*;
use std::hint::black_box;
use std::time::Instant;

const SIZE: usize = 512;
const FINE: Rule = Rule {
    azimuth: 64,
    pole: 64,
    tail: 64,
};

fn coord(i: usize) -> f64 {
    (i as f64 + 0.5) / SIZE as f64
}

/// Max |a − b| over both channels, and the texel (x, y) where it occurs.
fn max_error(a: &[f32], b: &[f32]) -> (f64, usize, usize) {
    let (mut worst, mut at) = (0.0, 0);
    for (i, (x, y)) in a.iter().zip(b).enumerate() {
        let e = (f64::from(*x) - f64::from(*y)).abs();
        if e > worst {
            (worst, at) = (e, i / 2);
        }
    }
    (worst, at % SIZE, at / SIZE)
}

fn subset() -> Vec<(usize, usize)> {
    let mut texels: Vec<(usize, usize)> = (0..SIZE)
        .step_by(8)
        .flat_map(|y| (0..SIZE).step_by(8).map(move |x| (x + 3, y + 3)))
        .collect();
    texels.extend((0..3).flat_map(|y| (0..SIZE).step_by(2).map(move |x| (x + 1, y))));
    texels.extend((0..2).flat_map(|x| (0..SIZE).step_by(2).map(move |y| (x, y))));
    texels
}

/// Max over `texels` of |table − reference| (both channels), and where.
fn subset_error(
    table: &[f32],
    texels: &[(usize, usize)],
    reference: &[(f64, f64)],
) -> (f64, usize, usize) {
    texels
        .iter()
        .zip(reference)
        .map(|(&(x, y), &(s, b))| {
            let i = (y * SIZE + x) * 2;
            let e = (f64::from(table[i]) - s)
                .abs()
                .max((f64::from(table[i + 1]) - b).abs());
            (e, x, y)
        })
        .fold((0.0, 0, 0), |a, b| if b.0 > a.0 { b } else { a })
}

/// What `gloffuse lut --kind split-sum` computes.
fn default() -> Estimate {
    Estimate::Quadrature(Rule::default())
}

fn report(g_model: GModel) {
    let t = Instant::now();
    let table = split_sum(SIZE, g_model, default(), &Quiet);
    let elapsed = t.elapsed().as_secs_f64();
    println!(
        "split-sum {g_model:?} {SIZE}x{SIZE}, quadrature {:?}: {elapsed:.3} s (first run) \
         on {} threads",
        Rule::default(),
        rayon::current_num_threads()
    );
    let fine_table = split_sum(SIZE, g_model, Estimate::Quadrature(FINE), &Quiet);
    let (err, x, y) = max_error(&table, &fine_table);
    println!("  max |error| vs the fine rule, all texels: {err:.2e} at (x, y) = ({x}, {y})");

    let texels = subset();
    let reference: Vec<(f64, f64)> = texels
        .par_iter()
        .map(|&(x, y)| split_sum_texel_quadrature(coord(x), coord(y), g_model, FINE))
        .collect();
    let (err, x, y) = subset_error(&table, &texels, &reference);
    println!(
        "  max |error| vs the fine rule in plain f64, {} texels: {err:.2e} at ({x}, {y})",
        texels.len()
    );
    let checked: Vec<usize> = (0..texels.len()).step_by(8).collect();
    let sampled_err = checked
        .par_iter()
        .map(|&i| {
            let (x, y) = texels[i];
            let (s, b) = split_sum_texel_sampled(
                coord(x),
                coord(y),
                1 << 20,
                g_model,
                Sampler::VisibleNormals,
            );
            (s - reference[i].0).abs().max((b - reference[i].1).abs())
        })
        .reduce(|| 0.0, f64::max);
    println!(
        "  the f64 fine rule vs the f64 visible-normal estimator with 2^20 samples, {} texels: \
         {sampled_err:.2e}",
        checked.len()
    );

    if g_model == GModel::HeightCorrelated {
        let fine = AlbedoIntegrator::new(Quadrature {
            theta: 64,
            phi: 24,
            mu: 64,
        });
        let e_err = texels
            .par_iter()
            .map(|&(x, y)| {
                let glossy = Glossy::new(
                    Distribution::Ggx,
                    Masking::HeightCorrelated,
                    Roughness::new(coord(x)).unwrap(),
                );
                let e = fine.directional_albedo(&glossy, coord(y));
                let i = (y * SIZE + x) * 2;
                (f64::from(table[i]) + f64::from(table[i + 1]) - e).abs()
            })
            .reduce(|| 0.0, f64::max);
        println!(
            "  max |scale + bias − E(μ, r)| vs the albedo quadrature, {} texels: {e_err:.2e}",
            texels.len()
        );
    }

    let others = [
        Estimate::Quadrature(Rule {
            azimuth: 8,
            pole: 12,
            tail: 8,
        }),
        Estimate::Quadrature(Rule {
            azimuth: 12,
            pole: 16,
            tail: 12,
        }),
        Estimate::Quadrature(Rule {
            azimuth: 16,
            pole: 32,
            tail: 24,
        }),
        Estimate::Classic { samples: 1024 },
        Estimate::Classic { samples: 2048 },
    ];
    for estimate in others {
        let t = Instant::now();
        let other = split_sum(SIZE, g_model, estimate, &Quiet);
        let elapsed = t.elapsed().as_secs_f64();
        let (err, x, y) = subset_error(&other, &texels, &reference);
        println!("  {estimate:?}: {elapsed:.3} s, max |error| = {err:.2e} at ({x}, {y})");
    }
}

fn lut(c: &mut Criterion) {
    report(GModel::Ue4);
    report(GModel::HeightCorrelated);
    let t = Instant::now();
    let kc = kulla_conty::kulla_conty(
        64,
        4096,
        Distribution::Ggx,
        Masking::HeightCorrelated,
        &Quiet,
    );
    let energy =
        kc.e.iter()
            .zip(&kc.fms)
            .map(|(e, f)| (e + f - 1.0).abs())
            .fold(0.0, f64::max);
    println!(
        "kulla-conty GGX 64x64, 4096 samples: {:.3} s; max |E + ∫f_ms cos − 1| = {energy:.2e}",
        t.elapsed().as_secs_f64()
    );

    let mut group = c.benchmark_group("lut");
    group.sample_size(10);
    group.bench_function("split_sum_512x512_quadrature_ue4", |b| {
        b.iter(|| black_box(split_sum(SIZE, GModel::Ue4, default(), &Quiet)))
    });
    group.bench_function("split_sum_512x512_quadrature_height_correlated", |b| {
        b.iter(|| black_box(split_sum(SIZE, GModel::HeightCorrelated, default(), &Quiet)))
    });
    group.finish();
}

criterion_group! {
    name = benches;
    // No HTML plots: they need system fonts, which a headless CI machine may not have.
    config = Criterion::default().without_plots();
    targets = lut
}
criterion_main!(benches);
