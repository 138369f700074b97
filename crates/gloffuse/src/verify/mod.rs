//! ④ Verify: render furnace spheres in one Blender process (`plan`, `render`), read the EXR
//! back (`image`), measure every sphere (`stats`) and judge it (`judge`): predict each row
//! (`predict`), judge it against 100 % and the prediction, and pick the notes (`notes`). The
//! verdict is data (`verdict`); `crate::report` renders it.

pub mod image;
pub mod judge;
pub mod modes;
pub mod notes;
pub mod plan;
pub mod predict;
pub mod render;
pub mod stats;
pub mod verdict;

pub use judge::judge;
pub use modes::{
    ANISOTROPIC_SWEEP, IOR_SWEEP, ModeSpec, SecondAxis, block_roughness, default_roughness, spec,
};
pub use plan::{Block, Plan, PlanReference, PlanRow, RenderSettings, Role};
pub use render::{RenderInfo, Rendered, render};
pub use verdict::{Judging, Note, ReferenceSphere, Row, Sweep, VerifyReport, WorstSphere};

use crate::blender::{Blender, BlenderOptions};
use crate::error::{Error, Field, Hint};
use crate::fit::Coefficients;
use crate::generate::tables::GlassTable;
use crate::generate::{ColorModel, Curves, GenerateParams, Mode};
use crate::measure::{Anisotropy, BlenderVersion, Distribution, Engine, Roughness, coat};
use crate::progress::Progress;

/// What `verify` renders and how it judges it. An input left empty or `None` takes the
/// default of the mode and engine ([`VerifyOptions::resolve`]), so a caller who sets only
/// the mode gets the sweep the command line renders for it.
#[derive(Clone, Debug, PartialEq)]
pub struct VerifyOptions {
    /// A preset or coefficients file (else the preset of the Blender used).
    pub coefficients: Option<String>,
    /// The distributions to check (empty: all the coefficients hold).
    pub distributions: Vec<Distribution>,
    /// The roughness values of the sweep, each once (empty: the mode's, [`ModeSpec::roughness`]).
    pub roughness: Vec<Roughness>,
    /// Layered and glass mode: the indices of refraction, each once, from 1 to
    /// [`coat::IOR_MAX`] (empty: [`IOR_SWEEP`]; every other mode: none).
    pub ior: Vec<f64>,
    /// Anisotropic mode: the lobes' anisotropies, each once, from −0.99 to 0.99 (empty:
    /// [`ANISOTROPIC_SWEEP`]; every other mode: none).
    pub anisotropy: Vec<f64>,
    /// The engine that renders the sweep.
    pub engine: Engine,
    /// Pixels per sphere cell.
    pub cell: u32,
    /// Samples per pixel (`None`: the mode's and engine's, [`ModeSpec::defaults`]).
    pub samples: Option<u32>,
    /// Cycles' random seed.
    pub seed: u32,
    pub mode: Mode,
    /// The spheres' colour (linear RGB, each in [0, 1]).
    pub color: [f64; 3],
    /// What the corrections promise for a colour.
    pub color_model: ColorModel,
    /// Allowed |mean − 100 %| of a corrected sphere, in percent (`None`: the mode's and
    /// engine's, [`ModeSpec::defaults`]).
    pub tolerance_percent: Option<f64>,
    /// Allowed |ring mean − 100 %| in the view modes, in percent (`None`: the sweep's).
    pub ring_tolerance_percent: Option<f64>,
    pub blender: BlenderOptions,
}

/// A verify sweep with every default filled in: what one run renders and judges by.
#[derive(Clone, Debug, PartialEq)]
pub struct Resolved {
    pub roughness: Vec<Roughness>,
    pub ior: Vec<f64>,
    pub anisotropy: Vec<f64>,
    pub render: RenderSettings,
    pub judging: Judging,
}

