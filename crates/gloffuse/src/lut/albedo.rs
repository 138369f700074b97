//! Kulla–Conty's albedo tables for the Glossy BSDF Cycles evaluates (chosen by the
//! distribution and the Blender version): **R = E(μ, r)** and **G = E_avg(r)** (the same in
//! every row of a column), both by the deterministic quadrature of
//! [`crate::measure::AlbedoIntegrator`] (no samples; max error 3.2e-5), in the n × n layout
//! at pixel centres every whole-table kind shares: the two tables a renderer needs to build
//! its own compensation. [`super::kulla_conty`] builds them ([`kulla_conty::albedo_table`]).

use super::{Bsdf, KindFacts, Spec, blender_bsdf, kulla_conty};

/// The albedo table: its facts for `lut`.
pub const KIND: KindFacts = KindFacts {
    key: "albedo",
    default_size: 64,
    size_limit: None,
    bsdf: |args| blender_bsdf(args, None).map(Bsdf::Blender),
    channels: &["R: E(μ, r)", "G: E_avg(r)"],
    steps_per_size: 1,
    slice_iors: None,
    slice_azimuths: None,
    compute: |spec: &Spec, progress| {
        let bsdf = spec.blender();
        kulla_conty::albedo_table(
            spec.size,
            bsdf.distribution,
            bsdf.blender_version.masking(),
            progress,
        )
    },
};
