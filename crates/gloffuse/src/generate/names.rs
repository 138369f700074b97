//! The public names of the node groups gloffuse builds: what a user finds in Blender, and
//! what the audit and the furnace look groups up by.

use crate::measure::{Distribution, Engine};

/// `Gloffuse Shading Normal` (EEVEE: `Gloffuse EEVEE Shading Normal`): the public name of
/// the helper group that finds the normal a glossy BSDF shades with and the view cosine
/// there. Cycles raises a bump normal whose mirror reflection would dip below the surface;
/// EEVEE shades with the bump normal as it is, its view cosine clamped at 0.
pub fn normal_group_name(engine: Engine) -> String {
    format!("Gloffuse{} Shading Normal", engine_infix(engine))
}

/// ` EEVEE` in the names of the groups calibrated for EEVEE; nothing for Cycles.
pub(super) fn engine_infix(engine: Engine) -> &'static str {
    match engine {
        Engine::Cycles => "",
        Engine::Eevee => " EEVEE",
    }
}

/// `Brightness Correction (GGX)` (EEVEE: `Brightness Correction EEVEE (GGX)`): the public
/// name of the gain group.
pub fn correction_group_name(engine: Engine, d: Distribution) -> String {
    format!(
        "Brightness Correction{} ({})",
        engine_infix(engine),
        d.label()
    )
}

/// `Gloffuse Layered (GGX)`: the public name of the glossy-over-diffuse group.
pub fn layered_group_name(d: Distribution) -> String {
    format!("Gloffuse Layered ({})", d.label())
}

/// `Gloffuse Anisotropic (GGX)`: the public name of the anisotropic glossy group.
pub fn anisotropic_group_name(d: Distribution) -> String {
    format!("Gloffuse Anisotropic ({})", d.label())
}

/// `Gloffuse Glass (GGX)`: the public name of the glass group.
pub fn glass_group_name(d: Distribution) -> String {
    format!("Gloffuse Glass ({})", d.label())
}

/// `Gloffuse Refraction (GGX)`: the public name of the refraction group.
pub fn refraction_group_name(d: Distribution) -> String {
    format!("Gloffuse Refraction ({})", d.label())
}

/// `Gloffuse Multiscatter (GGX)`: the public name of the Glossy + lost-energy group.
pub fn multiscatter_group_name(engine: Engine, d: Distribution) -> String {
    format!(
        "Gloffuse{} Multiscatter ({})",
        engine_infix(engine),
        d.label()
    )
}

/// `Gloffuse (GGX)` (EEVEE: `Gloffuse EEVEE (GGX)`): the public name of the corrected
/// shader group.
pub fn shader_group_name(engine: Engine, d: Distribution) -> String {
    format!("Gloffuse{} ({})", engine_infix(engine), d.label())
}
