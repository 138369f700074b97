//! Command-line definitions (clap). Each flag is documented once, here.

use clap::{Args, Parser, Subcommand};
use std::path::PathBuf;

use crate::blender::BlenderVersion;
use crate::blender::script::Mode;
use crate::coefficients::Target;
use crate::fit::{Point, Weighting};
use crate::microfacet::{Distribution, Roughness};

const ABOUT: &str = "Keep Blender's glossy shaders at full brightness.";
const LONG_ABOUT: &str = "\
Blender's single-scattering glossy BSDFs (Beckmann, GGX, Ashikhmin-Shirley) lose energy as \
roughness grows: a white glossy sphere under a white sky should be 100 % bright but comes out \
far darker when rough. gloffuse measures that loss by integrating exactly the BSDF Cycles \
evaluates, fits correction curves f(r) (the shader gain is 100/f(r)), builds Blender node groups \
that apply them, and checks them by rendering white furnace spheres in Blender headless.

Exit codes: 0 success; 1 a check failed (verify, refresh); 2 an error: bad input (the message \
names the flag or file and what would be right), no Blender found (it says where gloffuse \
looked and how to point at one), Blender failed or timed out (the message quotes its log, \
names the log file and prints the command to rerun it), or an output could not be written \
(nothing half-written is ever left behind).";

#[derive(Parser, Debug)]
#[command(name = "gloffuse", version, about = ABOUT, long_about = LONG_ABOUT)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Albedo of a white Glossy BSDF: E(μ, r) for one view, E_avg(r) for a whole sphere.
    ///
    /// E(μ, r) is the fraction of light a white glossy surface of roughness r reflects toward
    /// a viewer at view cosine μ under a uniform white sky (the centre of a furnace sphere is
    /// μ = 1). E_avg(r) = 2∫E(μ)μdμ is the mean brightness of the whole sphere.
    Albedo(AlbedoArgs),
    /// Fit a correction curve f(r) = 100 + c₂r² + c₃r³ + … (f(0) = 100, f'(0) = 0).
    ///
    /// Fits brightness points given by hand (--point ROUGHNESS:PERCENT), or all three
    /// distributions from the integrator (--from integrator) into a coefficients file. The
    /// shader gain that restores 100 % is 100/f(r).
    Fit(FitArgs),
    /// Write the brightness-correction node groups: a Python script, a new .blend, or into a .blend.
    ///
    /// Builds `Brightness Correction (…)` (gain = 100/f(r)) and `Gloffuse (…)` (a Glossy BSDF
    /// driven by the corrected colour) for each distribution in the coefficients. --script
    /// needs no Blender; --blend and --into run Blender headless (found or installed
    /// automatically, see --blender).
    Generate(GenerateArgs),
    /// Render furnace spheres in Blender and check that corrected ones come out at 100 %.
    ///
    /// One headless Blender process renders, for each distribution and roughness, a white
    /// sphere under a uniform white sky with the plain Glossy BSDF and with the `Gloffuse (…)`
    /// group built by the same script `generate` writes, plus Blender's own Multiscatter GGX
    /// as a reference. A sphere's mean brightness (Σ RGB / Σ alpha) must be 100 % ± tolerance.
    /// Exit code 0: all corrected spheres pass; 1: some failed; 2: bad input or Blender error.
    Verify(VerifyArgs),
    /// Measure E_avg in your Blender, fit new coefficients from it, then verify them.
    ///
    /// Renders plain Glossy furnace spheres of every distribution on a roughness grid, fits
    /// f(r) to their mean brightness with the same fitter as `fit`, writes a coefficients
    /// file whose provenance names this Blender, compares the measurement with the
    /// integrator's prediction (a disagreement above 0.5 % is a warning), and runs `verify`
    /// with the new file.
    Refresh(RefreshArgs),
    /// Write a lookup table for real-time renderers: the split-sum LUT or Kulla–Conty's.
    ///
    /// split-sum: the GGX "BRDF generator" texture (R = scale, G = bias; specular =
    /// F0·scale + bias). kulla-conty: for the Glossy BSDF Cycles evaluates, scale, bias,
    /// the missing multiple-scattering energy ∫f_ms cos and E_avg (RGBA), so a renderer can
    /// add back what single scattering loses. albedo: that BSDF's E(μ, r) and E_avg(r). Texel (x, y) holds roughness (x + ½)/n and
    /// N·V = (y + ½)/n, first row first; written as EXR, DDS (DX10) or KTX 2.0, half or float.
    Lut(crate::lut::LutArgs),
    /// Time the verify sweep as one Blender process against one process per sphere.
    Bench(BenchArgs),
    /// Inspect coefficient files and the built-in presets.
    Coefficients {
        #[command(subcommand)]
        action: CoefficientsCommand,
    },
}

