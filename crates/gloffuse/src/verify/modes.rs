//! Each mode's verify facts in one table, one entry a mode ([`spec`]): the sweep it renders
//! unless told (roughness values and the second axis), samples and thresholds per engine,
//! why it refuses the engines its groups are not built for and the colour models it takes,
//! whether its spheres are white or solid, and the words the reports call its spheres by.
//! Verify's checks, plan and judging, and the reports, read these facts here; the generate
//! facts (key, per-pixel, engines) are `Mode`'s own; the physics of a mode stays where it
//! is computed (`predict.rs`) and asks the spec a named question (`solid`).

use crate::generate::{ColorModel, Mode};
use crate::measure::{Engine, Roughness};

use super::Judging;

/// One mode's verify facts.
#[derive(Debug)]
pub struct ModeSpec {
    pub mode: Mode,
    /// The roughness values the sweep checks unless told.
    pub roughness: fn() -> Vec<Roughness>,
    /// What each block of rows holds fixed besides distribution and roughness.
    pub axis: SecondAxis,
    /// Samples and thresholds in Cycles, and in EEVEE (also where the mode refuses EEVEE,
    /// since the options resolve before they are checked).
    pub cycles: EngineDefaults,
    pub eevee: EngineDefaults,
    /// Why verify refuses the engines the mode's groups are not built for
    /// ([`Mode::engines`]).
    pub other_engines_refused: &'static str,
    /// The colour models the mode's groups promise, and why the others are refused.
    pub color_models: &'static [ColorModel],
    pub other_color_models_refused: &'static str,
    /// Why the spheres must be white, in a mode whose spheres must (`None`: any colour).
    pub white_only: Option<&'static str>,
    /// Whether the spheres are solid (light crosses them) rather than surfaces.
    pub solid: bool,
    /// What a report calls a row's plain sphere and its corrected sphere
    /// (`GGX Mix Shader`, `GGX layered`), and the reference spheres' shader.
    pub uncorrected: &'static str,
    pub corrected: &'static str,
    pub reference: &'static str,
    /// The terminal table's heading of its first column.
    pub row_heading: &'static str,
    /// What the spheres are, where the table's column names do not say it.
    pub legend: Option<&'static str>,
    /// What the target is, where the mode promises something other than the colour.
    pub own_target: Option<&'static str>,
    /// What the mode corrects and so what is judged.
    pub scope: &'static str,
    /// The brightness plot's title of one block of rows (`Layered furnace brightness · IOR
    /// 1.5`); a sweep without blocks is titled by its coefficients instead.
    pub block_plot_title: &'static str,
}

/// The second axis of a sweep, with its values unless told.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SecondAxis {
    None,
    /// The coat's or the glass's index of refraction.
    Ior(&'static [f64]),
    /// The lobe's anisotropy.
    Anisotropy(&'static [f64]),
}

/// What a sweep renders and judges by in one engine unless told.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EngineDefaults {
    pub samples: u32,
    pub judging: Judging,
}

impl ModeSpec {
    pub fn defaults(&self, engine: Engine) -> EngineDefaults {
        match engine {
            Engine::Cycles => self.cycles,
            Engine::Eevee => self.eevee,
        }
    }

    pub fn takes_ior(&self) -> bool {
        matches!(self.axis, SecondAxis::Ior(_))
    }

    pub fn takes_anisotropy(&self) -> bool {
        matches!(self.axis, SecondAxis::Anisotropy(_))
    }
}

/// The verify facts of `mode`.
pub fn spec(mode: Mode) -> &'static ModeSpec {
    match mode {
        Mode::Roughness => &ROUGHNESS,
        Mode::View => &VIEW,
        Mode::Multiscatter => &MULTISCATTER,
        Mode::Layered => &LAYERED,
        Mode::Anisotropic => &ANISOTROPIC,
        Mode::Glass => &GLASS,
    }
}

/// The verify sweep's roughness values: 0, 0.1, …, 1.
pub fn default_roughness() -> Vec<Roughness> {
    Roughness::grid(11)
}

/// The layered, anisotropic and glass sweeps' roughness values: 0.1, 0.25, 0.5, 0.75, 1
/// (a smooth lobe is a mirror, which the tables hold exactly). Shorter than
/// [`default_roughness`], each of its rows being repeated per index or anisotropy.
pub fn block_roughness() -> Vec<Roughness> {
    [0.1, 0.25, 0.5, 0.75, 1.0]
        .map(|r| Roughness::new(r).expect("in [0, 1]"))
        .to_vec()
}

