//! `gloffuse fit` and `gloffuse coefficients show`.

use clap::{Args, Subcommand};
use std::path::PathBuf;

use super::parse::{
    ENGINES, TARGETS, WEIGHTINGS, one_of, parse_distribution, parse_point, parse_version,
};
use gloffuse::fit::{FitOptions, Point, Target, Weighting};
use gloffuse::measure::{BlenderVersion, Distribution, Engine};

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum FitSource {
    /// gloffuse's integrator (exactly the BSDF Cycles evaluates).
    Integrator,
}

#[derive(Args, Debug)]
pub struct FitArgs {
    /// Distribution the --point values belong to (beckmann, ggx, ashikhmin-shirley).
    #[arg(long, short = 'd', value_parser = parse_distribution)]
    pub distribution: Option<Distribution>,

    /// A measured brightness, ROUGHNESS:PERCENT (e.g. 0.5:97); repeat for more points.
    #[arg(long = "point", short = 'p', value_name = "R:PERCENT", value_parser = parse_point, conflicts_with = "from", allow_hyphen_values = true)]
    pub points: Vec<Point>,

    /// Fit every distribution from this source instead of --point values.
    #[arg(long, value_enum)]
    pub from: Option<FitSource>,

    /// Polynomial degree in r, 2 to 8 [default: 3 for --point, 6 for --from integrator, the
    /// lowest degree that keeps every distribution's gain within 0.1 %].
    #[arg(long)]
    pub degree: Option<usize>,

    /// Minimise the error in brightness points (absolute) or in the gain 100/f (relative).
    #[arg(long, value_parser = one_of(WEIGHTINGS, Weighting::key), default_value = Weighting::Relative.key())]
    pub weighting: Weighting,

    /// With --from integrator: fit the sphere's mean brightness E_avg(r) or its centre E(1, r).
    #[arg(long, value_parser = one_of(TARGETS, Target::key), default_value = Target::Mean.key())]
    pub target: Target,

    /// With --from integrator: the Blender version whose masking to model.
    #[arg(long, default_value_t = BlenderVersion::DEFAULT, value_parser = parse_version)]
    pub blender_version: BlenderVersion,

    /// The engine whose Glossy the curves correct: with --from integrator, eevee models what
    /// EEVEE renders (every distribution as GGX with separable masking; the eevee preset).
    #[arg(long, value_parser = one_of(ENGINES, Engine::key), default_value = Engine::Cycles.key())]
    pub engine: Engine,

    /// Write a coefficients file (written atomically: never half-written).
    #[arg(long, value_name = "FILE.json")]
    pub out: Option<PathBuf>,

    /// Print JSON instead of text.
    #[arg(long)]
    pub json: bool,
}

impl FitArgs {
    pub fn options(&self) -> FitOptions {
        FitOptions {
            from_integrator: self.from.is_some(),
            distribution: self.distribution,
            points: self.points.clone(),
            degree: self.degree,
            weighting: self.weighting,
            target: self.target,
            engine: self.engine,
            blender_version: self.blender_version,
            out: self.out.clone(),
        }
    }
}

#[derive(Subcommand, Debug)]
pub enum CoefficientsCommand {
    /// Print a readable summary of a preset or coefficients file (no argument: list presets).
    Show {
        /// A preset name (seed, blender-3, blender-4) or a path to a coefficients file.
        #[arg(value_name = "PRESET|FILE")]
        source: Option<String>,
        /// Print the validated file as JSON.
        #[arg(long)]
        json: bool,
    },
}
