//! ④ Verify: render furnace spheres in one Blender process (`plan`, `render`), read the EXR
//! back (`image`), measure every sphere (`stats`) and judge it (`judge`): predict each row
//! (`predict`), judge it against 100 % and the prediction, and pick the notes (`notes`). The
//! verdict is data (`verdict`); `crate::report` renders it.

pub mod image;
pub mod judge;
pub mod notes;
pub mod plan;
pub mod predict;
pub mod render;
pub mod stats;
pub mod verdict;

pub use judge::judge;
pub use plan::reference_label;
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

/// What `verify` renders and how it judges it.
#[derive(Clone, Debug, PartialEq)]
pub struct VerifyOptions {
    /// A preset or coefficients file (else the preset of the Blender used).
    pub coefficients: Option<String>,
    /// The distributions to check (empty: all the coefficients hold).
    pub distributions: Vec<Distribution>,
    /// The roughness values of the sweep, each once.
    pub roughness: Vec<Roughness>,
    /// Layered mode: the coats' indices of refraction, each once, from 1 to
    /// [`coat::IOR_MAX`] (every other mode: none).
    pub ior: Vec<f64>,
    /// Anisotropic mode: the lobes' anisotropies, each once, from −0.99 to 0.99 (every
    /// other mode: none).
    pub anisotropy: Vec<f64>,
    pub render: RenderSettings,
    pub mode: Mode,
    /// The spheres' colour (linear RGB, each in [0, 1]).
    pub color: [f64; 3],
    /// What the corrections promise for a colour.
    pub color_model: ColorModel,
    pub judging: Judging,
    pub blender: BlenderOptions,
}

/// The verify sweep's roughness values: 0, 0.1, …, 1.
pub fn default_roughness() -> Vec<Roughness> {
    Roughness::grid(11)
}

/// The layered and anisotropic sweeps' roughness values: 0.1, 0.25, 0.5, 0.75, 1 (a smooth
/// lobe is a mirror, which the tables hold exactly).
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

