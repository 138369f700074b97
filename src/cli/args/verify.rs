//! `gloffuse verify`.

use clap::Args;
use std::path::PathBuf;

use super::blender::BlenderArgs;
use super::parse::{
    COLOR_MODELS, ENGINES, MODES, one_of, parse_color, parse_distribution, parse_ior,
    parse_roughness, parse_tolerance,
};
use gloffuse::generate::{ColorModel, Mode};
use gloffuse::measure::{Distribution, Engine, Roughness};
use gloffuse::verify::VerifyOptions;

fn verify_defaults() -> VerifyOptions {
    VerifyOptions::default()
}

#[derive(Args, Debug)]
pub struct VerifyArgs {
    /// A preset (seed, blender-3, blender-4, eevee) or a coefficients file [default: the
    /// preset of the engine and Blender used]. An EEVEE sweep with blender-4 shows what the
    /// Cycles groups do in EEVEE.
    #[arg(long, value_name = "PRESET|FILE")]
    pub coefficients: Option<String>,

    /// The engine to render in: cycles, or eevee (Legacy in 3.x, Next in 4.2+; rendered
    /// headless with the settings of docs/EEVEE.md, a white Diffuse sphere showing how bright
    /// its lighting is, and each sphere shown next to what Cycles renders).
    #[arg(long, value_parser = one_of(ENGINES, Engine::key), default_value = verify_defaults().engine.key())]
    pub engine: Engine,

    /// Distributions to check, comma-separated [default: all in the coefficients].
    #[arg(long, short = 'd', value_delimiter = ',', value_parser = parse_distribution)]
    pub distribution: Vec<Distribution>,

    /// Roughness values of the sweep, comma-separated, each from 0 to 1 and given once
    /// [default: 0, 0.1, …, 1; layered, anisotropic and glass mode: 0.1, 0.25, 0.5, 0.75, 1].
    #[arg(long, short = 'r', value_delimiter = ',', value_parser = parse_roughness, allow_hyphen_values = true)]
    pub roughness: Vec<Roughness>,

    /// Layered and glass mode: the coats' or the glass spheres' indices of refraction,
    /// comma-separated, each from 1 to 3 and given once [default: 1.33,1.5,2].
    #[arg(long, value_name = "N,...", value_delimiter = ',', value_parser = parse_ior)]
    pub ior: Vec<f64>,

    /// Anisotropic mode: the lobes' anisotropies, comma-separated, each from -0.99 to 0.99
    /// and given once [default: 0.5,0.9,-0.9]; each sphere's tangent is the world X.
    #[arg(
        long,
        value_name = "A,...",
        value_delimiter = ',',
        allow_hyphen_values = true
    )]
    pub anisotropy: Vec<f64>,

    /// Samples per pixel [default: Cycles 32, which keeps each sphere's standard error
    /// ≤ 0.2 %; glass mode 256, a solid glass sphere is far noisier; EEVEE 1, its furnace
    /// has no noise].
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=65_536))]
    pub spp: Option<u32>,

    /// Pixels across each sphere's cell.
    #[arg(long, default_value_t = verify_defaults().cell, value_parser = clap::value_parser!(u32).range(8..=1024))]
    pub resolution: u32,

    /// Allowed |mean − 100 %| of a corrected sphere, in percent [default: Cycles 1, EEVEE 2,
    /// glass mode 2].
    #[arg(long, value_parser = parse_tolerance)]
    pub tolerance: Option<f64>,

    /// Cycles' random seed (another seed gives the same means with fresh noise).
    #[arg(long, default_value_t = verify_defaults().seed)]
    pub seed: u32,

    /// Which correction to check: roughness (gain 100/f(r), judged by each sphere's mean),
    /// view (gain 1/E(μ, r)), multiscatter (Glossy + diffuse (1 − E)), layered (the
    /// glossy-over-diffuse groups at each --ior, next to the hand-made Mix Shader and
    /// Principled BSDF), anisotropic (gain 1/E(μ, φ, αx, αy) at each --anisotropy, next to
    /// Blender's anisotropic Multiscatter GGX; Cycles only) or glass (solid white Glass BSDF
    /// spheres at each --ior, 1,024 bounces, next to Multiscatter GGX glass; Cycles only),
    /// all but the first also judged ring by ring.
    #[arg(long, value_parser = one_of(MODES, Mode::key), default_value = verify_defaults().mode.key())]
    pub mode: Mode,

    /// The spheres' colour as linear R,G,B, each 0 to 1 (e.g. 0.95,0.64,0.54, a copper).
    #[arg(long, value_name = "R,G,B", value_parser = parse_color, default_value = "1,1,1")]
    pub color: [f64; 3],

    /// What a correction promises for a colour: exact (the sphere's albedo is the colour) or
    /// physical (tinted multiple bounces, as Multiscatter GGX); the spheres are judged by it.
    #[arg(long, value_parser = one_of(COLOR_MODELS, ColorModel::key), default_value = verify_defaults().color_model.key())]
    pub color_model: ColorModel,

    /// In the view modes: allowed |mean − 100 %| of every view-cosine ring, in percent
    /// [default: Cycles 1.5, EEVEE 2, glass mode 3].
    #[arg(long, value_parser = parse_tolerance)]
    pub ring_tolerance: Option<f64>,

    /// Also write report.html (a page with every sphere, failures first), report.json, the
    /// rendered sweep.exr, contact-sheet.png, brightness.png and deviation.png into this
    /// folder (made if missing; its parent must exist).
    #[arg(long, value_name = "DIR")]
    pub report: Option<PathBuf>,

    /// Also write the verdict as JUnit XML (one test case per sphere, and per sphere's rings
    /// in the view modes) for a CI server.
    #[arg(long, value_name = "FILE.xml")]
    pub junit: Option<PathBuf>,

    #[command(flatten)]
    pub blender: BlenderArgs,

    /// Print the JSON report instead of the table.
    #[arg(long)]
    pub json: bool,
}

impl VerifyArgs {
    /// Only what the user gave: the library fills the rest with the mode's and engine's
    /// defaults ([`VerifyOptions::resolve`]).
    pub fn options(&self) -> VerifyOptions {
        VerifyOptions {
            coefficients: self.coefficients.clone(),
            distributions: self.distribution.clone(),
            roughness: self.roughness.clone(),
            ior: self.ior.clone(),
            anisotropy: self.anisotropy.clone(),
            engine: self.engine,
            cell: self.resolution,
            samples: self.spp,
            seed: self.seed,
            mode: self.mode,
            color: self.color,
            color_model: self.color_model,
            tolerance_percent: self.tolerance,
            ring_tolerance_percent: self.ring_tolerance,
            blender: self.blender.options(self.json),
        }
    }
}
