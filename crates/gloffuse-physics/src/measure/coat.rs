//! A dielectric coat over a diffuse base: the albedo `A(μ, r, η)` of a glossy lobe whose
//! microfacets reflect with the exact dielectric Fresnel of index η, with the energy that
//! single scattering loses given back as Kulla and Conty do (and as Blender 4.x's
//! Multiscatter GGX does for a dielectric layer):
//!
//! `A = E_F(μ) (1 + Fms (1 − E(μ)) / E(μ))`, `Fms = F_avg E_avg / (1 − F_avg (1 − E_avg))`,
//!
//! where `E_F(μ) = ∫ f F(ωo·h, η) cosθi dωi` is the Fresnel-weighted albedo, `E` and `E_avg`
//! the white lobe's albedos, and `F_avg = 2 ∫ F(μ, η) μ dμ` the hemispherical average of the
//! smooth Fresnel. A white base under the coat then gets `1 − A`: a white layered sphere
//! reflects everything, at every roughness, view and index.

use gauss_quad::legendre::GaussLegendre;
use rayon::prelude::*;

use super::albedo::AlbedoIntegrator;
use super::fresnel;
use super::glossy::Glossy;
use super::microfacet::{Distribution, Masking, Roughness};

/// Kulla and Conty's tint of the energy multiple bounces add, for a reflectance `f` (a
/// colour channel, or a Fresnel average) and the white lobe's `E_avg`:
/// `Fms = f E_avg / (1 − f (1 − E_avg))`.
pub fn multiscatter_tint(f: f64, e_avg: f64) -> f64 {
    f * e_avg / (1.0 - f * (1.0 - e_avg))
}

/// The coat albedo from its parts: `E_F · coat_gain`.
pub fn coat_albedo(e_fresnel: f64, e: f64, f_avg: f64, e_avg: f64) -> f64 {
    e_fresnel * coat_gain(e, f_avg, e_avg)
}

/// `A / E_F = 1 + Fms (1 − E)/E`: what a single-scattering lobe with the Fresnel at its
/// microfacets is multiplied by to reflect A (1 where E is 0).
pub fn coat_gain(e: f64, f_avg: f64, e_avg: f64) -> f64 {
    if e <= 0.0 {
        return 1.0;
    }
    1.0 + multiscatter_tint(f_avg, e_avg) * (1.0 - e) / e
}

/// `F_avg(η) = 2 ∫₀¹ F(μ, η) μ dμ`. F is smooth in μ for η ≥ 1 but turns steeply towards 1 at
/// grazing, so the rule is in `μ = t²` (which flattens that end) with 64 nodes: exact to
/// about 1e-12 for η ∈ [1, 3] (checked against a million-point midpoint rule).
pub fn fresnel_average(eta: f64) -> f64 {
    GaussLegendre::new(std::num::NonZeroUsize::new(64).expect("64 > 0"))
        .as_node_weight_pairs()
        .iter()
        .map(|&(x, w)| {
            let t = 0.5 * (x + 1.0);
            let mu = t * t;
            // dμ = 2t dt, and [−1, 1] → [0, 1] halves the weight.
            0.5 * w * 2.0 * fresnel::dielectric(mu, eta) * mu * 2.0 * t
        })
        .sum()
}

/// The highest index the coat tables hold (a heavy flint glass; diamond is 2.42).
pub const IOR_MAX: f64 = 3.0;

/// Index slices of the coat tables, spaced evenly in `z = F0^¼` from η = 1 to
/// [`IOR_MAX`] (the axis Cycles' own dielectric tables use): A changes fast in η near 1 at
/// grazing views, and z is fine there. 12 slices keep the linear interpolation between
/// neighbours within 7.3e-3 of A over η ∈ [1, 3], μ, r ∈ [0.05, 1], every distribution
/// (`cargo run --release --example coat_table_error`).
pub const SLICES: usize = 12;

/// `z = F0(η)^¼`, the coordinate the slices are even in; `z(IOR_MAX) = 1/√2`.
pub fn slice_coordinate(eta: f64) -> f64 {
    fresnel::f0(eta.clamp(1.0, IOR_MAX)).sqrt().sqrt()
}

/// The indices of the [`SLICES`] slices.
pub fn slice_iors() -> [f64; SLICES] {
    let z_max = slice_coordinate(IOR_MAX);
    std::array::from_fn(|k| {
        let z = z_max * k as f64 / (SLICES - 1) as f64;
        fresnel::ior_from_f0(z.powi(4))
    })
}

