//! The words the generate stage is asked in: which correction a group applies ([`Mode`])
//! and what a coloured correction keeps ([`ColorModel`]).

use serde::Serialize;

use crate::measure::{BlenderVersion, Distribution, Engine};

/// Which correction a shader group applies.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Mode {
    /// Gain 100/f(r): the sphere's mean is 100 %, its centre darker, its rim brighter.
    Roughness,
    /// Gain 1/E(μ, r) with μ = N·I: every pixel of a furnace sphere is 100 %.
    View,
    /// Glossy plus a diffuse lobe of colour × (1 − E(μ, r)): every pixel 100 %, highlight unchanged.
    Multiscatter,
    /// A dielectric glossy coat over a diffuse base (`Gloffuse Layered (…)`): the coat
    /// reflects A(μ, r, IOR), the base gets the rest.
    Layered,
    /// An anisotropic Glossy (`Gloffuse Anisotropic (GGX)`) with gain 1/E(μ, φ, αx, αy),
    /// φ the view's azimuth from the tangent: every pixel of a furnace sphere is 100 %.
    Anisotropic,
    /// Glass and Refraction BSDFs (`Gloffuse Glass (GGX)`, `Gloffuse Refraction (GGX)`)
    /// with gain 1/E(μ, r, η), η = IOR on a front face and 1/IOR on a back face: every
    /// interface returns all the light that meets it.
    Glass,
}

impl Mode {
    pub const ALL: [Mode; 6] = [
        Mode::Roughness,
        Mode::View,
        Mode::Multiscatter,
        Mode::Layered,
        Mode::Anisotropic,
        Mode::Glass,
    ];

    pub fn key(self) -> &'static str {
        match self {
            Mode::Roughness => "roughness",
            Mode::View => "view",
            Mode::Multiscatter => "multiscatter",
            Mode::Layered => "layered",
            Mode::Anisotropic => "anisotropic",
            Mode::Glass => "glass",
        }
    }

    /// Does this mode's shader group read the view cosine (so that every pixel, not only
    /// the sphere's mean, is judged)?
    pub fn per_pixel(self) -> bool {
        self != Mode::Roughness
    }

    /// Why this mode's groups are built for Cycles only (`None`: for EEVEE too).
    pub fn cycles_only(self) -> Option<&'static str> {
        match self {
            Mode::Roughness | Mode::View | Mode::Multiscatter => None,
            Mode::Layered => Some(
                "the layered groups are calibrated for Cycles, and in EEVEE's furnace their \
                 rings miss 2 % (docs/EEVEE.md)",
            ),
            Mode::Anisotropic => Some(
                "EEVEE renders an anisotropic Glossy as an isotropic one, so the anisotropic \
                 groups are built for Cycles only",
            ),
            Mode::Glass => Some(
                "the glass groups restore the energy of Cycles' Glass and Refraction BSDFs, \
                 which EEVEE does not render",
            ),
        }
    }

    /// The engines this mode's groups are built for.
    pub fn engines(self) -> &'static [Engine] {
        match self.cycles_only() {
            Some(_) => &[Engine::Cycles],
            None => &[Engine::Cycles, Engine::Eevee],
        }
    }

    /// Does this mode have a group of `d`? The anisotropic and glass groups are GGX and
    /// Beckmann only: Ashikhmin–Shirley's anisotropic lobe is another model, and Blender's
    /// Glass and Refraction BSDFs have no such distribution.
    pub fn has_group_of(self, d: Distribution) -> bool {
        !matches!(self, Mode::Anisotropic | Mode::Glass) || d != Distribution::AshikhminShirley
    }

    /// Does Blender `version` render this mode's group of `d` as its table describes? The
    /// anisotropic Beckmann group from 3.5 on (Cycles 3.0–3.4 sample another lobe than they
    /// evaluate). Glass's one exception, 3.5, is the whole mode's (`GlassTable`).
    pub fn renders_group_of(self, d: Distribution, version: BlenderVersion) -> bool {
        self.has_group_of(d) && (self != Mode::Anisotropic || version.renders_anisotropic(d))
    }

    /// Does this mode's group read the isotropic view table E(μ, r) (the anisotropic and
    /// glass groups read their own tables instead)?
    pub fn reads_view_table(self) -> bool {
        matches!(self, Mode::View | Mode::Multiscatter | Mode::Layered)
    }
}

/// What a coloured correction keeps (`--color-model`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum ColorModel {
    /// The surface's albedo is exactly `Color`, whatever the roughness.
    Exact,
    /// The energy multiple bounces add is tinted by the colour, as Kulla and Conty (and
    /// Blender's Multiscatter GGX) compute it: `Fms = F·E_avg / (1 − F(1 − E_avg))`, so a rough
    /// coloured metal renders darker and more saturated than `Color`.
    Physical,
}

impl ColorModel {
    pub const ALL: [ColorModel; 2] = [ColorModel::Exact, ColorModel::Physical];

    pub fn key(self) -> &'static str {
        match self {
            ColorModel::Exact => "exact",
            ColorModel::Physical => "physical",
        }
    }
}
