//! The 512 × 512 split-sum LUT at its default 2048 visible-normal samples: time (criterion)
//! and the measured max |error| against converged references, printed once before timing:
//!
//! * the same estimator with 16× the samples, over every texel;
//! * plain f64, sample by sample, with 64× the samples, on a subset of texels (every 16th
//!   texel, plus every 4th texel of the three most grazing rows);
//! * for height-correlated G, `scale + bias` against the Cycles-exact albedo quadrature
//!   (`AlbedoIntegrator`, fine rules), which shares no code with the LUT.
//!
//! Goal: ≤ 0.5 s on the 2-core machine with max |error| ≤ 1e-3.
//! Also printed: fewer samples, the classic estimator at 1024 samples (the textbook recipe
//! verbatim), and the 64 × 64 Kulla–Conty GGX table.

use criterion::{Criterion, criterion_group, criterion_main};
use gloffuse::lut::split_sum::{split_sum, split_sum_texel_f64};
use gloffuse::lut::{GModel, Sampling, kulla_conty};
use gloffuse::measure::{AlbedoIntegrator, Distribution, Glossy, Masking, Quadrature, Roughness};
use gloffuse::progress::Quiet;
use rayon::prelude::*;
use std::hint::black_box;
use std::time::Instant;

const SIZE: usize = 512;
const SAMPLES: u32 = 2048;
const VN: Sampling = Sampling::VisibleNormals;

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
        .step_by(16)
        .flat_map(|y| (0..SIZE).step_by(16).map(move |x| (x + 7, y + 7)))
        .collect();
    texels.extend((0..3).flat_map(|y| (0..SIZE).step_by(4).map(move |x| (x + 1, y))));
    texels
}

fn report(g_model: GModel) {
    let t = Instant::now();
    let table = split_sum(SIZE, SAMPLES, g_model, VN, &Quiet);
    let elapsed = t.elapsed().as_secs_f64();
    let reference = split_sum(SIZE, 16 * SAMPLES, g_model, VN, &Quiet);
    let (err, x, y) = max_error(&table, &reference);
    println!(
        "split-sum {g_model:?} {SIZE}x{SIZE}, {SAMPLES} visible-normal samples: {elapsed:.3} s \
         (first run) on {} threads",
        rayon::current_num_threads()
    );
    println!("  max |error| vs 16x samples, all texels: {err:.2e} at (x, y) = ({x}, {y})");

    let texels = subset();
    let f64_err = texels
        .par_iter()
        .map(|&(x, y)| {
            let (s, b) = split_sum_texel_f64(coord(x), coord(y), 64 * SAMPLES, g_model, VN);
            let i = (y * SIZE + x) * 2;
            (f64::from(table[i]) - s)
                .abs()
                .max((f64::from(table[i + 1]) - b).abs())
        })
        .reduce(|| 0.0, f64::max);
    println!(
        "  max |error| vs plain f64 with 64x samples, {} texels: {f64_err:.2e}",
        texels.len()
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

    for (samples, sampling) in [
        (1024, VN),
        (1536, VN),
        (1024, Sampling::Classic),
        (SAMPLES, Sampling::Classic),
    ] {
        let t = Instant::now();
        let other = split_sum(SIZE, samples, g_model, sampling, &Quiet);
        let elapsed = t.elapsed().as_secs_f64();
        let (err, x, y) = max_error(&other, &reference);
        println!(
            "  {sampling:?} {samples} samples: {elapsed:.3} s, max |error| = {err:.2e} at ({x}, {y})"
        );
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
    group.bench_function("split_sum_512x512_2048_ue4", |b| {
        b.iter(|| black_box(split_sum(SIZE, SAMPLES, GModel::Ue4, VN, &Quiet)))
    });
    group.bench_function("split_sum_512x512_2048_height_correlated", |b| {
        b.iter(|| {
            black_box(split_sum(
                SIZE,
                SAMPLES,
                GModel::HeightCorrelated,
                VN,
                &Quiet,
            ))
        })
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