/// `A(μ_i, r_j, η_k)` of one distribution and masking on a grid, with the white lobe's
/// `E(μ_i, r_j)` that the groups divide by (a Glossy BSDF in Blender reflects `E`, so its
/// colour is `A / E`).
#[derive(Clone, Debug, PartialEq)]
pub struct CoatGrid {
    pub roughness: Vec<Roughness>,
    pub mu: Vec<f64>,
    pub ior: [f64; SLICES],
    /// `a[(k * mu.len() + i) * roughness.len() + j] = A(μ_i, r_j, η_k)`: one slice per index.
    pub a: Vec<f64>,
    /// `A / E_F` ([`coat_gain`]) in the layout of `a`.
    pub gain: Vec<f64>,
    /// `e[i * roughness.len() + j] = E(μ_i, r_j)`.
    pub e: Vec<f64>,
}

impl CoatGrid {
    pub fn a(&self, k: usize, i: usize, j: usize) -> f64 {
        self.a[(k * self.mu.len() + i) * self.roughness.len() + j]
    }

    pub fn e(&self, i: usize, j: usize) -> f64 {
        self.e[i * self.roughness.len() + j]
    }

    pub fn gain(&self, k: usize, i: usize, j: usize) -> f64 {
        self.gain[(k * self.mu.len() + i) * self.roughness.len() + j]
    }
}

/// One coat (a lobe and an index) with its view-independent parts computed once, for
/// evaluating `A(μ)` at many views.
pub struct Coat<'a> {
    integrator: &'a AlbedoIntegrator,
    pub glossy: Glossy,
    pub eta: f64,
    f_avg: f64,
    e_avg: f64,
}

impl<'a> Coat<'a> {
    pub fn new(integrator: &'a AlbedoIntegrator, glossy: Glossy, eta: f64) -> Self {
        Coat {
            integrator,
            glossy,
            eta,
            f_avg: fresnel_average(eta),
            e_avg: integrator.average_albedo(&glossy),
        }
    }

    /// `A(μ)`.
    pub fn albedo(&self, mu: f64) -> f64 {
        let (e_f, e) = self.integrator.fresnel_albedo(&self.glossy, mu, self.eta);
        coat_albedo(e_f, e, self.f_avg, self.e_avg)
    }

    /// `2 ∫₀¹ A(μ) μ dμ`: the mean of A over an orthographic sphere.
    pub fn average(&self) -> f64 {
        self.integrator.hemispherical_average(|mu| self.albedo(mu))
    }

    /// The white lobe's `E_avg`.
    pub fn e_avg(&self) -> f64 {
        self.e_avg
    }

    /// The mean over an orthographic sphere of what the hand-made glossy-over-diffuse
    /// material reflects, per channel of the base: a Mix Shader whose factor is the smooth
    /// Fresnel `F(μ)` (Blender's Fresnel node) over a white Glossy of this lobe and a Diffuse
    /// of reflectance `base`, `F(μ) E(μ) + (1 − F(μ)) base`. It is linear in the base, so
    /// its mean is `2∫ F E μ dμ + base (1 − F_avg)`.
    pub fn hand_mix_average(&self, base: [f64; 3]) -> [f64; 3] {
        let glossy = self.integrator.hemispherical_average(|mu| {
            fresnel::dielectric(mu, self.eta) * self.integrator.directional_albedo(&self.glossy, mu)
        });
        base.map(|c| glossy + c * (1.0 - self.f_avg))
    }
}

/// One more moment than slices: the white albedo E rides along with the Fresnel ones.
const MOMENTS: usize = SLICES + 1;

/// One (μ, r) entry of the coat grid: A and its gain per slice, and E.
struct CoatEntry {
    a: [f64; SLICES],
    gain: [f64; SLICES],
    e: f64,
}

impl AlbedoIntegrator {
    /// `E_F(μ) = ∫ f F(ωo·h, η) cosθi dωi` and `E(μ)` in one pass.
    pub fn fresnel_albedo(&self, glossy: &Glossy, mu: f64, eta: f64) -> (f64, f64) {
        let [e_f, e] =
            self.directional_moments(glossy, mu, &|c| [fresnel::dielectric(c, eta), 1.0]);
        (e_f, e)
    }

    /// `A(μ, r, η)` of one lobe at one view (see the module's formula).
    pub fn coat(&self, glossy: &Glossy, mu: f64, eta: f64) -> f64 {
        Coat::new(self, *glossy, eta).albedo(mu)
    }

