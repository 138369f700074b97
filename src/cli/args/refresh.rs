//! `gloffuse refresh`.

use clap::Args;
use std::path::PathBuf;

use super::blender::BlenderArgs;
use super::parse::{ENGINES, one_of};
use gloffuse::measure::Engine;
use gloffuse::refresh::RefreshOptions;

fn refresh_defaults() -> RefreshOptions {
    RefreshOptions::default()
}

#[derive(Args, Debug)]
pub struct RefreshArgs {
    /// Where to write the new coefficients file (atomically).
    #[arg(long, value_name = "FILE.json", default_value_os_t = refresh_defaults().out)]
    pub out: PathBuf,

    /// Polynomial degree in r (6 keeps every distribution within 0.1 % of the measurement).
    #[arg(long, default_value_t = refresh_defaults().degree as u64, value_parser = clap::value_parser!(u64).range(2..=8))]
    pub degree: u64,

    /// The engine to measure: cycles, or eevee (the file then corrects EEVEE's Glossy, each
    /// sphere divided by a white Diffuse one: EEVEE Next's lighting is 0.8 % dark).
    #[arg(long, value_parser = one_of(ENGINES, Engine::key), default_value = refresh_defaults().engine.key())]
    pub engine: Engine,

    /// Samples per pixel for the measurement [default: Cycles 64, EEVEE 1].
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=65_536))]
    pub spp: Option<u32>,

    /// Pixels across each sphere's cell.
    #[arg(long, default_value_t = refresh_defaults().cell, value_parser = clap::value_parser!(u32).range(8..=1024))]
    pub resolution: u32,

    /// Skip the verify run with the new coefficients.
    #[arg(long)]
    pub no_verify: bool,

    #[command(flatten)]
    pub blender: BlenderArgs,

    /// Print JSON instead of tables.
    #[arg(long)]
    pub json: bool,
}

impl RefreshArgs {
    /// Only what the user gave: the library picks the engine's samples.
    pub fn options(&self) -> RefreshOptions {
        RefreshOptions {
            out: self.out.clone(),
            degree: self.degree as usize,
            engine: self.engine,
            cell: self.resolution,
            samples: self.spp,
            verify: !self.no_verify,
            blender: self.blender.options(self.json),
        }
    }
}
