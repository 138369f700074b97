//! How finely the E(μ, r) image must sample for `--mode view`: the worst relative error of
//! bilinear interpolation (what the groups compute from the cell's corners) at cell midpoints, for
//! μ ≥ 0.05 (a sphere's rim pixels below that are a sliver). Run:
//! `cargo run --release --example view_table_error`

use gloffuse::measure::{AlbedoIntegrator, Distribution, Glossy, Masking, Roughness};

fn main() {
    let q = AlbedoIntegrator::default();
    for n in [16usize, 32, 48, 64, 96, 128] {
        let mut worst = (0.0f64, String::new());
        for d in Distribution::ALL {
            let g = |r: f64| {
                Glossy::new(
                    d,
                    Masking::HeightCorrelated,
                    Roughness::new(r).expect("roughness in [0, 1]"),
                )
            };
            let grid: Vec<f64> = (0..n * n)
                .map(|k| {
                    let (i, j) = (k / n, k % n);
                    let mu = (i as f64 / (n - 1) as f64).max(1e-3);
                    q.directional_albedo(&g(j as f64 / (n - 1) as f64), mu)
                })
                .collect();
            for i in 0..n - 1 {
                for j in 0..n - 1 {
                    let (mu, r) = (
                        (i as f64 + 0.5) / (n - 1) as f64,
                        (j as f64 + 0.5) / (n - 1) as f64,
                    );
                    if mu < 0.05 {
                        continue;
                    }
                    let bilinear = 0.25
                        * (grid[i * n + j]
                            + grid[i * n + j + 1]
                            + grid[(i + 1) * n + j]
                            + grid[(i + 1) * n + j + 1]);
                    let exact = q.directional_albedo(&g(r), mu);
                    let e = (bilinear / exact - 1.0).abs();
                    if e > worst.0 {
                        worst = (e, format!("{d} r={r:.3} mu={mu:.3}"));
                    }
                }
            }
        }
        println!(
            "{n:4} x {n:<4}: worst relative error {:.3} % at {}",
            100.0 * worst.0,
            worst.1
        );
    }
    // The alternative: E as a bivariate polynomial of total degree k in (r, μ), least squares
    // on a 41 × 41 grid (μ ≥ 0.05), one Multiply-Add node per coefficient.
    for k in [4usize, 6, 8, 10] {
        let powers: Vec<(i32, i32)> = (0..=k as i32)
            .flat_map(|a| (0..=k as i32 - a).map(move |b| (a, b)))
            .collect();
        let mut worst = (0.0f64, String::new());
        for d in Distribution::ALL {
            let g = |r: f64| {
                Glossy::new(
                    d,
                    Masking::HeightCorrelated,
                    Roughness::new(r).expect("roughness in [0, 1]"),
                )
            };
            let pts: Vec<(f64, f64, f64)> = (0..41 * 41)
                .map(|k| {
                    let (i, j) = (k / 41, k % 41);
                    let mu = 0.05 + 0.95 * i as f64 / 40.0;
                    let r = j as f64 / 40.0;
                    (r, mu, q.directional_albedo(&g(r), mu))
                })
                .collect();
            let a = nalgebra::DMatrix::from_fn(pts.len(), powers.len(), |i, j| {
                pts[i].0.powi(powers[j].0) * pts[i].1.powi(powers[j].1) / pts[i].2
            });
            let b = nalgebra::DVector::from_element(pts.len(), 1.0);
            let c = a.clone().svd(true, true).solve(&b, 1e-14).unwrap();
            let fitted = &a * &c;
            for (i, p) in pts.iter().enumerate() {
                let e = (fitted[i] - 1.0).abs();
                if e > worst.0 {
                    worst = (e, format!("{d} r={:.3} mu={:.3}", p.0, p.1));
                }
            }
        }
        println!(
            "degree {k:2} in (r, mu), {} Multiply-Add nodes: worst relative error {:.3} % at {}",
            powers.len(),
            100.0 * worst.0,
            worst.1
        );
    }
}
