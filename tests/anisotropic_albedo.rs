//! The anisotropic integrator against independent oracles: a brute-force midpoint rule over
//! the half vector that evaluates D and G2 (the integrator never evaluates D), the isotropic
//! integrator where the two widths agree, the swap symmetry of X and Y (and the grid built with
//! it, against the integrator point by point), and the closed form of GGX at α = 1.
//!
//! Tier: fast (no Blender; `scripts/test.sh --fast` runs it).

mod common;

use common::oracle::brute_force_anisotropic;
use glam::DVec3;
use gloffuse::measure::anisotropic::{AnisotropicAxes, local_direction, view};
use gloffuse::measure::{
    AlbedoIntegrator, AnisotropicIntegrator, AnisotropicLobe, Distribution, Glossy, Masking,
    Roughness,
};
use rayon::prelude::*;
use std::f64::consts::{FRAC_PI_2, LN_2};

const TOLERANCE: f64 = 2e-4;
const MASKINGS: [Masking; 2] = [Masking::Separable, Masking::HeightCorrelated];
const DISTRIBUTIONS: [Distribution; 2] = [Distribution::Beckmann, Distribution::Ggx];

fn lobe(d: Distribution, m: Masking, alpha_x: f64, alpha_y: f64) -> AnisotropicLobe {
    AnisotropicLobe::new(d, m, alpha_x, alpha_y).unwrap()
}

#[test]
fn matches_a_brute_force_midpoint_rule() {
    let widths = [
        (0.05, 0.4),
        (0.2, 1.0),
        (0.5, 0.1),
        (0.01, 0.6),
        (1.0, 0.3),
        (0.7, 0.7),
    ];
    let mus = [0.05, 0.3, 0.8];
    let phis = [0.0, 0.7, FRAC_PI_2];
    let mut cases = Vec::new();
    for d in DISTRIBUTIONS {
        for m in MASKINGS {
            for &(ax, ay) in &widths {
                for &mu in &mus {
                    for &phi in &phis {
                        cases.push((lobe(d, m, ax, ay), mu, phi));
                    }
                }
            }
        }
    }
    let q = AnisotropicIntegrator::default();
    let failures: Vec<String> = cases
        .par_iter()
        .filter_map(|(l, mu, phi)| {
            let wo = view(*mu, *phi);
            let reference = brute_force_anisotropic(l, wo, 2000, 2000);
            let e = q.directional_albedo(l, wo);
            ((e - reference).abs() > TOLERANCE)
                .then(|| format!("{l:?} μ {mu} φ {phi}: {e} vs {reference}"))
        })
        .collect();
    assert!(
        failures.is_empty(),
        "{} of {} cases off:\n{}",
        failures.len(),
        cases.len(),
        failures.join("\n")
    );
}

#[test]
fn equal_widths_give_the_isotropic_albedo() {
    let iso = AlbedoIntegrator::default();
    let q = AnisotropicIntegrator::default();
    for d in DISTRIBUTIONS {
        for m in MASKINGS {
            for r in [0.1, 0.3, 0.6, 0.9, 1.0] {
                let g = Glossy::new(d, m, Roughness::new(r).unwrap());
                let l = lobe(d, m, r * r, r * r);
                for mu in [0.02, 0.1, 0.4, 0.7, 1.0] {
                    let want = iso.directional_albedo(&g, mu);
                    for phi in [0.0, 0.3, 1.2] {
                        let e = q.directional_albedo(&l, view(mu, phi));
                        assert!(
                            (e - want).abs() < TOLERANCE,
                            "{d} {m} r {r} μ {mu} φ {phi}: {e} vs {want}"
                        );
                    }
                }
            }
        }
    }
}

#[test]
fn swapping_the_widths_turns_the_view_by_a_right_angle() {
    let q = AnisotropicIntegrator::default();
    for d in DISTRIBUTIONS {
        let (a, b) = (
            lobe(d, Masking::HeightCorrelated, 0.1, 0.8),
            lobe(d, Masking::HeightCorrelated, 0.8, 0.1),
        );
        for mu in [0.1, 0.5] {
            for phi in [0.0, 0.5, 1.1] {
                let e = q.directional_albedo(&a, view(mu, phi));
                let turned = q.directional_albedo(&b, view(mu, FRAC_PI_2 - phi));
                assert!(
                    (e - turned).abs() < 1e-9,
                    "{d} μ {mu} φ {phi}: {e} vs {turned}"
                );
            }
        }
        // and the view's azimuth matters: the lobe is not isotropic
        let along_narrow = q.directional_albedo(&a, view(0.2, 0.0));
        let along_wide = q.directional_albedo(&a, view(0.2, FRAC_PI_2));
        assert!(
            (along_narrow - along_wide).abs() > 0.05,
            "{d}: {along_narrow} vs {along_wide}"
        );
    }
}

