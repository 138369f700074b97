//! Blender's Glass and Refraction BSDFs (GGX, Beckmann) as Cycles samples them for a white
//! colour, and their directional albedo `E(μ, r, η)`: what one interface returns of the
//! light that meets it, reflected and transmitted together.
//!
//! η is the index on the far side over the index on the viewer's side: the node's IOR on a
//! front face, 1/IOR on a back face (Cycles flips the normal to face the viewer there), so
//! the albedo of a glass interface seen from inside is `E(μ, r, 1/IOR)`. Cycles applies no
//! 1/η² to transmitted radiance. Two forms, read in Cycles' `svm/closure.h` and
//! `closure/bsdf_microfacet.h` (docs/PHYSICS.md §15):
//! - **Blender 3.0–3.5** ([`GlassForm::TwoClosures`]): the Glass node is two closures, a
//!   reflection lobe weighted by the Fresnel at the shading normal `F(μ)` and a refraction
//!   lobe weighted by `max(1e-4, 1 − F(μ))`, neither with a Fresnel of its own. A microfacet
//!   that would reflect totally ends the path: its light is lost.
//! - **Blender 3.6 on** ([`GlassForm::OneClosure`]): one closure that reflects with the
//!   Fresnel of each microfacet `F(v·h)` and refracts with `1 − F(v·h)`; a microfacet that
//!   reflects totally reflects.
//!
//! The Refraction node is the transmitted lobe alone, without a Fresnel (a microfacet that
//! would reflect totally ends the path), in every version. Each lobe has the masking family
//! of its version. A reflection the sampler sends below the surface ends the path; so does
//! a refraction sent above it from 3.6 on (3.0–3.5 keep it: it leaves as it is).
//!
//! The albedo is what Cycles' sampler returns on average: an integral over the visible
//! microfacet normals, `∫ G1(v) (v·h)⁺ D(h) / μ · w(h) dh`, with `w` the sample's weight (a
//! lobe's `G2/G1(v)`, times its Fresnel); in 3.0–3.4 a Beckmann normal is drawn through a
//! slope table, whose excess over the lobe is added ([`Sampler::BeckmannTable`]). Cycles'
//! own evaluation also gives a value to pairs
//! of directions no microfacet connects (its source says the check is missing), which only
//! light sampling reaches; the sampler, and Cycles' own `ggx_glass_E` tables, do not.
//!
//! The BSDF itself is in `bsdf` (the node, its form and sampler per version, one sample's
//! weight), its albedo in `integrator`, the glass tables' view-cosine axes in `axes` and
//! their builder in `grid`.

mod axes;
mod bsdf;
mod grid;
mod integrator;

pub use axes::{
    critical_cosine, critical_crowded, critical_crowded_coordinate, grazing_crowded,
    grazing_crowded_coordinate,
};
pub use bsdf::{Dielectric, DielectricNode, GlassForm, Sampler};
pub use grid::{DielectricGrid, Side};
pub use integrator::{DielectricIntegrator, DielectricQuadrature};
