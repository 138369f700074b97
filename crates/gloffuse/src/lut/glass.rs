//! The glass table for real-time renderers: `E(μ, r, η)` of Cycles' Glass and Refraction
//! BSDFs (GGX or Beckmann, the form of a Blender version), the albedo of one rough
//! dielectric interface, from the same [`DielectricIntegrator::grid`] that `generate` packs
//! for Blender.
//!
//! Layout: [`SLICES`] slices side by side and two rows of them, each slice `n × n` at pixel
//! centres (`r = (x + ½)/n`, `N·V = (y + ½)/n`). Slice k is the index `ior[k]` (even in
//! `z = F0^¼`, from 1 to [`crate::measure::coat::IOR_MAX`]); the top row holds light
//! entering (η = IOR, a front face), the bottom row light leaving (η = 1/IOR, a back face).
//! R = E of the Glass BSDF (reflection and refraction), G = E of the Refraction BSDF. A
//! renderer divides its single-scattering lobe by E to keep every interface's energy.

use super::{Bsdf, KindFacts, SizeLimit, Spec, Table, blender_bsdf, microfacet_only};
use crate::measure::coat::SLICES;
use crate::measure::dielectric::{DielectricNode, Side};
use crate::measure::{BlenderVersion, DielectricIntegrator, Distribution, Roughness};
use crate::progress::Progress;

/// The glass table: its facts for `lut` (see the module's doc for its layout).
pub const KIND: KindFacts = KindFacts {
    key: "glass",
    default_size: 32,
    size_limit: Some(SizeLimit {
        min: 1,
        max: MAX_SIZE,
        why: || format!("its atlas is {SLICES} slices wide and two high"),
    }),
    bsdf: |args| {
        let bsdf = blender_bsdf(args, None)?;
        microfacet_only(
            bsdf.distribution,
            args.kind,
            "Blender's Glass and Refraction BSDFs have no Ashikhmin-Shirley",
        )?;
        Ok(Bsdf::Blender(bsdf))
    },
    channels: &[
        "R: E(μ, r, η) of the Glass BSDF, η = IOR of the slice (top row) or 1/IOR (bottom row)",
        "G: E(μ, r, η) of the Refraction BSDF",
    ],
    steps_per_size: 1,
    slice_iors: Some(super::coat::ior),
    slice_azimuths: None,
    compute: |spec: &Spec, progress| {
        let bsdf = spec.blender();
        glass_table(spec.size, bsdf.distribution, bsdf.blender_version, progress)
    },
};

/// The largest `--size`: 12 slices of 256 make a 3072-texel-wide atlas of 1.6 million
/// albedos, several minutes on two cores.
pub const MAX_SIZE: u32 = 256;

/// The glass atlas of `distribution` as Blender `version` renders it, `size` texels per
/// slice side; `progress` steps once per row of view cosines.
pub fn glass_table(
    size: usize,
    distribution: Distribution,
    version: BlenderVersion,
    progress: &dyn Progress,
) -> Table {
    let centres = Roughness::pixel_centres(size);
    let mus: Vec<f64> = centres.iter().map(|mu| mu.get()).collect();
    let grid = DielectricIntegrator::default()
        .grid(distribution, version, &mus, &centres, &|| progress.step());
    let mut data = Vec::with_capacity(2 * size * size * SLICES * 2);
    for side in Side::BOTH {
        for y in 0..size {
            for k in 0..SLICES {
                for x in 0..size {
                    data.extend_from_slice(&[
                        grid.e(DielectricNode::Glass, side, k, y, x) as f32,
                        grid.e(DielectricNode::Refraction, side, k, y, x) as f32,
                    ]);
                }
            }
        }
    }
    Table {
        width: size * SLICES,
        height: 2 * size,
        channels: &["R", "G"],
        data,
    }
}