#[derive(Args, Debug)]
pub struct AlbedoArgs {
    /// beckmann, ggx or ashikhmin-shirley (case-insensitive; BECKMANN, GGX, ASHIKHMIN_SHIRLEY work too).
    #[arg(long, short = 'd', value_parser = parse_distribution, required_unless_present = "model")]
    pub distribution: Option<Distribution>,

    /// A classic BRDF instead of Blender's Glossy: lambert, phong (normalised modified Phong),
    /// ward (anisotropic), cook-torrance (Beckmann D, Schlick Fresnel), fresnel-blend
    /// (Ashikhmin–Shirley's diffuse term). Parameters: --rho, --rs, --exponent, --alpha-x, --alpha-y.
    #[arg(long, value_parser = parse_model, conflicts_with_all = ["distribution", "roughness", "table"])]
    pub model: Option<crate::brdf::Model>,

    /// --model: reflectance ρ (Lambert), ρs (Phong, Ward), f0 (Cook–Torrance) or Rd (Fresnel blend).
    #[arg(long, default_value_t = 1.0, allow_hyphen_values = true)]
    pub rho: f64,

    /// --model fresnel-blend: specular reflectance Rs at normal incidence.
    #[arg(long, default_value_t = 0.04, allow_hyphen_values = true)]
    pub rs: f64,

    /// --model phong: the exponent n.
    #[arg(long, default_value_t = 32.0, allow_hyphen_values = true)]
    pub exponent: f64,

    /// --model ward: αx (along the tangent); --model cook-torrance: α.
    #[arg(long, default_value_t = 0.3, allow_hyphen_values = true)]
    pub alpha_x: f64,

    /// --model ward: αy (along the bitangent).
    #[arg(long, default_value_t = 0.3, allow_hyphen_values = true)]
    pub alpha_y: f64,

    /// The Glossy node's Roughness, 0 to 1 (Cycles uses alpha = r²).
    #[arg(long, short = 'r', value_parser = parse_roughness, allow_hyphen_values = true)]
    pub roughness: Option<Roughness>,

    /// View cosine μ = N·V in (0, 1]; 1 looks straight at the surface (a sphere's centre).
    #[arg(long, default_value = "1", value_parser = parse_mu, allow_hyphen_values = true)]
    pub mu: f64,

    /// Blender version whose masking to model: 3.0–3.5 separable, 3.6 and later height-correlated.
    #[arg(long, default_value = "4.5", value_parser = parse_version)]
    pub blender_version: BlenderVersion,

    /// Write a CSV grid instead: roughness j/(N−1) for j < N, μ = (i + ½)/N for i < N.
    #[arg(long, value_name = "FILE.csv")]
    pub table: Option<PathBuf>,

    /// Grid size N for --table.
    #[arg(long, default_value_t = 64, value_parser = clap::value_parser!(u32).range(2..=4096))]
    pub grid: u32,