/// The grid computes half of a square table and takes the rest from the swap symmetry:
/// every entry must still be the integrator's own value at that point, and the averages
/// its hemispherical average. Within the integrator's own accuracy ([`TOLERANCE`]): the two
/// evaluations are two quadratures of one integral whose azimuths start at the view's own
/// angle (measured: at most 2.5e-5 apart, at a normal view of the most stretched lobe; a
/// wrong mapping misses by 0.05 and more, see the test above).
#[test]
fn the_grid_is_the_integrator_at_every_point() {
    let q = AnisotropicIntegrator::default();
    let (d, m) = (Distribution::Ggx, Masking::HeightCorrelated);
    let axes = AnisotropicAxes::table(3, 4);
    assert!(axes.is_square());
    let grid = q.grid(d, m, axes.clone(), &|| {}).unwrap();
    let e_avg = q.average_grid(d, m, &axes.rx, &axes.ry, &|| {}).unwrap();
    for (l, ry) in axes.ry.iter().enumerate() {
        for (j, rx) in axes.rx.iter().enumerate() {
            let lobe = lobe(d, m, rx * rx, ry * ry);
            for (i, &mu) in axes.mu.iter().enumerate() {
                for (k, &phi) in axes.phi.iter().enumerate() {
                    let direct = q.directional_albedo(&lobe, view(mu, phi));
                    let e = grid.e(i, k, j, l);
                    assert!(
                        (e - direct).abs() < TOLERANCE,
                        "μ {mu} φ {phi} rx {rx} ry {ry}: grid {e}, integrator {direct}"
                    );
                }
            }
            let average = q.average_albedo(&lobe);
            assert_eq!(e_avg[l * axes.rx.len() + j], average, "rx {rx} ry {ry}");
        }
    }
    // A table with other widths on its two axes is computed in full.
    let mut wide = axes.clone();
    wide.ry = vec![0.5, 0.9];
    assert!(!wide.is_square());
    let grid = q.grid(d, m, wide.clone(), &|| {}).unwrap();
    let direct = q.directional_albedo(&lobe(d, m, 1e-4, 0.81), view(wide.mu[1], wide.phi[1]));
    assert!((grid.e(1, 1, 0, 1) - direct).abs() < 1e-12);
}

#[test]
fn closed_form_ggx_alpha_one_normal_incidence() {
    // At αx = αy = 1 and μ = 1, E = 1 − ln 2 (see albedo_accuracy.rs).
    let q = AnisotropicIntegrator::default();
    for m in MASKINGS {
        let e = q.directional_albedo(&lobe(Distribution::Ggx, m, 1.0, 1.0), view(1.0, 0.0));
        assert!((e - (1.0 - LN_2)).abs() < 1e-6, "{m}: {e}");
    }
}

#[test]
fn a_mirror_reflects_everything_and_a_sliver_almost_everything() {
    let q = AnisotropicIntegrator::default();
    for d in DISTRIBUTIONS {
        assert_eq!(
            q.directional_albedo(
                &lobe(d, Masking::HeightCorrelated, 0.0, 0.0),
                view(0.3, 0.2)
            ),
            1.0
        );
        let e = q.directional_albedo(
            &lobe(d, Masking::HeightCorrelated, 0.005, 0.02),
            view(0.3, 0.2),
        );
        assert!((e - 1.0).abs() < 2e-3, "{d}: {e}");
    }
}

/// The sphere mean under a constant world-X tangent (verify's anisotropic spheres) against
/// a pixel grid over the disk, each pixel's frame built from its own normal: another route
/// through the geometry (Cartesian pixels, no symmetry folding). It must also differ from
/// the turning-tangent average where the lobe is stretched, or the geometry would not matter.
#[test]
fn constant_tangent_sphere_mean_matches_a_pixel_grid() {
    let q = AnisotropicIntegrator::default();
    for (alpha_x, alpha_y) in [(0.05, 0.8), (0.6, 0.2), (0.3, 0.3)] {
        let l = lobe(
            Distribution::Ggx,
            Masking::HeightCorrelated,
            alpha_x,
            alpha_y,
        );
        const N: usize = 120;
        let (sum, count) = (0..N * N)
            .into_par_iter()
            .filter_map(|p| {
                let x = ((p % N) as f64 + 0.5) / N as f64 * 2.0 - 1.0;
                let y = ((p / N) as f64 + 0.5) / N as f64 * 2.0 - 1.0;
                let rr = x * x + y * y;
                (rr < 1.0).then(|| {
                    let normal = DVec3::new(x, y, (1.0 - rr).sqrt());
                    q.directional_albedo(&l, local_direction(normal, DVec3::X, DVec3::Z))
                })
            })
            .fold(|| (0.0, 0usize), |(s, n), e| (s + e, n + 1))
            .reduce(|| (0.0, 0), |a, b| (a.0 + b.0, a.1 + b.1));
        let grid = sum / count as f64;
        let mean = q.constant_tangent_sphere_mean(&l);
        assert!(
            (mean - grid).abs() < 1e-3,
            "αx {alpha_x} αy {alpha_y}: quadrature {mean}, pixel grid {grid}"
        );
        let turning = q.average_albedo(&l);
        if alpha_x == alpha_y {
            assert!(
                (mean - turning).abs() < 2e-4,
                "isotropic: {mean} vs {turning}"
            );
        } else {
            assert!((mean - turning).abs() > 5e-3, "{mean} vs {turning}");
        }
    }
}