impl VerifyOptions {
    /// The options with each input left unset taken from the mode and engine: the one place
    /// verify's defaults are chosen, for the command line and every other caller.
    pub fn resolve(&self) -> Resolved {
        let spec = spec(self.mode);
        let defaults = spec.defaults(self.engine);
        let given_or = |given: &[f64], default: &[f64]| match given.is_empty() {
            true => default.to_vec(),
            false => given.to_vec(),
        };
        Resolved {
            roughness: match self.roughness.is_empty() {
                true => (spec.roughness)(),
                false => self.roughness.clone(),
            },
            ior: match spec.axis {
                SecondAxis::Ior(sweep) => given_or(&self.ior, sweep),
                _ => self.ior.clone(),
            },
            anisotropy: match spec.axis {
                SecondAxis::Anisotropy(sweep) => given_or(&self.anisotropy, sweep),
                _ => self.anisotropy.clone(),
            },
            render: RenderSettings {
                cell: self.cell,
                samples: self.samples.unwrap_or(defaults.samples),
                seed: self.seed,
                ..RenderSettings::for_engine(self.engine)
            },
            judging: Judging {
                tolerance_percent: self
                    .tolerance_percent
                    .unwrap_or(defaults.judging.tolerance_percent),
                ring_tolerance_percent: self
                    .ring_tolerance_percent
                    .unwrap_or(defaults.judging.ring_tolerance_percent),
            },
        }
    }
}

impl Default for VerifyOptions {
    fn default() -> Self {
        let render = RenderSettings::default();
        VerifyOptions {
            coefficients: None,
            distributions: Vec::new(),
            roughness: Vec::new(),
            ior: Vec::new(),
            anisotropy: Vec::new(),
            engine: render.engine,
            cell: render.cell,
            samples: None,
            seed: render.seed,
            mode: Mode::Roughness,
            color: [1.0; 3],
            color_model: ColorModel::Exact,
            tolerance_percent: None,
            ring_tolerance_percent: None,
            blender: BlenderOptions::default(),
        }
    }
}

/// A verify run: the verdict and what it was judged from.
pub struct Verification {
    pub report: VerifyReport,
    pub rendered: Rendered,
}

/// Checks the options, finds Blender, then [`verify_with`]. Bad input fails before Blender
/// is looked for.
pub fn verify(v: &VerifyOptions, progress: &dyn Progress) -> Result<Verification, Error> {
    check_options(v, &v.resolve())?;
    check_color(v.color)?;
    if let Some(name) = &v.coefficients {
        distributions_of(v, &Coefficients::load(name)?, name)?;
    }
    let blender = v.blender.find(progress)?;
    verify_with(&blender, v, progress)
}

/// Renders the verify sweep in `blender` and judges it.
pub fn verify_with(
    blender: &Blender,
    v: &VerifyOptions,
    progress: &dyn Progress,
) -> Result<Verification, Error> {
    let resolved = v.resolve();
    check_options(v, &resolved)?;
    let (coefficients, source) =
        Coefficients::load_or_preset(v.coefficients.as_deref(), v.engine, blender.version)?;
    let distributions = distributions_of(v, &coefficients, &source)?;
    let distributions = with_groups(v, distributions, blender.version)?;
    let blocks = blocks(&resolved);
    let plan = Plan::verify(
        &distributions,
        &resolved.roughness,
        &blocks,
        resolved.render,
    );
    let curves = Curves::Pinned {
        coefficients: &coefficients,
        name: &source,
    };
    let groups = GenerateParams::new(
        curves,
        &[blender.version.masking()],
        &[v.mode],
        v.color_model,
    )?;
    let rendered = render(
        blender, &plan, &groups, v.mode, v.color, &v.blender, progress,
    )?;
    let sweep = Sweep {
        coefficients: &coefficients,
        source: &source,
        distributions: &distributions,
        roughness: &resolved.roughness,
        blocks: &blocks,
        mode: v.mode,
        color: v.color,
        color_model: v.color_model,
    };
    let report = judge(&rendered, &sweep, resolved.judging, blender.version);
    Ok(Verification { report, rendered })
}

/// What can be checked before Blender is found (`resolved`: the options' defaults filled).
fn check_options(v: &VerifyOptions, resolved: &Resolved) -> Result<(), Error> {
    check_roughness(&resolved.roughness)?;
    check_ior(v.mode, &resolved.ior)?;
    check_anisotropy(v.mode, &resolved.anisotropy)?;
    check_engine(v.engine, v.mode)?;
    check_color_model(v.mode, v.color_model)?;
    check_white(v.mode, v.color)
}

