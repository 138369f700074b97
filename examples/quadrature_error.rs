//! Measures the integrator's error against a brute-force midpoint reference for several
//! quadrature sizes: the numbers behind `Quadrature::default()`.
//! Run: `cargo run --release --example quadrature_error`

// The shared test oracles; this example uses the isotropic one only.
#[path = "../tests/common/oracle.rs"]
#[allow(dead_code)]
mod oracle;

use gloffuse::measure::{AlbedoIntegrator, Distribution, Glossy, Masking, Quadrature, Roughness};
use rayon::prelude::*;

fn main() {
    let mus = [0.02, 0.05, 0.1, 0.2, 0.4, 0.7, 1.0];
    let rs = [0.03, 0.1, 0.2, 0.35, 0.5, 0.7, 0.85, 1.0];
    let mut cases = Vec::new();
    for d in Distribution::ALL {
        for m in [Masking::Separable, Masking::HeightCorrelated] {
            for &r in &rs {
                for &mu in &mus {
                    cases.push((Glossy::new(d, m, Roughness::new(r).unwrap()), mu));
                }
            }
        }
    }
    let reference: Vec<f64> = cases
        .par_iter()
        .map(|(g, mu)| oracle::brute_force_albedo(g, *mu, 3000, 3000))
        .collect();
    for (theta, phi) in [
        (12, 6),
        (16, 8),
        (20, 8),
        (24, 8),
        (24, 12),
        (32, 8),
        (32, 16),
        (48, 16),
    ] {
        let q = AlbedoIntegrator::new(Quadrature { theta, phi, mu: 24 });
        let mut worst = (0.0, String::new());
        for ((g, mu), r) in cases.iter().zip(&reference) {
            let e = (q.directional_albedo(g, *mu) - r).abs();
            if e > worst.0 {
                worst = (
                    e,
                    format!(
                        "{} {} alpha={:.4} mu={mu}",
                        g.distribution(),
                        g.masking,
                        g.microfacet.alpha
                    ),
                );
            }
        }
        println!(
            "theta={theta:3} phi={phi:3}: max |error| = {:.2e} at {}",
            worst.0, worst.1
        );
    }
}
