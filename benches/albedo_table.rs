//! A 64 × 64 (μ, r) table of E for GGX at the default quadrature: time (criterion) and the
//! measured error against a much finer quadrature (printed once before timing).
//! Goal: ≤ 0.2 s on the 2-core machine with max |error| ≤ 2e-4.

use criterion::{Criterion, criterion_group, criterion_main};
use gloffuse::microfacet::{AlbedoIntegrator, Distribution, Glossy, Masking, Quadrature};
use std::hint::black_box;

fn grid() -> (Vec<f64>, Vec<f64>) {
    let mus = (0..64).map(|i| (i as f64 + 0.5) / 64.0).collect();
    let rs = (0..64).map(|j| j as f64 / 63.0).collect();
    (mus, rs)
}

fn table(c: &mut Criterion) {
    let (mus, rs) = grid();
    let q = AlbedoIntegrator::default();
    let fine = AlbedoIntegrator::new(Quadrature {
        theta: 64,
        phi: 24,
        mu: 64,
    });
    for d in Distribution::ALL {
        let make = |r: f64| Glossy {
            distribution: d,
            masking: Masking::HeightCorrelated,
            alpha: r * r,
        };
        let t = std::time::Instant::now();
        let fast = q.table(make, &mus, &rs);
        let elapsed = t.elapsed();
        let reference = fine.table(make, &mus, &rs);
        let err = fast
            .iter()
            .zip(&reference)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        println!(
            "{d}: 64x64 table in {:.3} s on {} threads, max |error| vs 64x24 quadrature = {err:.2e}",
            elapsed.as_secs_f64(),
            rayon::current_num_threads()
        );
    }
    let make = |r: f64| Glossy {
        distribution: Distribution::Ggx,
        masking: Masking::HeightCorrelated,
        alpha: r * r,
    };
    let mut group = c.benchmark_group("albedo");
    group.sample_size(20);
    group.bench_function("ggx_table_64x64", |b| {
        b.iter(|| black_box(q.table(make, &mus, &rs)))
    });
    group.finish();
}

criterion_group! {
    name = benches;
    // No HTML plots: they need system fonts, which a headless CI machine may not have.
    config = Criterion::default().without_plots();
    targets = table
}
criterion_main!(benches);