/// A colour the mode's spheres may take (glass's are white).
fn check_white(mode: Mode, color: [f64; 3]) -> Result<(), Error> {
    if let Some(why) = spec(mode).white_only
        && color != [1.0; 3]
    {
        let text: Vec<String> = color.iter().map(|c| c.to_string()).collect();
        return Err(Error::input(
            Field::Color,
            text.join(","),
            Hint::new(
                format!("1,1,1 with {{}} {} ({why})", mode.key()),
                [Field::Mode],
            ),
        ));
    }
    Ok(())
}

/// Each block of rows: the indices (layered mode) or the anisotropies (anisotropic mode).
fn blocks(resolved: &Resolved) -> Vec<Block> {
    let ior = resolved.ior.iter().map(|&n| Block::Ior(n));
    ior.chain(resolved.anisotropy.iter().map(|&a| Block::Anisotropy(a)))
        .collect()
}

/// An engine the mode renders in (EEVEE renders the roughness and view modes only).
fn check_engine(engine: Engine, mode: Mode) -> Result<(), Error> {
    if !mode.engines().contains(&engine) {
        let allowed: Vec<&str> = mode.engines().iter().map(|e| e.key()).collect();
        return Err(Error::input(
            Field::Engine,
            engine.key(),
            Hint::new(
                format!(
                    "{} with {{}} {} ({})",
                    allowed.join(" or "),
                    mode.key(),
                    spec(mode).other_engines_refused
                ),
                [Field::Mode],
            ),
        ));
    }
    Ok(())
}

/// A colour model the mode's groups promise (the anisotropic and glass groups keep the
/// colour exact, colour / E); no other promise is judged.
fn check_color_model(mode: Mode, model: ColorModel) -> Result<(), Error> {
    let spec = spec(mode);
    if !spec.color_models.contains(&model) {
        let allowed: Vec<&str> = spec.color_models.iter().map(|m| m.key()).collect();
        return Err(Error::input(
            Field::ColorModel,
            model.key(),
            Hint::new(
                format!(
                    "{} with {{}} {} ({})",
                    allowed.join(" or "),
                    mode.key(),
                    spec.other_color_models_refused
                ),
                [Field::Mode],
            ),
        ));
    }
    Ok(())
}

/// The anisotropies of a mode that sweeps them (anisotropic) are each given once and in
/// [−0.99, 0.99] (what Cycles clamps to); every other mode takes none.
fn check_anisotropy(mode: Mode, anisotropy: &[f64]) -> Result<(), Error> {
    if !spec(mode).takes_anisotropy() {
        return match anisotropy.first() {
            Some(a) => Err(Error::input(
                Field::Anisotropy,
                a,
                Hint::new(
                    format!(
                        "no anisotropy: {{}} goes with {{}} {}",
                        modes_taking(ModeSpec::takes_anisotropy)
                    ),
                    [Field::Anisotropy, Field::Mode],
                ),
            )),
            None => Ok(()),
        };
    }
    for (i, &a) in anisotropy.iter().enumerate() {
        let clamped = Anisotropy::new(a).ok().map(Anisotropy::get);
        if clamped != Some(a) || anisotropy[..i].contains(&a) {
            return Err(Error::input(
                Field::Anisotropy,
                a,
                "each anisotropy once, from -0.99 to 0.99 (Cycles clamps beyond)",
            ));
        }
    }
    Ok(())
}

/// A colour every channel of which is finite and in [0, 1].
pub fn check_color(color: [f64; 3]) -> Result<(), Error> {
    if color.iter().all(|c| (0.0..=1.0).contains(c)) {
        return Ok(());
    }
    let text: Vec<String> = color.iter().map(|c| c.to_string()).collect();
    Err(Error::input(
        Field::Color,
        text.join(","),
        "three linear values from 0 to 1, e.g. 0.95,0.64,0.54",
    ))
}

/// The indices of refraction of a mode that sweeps them (layered, glass) are each given
/// once and within the tables (the coat's and the glass's share their axis); every other
/// mode takes none.
fn check_ior(mode: Mode, ior: &[f64]) -> Result<(), Error> {
    if !spec(mode).takes_ior() {
        return match ior.first() {
            Some(n) => Err(Error::input(
                Field::Ior,
                n,
                Hint::new(
                    format!(
                        "no index of refraction: {{}} goes with {{}} {}",
                        modes_taking(ModeSpec::takes_ior)
                    ),
                    [Field::Ior, Field::Mode],
                ),
            )),
            None => Ok(()),
        };
    }
    for (i, n) in ior.iter().enumerate() {
        let range = 1.0..=coat::IOR_MAX;
        if !range.contains(n) || ior[..i].contains(n) {
            return Err(Error::input(
                Field::Ior,
                n,
                format!("each index once, from 1 to {}", coat::IOR_MAX),
            ));
        }
    }
    Ok(())
}

