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
pub use plan::{Plan, PlanReference, PlanRow, RenderSettings, Role};
pub use render::{RenderInfo, Rendered, render};
pub use verdict::{Judging, Note, ReferenceSphere, Row, Sweep, VerifyReport, WorstSphere};

use crate::blender::{Blender, BlenderOptions};
use crate::error::{Error, Field, Hint};
use crate::fit::Coefficients;
use crate::generate::{ColorModel, Curves, GenerateParams, Mode};
use crate::measure::{Distribution, Engine, Roughness, coat};
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

/// The layered sweep's roughness values: 0.1, 0.25, 0.5, 0.75, 1 (a smooth coat is a
/// mirror, which the table holds exactly).
pub fn layered_roughness() -> Vec<Roughness> {
    [0.1, 0.25, 0.5, 0.75, 1.0]
        .map(|r| Roughness::new(r).expect("in [0, 1]"))
        .to_vec()
}

/// The layered sweep's indices of refraction: water, glass, and a dense flint.
pub const LAYERED_IOR: [f64; 3] = [1.33, 1.5, 2.0];

impl Default for VerifyOptions {
    fn default() -> Self {
        VerifyOptions {
            coefficients: None,
            distributions: Vec::new(),
            roughness: default_roughness(),
            ior: Vec::new(),
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
    check_mode(v.mode)?;
    check_roughness(&v.roughness)?;
    check_ior(v.mode, &v.ior)?;
    check_color(v.color)?;
    check_engine(v.render.engine, v.mode)?;
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
    check_mode(v.mode)?;
    check_roughness(&v.roughness)?;
    check_ior(v.mode, &v.ior)?;
    check_engine(v.render.engine, v.mode)?;
    let (coefficients, source) =
        Coefficients::load_or_preset(v.coefficients.as_deref(), v.render.engine, blender.version)?;
    let distributions = distributions_of(v, &coefficients, &source)?;
    let plan = Plan::verify(&distributions, &v.roughness, &v.ior, v.render);
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
        ior: &v.ior,
        mode: v.mode,
        color: v.color,
        color_model: v.color_model,
    };
    let report = judge(&rendered, &sweep, v.judging, blender.version);
    Ok(Verification { report, rendered })
}

/// The modes a verify sweep judges: not yet the anisotropic groups, whose sweep needs a
/// tangent per sphere and an anisotropy per row.
fn check_mode(mode: Mode) -> Result<(), Error> {
    if mode == Mode::Anisotropic {
        return Err(Error::input(
            Field::Mode,
            mode.key(),
            "roughness, view, multiscatter or layered (verify does not judge the anisotropic \
             groups yet; tests/anisotropic_e2e.rs renders them in the furnace)",
        ));
    }
    Ok(())
}

/// EEVEE renders the roughness and view modes; the layered groups are Cycles' only (in
/// EEVEE's furnace their rings miss 2 %).
fn check_engine(engine: Engine, mode: Mode) -> Result<(), Error> {
    if engine == Engine::Eevee && mode == Mode::Layered {
        return Err(Error::input(
            Field::Engine,
            engine.key(),
            Hint::new(
                "cycles with {} layered (the layered groups are calibrated for Cycles; in \
                 EEVEE's furnace their rings miss 2 %, docs/EEVEE.md)",
                [Field::Mode],
            ),
        ));
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

/// Layered mode needs indices of refraction, each once and within the coat tables; every
/// other mode takes none.
fn check_ior(mode: Mode, ior: &[f64]) -> Result<(), Error> {
    if mode != Mode::Layered {
        return match ior.first() {
            Some(n) => Err(Error::input(
                Field::Ior,
                n,
                Hint::new(
                    "no index of refraction: {} goes with {} layered",
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
                "at least one index of refraction for {} layered",
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