/// The layered and glass sweeps' indices of refraction: water, glass, and a dense flint.
/// Not diamond's 2.4 by default: there a rough solid glass sphere's noise needs about
/// 1,024 spp (`--ior 2.4`).
pub const IOR_SWEEP: [f64; 3] = [1.33, 1.5, 2.0];

/// The anisotropic sweep's anisotropies: a moderate and a strong stretch along the tangent,
/// and a strong one across it (a negative anisotropy swaps the widths).
pub const ANISOTROPIC_SWEEP: [f64; 3] = [0.5, 0.9, -0.9];

/// Cycles 32 spp keeps the standard error of every sphere's mean ≤ 0.2 % (measured in 3.4,
/// 4.5 and 5.0 over six seeds; 16 spp reaches 0.5 % in 3.4).
const CYCLES: EngineDefaults = EngineDefaults {
    samples: 32,
    judging: Judging {
        // 1 %: five times the largest standard error of a sphere's mean at 32 spp.
        tolerance_percent: 1.0,
        // 1.5 %: a ring holds fewer pixels than a sphere, so it is noisier.
        ring_tolerance_percent: 1.5,
    },
};

/// EEVEE's furnace is deterministic: 1, 64 and 256 samples agree within 0.03 %. It has no
/// noise but its own errors: Next's lighting is 0.8 % dark, and its split-sum table is
/// within 0.5 % of the integrator's.
const EEVEE: EngineDefaults = EngineDefaults {
    samples: 1,
    judging: Judging {
        tolerance_percent: 2.0,
        ring_tolerance_percent: 2.0,
    },
};

/// A solid glass sphere is far noisier (its light crosses many surfaces, each multiplying
/// its weight): at 128 spp GGX r 1 IOR 2 scatters by 0.9 %, so glass takes 256 (5.0.1).
/// Its thresholds are wider (±2 % per sphere, ±3 % per ring, the goal it was built to):
/// the noise is heavy-tailed, its standard error falling only about as n^-1/3 with the
/// samples (GGX r 1 IOR 2.4 in 5.0.1: 1.2 % at 128 spp, 0.6 % at 1,024).
const GLASS_JUDGING: Judging = Judging {
    tolerance_percent: 2.0,
    ring_tolerance_percent: 3.0,
};

const BOTH_COLOR_MODELS: &[ColorModel] = &[ColorModel::Exact, ColorModel::Physical];
/// The anisotropic and glass groups keep the colour exact (colour / E).
const ONLY_EXACT: &[ColorModel] = &[ColorModel::Exact];
const ONLY_EXACT_WHY: &str = "its groups multiply the colour by 1/E";

const EVERY_VIEW_DIRECTION: &str = "This mode corrects every view direction, so both the \
     sphere's mean and every view-cosine ring are judged.";

const ROUGHNESS: ModeSpec = ModeSpec {
    mode: Mode::Roughness,
    roughness: default_roughness,
    axis: SecondAxis::None,
    cycles: CYCLES,
    eevee: EEVEE,
    other_engines_refused: "",
    color_models: BOTH_COLOR_MODELS,
    other_color_models_refused: "",
    white_only: None,
    solid: false,
    uncorrected: "uncorrected",
    corrected: "corrected",
    reference: "Multiscatter GGX",
    row_heading: "distribution",
    legend: None,
    own_target: None,
    scope: "Roughness mode corrects only each sphere's mean brightness (one gain per \
         roughness), not how brightness changes with the view direction: a corrected \
         sphere's centre and rim stay off target in opposite directions (which is \
         brighter depends on the roughness). So only the mean is judged; the rings are \
         shown, not judged, and red and blue rings in the false colour are expected. \
         View mode corrects every view direction.",
    block_plot_title: "Roughness",
};

const VIEW: ModeSpec = ModeSpec {
    mode: Mode::View,
    scope: EVERY_VIEW_DIRECTION,
    block_plot_title: "View",
    ..ROUGHNESS
};

const MULTISCATTER: ModeSpec = ModeSpec {
    mode: Mode::Multiscatter,
    scope: EVERY_VIEW_DIRECTION,
    block_plot_title: "Multiscatter",
    ..ROUGHNESS
};

const LAYERED: ModeSpec = ModeSpec {
    mode: Mode::Layered,
    roughness: block_roughness,
    axis: SecondAxis::Ior(&IOR_SWEEP),
    other_engines_refused: "the layered groups are calibrated for Cycles; in EEVEE's \
         furnace their rings miss 2 %, docs/EEVEE.md",
    uncorrected: "Mix Shader",
    corrected: "layered",
    reference: "Principled BSDF",
    row_heading: "coat",
    legend: Some(
        "uncorrected = Mix Shader(Fresnel(IOR), Diffuse, Glossy) as artists build it; \
         corrected = Gloffuse Layered; reference = Principled BSDF; percentages are of \
         what the layered coat promises",
    ),
    own_target: Some(
        "the target is what the layered coat promises: A + Base Color × (1 − A), with A \
         the coat's albedo, averaged over the sphere (100 % for a white base)",
    ),
    scope: "Layered mode corrects the coat at every view direction, so both the sphere's \
         mean and every view-cosine ring are judged.",
    block_plot_title: "Layered",
    ..ROUGHNESS
};

