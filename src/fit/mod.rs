//! ② Fit: correction curves `f(r)` by constrained least squares (`curve`) and the versioned
//! coefficients file that holds one curve per distribution (`coefficients`).

pub mod coefficients;
pub mod curve;

pub use coefficients::{
    Coefficients, ColorSpace, FitSpec, Provenance, Source, Target, preset_for, preset_for_masking,
};
pub use curve::{Curve, Fit, Point, Residuals, Variable, Weighting, fit_polynomial};

use crate::Error;
use crate::measure::{BlenderVersion, Distribution, Engine};

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