    /// Print JSON instead of text.
    #[arg(long)]
    pub json: bool,
}

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
    #[arg(long, value_enum, default_value = "relative")]
    pub weighting: Weighting,

    /// With --from integrator: fit the sphere's mean brightness E_avg(r) or its centre E(1, r).
    #[arg(long, value_enum, default_value = "mean")]
    pub target: Target,

    /// With --from integrator: the Blender version whose masking to model.
    #[arg(long, default_value = "4.5", value_parser = parse_version)]
    pub blender_version: BlenderVersion,

    /// Write a coefficients file (written atomically: never half-written).
    #[arg(long, value_name = "FILE.json")]
    pub out: Option<PathBuf>,

    /// Print JSON instead of text.
    #[arg(long)]
    pub json: bool,
}

/// Where Blender comes from and how long it may run: shared by every command that runs it.
#[derive(Args, Debug, Clone)]
pub struct BlenderArgs {
    /// A Blender executable, or a Python interpreter that imports bpy. Otherwise gloffuse
    /// tries $GLOFFUSE_BLENDER, `blender` on PATH, then a bpy it installed earlier, and
    /// finally installs bpy 4.5 LTS into its cache directory.
    #[arg(long, value_name = "PATH")]
    pub blender: Option<PathBuf>,

    /// Never install bpy; fail with advice instead when no Blender is found.
    #[arg(long)]
    pub no_provision: bool,

    /// Kill Blender (and its children) after this many seconds.
    #[arg(long, value_name = "SECONDS", default_value_t = 600, value_parser = clap::value_parser!(u64).range(1..=86_400))]
    pub timeout: u64,
}

#[derive(Args, Debug)]
pub struct GenerateArgs {
    /// A preset (seed, blender-3, blender-4) or a coefficients file [default: the preset of
    /// the Blender used: blender-3 for 3.0–3.5, blender-4 for 3.6 and later].
    #[arg(long, value_name = "PRESET|FILE")]
    pub coefficients: Option<String>,

    /// Write the generated Python script here (no Blender needed). Run it in Blender's
    /// Text Editor, or `blender -b --python FILE -- --save OUT.blend`.
    #[arg(long, value_name = "OUT.py")]
    pub script: Option<PathBuf>,

    /// Write a new .blend library holding the groups (marked as assets).
    #[arg(long, value_name = "OUT.blend", conflicts_with = "into")]
    pub blend: Option<PathBuf>,

    /// Add or replace the groups in an existing .blend, in place (materials using them keep
    /// working); the previous file is kept as FILE.blend1.
    #[arg(long, value_name = "EXISTING.blend")]
    pub into: Option<PathBuf>,

    /// Which groups to build besides the roughness-only pair (repeatable): view adds
    /// `Brightness Correction View (…)` and `Gloffuse View (…)` (gain 1/E(μ, r)), and
    /// multiscatter adds `Gloffuse Multiscatter (…)`; both add the packed E(μ, r) table.
    #[arg(long, value_enum, value_delimiter = ',', default_value = "roughness")]
    pub mode: Vec<Mode>,

    /// With only --script: the Blender version whose preset to use by default.
    #[arg(long, default_value = "4.5", value_parser = parse_version)]
    pub blender_version: BlenderVersion,

    #[command(flatten)]
    pub blender: BlenderArgs,

    /// Print a JSON summary instead of text.
    #[arg(long)]
    pub json: bool,
}

#[derive(Args, Debug)]
pub struct VerifyArgs {
    /// A preset (seed, blender-3, blender-4) or a coefficients file [default: the preset of
    /// the Blender used].
    #[arg(long, value_name = "PRESET|FILE")]
    pub coefficients: Option<String>,

    /// Distributions to check, comma-separated [default: all in the coefficients].
    #[arg(long, short = 'd', value_delimiter = ',', value_parser = parse_distribution)]
    pub distribution: Vec<Distribution>,

