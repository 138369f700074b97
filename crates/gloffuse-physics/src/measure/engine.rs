//! The render engine a Glossy node is evaluated by, and which BSDF that means.
//!
//! Cycles evaluates the node's distribution with the masking of its Blender version. EEVEE
//! (Legacy in 3.x, Next in 4.2+) ignores the distribution: Beckmann and Ashikhmin–Shirley
//! render as GGX, whose energy comes from a split-sum table integrated with separable Smith
//! masking. The integrator's separable GGX reproduces EEVEE's furnace spheres within 0.5 %
//! (docs/EEVEE.md), so that is EEVEE's model here.

use serde::{Deserialize, Serialize};

use super::{Distribution, Glossy, Masking, Roughness};
use crate::error::{Error, Quantity};

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Engine {
    #[default]
    Cycles,
    Eevee,
}

impl Engine {
    pub const ALL: [Engine; 2] = [Engine::Cycles, Engine::Eevee];

    pub fn key(self) -> &'static str {
        match self {
            Engine::Cycles => "cycles",
            Engine::Eevee => "eevee",
        }
    }

    pub fn label(self) -> &'static str {
        match self {
            Engine::Cycles => "Cycles",
            Engine::Eevee => "EEVEE",
        }
    }

    pub fn is_cycles(&self) -> bool {
        *self == Engine::Cycles
    }

    /// The masking this engine evaluates in a Blender whose Cycles uses `masking`.
    pub fn masking(self, masking: Masking) -> Masking {
        match self {
            Engine::Cycles => masking,
            Engine::Eevee => Masking::Separable,
        }
    }

    /// The distribution and masking this engine evaluates for a Glossy node of
    /// `distribution` in a Blender whose Cycles uses `masking`.
    pub fn model(self, distribution: Distribution, masking: Masking) -> (Distribution, Masking) {
        let distribution = match self {
            Engine::Cycles => distribution,
            Engine::Eevee => Distribution::Ggx,
        };
        (distribution, self.masking(masking))
    }

    /// The BSDF this engine renders for a Glossy node of `distribution` and `roughness`.
    pub fn glossy(
        self,
        distribution: Distribution,
        masking: Masking,
        roughness: Roughness,
    ) -> Glossy {
        let (d, m) = self.model(distribution, masking);
        Glossy::new(d, m, roughness)
    }
}

impl std::fmt::Display for Engine {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.label())
    }
}

impl std::str::FromStr for Engine {
    type Err = Error;

    fn from_str(s: &str) -> Result<Self, Error> {
        Engine::ALL
            .into_iter()
            .find(|e| e.key().eq_ignore_ascii_case(s))
            .ok_or_else(|| Error::input(Quantity::Engine, s, "cycles or eevee"))
    }
}
