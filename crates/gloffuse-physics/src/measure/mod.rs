//! ① Measure: the physics. The microfacet distributions (`microfacet`), the Glossy BSDF as
//! Cycles evaluates it (`glossy`), its albedo by quadrature (`albedo`), the anisotropic lobe
//! and its albedo (`anisotropic`), the masking family of each Blender version (`version`),
//! the BSDF each render engine evaluates (`engine`), the normal a glossy BSDF shades with
//! (`shading_normal`), the dielectric Fresnel (`fresnel`) and the coat of the layered shader
//! (`coat`), the Glass and Refraction BSDFs and their albedo (`dielectric`; Cycles 3.0–3.4's
//! Beckmann sampler reads `beckmann_table`), and the classic BRDF set (`brdf`). A value out
//! of their range is an [`Error`] naming its [`Quantity`].

pub mod albedo;
pub mod anisotropic;
pub mod beckmann_table;
pub mod brdf;
pub mod coat;
pub mod dielectric;
pub mod engine;
pub mod fresnel;
pub mod glossy;
pub mod microfacet;
pub mod shading_normal;
pub mod version;

pub use crate::error::{Error, Quantity};
pub use albedo::{AlbedoGrid, AlbedoIntegrator, Quadrature};
pub use anisotropic::{AnisotropicIntegrator, AnisotropicLobe, Anisotropy};
pub use dielectric::{
    Dielectric, DielectricIntegrator, DielectricNode, GlassForm, Sampler, critical_cosine,
    critical_crowded, critical_crowded_coordinate, grazing_crowded, grazing_crowded_coordinate,
};
pub use engine::Engine;
pub use glossy::Glossy;
pub use microfacet::{Distribution, Masking, Microfacet, Polar, Roughness};
pub use version::BlenderVersion;