    /// Roughness values, comma-separated.
    #[arg(long, short = 'r', value_delimiter = ',', value_parser = parse_roughness, allow_hyphen_values = true,
          default_value = "0,0.1,0.2,0.3,0.4,0.5,0.6,0.7,0.8,0.9,1")]
    pub roughness: Vec<Roughness>,

    /// Cycles samples per pixel (32 keeps each sphere's standard error ≤ 0.2 %).
    #[arg(long, default_value_t = 32, value_parser = clap::value_parser!(u32).range(1..=65_536))]
    pub spp: u32,

    /// Pixels across each sphere's cell.
    #[arg(long, default_value_t = 64, value_parser = clap::value_parser!(u32).range(8..=1024))]
    pub resolution: u32,

    /// Allowed |mean − 100 %| of a corrected sphere, in percent.
    #[arg(long, default_value_t = 1.0, value_parser = parse_tolerance)]
    pub tolerance: f64,

    /// Cycles' random seed.
    #[arg(long, default_value_t = 0)]
    pub seed: u32,

    /// Which correction to check: roughness (gain 100/f(r), judged by each sphere's mean),
    /// view (gain 1/E(μ, r)) or multiscatter (Glossy + diffuse (1 − E)), the last two also
    /// judged ring by ring.
    #[arg(long, value_enum, default_value = "roughness")]
    pub mode: Mode,

    /// In the view modes: allowed |mean − 100 %| of every view-cosine ring, in percent.
    #[arg(long, default_value_t = 1.5, value_parser = parse_tolerance)]
    pub ring_tolerance: f64,

    /// Also write report.json, the rendered sweep.exr, contact-sheet.png and brightness.png here.
    #[arg(long, value_name = "DIR")]
    pub report: Option<PathBuf>,

    #[command(flatten)]
    pub blender: BlenderArgs,

    /// Print the JSON report instead of the table.
    #[arg(long)]
    pub json: bool,
}

#[derive(Args, Debug)]
pub struct RefreshArgs {
    /// Where to write the new coefficients file (atomically).
    #[arg(long, value_name = "FILE.json", default_value = "coefficients.json")]
    pub out: PathBuf,

    /// Polynomial degree in r (6 keeps every distribution within 0.1 % of the measurement).
    #[arg(long, default_value_t = 6, value_parser = clap::value_parser!(u64).range(2..=8))]
    pub degree: u64,

    /// Cycles samples per pixel for the measurement.
    #[arg(long, default_value_t = 64, value_parser = clap::value_parser!(u32).range(1..=65_536))]
    pub spp: u32,

    /// Pixels across each sphere's cell.
    #[arg(long, default_value_t = 64, value_parser = clap::value_parser!(u32).range(8..=1024))]
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

#[derive(Args, Debug)]
pub struct BenchArgs {
    /// Roughness values of the sweep, comma-separated (the default is verify's sweep).
    #[arg(long, short = 'r', value_delimiter = ',', value_parser = parse_roughness,
          default_value = "0,0.1,0.2,0.3,0.4,0.5,0.6,0.7,0.8,0.9,1")]
    pub roughness: Vec<Roughness>,

    /// Cycles samples per pixel.
    #[arg(long, default_value_t = 32, value_parser = clap::value_parser!(u32).range(1..=65_536))]
    pub spp: u32,

    #[command(flatten)]
    pub blender: BlenderArgs,
}

fn parse_tolerance(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 && v <= 100.0 => Ok(v),
        _ => Err(format!(
            "invalid tolerance '{s}': expected a percentage above 0 and at most 100, e.g. 1"
        )),
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

pub(crate) fn parse_distribution(s: &str) -> Result<Distribution, String> {
    s.parse().map_err(|e: crate::Error| e.to_string())
}

fn parse_model(s: &str) -> Result<crate::brdf::Model, String> {
    s.parse().map_err(|e: crate::Error| e.to_string())
}

fn parse_roughness(s: &str) -> Result<Roughness, String> {
    s.parse().map_err(|e: crate::Error| e.to_string())
}

pub(crate) fn parse_version(s: &str) -> Result<BlenderVersion, String> {
    s.parse().map_err(|e: crate::Error| e.to_string())
}

fn parse_point(s: &str) -> Result<Point, String> {
    s.parse().map_err(|e: crate::Error| e.to_string())
}

fn parse_mu(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 && v <= 1.0 => Ok(v),
        _ => Err(format!(
            "invalid view cosine '{s}': expected a number in (0, 1], e.g. 1 or 0.5"
        )),
    }
}
