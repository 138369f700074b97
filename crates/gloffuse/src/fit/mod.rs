//! ② Fit: correction curves `f(r)` by constrained least squares (`curve`) and the versioned
//! coefficients file that holds one curve per distribution (`coefficients`).

pub mod coefficients;
pub mod curve;

pub use coefficients::{
    Coefficients, ColorSpace, FitSpec, Provenance, Source, Target, preset_for, preset_for_masking,
};
pub use curve::{Curve, Fit, Point, Residuals, Variable, Weighting, fit_polynomial};

use std::path::PathBuf;

use serde::Serialize;

use crate::error::{Error, Field, Hint};
use crate::measure::{BlenderVersion, Distribution, Engine};
use crate::output::check_destination;

/// The degree of a fit through hand points unless one is given: the seed's cubic.
pub const POINTS_DEGREE: usize = 3;

/// `gloffuse fit --point`: a coefficients file holding one distribution's curve through
/// hand-measured brightness points.
pub fn fit_points(
    distribution: Distribution,
    points: &[Point],
    degree: usize,
    weighting: Weighting,
    target: Target,
    engine: Engine,
    version: BlenderVersion,
) -> Result<Coefficients, Error> {
    let spec = FitSpec {
        degree,
        weighting,
        target,
        masking: engine.masking(version.masking()),
        engine,
        provenance: Provenance {
            source: Source::Points,
            blender_version: None,
            samples: None,
            resolution: None,
            points: 0,
            date: Some(coefficients::today()),
            note: Some(
                points
                    .iter()
                    .map(|p| format!("{}:{}", p.roughness, p.percent))
                    .collect::<Vec<_>>()
                    .join(" "),
            ),
        },
    };
    Coefficients::fit(
        format!("{distribution} fit"),
        format!("Fitted by hand to {} points.", points.len()),
        &spec,
        [(distribution, points.to_vec())],
    )
}

/// What `fit` is asked for: a curve through hand-measured points of one distribution, or
/// (`from_integrator`) the curves of all three distributions from gloffuse's integrator.
#[derive(Clone, Debug, PartialEq)]
pub struct FitOptions {
    pub from_integrator: bool,
    pub distribution: Option<Distribution>,
    pub points: Vec<Point>,
    /// [`POINTS_DEGREE`] or [`coefficients::INTEGRATOR_DEGREE`] unless given.
    pub degree: Option<usize>,
    pub weighting: Weighting,
    pub target: Target,
    pub engine: Engine,
    pub blender_version: BlenderVersion,
    /// Where to write the coefficients file.
    pub out: Option<PathBuf>,
}

/// The coefficients a fit made, and the file they were written to.
#[derive(Clone, Debug)]
pub struct Fitted {
    pub coefficients: Coefficients,
    pub wrote: Option<PathBuf>,
}

/// Fits as `options` say and writes the coefficients file if asked to (its destination is
/// checked before any fitting).
pub fn fit(options: &FitOptions) -> Result<Fitted, Error> {
    if let Some(path) = &options.out {
        check_destination(path)?;
    }
    let coefficients = if options.from_integrator {
        from_integrator(options)?
    } else {
        from_points(options)?
    };
    if let Some(path) = &options.out {
        coefficients.write(path)?;
    }
    Ok(Fitted {
        coefficients,
        wrote: options.out.clone(),
    })
}

fn from_integrator(options: &FitOptions) -> Result<Coefficients, Error> {
    if let Some(d) = options.distribution {
        return Err(Error::input(
            Field::Distribution,
            d,
            Hint::new(
                "nothing with {} integrator (it fits all three distributions)",
                [Field::FitSource],
            ),
        ));
    }
    Coefficients::from_integrator(
        options.engine,
        options.blender_version,
        options.degree.unwrap_or(coefficients::INTEGRATOR_DEGREE),
        options.target,
        options.weighting,
        Some(coefficients::today()),
    )
}

fn from_points(options: &FitOptions) -> Result<Coefficients, Error> {
    let Some(d) = options.distribution else {
        return Err(Error::input(
            Field::Arguments,
            "(no distribution)",
            Hint::new(
                "{} D with {} R:PERCENT values, or {} integrator",
                [Field::Distribution, Field::Point, Field::FitSource],
            ),
        ));
    };
    if options.points.is_empty() {
        return Err(Error::input(
            Field::Arguments,
            "(no point)",
            Hint::new(
                "at least one {} ROUGHNESS:PERCENT (e.g. {} 0.5:97 {} 1:71), or {} integrator",
                [Field::Point, Field::Point, Field::Point, Field::FitSource],
            ),
        ));
    }
    fit_points(
        d,
        &options.points,
        options.degree.unwrap_or(POINTS_DEGREE),
        options.weighting,
        options.target,
        options.engine,
        options.blender_version,
    )
}

/// A fit's curves as `fit --json` prints them: `{"fits": [...]}`.
#[derive(Clone, Debug, Serialize)]
pub struct FitSummary {
    pub fits: Vec<FitRow>,
}

/// One distribution's curve; `a`–`d` are the seed's cubic `a r³ + b r² + c r + d` (0 past
/// the degree). Keys in alphabetical order, as the command has always printed them.
#[derive(Clone, Debug, Serialize)]
pub struct FitRow {
    pub a: f64,
    pub b: f64,
    pub c: f64,
    pub coefficients_ascending: Vec<f64>,
    pub curve: Curve,
    pub d: f64,
    pub degree: usize,
    pub distribution: Distribution,
    pub residuals: Residuals,
    pub weighting: Weighting,
}

impl FitSummary {
    pub fn of(coefficients: &Coefficients) -> Self {
        let fits = coefficients
            .distributions
            .iter()
            .map(|(&distribution, e)| {
                let n = &e.curve.numerator;
                let c = |k: usize| n.get(k).copied().unwrap_or(0.0);
                FitRow {
                    a: c(3),
                    b: c(2),
                    c: c(1),
                    coefficients_ascending: n.clone(),
                    curve: e.curve.clone(),
                    d: c(0),
                    degree: e.degree,
                    distribution,
                    residuals: e.residuals,
                    weighting: e.weighting,
                }
            })
            .collect();
        FitSummary { fits }
    }
}

/// What `coefficients show` shows: the built-in presets, or one set of coefficients.
#[derive(Clone, Debug)]
pub enum Shown {
    /// Each preset's name and one-line summary.
    Presets(Vec<(&'static str, &'static str)>),
    Coefficients(Box<Coefficients>),
}

/// The presets when `source` is `None`, else the coefficients it names (a preset or a file).
pub fn show(source: Option<&str>) -> Result<Shown, Error> {
    Ok(match source {
        None => Shown::Presets(
            coefficients::PRESETS
                .iter()
                .map(|&(name, _, summary)| (name, summary))
                .collect(),
        ),
        Some(source) => Shown::Coefficients(Box::new(Coefficients::load(source)?)),
    })
}
