//! The physics: Cycles' Glossy BSDF (`model`) and its albedo integrals (`albedo`).

pub mod albedo;
pub mod model;

pub use albedo::{AlbedoIntegrator, Quadrature};
pub use model::{Distribution, Glossy, Masking, Roughness};
