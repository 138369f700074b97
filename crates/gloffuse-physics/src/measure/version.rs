//! Blender versions as plain data, and what they imply for the physics: the masking family
//! of each version's Cycles.

use super::microfacet::{Distribution, Masking};
use crate::error::{Error, Quantity};

/// A Blender release, `major.minor` (a patch number is accepted and ignored).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub struct BlenderVersion {
    pub major: u32,
    pub minor: u32,
}

impl BlenderVersion {
    /// The oldest Blender whose Glossy BSDF gloffuse models (the 3.x series onwards).
    pub const OLDEST: BlenderVersion = BlenderVersion { major: 3, minor: 0 };

    /// The newest Blender gloffuse has run and measured (bpy 5.0 is the newest wheel that
    /// installs on the machines it is tested on). A newer one runs on this version's rules,
    /// with a notice naming them (`blender::probe::newer_than_known`).
    pub const NEWEST_KNOWN: BlenderVersion = BlenderVersion { major: 5, minor: 0 };

    /// The version modelled when none is named: 4.5 LTS, the series gloffuse installs.
    pub const DEFAULT: BlenderVersion = BlenderVersion { major: 4, minor: 5 };

    /// The first version whose Cycles uses the height-correlated masking: Cycles commit
    /// ef22429288cb ("Switch microfacet code to non-separable shadowing-masking term",
    /// January 2023) is in v3.5.0 and not in v3.4 (`docs/PHYSICS.md` §3).
    pub const HEIGHT_CORRELATED_FROM: BlenderVersion = BlenderVersion { major: 3, minor: 5 };

    /// The masking–shadowing form Cycles uses in this version: the separable
    /// `G1(ωi) G1(ωo)` before 3.5, the height-correlated `1/(1 + Λi + Λo)` from 3.5 on.
    pub fn masking(self) -> Masking {
        if self >= Self::HEIGHT_CORRELATED_FROM {
            Masking::HeightCorrelated
        } else {
            Masking::Separable
        }
    }

    /// Whether this version's Cycles renders the anisotropic lobe of `distribution` as it
    /// evaluates it. Not Beckmann before 3.5: Cycles 3.0–3.4 sample an isotropic lobe of
    /// width αx (`microfacet_sample_stretched(kg, local_I, alpha_x, alpha_x, …)` in
    /// `bsdf_microfacet.h`) and weight it as if it were the anisotropic one, so a furnace
    /// sphere renders far from the lobe's albedo (measured in 3.4.1: 0.34 where the lobe
    /// reflects 0.92). 3.5 rewrote the sampler.
    pub fn renders_anisotropic(self, distribution: Distribution) -> bool {
        distribution != Distribution::Beckmann || self >= Self::HEIGHT_CORRELATED_FROM
    }

    /// Newer than [`Self::NEWEST_KNOWN`]: gloffuse has never run it, so what it does there
    /// is assumed, not measured.
    pub fn is_newer_than_known(self) -> bool {
        self > Self::NEWEST_KNOWN
    }
}

impl std::fmt::Display for BlenderVersion {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}.{}", self.major, self.minor)
    }
}

impl std::str::FromStr for BlenderVersion {
    type Err = Error;

    /// Accepts `4.5`, `4.5.4`, `3.4.1`, with an optional leading `v` or `Blender `.
    fn from_str(s: &str) -> Result<Self, Error> {
        let bad = || {
            Error::input(
                Quantity::BlenderVersion,
                s,
                "a version like 3.4, 4.5 or 5.0 (3.0 or later)",
            )
        };
        let t = s.trim();
        let t = t.strip_prefix("Blender ").unwrap_or(t);
        let t = t.strip_prefix('v').unwrap_or(t);
        let mut parts = t.split('.');
        let major: u32 = parts.next().ok_or_else(bad)?.parse().map_err(|_| bad())?;
        let minor: u32 = parts.next().ok_or_else(bad)?.parse().map_err(|_| bad())?;
        if let Some(patch) = parts.next() {
            patch.parse::<u32>().map_err(|_| bad())?;
        }
        if parts.next().is_some() {
            return Err(bad());
        }
        let v = BlenderVersion { major, minor };
        if v < Self::OLDEST {
            return Err(Error::input(
                Quantity::BlenderVersion,
                s,
                "Blender 3.0 or later (older Glossy BSDFs are not modelled)",
            ));
        }
        Ok(v)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_and_picks_masking() {
        let v: BlenderVersion = "3.4.1".parse().unwrap();
        assert_eq!(v, BlenderVersion { major: 3, minor: 4 });
        assert_eq!(v.masking(), Masking::Separable);
        assert_eq!(
            "3.5.1".parse::<BlenderVersion>().unwrap().masking(),
            Masking::HeightCorrelated
        );
        assert_eq!(
            "4.5".parse::<BlenderVersion>().unwrap().masking(),
            Masking::HeightCorrelated
        );
        assert!("2.79".parse::<BlenderVersion>().is_err());
        assert!("four".parse::<BlenderVersion>().is_err());
        assert!("4".parse::<BlenderVersion>().is_err());
        assert!("4.5.1.2".parse::<BlenderVersion>().is_err());
    }

    #[test]
    fn newer_than_known_is_strictly_after_5_0_and_keeps_its_masking() {
        let v = |s: &str| s.parse::<BlenderVersion>().unwrap();
        assert_eq!(BlenderVersion::NEWEST_KNOWN, v("5.0"));
        assert!(!v("5.0.1").is_newer_than_known());
        assert!(!v("3.4").is_newer_than_known());
        assert!(v("5.1").is_newer_than_known());
        assert!(v("5.2.0").is_newer_than_known());
        assert!(v("6.0").is_newer_than_known());
        // A newer Cycles is assumed to keep the height-correlated masking (it does in 5.1, 5.2).
        assert_eq!(v("5.2").masking(), Masking::HeightCorrelated);
        assert_eq!(v("6.0").masking(), Masking::HeightCorrelated);
    }
}