impl Default for VerifyOptions {
    fn default() -> Self {
        VerifyOptions {
            coefficients: None,
            distributions: Vec::new(),
            roughness: default_roughness(),
            ior: Vec::new(),
            anisotropy: Vec::new(),
            render: RenderSettings::default(),
            mode: Mode::Roughness,
            color: [1.0; 3],
            color_model: ColorModel::Exact,
            judging: Judging::default(),
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
    check_options(v)?;
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
    check_options(v)?;
    let (coefficients, source) =
        Coefficients::load_or_preset(v.coefficients.as_deref(), v.render.engine, blender.version)?;
    let distributions = distributions_of(v, &coefficients, &source)?;
    let distributions = with_groups(v, distributions, blender.version)?;
    let blocks = blocks(v);
    let plan = Plan::verify(&distributions, &v.roughness, &blocks, v.render);
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
        roughness: &v.roughness,
        blocks: &blocks,
        mode: v.mode,
        color: v.color,
        color_model: v.color_model,
    };
    let report = judge(&rendered, &sweep, v.judging, blender.version);
    Ok(Verification { report, rendered })
}

/// What can be checked before Blender is found.
fn check_options(v: &VerifyOptions) -> Result<(), Error> {
    check_roughness(&v.roughness)?;
    check_ior(v.mode, &v.ior)?;
    check_anisotropy(v.mode, &v.anisotropy)?;
    check_engine(v.render.engine, v.mode)?;
    check_color_model(v.mode, v.color_model)?;
    check_glass_color(v.mode, v.color)
}

/// Glass mode's spheres are white: a coloured glass tints light at every surface it
/// crosses, so a solid sphere's colour in the furnace has no closed form to judge by.
fn check_glass_color(mode: Mode, color: [f64; 3]) -> Result<(), Error> {
    if mode == Mode::Glass && color != [1.0; 3] {
        let text: Vec<String> = color.iter().map(|c| c.to_string()).collect();
        return Err(Error::input(
            Field::Color,
            text.join(","),
            Hint::new(
                "1,1,1 with {} glass (a coloured glass tints light at every surface it \
                 crosses, so a solid sphere's colour has no closed form to judge by)",
                [Field::Mode],
            ),
        ));
    }
    Ok(())
}

/// Each block of rows: the indices (layered mode) or the anisotropies (anisotropic mode).
fn blocks(v: &VerifyOptions) -> Vec<Block> {
    let ior = v.ior.iter().map(|&n| Block::Ior(n));
    ior.chain(v.anisotropy.iter().map(|&a| Block::Anisotropy(a)))
        .collect()
}

/// EEVEE renders the roughness and view modes; the layered groups are Cycles' only (in
/// EEVEE's furnace their rings miss 2 %), EEVEE ignores anisotropy, and the glass groups
/// restore Cycles' glass.
fn check_engine(engine: Engine, mode: Mode) -> Result<(), Error> {
    let why = match mode {
        Mode::Layered => {
            "the layered groups are calibrated for Cycles; in EEVEE's furnace their rings \
             miss 2 %, docs/EEVEE.md"
        }
        Mode::Anisotropic => {
            "EEVEE renders an anisotropic Glossy as an isotropic one, docs/EEVEE.md"
        }
        Mode::Glass => {
            "the glass groups restore the energy of Cycles' Glass BSDF; EEVEE renders glass \
             its own way, docs/EEVEE.md"
        }
        _ => return Ok(()),
    };
    if engine == Engine::Eevee {
        return Err(Error::input(
            Field::Engine,
            engine.key(),
            Hint::new(
                format!("cycles with {{}} {} ({why})", mode.key()),
                [Field::Mode],
            ),
        ));
    }
    Ok(())
}

/// The anisotropic and glass groups keep the colour exact (colour / E); no other promise is
/// judged.
fn check_color_model(mode: Mode, model: ColorModel) -> Result<(), Error> {
    if matches!(mode, Mode::Anisotropic | Mode::Glass) && model != ColorModel::Exact {
        return Err(Error::input(
            Field::ColorModel,
            model.key(),
            Hint::new(
                format!(
                    "exact with {{}} {} (its groups multiply the colour by 1/E)",
                    mode.key()
                ),
                [Field::Mode],
            ),
        ));
    }
    Ok(())
}

/// Anisotropic mode needs anisotropies, each once and in [−0.99, 0.99] (what Cycles
/// clamps to); every other mode takes none.
fn check_anisotropy(mode: Mode, anisotropy: &[f64]) -> Result<(), Error> {
    if mode != Mode::Anisotropic {
        return match anisotropy.first() {
            Some(a) => Err(Error::input(
                Field::Anisotropy,
                a,
                Hint::new(
                    "no anisotropy: {} goes with {} anisotropic",
                    [Field::Anisotropy, Field::Mode],
                ),
            )),
            None => Ok(()),
        };
    }
    if anisotropy.is_empty() {
        return Err(Error::input(
            Field::Anisotropy,
            "",
            Hint::new("at least one anisotropy for {} anisotropic", [Field::Mode]),
        ));
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

/// Layered and glass mode need indices of refraction, each once and within the tables
/// (the coat's and the glass's share their axis); every other mode takes none.
fn check_ior(mode: Mode, ior: &[f64]) -> Result<(), Error> {
    if !matches!(mode, Mode::Layered | Mode::Glass) {
        return match ior.first() {
            Some(n) => Err(Error::input(
                Field::Ior,
                n,
                Hint::new(
                    "no index of refraction: {} goes with {} layered or glass",
                    [Field::Ior, Field::Mode],
                ),
            )),
            None => Ok(()),
        };
    }
    if ior.is_empty() {
        return Err(Error::input(
            Field::Ior,
            "",
            Hint::new(
                format!("at least one index of refraction for {{}} {}", mode.key()),
                [Field::Mode],
            ),
        ));
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

/// Anisotropic mode sweeps the distributions whose anisotropic group Blender `version`
/// builds: GGX, and Beckmann from 3.5 (Cycles 3.0–3.4 sample another lobe than they
/// evaluate); glass mode GGX and Beckmann, in every Blender but 3.5 (whose glass neither
/// table describes). A distribution named outright that has none is an error.
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
    if !matches!(v.mode, Mode::Anisotropic | Mode::Glass) {
        return Ok(distributions);
    }
    // Past the refusal above, every glass distribution but Ashikhmin–Shirley has a group.
    let has_group = |d: Distribution| {
        d != Distribution::AshikhminShirley
            && (v.mode == Mode::Glass || version.renders_anisotropic(d))
    };
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