/// The modes whose spec answers yes, for a hint: `layered or glass`.
fn modes_taking(takes: fn(&ModeSpec) -> bool) -> String {
    let keys: Vec<&str> = Mode::ALL
        .into_iter()
        .filter(|&m| takes(spec(m)))
        .map(Mode::key)
        .collect();
    keys.join(" or ")
}

fn check_roughness(roughness: &[Roughness]) -> Result<(), Error> {
    for (i, r) in roughness.iter().enumerate() {
        if roughness[..i].contains(r) {
            return Err(Error::input(
                Field::Roughness,
                r.get(),
                "each roughness once",
            ));
        }
    }
    Ok(())
}

/// A sweep checks the distributions whose group of the mode Blender `version` renders
/// ([`Mode::renders_group_of`]: anisotropic GGX, and Beckmann from 3.5; glass GGX and
/// Beckmann), and glass mode none in 3.5 (whose glass neither table describes). A
/// distribution named outright that has none is an error.
fn with_groups(
    v: &VerifyOptions,
    distributions: Vec<Distribution>,
    version: BlenderVersion,
) -> Result<Vec<Distribution>, Error> {
    if v.mode == Mode::Glass && !GlassTable::builds_groups_for(version) {
        return Err(Error::input(
            Field::Mode,
            v.mode.key(),
            format!(
                "another mode, or another Blender than {version} for glass (its Glass BSDF \
                 has 3.4's two closures with 3.6's masking, which neither glass table \
                 describes, so gloffuse builds no glass groups for it)"
            ),
        ));
    }
    let has_group = |d: Distribution| v.mode.renders_group_of(d, version);
    if let Some(&d) = v.distributions.iter().find(|&&d| !has_group(d)) {
        return Err(Error::input(
            Field::Distribution,
            d.key(),
            format!(
                "ggx{} (Blender {version} has no {} group of {})",
                if has_group(Distribution::Beckmann) {
                    " or beckmann"
                } else {
                    ""
                },
                v.mode.key(),
                d.label()
            ),
        ));
    }
    Ok(distributions
        .into_iter()
        .filter(|&d| has_group(d))
        .collect())
}