const ANISOTROPIC: ModeSpec = ModeSpec {
    mode: Mode::Anisotropic,
    roughness: block_roughness,
    axis: SecondAxis::Anisotropy(&ANISOTROPIC_SWEEP),
    other_engines_refused: "EEVEE renders an anisotropic Glossy as an isotropic one, \
         docs/EEVEE.md",
    color_models: ONLY_EXACT,
    other_color_models_refused: ONLY_EXACT_WHY,
    scope: EVERY_VIEW_DIRECTION,
    block_plot_title: "Anisotropic",
    ..ROUGHNESS
};

const GLASS: ModeSpec = ModeSpec {
    mode: Mode::Glass,
    roughness: block_roughness,
    axis: SecondAxis::Ior(&IOR_SWEEP),
    cycles: EngineDefaults {
        samples: 256,
        judging: GLASS_JUDGING,
    },
    eevee: EngineDefaults {
        judging: GLASS_JUDGING,
        ..EEVEE
    },
    other_engines_refused: "the glass groups restore the energy of Cycles' Glass BSDF; \
         EEVEE renders glass its own way, docs/EEVEE.md",
    color_models: ONLY_EXACT,
    other_color_models_refused: ONLY_EXACT_WHY,
    white_only: Some(
        "a coloured glass tints light at every surface it crosses, so a solid sphere's \
         colour has no closed form to judge by",
    ),
    solid: true,
    uncorrected: "Glass BSDF",
    reference: "Multiscatter GGX glass",
    legend: Some(
        "solid spheres, 1,024 bounces: uncorrected = Blender's Glass BSDF; corrected = \
         Gloffuse Glass; reference = Multiscatter GGX glass",
    ),
    scope: "Glass mode corrects the interface at every view direction, light entering and \
         leaving, so both a solid sphere's mean and every view-cosine ring are judged. \
         Light crosses a solid sphere's surfaces many times (1,024 bounces are rendered), \
         so the plain Glass BSDF's sphere has no prediction, and the renders are noisier \
         than a glossy sphere's: hence the wider default tolerances.",
    block_plot_title: "Solid glass",
    ..ROUGHNESS
};

#[cfg(test)]
mod tests {
    use super::*;

    /// Every mode's entry is its own, names its spheres, renders in an engine with samples
    /// and positive thresholds, takes a colour model, and refuses with a reason.
    #[test]
    fn every_mode_has_a_whole_spec() {
        for mode in Mode::ALL {
            let s = spec(mode);
            let key = mode.key();
            assert_eq!(s.mode, mode, "{key}: another mode's entry");
            for name in [
                s.uncorrected,
                s.corrected,
                s.reference,
                s.row_heading,
                s.scope,
            ] {
                assert!(!name.is_empty(), "{key}: a name is missing");
            }
            assert!(!s.block_plot_title.is_empty(), "{key}");
            assert!(!(s.roughness)().is_empty(), "{key}: no roughness sweep");
            match s.axis {
                SecondAxis::None => {}
                SecondAxis::Ior(v) | SecondAxis::Anisotropy(v) => assert!(!v.is_empty(), "{key}"),
            }
            assert!(!mode.engines().is_empty(), "{key}: no engine");
            for engine in [Engine::Cycles, Engine::Eevee] {
                let d = s.defaults(engine);
                assert!(d.samples > 0, "{key} in {}", engine.key());
                assert!(
                    d.judging.tolerance_percent > 0.0,
                    "{key} in {}",
                    engine.key()
                );
                assert!(
                    d.judging.ring_tolerance_percent > 0.0,
                    "{key} in {}",
                    engine.key()
                );
            }
            let refuses_an_engine = mode.engines().len() < 2;
            assert_eq!(
                refuses_an_engine,
                !s.other_engines_refused.is_empty(),
                "{key}"
            );
            assert!(s.color_models.contains(&ColorModel::Exact), "{key}");
            let refuses_a_model = s.color_models.len() < ColorModel::ALL.len();
            assert_eq!(
                refuses_a_model,
                !s.other_color_models_refused.is_empty(),
                "{key}"
            );
        }
    }
}