    /// The coat table (A, its gain, E) at the [`slice_iors`]: each (μ, r) entry takes one
    /// pass over the half vectors for every slice and E at once. Columns (one per roughness)
    /// run in parallel; `step` is called once per column.
    pub fn coat_grid(
        &self,
        distribution: Distribution,
        masking: Masking,
        roughness: &[Roughness],
        mu: &[f64],
        step: &(dyn Fn() + Sync),
    ) -> CoatGrid {
        let ior = slice_iors();
        let f_avg = ior.map(fresnel_average);
        let columns: Vec<Vec<CoatEntry>> = roughness
            .par_iter()
            .map(|&r| {
                let glossy = Glossy::new(distribution, masking, r);
                let e_avg = self.average_albedo(&glossy);
                let column = mu
                    .iter()
                    .map(|&m| {
                        let moments: [f64; MOMENTS] = self.directional_moments(&glossy, m, &|c| {
                            std::array::from_fn(|k| {
                                if k < SLICES {
                                    fresnel::dielectric(c, ior[k])
                                } else {
                                    1.0
                                }
                            })
                        });
                        let e = moments[SLICES];
                        let gain = std::array::from_fn(|k| coat_gain(e, f_avg[k], e_avg));
                        CoatEntry {
                            a: std::array::from_fn(|k| moments[k] * gain[k]),
                            gain,
                            e,
                        }
                    })
                    .collect();
                step();
                column
            })
            .collect();
        let (width, height) = (roughness.len(), mu.len());
        let mut grid = CoatGrid {
            roughness: roughness.to_vec(),
            mu: mu.to_vec(),
            ior,
            a: vec![0.0; SLICES * height * width],
            gain: vec![0.0; SLICES * height * width],
            e: vec![0.0; height * width],
        };
        for (j, column) in columns.iter().enumerate() {
            for (i, entry) in column.iter().enumerate() {
                grid.e[i * width + j] = entry.e;
                for k in 0..SLICES {
                    grid.a[(k * height + i) * width + j] = entry.a[k];
                    grid.gain[(k * height + i) * width + j] = entry.gain[k];
                }
            }
        }
        grid
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_fresnel_average_matches_a_fine_midpoint_rule() {
        for eta in [1.0, 1.33, 1.5, 2.0, 3.0] {
            let n = 1_000_000;
            let midpoint: f64 = (0..n)
                .map(|i| {
                    let mu = (i as f64 + 0.5) / n as f64;
                    2.0 * fresnel::dielectric(mu, eta) * mu / n as f64
                })
                .sum();
            let quadrature = fresnel_average(eta);
            assert!(
                (quadrature - midpoint).abs() < 1e-9,
                "{eta}: {quadrature} vs {midpoint}"
            );
        }
    }

    #[test]
    fn the_grid_agrees_with_one_view_at_a_time() {
        let q = AlbedoIntegrator::default();
        let rs = [Roughness::new(0.3).unwrap(), Roughness::new(0.9).unwrap()];
        let grid = q.coat_grid(
            Distribution::Ggx,
            Masking::HeightCorrelated,
            &rs,
            &[0.2, 0.8],
            &|| {},
        );
        assert_eq!(grid.ior[0], 1.0);
        assert!((grid.ior[SLICES - 1] - IOR_MAX).abs() < 1e-12);
        for (k, &eta) in grid.ior.iter().enumerate() {
            for (i, &mu) in grid.mu.iter().enumerate() {
                for (j, &r) in rs.iter().enumerate() {
                    let g = Glossy::new(Distribution::Ggx, Masking::HeightCorrelated, r);
                    assert!((grid.a(k, i, j) - q.coat(&g, mu, eta)).abs() < 1e-15);
                    let (e_f, _) = q.fresnel_albedo(&g, mu, eta);
                    if e_f > 0.0 {
                        let ratio = grid.a(k, i, j) / e_f;
                        assert!((grid.gain(k, i, j) - ratio).abs() < 1e-12 * ratio);
                    } else {
                        assert_eq!(grid.gain(k, i, j), 1.0);
                    }
                    assert_eq!(grid.e(i, j), q.directional_albedo(&g, mu));
                }
            }
        }
    }

    #[test]
    fn limits_of_the_coat() {
        let q = AlbedoIntegrator::default();
        // A mirror coat reflects the smooth Fresnel; an index of 1 reflects nothing.
        let mirror = Glossy::new(
            Distribution::Ggx,
            Masking::HeightCorrelated,
            Roughness::new(0.0).unwrap(),
        );
        for mu in [0.1, 0.5, 1.0] {
            assert!((q.coat(&mirror, mu, 1.5) - fresnel::dielectric(mu, 1.5)).abs() < 1e-15);
        }
        let rough = Glossy::new(
            Distribution::Beckmann,
            Masking::Separable,
            Roughness::new(0.7).unwrap(),
        );
        assert_eq!(q.coat(&rough, 0.6, 1.0), 0.0);
        // With Fresnel 1 everywhere the coat is white: the compensation brings E back to 1.
        assert!((coat_albedo(0.41, 0.41, 1.0, 0.41) - 1.0).abs() < 1e-15);
    }
}