/// The distributions to check (all in the coefficients unless some are named), each of
/// which the coefficients must hold.
fn distributions_of(
    v: &VerifyOptions,
    coefficients: &Coefficients,
    source: &str,
) -> Result<Vec<Distribution>, Error> {
    if v.distributions.is_empty() {
        return Ok(coefficients.distributions.keys().copied().collect());
    }
    for d in &v.distributions {
        if !coefficients.distributions.contains_key(d) {
            let have: Vec<_> = coefficients.distributions.keys().map(|d| d.key()).collect();
            return Err(Error::input(
                Field::Distribution,
                d.key(),
                format!("one the coefficients '{source}' hold: {}", have.join(", ")),
            ));
        }
    }
    Ok(v.distributions.clone())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn version(v: &str) -> BlenderVersion {
        v.parse().unwrap()
    }

    fn roughness(values: &[f64]) -> Vec<Roughness> {
        values.iter().map(|&r| Roughness::new(r).unwrap()).collect()
    }

    /// Each mode and engine with nothing set resolves to the sweep the command line runs
    /// with no flags (the numbers written out here, not read from the constants).
    #[test]
    fn each_mode_with_nothing_set_resolves_to_its_defaults() {
        let grid = roughness(&[0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0]);
        let block = roughness(&[0.1, 0.25, 0.5, 0.75, 1.0]);
        let iors = vec![1.33, 1.5, 2.0];
        let (none, anisotropies) = (vec![], vec![0.5, 0.9, -0.9]);
        // One line a case: mode, engine, roughness, IORs, anisotropies, spp, tolerances.
        #[rustfmt::skip]
        let cases = [
            (Mode::Roughness, Engine::Cycles, &grid, &none, &none, 32, 1.0, 1.5),
            (Mode::View, Engine::Cycles, &grid, &none, &none, 32, 1.0, 1.5),
            (Mode::Multiscatter, Engine::Cycles, &grid, &none, &none, 32, 1.0, 1.5),
            (Mode::Roughness, Engine::Eevee, &grid, &none, &none, 1, 2.0, 2.0),
            (Mode::View, Engine::Eevee, &grid, &none, &none, 1, 2.0, 2.0),
            (Mode::Multiscatter, Engine::Eevee, &grid, &none, &none, 1, 2.0, 2.0),
            (Mode::Layered, Engine::Cycles, &block, &iors, &none, 32, 1.0, 1.5),
            (Mode::Anisotropic, Engine::Cycles, &block, &none, &anisotropies, 32, 1.0, 1.5),
            (Mode::Glass, Engine::Cycles, &block, &iors, &none, 256, 2.0, 3.0),
        ];
        for (mode, engine, roughness, ior, anisotropy, samples, tolerance, ring) in cases {
            let v = VerifyOptions {
                mode,
                engine,
                ..VerifyOptions::default()
            };
            let resolved = v.resolve();
            let case = format!("{} in {}", mode.key(), engine.key());
            assert_eq!(&resolved.roughness, roughness, "{case}");
            assert_eq!(&resolved.ior, ior, "{case}");
            assert_eq!(&resolved.anisotropy, anisotropy, "{case}");
            let render = resolved.render;
            assert_eq!(
                (render.engine, render.cell, render.samples, render.seed),
                (engine, 64, samples, 0),
                "{case}"
            );
            assert_eq!(
                (
                    resolved.judging.tolerance_percent,
                    resolved.judging.ring_tolerance_percent
                ),
                (tolerance, ring),
                "{case}"
            );
            check_options(&v, &resolved).unwrap_or_else(|e| panic!("{case}: {e}"));
        }
    }

    /// What a caller sets is kept, whatever the mode's default.
    #[test]
    fn what_is_set_overrides_the_defaults() {
        let v = VerifyOptions {
            mode: Mode::Glass,
            roughness: roughness(&[0.5]),
            ior: vec![1.2],
            samples: Some(64),
            tolerance_percent: Some(4.0),
            ..VerifyOptions::default()
        };
        let resolved = v.resolve();
        assert_eq!(resolved.roughness, roughness(&[0.5]));
        assert_eq!(resolved.ior, [1.2]);
        assert_eq!(resolved.render.samples, 64);
        assert_eq!(resolved.judging.tolerance_percent, 4.0);
        assert_eq!(resolved.judging.ring_tolerance_percent, 3.0);
        // An index in a mode that takes none is kept, so the check refuses it.
        let roughness_mode = VerifyOptions {
            ior: vec![1.5],
            ..VerifyOptions::default()
        };
        let refused = check_options(&roughness_mode, &roughness_mode.resolve()).unwrap_err();
        assert!(
            refused.to_string().contains("index of refraction"),
            "{refused}"
        );
    }

    /// Glass mode sweeps GGX and Beckmann in every Blender that gets glass groups, and
    /// refuses 3.5 (3.4's two closures with 3.6's masking) outright.
    #[test]
    fn glass_sweeps_the_blenders_with_glass_groups() {
        let v = VerifyOptions {
            mode: Mode::Glass,
            ..VerifyOptions::default()
        };
        let all = vec![
            Distribution::Beckmann,
            Distribution::Ggx,
            Distribution::AshikhminShirley,
        ];
        for ok in ["3.4", "3.6", "4.5", "5.0"] {
            let swept = with_groups(&v, all.clone(), version(ok)).unwrap();
            assert_eq!(swept, [Distribution::Beckmann, Distribution::Ggx], "{ok}");
        }
        let refused = with_groups(&v, all.clone(), version("3.5")).unwrap_err();
        assert!(
            refused.to_string().contains("than 3.5 for glass"),
            "{refused}"
        );
        let named = VerifyOptions {
            distributions: vec![Distribution::AshikhminShirley],
            ..v
        };
        let refused = with_groups(&named, all, version("4.5")).unwrap_err();
        assert!(
            refused.to_string().contains("no glass group of Ashikhmin"),
            "{refused}"
        );
    }
}
