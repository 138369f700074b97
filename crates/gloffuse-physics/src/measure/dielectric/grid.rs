//! The glass tables' builder, [`DielectricGrid`], over the view-cosine axes of `axes`.

use rayon::prelude::*;

use super::axes::critical_crowded;
use super::bsdf::{Dielectric, DielectricNode};
use super::integrator::DielectricIntegrator;
use crate::measure::coat;
use crate::measure::microfacet::{Distribution, Roughness};
use crate::measure::version::BlenderVersion;

/// `E(μ, r, η)` of the Glass and Refraction nodes of one distribution and Blender version on
/// a grid: μ and r on the given axes, η on the coat tables' index slices
/// ([`coat::slice_iors`], 1 to [`coat::IOR_MAX`], even in `z = F0^¼`), entering (η = IOR)
/// and leaving (η = 1/IOR). The table builder for the LUT and the Blender groups, with
/// [`DielectricIntegrator::refraction_leaving`] for the groups' leaving Refraction lobe.
#[derive(Clone, Debug, PartialEq)]
pub struct DielectricGrid {
    pub ior: [f64; coat::SLICES],
    pub mu: Vec<f64>,
    pub roughness: Vec<f64>,
    /// `[node][side][k][i][j]` flattened: node 0 Glass, 1 Refraction; side 0 entering, 1
    /// leaving.
    values: Vec<f64>,
    /// `[i][j]`: the reflected lobe's albedo R of 3.0–3.5's glass (whatever η; see
    /// [`DielectricIntegrator::lobe_albedos`]).
    reflection: Vec<f64>,
}

/// Which way the light crosses the interface of a [`DielectricGrid`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(usize)]
pub enum Side {
    /// From outside, η = IOR (a front face).
    Entering,
    /// From inside, η = 1/IOR (a back face).
    Leaving,
}

impl Side {
    pub const BOTH: [Side; 2] = [Side::Entering, Side::Leaving];

    /// The relative index on this side of an interface of index `ior`.
    pub fn eta(self, ior: f64) -> f64 {
        match self {
            Side::Entering => ior,
            Side::Leaving => 1.0 / ior,
        }
    }
}

impl DielectricGrid {
    /// `E(μ_i, r_j)` of `node` on `side` of slice k.
    pub fn e(&self, node: DielectricNode, side: Side, k: usize, i: usize, j: usize) -> f64 {
        let (n, m) = (self.mu.len(), self.roughness.len());
        let node = node as usize;
        let side = side as usize;
        self.values[(((node * 2 + side) * coat::SLICES + k) * n + i) * m + j]
    }

    /// `R(μ_i, r_j)` of 3.0–3.5's glass (meaningful for that form only).
    pub fn reflection(&self, i: usize, j: usize) -> f64 {
        self.reflection[i * self.roughness.len() + j]
    }
}

impl DielectricIntegrator {
    /// The Refraction node's albedo leaving a glass (η = 1/IOR) on [`critical_crowded`]'s
    /// axis, `[i][k][j]`: at `ss[i]` about the critical cosine of index slice k
    /// ([`coat::slice_iors`]), roughness `roughness[j]`; rows of s run in parallel.
    pub fn refraction_leaving(
        &self,
        distribution: Distribution,
        version: BlenderVersion,
        ss: &[Roughness],
        roughness: &[Roughness],
    ) -> Vec<Vec<Vec<f64>>> {
        let ior = coat::slice_iors();
        ss.par_iter()
            .map(|s| {
                ior.iter()
                    .map(|&n| {
                        let mu = critical_crowded(s.get(), n).max(1e-3);
                        roughness
                            .iter()
                            .map(|&r| {
                                let lobe = Dielectric::new(
                                    DielectricNode::Refraction,
                                    distribution,
                                    r,
                                    version,
                                );
                                self.directional_albedo(&lobe, mu, 1.0 / n)
                            })
                            .collect()
                    })
                    .collect()
            })
            .collect()
    }

    /// `E_avg` ([`Self::average_albedo`]) of `node` on `side` as Blender `version` renders
    /// it, `[k][j]`: index slice k ([`coat::slice_iors`]), `roughness[j]`; slices in parallel.
    pub fn average_grid(
        &self,
        distribution: Distribution,
        version: BlenderVersion,
        node: DielectricNode,
        side: Side,
        roughness: &[Roughness],
    ) -> Vec<Vec<f64>> {
        coat::slice_iors()
            .par_iter()
            .map(|&n| {
                roughness
                    .iter()
                    .map(|&r| {
                        let bsdf = Dielectric::new(node, distribution, r, version);
                        self.average_albedo(&bsdf, side.eta(n))
                    })
                    .collect()
            })
            .collect()
    }

    /// The grid of `distribution` (GGX or Beckmann) as Blender `version` renders it, over
    /// `mus` and `roughness`; rows of μ run in parallel and `step` is called once per row.
    pub fn grid(
        &self,
        distribution: Distribution,
        version: BlenderVersion,
        mus: &[f64],
        roughness: &[Roughness],
        step: &(dyn Fn() + Sync),
    ) -> DielectricGrid {
        let ior = coat::slice_iors();
        let (n, m) = (mus.len(), roughness.len());
        let rows: Vec<(Vec<f64>, Vec<f64>)> = mus
            .par_iter()
            .map(|&mu| {
                let reflection = roughness
                    .iter()
                    .map(|&r| {
                        let glass =
                            Dielectric::new(DielectricNode::Glass, distribution, r, version);
                        self.lobe_albedos(&glass, mu, 1.5).0
                    })
                    .collect();
                let mut row = vec![0.0; 2 * 2 * coat::SLICES * m];
                for node in [DielectricNode::Glass, DielectricNode::Refraction] {
                    for side in Side::BOTH {
                        for (k, &n_k) in ior.iter().enumerate() {
                            for (j, &r) in roughness.iter().enumerate() {
                                let bsdf = Dielectric::new(node, distribution, r, version);
                                let at = ((node as usize * 2 + side as usize) * coat::SLICES + k)
                                    * m
                                    + j;
                                row[at] = self.directional_albedo(&bsdf, mu, side.eta(n_k));
                            }
                        }
                    }
                }
                step();
                (row, reflection)
            })
            .collect();
        let mut values = vec![0.0; 2 * 2 * coat::SLICES * n * m];
        let reflection = rows.iter().flat_map(|(_, r)| r.iter().copied()).collect();
        for (i, (row, _)) in rows.iter().enumerate() {
            for (block, chunk) in row.chunks(m).enumerate() {
                let start = (block * n + i) * m;
                values[start..start + m].copy_from_slice(chunk);
            }
        }
        DielectricGrid {
            ior,
            mu: mus.to_vec(),
            roughness: roughness.iter().map(|r| r.get()).collect(),
            values,
            reflection,
        }
    }
}
