//! A 64 × 64 (μ, r) table of E for GGX at the default quadrature: time (criterion) and the
//! measured error against a much finer quadrature (printed once before timing).
//! Goal: ≤ 0.2 s on the 2-core machine with max |error| ≤ 2e-4.

use criterion::{Criterion, criterion_group, criterion_main};
use gloffuse::measure::{AlbedoIntegrator, Distribution, Masking, Quadrature, Roughness};
use std::hint::black_box;

fn grid() -> (Vec<f64>, Vec<Roughness>) {
    let mus = (0..64).map(|i| (i as f64 + 0.5) / 64.0).collect();
    (mus, Roughness::grid(64))
}

fn table(c: &mut Criterion) {
    let (mus, rs) = grid();
    let q = AlbedoIntegrator::default();
    let fine = AlbedoIntegrator::new(Quadrature {
        theta: 64,
        phi: 24,
        mu: 64,
    });
    let masking = Masking::HeightCorrelated;
    for d in Distribution::ALL {
        let t = std::time::Instant::now();
        let fast = q.grid(d, masking, &rs, &mus, &|| {});
        let elapsed = t.elapsed();
        let reference = fine.grid(d, masking, &rs, &mus, &|| {});
        let err = fast
            .e
            .iter()
            .zip(&reference.e)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        println!(
            "{d}: 64x64 table (with E_avg) in {:.3} s on {} threads, max |error| vs 64x24 quadrature = {err:.2e}",
            elapsed.as_secs_f64(),
            rayon::current_num_threads()
        );
    }
    let mut group = c.benchmark_group("albedo");
    group.sample_size(20);
    group.bench_function("ggx_table_64x64", |b| {
        b.iter(|| black_box(q.grid(Distribution::Ggx, masking, &rs, &mus, &|| {})))
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
