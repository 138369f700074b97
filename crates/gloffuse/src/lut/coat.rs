//! The coat table of the layered shader for real-time renderers: the albedo
//! `A(μ, r, η)` of a dielectric microfacet coat with its lost energy given back
//! (`crate::measure::coat`), from the same [`AlbedoIntegrator::coat_grid`] that `generate`
//! packs for Blender.
//!
//! Layout: [`SLICES`] slices side by side, each `n × n` at pixel centres
//! (`r = (x + ½)/n`, `N·V = (y + ½)/n`), slice k for the index `ior[k]` (even in
//! `z = F0^¼`, from 1 to [`crate::measure::coat::IOR_MAX`]; see [`slice_iors`]). R = A, G = E(μ, r), the white
//! lobe's albedo (so a renderer whose own lobe reflects E can weight it by A / E). A base
//! under the coat is weighted by `1 − A`.

use super::{Bsdf, KindFacts, SizeLimit, Spec, Table, blender_bsdf};
use crate::measure::coat::{SLICES, slice_iors};
use crate::measure::{AlbedoIntegrator, Distribution, Masking, Roughness};
use crate::progress::Progress;

/// The coat table: its facts for `lut` (see the module's doc for its layout).
pub const KIND: KindFacts = KindFacts {
    key: "coat",
    default_size: 64,
    size_limit: Some(SizeLimit {
        min: 1,
        max: MAX_SIZE,
        why: || format!("its atlas is {SLICES} slices wide"),
    }),
    bsdf: |args| blender_bsdf(args, None).map(Bsdf::Blender),
    channels: &["R: A(μ, r, IOR of the slice)", "G: E(μ, r)"],
    steps_per_size: 1,
    slice_iors: Some(ior),
    slice_azimuths: None,
    compute: |spec: &Spec, progress| {
        let bsdf = spec.blender();
        coat_table(
            spec.size,
            bsdf.distribution,
            bsdf.blender_version.masking(),
            progress,
        )
    },
};

/// The largest `--size` of a coat table: 12 slices of 1024 make a 12288-texel-wide atlas,
/// within what GPUs sample (16384).
pub const MAX_SIZE: u32 = 1024;

/// The coat atlas of `distribution` with `masking`, `size` texels per slice side;
/// `progress` steps once per roughness column.
pub fn coat_table(
    size: usize,
    distribution: Distribution,
    masking: Masking,
    progress: &dyn Progress,
) -> Table {
    let centres = Roughness::pixel_centres(size);
    let mus: Vec<f64> = centres.iter().map(|mu| mu.get()).collect();
    let grid =
        AlbedoIntegrator::default()
            .coat_grid(distribution, masking, &centres, &mus, &|| progress.step());
    let mut data = Vec::with_capacity(size * size * SLICES * 2);
    for y in 0..size {
        for k in 0..SLICES {
            for x in 0..size {
                data.extend_from_slice(&[grid.a(k, y, x) as f32, grid.e(y, x) as f32]);
            }
        }
    }
    Table {
        width: size * SLICES,
        height: size,
        channels: &["R", "G"],
        data,
    }
}

/// The indices of the slices, in order (the first is 1, the last
/// [`crate::measure::coat::IOR_MAX`]).
pub fn ior() -> Vec<f64> {
    slice_iors().to_vec()
}
