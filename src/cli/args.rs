//! The command line: clap definitions (each flag documented once, here) and the one place
//! that turns typed flags into the library's option structs. Every default is taken from
//! the library's `Default`s, so it is written once.

use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser};
use clap::{Args, Parser, Subcommand};
use std::path::PathBuf;
use std::time::Duration;

use gloffuse::Field;
use gloffuse::albedo::AlbedoOptions;
use gloffuse::audit::{AuditJudging, AuditOptions, FixTarget, Verdict};
use gloffuse::bench::BenchOptions;
use gloffuse::bench::audit::AuditBenchOptions;
use gloffuse::blender::{BlenderOptions, InstallerOutput};
use gloffuse::fit::{FitOptions, Point, Target, Weighting};
use gloffuse::generate::{ColorModel, GenerateOptions, Mode};
use gloffuse::lut::{Bits, Format, GModel, Kind, LutOptions, Method};
use gloffuse::measure::brdf::{Model, ModelParams};
use gloffuse::measure::{BlenderVersion, Distribution, Engine, Roughness};
use gloffuse::refresh::RefreshOptions;
use gloffuse::shard::Shard;
use gloffuse::verify::plan::default_samples;
use gloffuse::verify::{
    ANISOTROPIC_SWEEP, IOR_SWEEP, Judging, RenderSettings, VerifyOptions, block_roughness,
};

const ABOUT: &str = "Keep Blender's glossy shaders at full brightness.";
const LONG_ABOUT: &str = "\
Blender's single-scattering glossy BSDFs (Beckmann, GGX, Ashikhmin-Shirley) lose energy as \
roughness grows: a white glossy sphere under a white sky should be 100 % bright but comes out \
far darker when rough. gloffuse measures that loss by integrating exactly the BSDF Cycles \
evaluates, fits correction curves f(r) (the shader gain is 100/f(r)), builds Blender node groups \
that apply them, and checks them by rendering white furnace spheres in Blender headless.

Exit codes: 0 success; 1 a check failed (verify, refresh, audit, report merge); 2 an error: bad input (the message \
names the flag or file and what would be right), no Blender found (it says where gloffuse \
looked and how to point at one), Blender failed or timed out (the message quotes its log, \
names the log file and prints the command to rerun it), or an output could not be written \
(nothing half-written is ever left behind); 128 + the signal when stopped (130 Ctrl-C, 143 \
SIGTERM, 129 SIGHUP; Blender is stopped, nothing is written). A closed stdout (| head) keeps \
the command's own exit code.";

const GENERATE_EXAMPLES: &str = "\
Examples:
  gloffuse generate --extension gloffuse.zip     an extension to install in Blender 4.2+
  gloffuse generate --blend lib/gloffuse.blend --mode roughness,view
                                                 a library .blend with the view groups too
  gloffuse generate --blend lib/gloffuse.blend --mode layered
                                                 the glossy-over-diffuse Gloffuse Layered groups
  gloffuse generate --into scene.blend           update the groups in your file, in place
  gloffuse generate --script gloffuse.py         a script for Blender's Text Editor";

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
    /// Write the brightness-correction node groups: a script, a .blend, or a Blender extension.
    ///
    /// Builds `Brightness Correction (…)` (gain = 100/f(r)) and `Gloffuse (…)` (a Glossy BSDF
    /// driven by the corrected colour) for each distribution in the coefficients, and with
    /// --mode the view and multiscatter groups. --script needs no Blender; --blend, --into
    /// and --extension run Blender headless (found or installed automatically, see
    /// --blender).
    #[command(after_long_help = GENERATE_EXAMPLES)]
    Generate(GenerateArgs),
    /// Render furnace spheres in Blender and check that corrected ones come out at 100 %.
    ///
    /// One headless Blender process renders, for each distribution and roughness, a white
    /// sphere under a uniform white sky with the plain Glossy BSDF and with the `Gloffuse (…)`
    /// group built by the same script `generate` writes, plus Blender's own Multiscatter GGX
    /// as a reference. A sphere's mean brightness (Σ RGB / Σ alpha) must be 100 % ± tolerance.
    /// Exit code 0: all corrected spheres pass; 1: some failed; 2: bad input or Blender error.
    Verify(VerifyArgs),
    /// Audit the materials in your .blend files: rules, a furnace render beside each
    /// material's energy-conserving twin, and a fix.
    ///
    /// For every material (and every node group it uses, nested) the rules flag nodes that
    /// Cycles leaves uncompensated in the Blender that runs (single-scatter glossy, glass and
    /// Principled lobes, Fresnel-mixed fake layering) and nodes that create energy (an Add
    /// Shader of two reflecting lobes, colours above 1, Principled BSDF before 4.0, Toon
    /// smoothing). Then one Blender process per file renders each material as authored
    /// (textures, colours and bump kept) on a sphere in a white furnace, beside its twin: the
    /// same material with every flagged lobe replaced by its conserving equivalent
    /// (Multiscatter GGX, or a gloffuse group where Blender has none). Each material gets ok,
    /// loses, creates or error. The files are only read, unless you ask for a fix.
    /// Exit code 0: no material has a verdict in --fail-on; 1: some have; 2: bad input.
    #[command(after_long_help = AUDIT_EXAMPLES)]
    Audit(AuditArgs),
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
    /// add back what single scattering loses. albedo: that BSDF's E(μ, r) and E_avg(r).
    /// Texel (x, y) holds roughness (x + ½)/n and N·V = (y + ½)/n, first row first; written
    /// as EXR, DDS (DX10) or KTX 2.0, half or float.
    Lut(LutArgs),
    /// Time the verify sweep as one Blender process against one process per sphere.
    Bench(BenchArgs),
    /// Run a sharded audit on a farm: a Slurm array job, or an Open Job Description template.
    ///
    /// Writes into --out what the farm runs: one `gloffuse audit … --shard K/N` task per
    /// shard, each writing DIR/shard-K/ and DIR/shard-K.xml, then one `gloffuse report merge`
    /// task after them all, writing DIR/merged/ (report.html, report.json, pictures),
    /// DIR/merged.json and DIR/merged.xml: the report one unsharded audit gives. DIR must be
    /// on a filesystem every node shares; each node needs gloffuse (--gloffuse) and a
    /// Blender (pass `-- --blender PATH`, or let each node find or install its own).
    #[command(after_long_help = FARM_EXAMPLES)]
    Farm {
        #[command(subcommand)]
        action: FarmCommand,
    },
    /// Work on reports: join the shards of a farm run into one.
    Report {
        #[command(subcommand)]
        action: ReportCommand,
    },
    /// Inspect coefficient files and the built-in presets.
    Coefficients {
        #[command(subcommand)]
        action: CoefficientsCommand,
    },
}

// ---------------------------------------------------------------------------------------
// Value parsers

/// One value of an enumerated flag: the value, its help, and another spelling it accepts.
pub struct Choice<T: 'static> {
    value: T,
    help: &'static str,
    alias: Option<&'static str>,
}

const fn choice<T>(value: T, help: &'static str) -> Choice<T> {
    Choice {
        value,
        help,
        alias: None,
    }
}

/// A parser for one of `choices`, spelled as `key` names them (the library's spelling, so
/// the command line and the files agree); `--help` lists each with its help.
fn one_of<T: Copy + Send + Sync + 'static>(
    choices: &'static [Choice<T>],
    key: fn(T) -> &'static str,
) -> impl TypedValueParser<Value = T> {
    let values = choices.iter().map(move |c| {
        let v = PossibleValue::new(key(c.value)).help(c.help);
        match c.alias {
            Some(a) => v.alias(a),
            None => v,
        }
    });
    PossibleValuesParser::new(values).map(move |name| {
        choices
            .iter()
            .find(|c| key(c.value) == name || c.alias == Some(name.as_str()))
            .map(|c| c.value)
            .expect("clap only passes a listed value")
    })
}

const MODES: &[Choice<Mode>] = &[
    choice(
        Mode::Roughness,
        "gain 100/f(r): the sphere's mean is 100 %, its centre darker, its rim brighter",
    ),
    choice(
        Mode::View,
        "gain 1/E(μ, r) with μ = N·I: every pixel of a furnace sphere is 100 %",
    ),
    choice(
        Mode::Multiscatter,
        "Glossy plus a diffuse lobe of colour × (1 − E(μ, r)): every pixel 100 %, highlight unchanged",
    ),
    choice(
        Mode::Layered,
        "a dielectric glossy coat (IOR) over a diffuse base: a white base reflects 100 % at every pixel",
    ),
    choice(
        Mode::Anisotropic,
        "an anisotropic Glossy (GGX; Cycles) with gain 1/E(μ, φ, αx, αy), φ the view's azimuth from the tangent: every pixel 100 %",
    ),
    choice(
        Mode::Glass,
        "Glass and Refraction BSDFs (GGX, Beckmann; Cycles) with gain 1/E(μ, r, η), η = IOR on front faces and 1/IOR on back faces: every interface returns all the light meeting it",
    ),
];

const ENGINES: &[Choice<Engine>] = &[
    choice(
        Engine::Cycles,
        "Cycles: each distribution as its Glossy node evaluates it",
    ),
    choice(
        Engine::Eevee,
        "EEVEE (Legacy in 3.x, Next in 4.2+): every distribution renders as its split-sum GGX",
    ),
];

const COLOR_MODELS: &[Choice<ColorModel>] = &[
    choice(
        ColorModel::Exact,
        "the surface's albedo is exactly Color at every roughness",
    ),
    choice(
        ColorModel::Physical,
        "the energy of multiple bounces is tinted by Color (Kulla–Conty, as Multiscatter GGX does): rough coloured metals come out darker and more saturated",
    ),
];

const TARGETS: &[Choice<Target>] = &[
    choice(
        Target::Mean,
        "E_avg(r): the mean brightness of an evenly lit sphere",
    ),
    choice(
        Target::Center,
        "E(1, r): the brightness at the centre of the sphere (view along the normal)",
    ),
];

const WEIGHTINGS: &[Choice<Weighting>] = &[
    choice(
        Weighting::Absolute,
        "minimise the error in brightness points",
    ),
    choice(
        Weighting::Relative,
        "minimise the relative error f/y − 1, i.e. the gain error (right for a gain)",
    ),
];

const KINDS: &[Choice<Kind>] = &[
    choice(Kind::SplitSum, "GGX split-sum (R = scale, G = bias)"),
    choice(
        Kind::KullaConty,
        "Kulla–Conty for a Cycles Glossy BSDF (R = scale, G = bias, B = ∫f_ms cos, A = E_avg)",
    ),
    choice(
        Kind::Albedo,
        "Kulla–Conty's albedo tables for a Cycles Glossy BSDF (R = E(μ, r), G = E_avg(r))",
    ),
    choice(
        Kind::Coat,
        "the layered shader's dielectric coat: 12 IOR slices side by side (R = A(μ, r, IOR), G = E(μ, r))",
    ),
    choice(
        Kind::Anisotropic,
        "Cycles' anisotropic GGX or Beckmann lobe: 16 view azimuths × --size bitangent widths of slices at grid points (R = E(μ, φ, αx, αy), G = E_avg(αx, αy))",
    ),
    choice(
        Kind::Glass,
        "Cycles' Glass and Refraction BSDFs: 12 IOR slices side by side, light entering (top row) and leaving (bottom row) (R = E(μ, r, η) of Glass, G = of Refraction)",
    ),
];

const G_MODELS: &[Choice<GModel>] = &[
    choice(
        GModel::Ue4,
        "separable Schlick-GGX with k = α/2 (Karis' UE4 table)",
    ),
    choice(
        GModel::HeightCorrelated,
        "Smith GGX height-correlated, G2 = 1/(1 + Λ(V) + Λ(L)) (Cycles 3.5+, Filament)",
    ),
];

const METHODS: &[Choice<Method>] = &[
    choice(
        Method::Quadrature,
        "deterministic Gauss–Legendre quadrature cut at the horizon of L: within 5e-5",
    ),
    choice(
        Method::Classic,
        "the textbook (UE4) estimator to the letter: H ~ D·N·H; up to 1e-2 off near grazing at 1024",
    ),
];

const FORMATS: &[Choice<Format>] = &[
    choice(Format::Exr, "OpenEXR, ZIP-compressed scan lines"),
    choice(Format::Dds, "DirectDraw Surface with a DX10 header"),
    Choice {
        value: Format::Ktx,
        help: "KTX 2.0 (not KTX 1)",
        alias: Some("ktx"),
    },
];

const BITS: &[Choice<Bits>] = &[
    choice(
        Bits::Half,
        "IEEE half floats (what GPUs sample fastest; rounding error ≤ 2.5e-4 below 1)",
    ),
    choice(
        Bits::Float,
        "IEEE single floats (exactly the computed values)",
    ),
];

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum FitSource {
    /// gloffuse's integrator (exactly the BSDF Cycles evaluates).
    Integrator,
}

fn parse_distribution(s: &str) -> Result<Distribution, String> {
    s.parse().map_err(|e: gloffuse::Error| e.to_string())
}

fn parse_model(s: &str) -> Result<Model, String> {
    s.parse().map_err(|e: gloffuse::Error| e.to_string())
}

fn parse_ior(s: &str) -> Result<f64, String> {
    let max = gloffuse::measure::coat::IOR_MAX;
    match s.trim().parse::<f64>() {
        Ok(n) if (1.0..=max).contains(&n) => Ok(n),
        _ => Err(format!(
            "'{s}' is not an index of refraction from 1 to {max} (e.g. 1.5, glass)"
        )),
    }
}

fn parse_roughness(s: &str) -> Result<Roughness, String> {
    s.parse().map_err(|e: gloffuse::Error| e.to_string())
}

fn parse_version(s: &str) -> Result<BlenderVersion, String> {
    s.parse().map_err(|e: gloffuse::Error| e.to_string())
}

fn parse_point(s: &str) -> Result<Point, String> {
    s.parse().map_err(|e: gloffuse::Error| e.to_string())
}

fn parse_mu(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 && v <= 1.0 => Ok(v),
        _ => Err(format!(
            "invalid view cosine '{s}': expected a number in (0, 1], e.g. 1 or 0.5"
        )),
    }
}

fn parse_color(s: &str) -> Result<[f64; 3], String> {
    let bad = || {
        format!(
            "invalid colour '{s}': expected R,G,B, three numbers from 0 to 1, e.g. 0.95,0.64,0.54"
        )
    };
    let values: Vec<f64> = s
        .split(',')
        .map(|v| v.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| bad())?;
    match values.as_slice() {
        &[r, g, b] if values.iter().all(|v| (0.0..=1.0).contains(v)) => Ok([r, g, b]),
        _ => Err(bad()),
    }
}

fn parse_tolerance(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 && v <= 100.0 => Ok(v),
        _ => Err(format!(
            "invalid tolerance '{s}': expected a percentage above 0 and at most 100, e.g. 1"
        )),
    }
}

fn verify_defaults() -> VerifyOptions {
    VerifyOptions::default()
}

fn refresh_defaults() -> RefreshOptions {
    RefreshOptions::default()
}

// ---------------------------------------------------------------------------------------
// Commands

#[derive(Args, Debug)]
pub struct AlbedoArgs {
    /// beckmann, ggx or ashikhmin-shirley (case-insensitive; BECKMANN, GGX, ASHIKHMIN_SHIRLEY work too).
    #[arg(long, short = 'd', value_parser = parse_distribution, required_unless_present = "model")]
    pub distribution: Option<Distribution>,

    /// A classic BRDF instead of Blender's Glossy: lambert, phong (normalised modified Phong),
    /// ward (anisotropic), cook-torrance (Beckmann D, Schlick Fresnel), fresnel-blend
    /// (Ashikhmin–Shirley's diffuse term). Parameters: --rho, --rs, --exponent, --alpha-x, --alpha-y.
    #[arg(long, value_parser = parse_model, conflicts_with_all = ["distribution", "roughness", "table"])]
    pub model: Option<Model>,

    /// --model: reflectance ρ (Lambert), ρs (Phong, Ward), f0 (Cook–Torrance) or Rd (Fresnel blend).
    #[arg(long, default_value_t = ModelParams::default().rho, allow_hyphen_values = true)]
    pub rho: f64,

    /// --model fresnel-blend: specular reflectance Rs at normal incidence.
    #[arg(long, default_value_t = ModelParams::default().rs, allow_hyphen_values = true)]
    pub rs: f64,

    /// --model phong: the exponent n.
    #[arg(long, default_value_t = ModelParams::default().exponent, allow_hyphen_values = true)]
    pub exponent: f64,

    /// --model ward: αx (along the tangent); --model cook-torrance: α.
    #[arg(long, default_value_t = ModelParams::default().alpha_x, allow_hyphen_values = true)]
    pub alpha_x: f64,

    /// --model ward: αy (along the bitangent).
    #[arg(long, default_value_t = ModelParams::default().alpha_y, allow_hyphen_values = true)]
    pub alpha_y: f64,

    /// The Glossy node's Roughness, 0 to 1 (Cycles uses alpha = r²).
    #[arg(long, short = 'r', value_parser = parse_roughness, allow_hyphen_values = true)]
    pub roughness: Option<Roughness>,

    /// View cosine μ = N·V in (0, 1]; 1 looks straight at the surface (a sphere's centre).
    #[arg(long, default_value = "1", value_parser = parse_mu, allow_hyphen_values = true)]
    pub mu: f64,

    /// Blender version whose masking to model: 3.0–3.4 separable, 3.5 and later height-correlated.
    #[arg(long, default_value_t = BlenderVersion::DEFAULT, value_parser = parse_version)]
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

impl AlbedoArgs {
    pub fn options(&self) -> AlbedoOptions {
        AlbedoOptions {
            distribution: self.distribution,
            model: self.model,
            params: ModelParams {
                rho: self.rho,
                rs: self.rs,
                exponent: self.exponent,
                alpha_x: self.alpha_x,
                alpha_y: self.alpha_y,
            },
            roughness: self.roughness,
            mu: self.mu,
            blender_version: self.blender_version,
            table: self.table.clone(),
            grid: self.grid as usize,
        }
    }
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
    #[arg(long, value_name = "SECONDS", default_value_t = BlenderOptions::default().timeout.as_secs(),
          value_parser = clap::value_parser!(u64).range(1..=86_400))]
    pub timeout: u64,
}

impl BlenderArgs {
    /// The options; pip's output goes to the install log when stdout carries JSON (`quiet`).
    pub fn options(&self, quiet: bool) -> BlenderOptions {
        BlenderOptions {
            program: self.blender.clone(),
            provision: !self.no_provision,
            installer_output: if quiet {
                InstallerOutput::Log
            } else {
                InstallerOutput::Stderr
            },
            timeout: Duration::from_secs(self.timeout),
            cancel: super::cancel().clone(),
        }
    }
}

#[derive(Args, Debug)]
pub struct GenerateArgs {
    /// A preset (seed, blender-3, blender-4) or a coefficients file [default: the preset of
    /// the Blender the groups are built in: blender-3 for 3.0–3.4, blender-4 for 3.5 and
    /// later; a script carries both and picks when it runs].
    #[arg(long, value_name = "PRESET|FILE")]
    pub coefficients: Option<String>,

    /// Write the generated Python script here (no Blender needed). Run it in Blender's
    /// Text Editor, or `blender -b --python FILE -- --save OUT.blend`.
    #[arg(long, value_name = "OUT.py")]
    pub script: Option<PathBuf>,

    /// Write a new .blend library holding the groups, as assets with previews, and its
    /// catalog file beside it (blender_assets.cats.txt, merged into an existing one): mark
    /// the folder as an asset library in Preferences ▸ File Paths, or File ▸ Append.
    #[arg(long, value_name = "OUT.blend", conflicts_with = "into")]
    pub blend: Option<PathBuf>,

    /// Let --blend replace an existing .blend that is not a gloffuse library (a scene, or a
    /// library made before gloffuse marked its libraries). Without it such a file is refused.
    #[arg(long, requires = "blend")]
    pub force: bool,

    /// Add or replace the groups in an existing .blend, in place (materials using them keep
    /// working); the previous file is kept as FILE.blend1.
    #[arg(long, value_name = "EXISTING.blend")]
    pub into: Option<PathBuf>,

    /// Let --into open a file saved by a newer Blender than the one that runs. Without it,
    /// such a file is refused: the older Blender would drop what it does not know (newer
    /// nodes become undefined ones) when it saves.
    #[arg(long, requires = "into")]
    pub allow_downgrade: bool,

    /// Write a Blender extension (4.2+): drag the .zip into Blender, or Edit ▸ Preferences ▸
    /// Get Extensions ▸ Install from Disk. Enabling it registers the library as the asset
    /// library "Gloffuse", so the groups show in the Asset Browser and in the shader
    /// editor's Add ▸ Shader menu. Needs a Blender 4.2 or later to build; it runs in that
    /// version and later.
    #[arg(long, value_name = "OUT.zip", conflicts_with = "into")]
    pub extension: Option<PathBuf>,

    /// Which groups to build besides the roughness-only pair (repeatable): view adds
    /// `Brightness Correction View (…)` and `Gloffuse View (…)` (gain 1/E(μ, r)), and
    /// multiscatter adds `Gloffuse Multiscatter (…)`; both add the packed E(μ, r) table.
    #[arg(long, value_parser = one_of(MODES, Mode::key), value_delimiter = ',', default_value = Mode::Roughness.key())]
    pub mode: Vec<Mode>,

    /// The engines to build groups for, comma-separated: cycles builds `Gloffuse (…)` and the
    /// rest, eevee builds `Gloffuse EEVEE (…)` and the rest, calibrated on what EEVEE renders
    /// (every distribution as GGX); cycles,eevee puts both sets into one library [default:
    /// cycles, or the engine the --coefficients were fitted for].
    #[arg(long, value_parser = one_of(ENGINES, Engine::key), value_delimiter = ',')]
    pub engine: Vec<Engine>,

    /// What a coloured correction keeps: exact (the surface's albedo is Color) or physical
    /// (multiple bounces tint and darken a coloured rough surface, as in Multiscatter GGX).
    #[arg(long, value_parser = one_of(COLOR_MODELS, ColorModel::key), default_value = GenerateOptions::default().color_model.key())]
    pub color_model: ColorModel,

    #[command(flatten)]
    pub blender: BlenderArgs,

    /// Print a JSON summary instead of text.
    #[arg(long)]
    pub json: bool,
}

impl GenerateArgs {
    pub fn options(&self) -> GenerateOptions {
        GenerateOptions {
            coefficients: self.coefficients.clone(),
            script: self.script.clone(),
            blend: self.blend.clone(),
            into: self.into.clone(),
            allow_downgrade: self.allow_downgrade,
            force: self.force,
            extension: self.extension.clone(),
            modes: self.mode.clone(),
            engines: self.engine.clone(),
            color_model: self.color_model,
            blender: self.blender.options(false),
        }
    }
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
    #[arg(long, value_parser = one_of(ENGINES, Engine::key), default_value = Engine::Cycles.key())]
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
    #[arg(long, default_value_t = verify_defaults().render.cell, value_parser = clap::value_parser!(u32).range(8..=1024))]
    pub resolution: u32,

    /// Allowed |mean − 100 %| of a corrected sphere, in percent [default: Cycles 1, EEVEE 2,
    /// glass mode 2].
    #[arg(long, value_parser = parse_tolerance)]
    pub tolerance: Option<f64>,

    /// Cycles' random seed (another seed gives the same means with fresh noise).
    #[arg(long, default_value_t = verify_defaults().render.seed)]
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

const AUDIT_EXAMPLES: &str = "Examples:
  gloffuse audit assets/                         every .blend below assets/, a table
  gloffuse audit lib.blend --report audit-report an HTML page with each material beside its twin
  gloffuse audit assets/ --junit audit.xml --fail-on creates,error
                                                 a CI check that fails only on energy creation
  gloffuse audit lib.blend --fix lib-fixed.blend a fixed copy, audited again (before and after)
  gloffuse audit assets/ --fix-dir fixed/        fixed copies of every file, same layout
  gloffuse audit lib.blend --in-place            fix the file itself (the old one kept as lib.blend1)
  gloffuse audit assets/ --no-render             the rules alone, no Blender render";

#[derive(Args, Debug)]
pub struct AuditArgs {
    /// .blend files, or folders searched recursively for them (hidden folders and linked
    /// folders skipped; .blend1 backups ignored).
    #[arg(value_name = "PATH", required = true)]
    pub paths: Vec<PathBuf>,

    /// Allowed brightness above 100 %, and allowed loss against the twin, in percent (plus
    /// three standard errors of render noise).
    #[arg(long, value_parser = parse_tolerance, default_value_t = 100.0 * AuditJudging::default().tolerance)]
    pub tolerance: f64,

    /// Allowed brightness above 100 % of any view-cosine ring, in percent.
    #[arg(long, value_parser = parse_tolerance, default_value_t = 100.0 * AuditJudging::default().ring_tolerance)]
    pub ring_tolerance: f64,

    /// The verdicts that fail the check (exit 1), comma-separated: loses, creates, error,
    /// ok [default: loses,creates,error].
    #[arg(long, value_name = "VERDICT,...", value_delimiter = ',', value_parser = parse_verdict)]
    pub fail_on: Vec<Verdict>,

    /// The rules alone: no furnace render (each material judged by its findings and the
    /// integrator's predictions).
    #[arg(long)]
    pub no_render: bool,

    /// Pixels across each sphere's cell.
    #[arg(long, default_value_t = verify_defaults().render.cell, value_parser = clap::value_parser!(u32).range(8..=1024))]
    pub resolution: u32,

    /// Samples per pixel (the default keeps a sphere's standard error near 0.2 %).
    #[arg(long, default_value_t = verify_defaults().render.samples, value_parser = clap::value_parser!(u32).range(1..=65_536))]
    pub spp: u32,

    /// Cycles' random seed (another seed gives the same means with fresh noise).
    #[arg(long, default_value_t = verify_defaults().render.seed)]
    pub seed: u32,

    /// Write a fixed copy of the one audited file here (flagged lobes replaced by their
    /// conserving twins), then audit the copy: the report shows before and after.
    #[arg(long, value_name = "OUT.blend", conflicts_with_all = ["fix_dir", "in_place"])]
    pub fix: Option<PathBuf>,

    /// Write a fixed copy of every audited file into this folder, under its path below the
    /// folder it was found in, then audit the copies.
    #[arg(long, value_name = "DIR", conflicts_with = "in_place")]
    pub fix_dir: Option<PathBuf>,

    /// Fix the audited files themselves (only those with something to replace), each saved
    /// atomically with its previous version kept as FILE.blend1, then audit them again.
    #[arg(long)]
    pub in_place: bool,

    /// Let a fix save a file that a newer Blender wrote (what this Blender does not know is
    /// lost in the saved file).
    #[arg(long)]
    pub allow_downgrade: bool,

    /// Also write report.html (each material as authored, its twin and their difference,
    /// failures first) and report.json into this folder (made if missing; its parent must
    /// exist).
    #[arg(long, value_name = "DIR")]
    pub report: Option<PathBuf>,

    /// Also write the verdict as JUnit XML (one test case per material) for a CI server.
    #[arg(long, value_name = "FILE.xml")]
    pub junit: Option<PathBuf>,

    /// Audit only part K of N of the files (K from 1 to N), for a farm: every machine
    /// computes the same split, balanced by each file's material count, and `gloffuse report
    /// merge` joins the shards' reports into the one a single run gives.
    #[arg(long, value_name = "K/N", value_parser = parse_shard)]
    pub shard: Option<Shard>,

    /// Exit 0 even when materials fail the check (the verdict stays in the reports): for a
    /// farm task whose failure would keep the merge from running. Bad input and a Blender
    /// that cannot run still exit 2.
    #[arg(long)]
    pub exit_zero: bool,

    #[command(flatten)]
    pub blender: BlenderArgs,

    /// Print the JSON report instead of the table.
    #[arg(long)]
    pub json: bool,
}

fn parse_shard(s: &str) -> Result<Shard, String> {
    s.parse::<Shard>()
        .map_err(|e| e.render(|_| "shard".to_string()))
}

fn parse_verdict(s: &str) -> Result<Verdict, String> {
    Verdict::ALL
        .into_iter()
        .find(|v| v.key() == s.trim())
        .ok_or_else(|| format!("invalid verdict '{s}': expected ok, loses, creates or error"))
}

impl AuditArgs {
    pub fn options(&self) -> AuditOptions {
        AuditOptions {
            paths: self.paths.clone(),
            render: !self.no_render,
            settings: RenderSettings {
                cell: self.resolution,
                samples: self.spp,
                seed: self.seed,
                ..RenderSettings::default()
            },
            judging: AuditJudging {
                tolerance: self.tolerance / 100.0,
                ring_tolerance: self.ring_tolerance / 100.0,
                fail_on: if self.fail_on.is_empty() {
                    AuditJudging::default().fail_on
                } else {
                    self.fail_on.clone()
                },
            },
            fix: match (&self.fix, &self.fix_dir, self.in_place) {
                (Some(out), _, _) => FixTarget::File(out.clone()),
                (_, Some(dir), _) => FixTarget::Dir(dir.clone()),
                (_, _, true) => FixTarget::InPlace,
                _ => FixTarget::None,
            },
            allow_downgrade: self.allow_downgrade,
            shard: self.shard,
            blender: self.blender.options(self.json),
        }
    }
}

impl VerifyArgs {
    pub fn options(&self) -> VerifyOptions {
        VerifyOptions {
            coefficients: self.coefficients.clone(),
            distributions: self.distribution.clone(),
            roughness: match (self.roughness.is_empty(), self.mode) {
                (false, _) => self.roughness.clone(),
                (true, Mode::Layered | Mode::Anisotropic | Mode::Glass) => block_roughness(),
                (true, _) => verify_defaults().roughness,
            },
            ior: match (self.ior.is_empty(), self.mode) {
                (true, Mode::Layered | Mode::Glass) => IOR_SWEEP.to_vec(),
                _ => self.ior.clone(),
            },
            anisotropy: match (self.anisotropy.is_empty(), self.mode) {
                (true, Mode::Anisotropic) => ANISOTROPIC_SWEEP.to_vec(),
                _ => self.anisotropy.clone(),
            },
            render: RenderSettings {
                cell: self.resolution,
                samples: self.spp.unwrap_or(default_samples(self.engine, self.mode)),
                seed: self.seed,
                ..RenderSettings::for_engine(self.engine)
            },
            mode: self.mode,
            color: self.color,
            color_model: self.color_model,
            judging: {
                let defaults = Judging::for_sweep(self.engine, self.mode);
                Judging {
                    tolerance_percent: self.tolerance.unwrap_or(defaults.tolerance_percent),
                    ring_tolerance_percent: self
                        .ring_tolerance
                        .unwrap_or(defaults.ring_tolerance_percent),
                }
            },
            blender: self.blender.options(self.json),
        }
    }
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
    #[arg(long, value_parser = one_of(ENGINES, Engine::key), default_value = Engine::Cycles.key())]
    pub engine: Engine,

    /// Samples per pixel for the measurement [default: Cycles 64, EEVEE 1].
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=65_536))]
    pub spp: Option<u32>,

    /// Pixels across each sphere's cell.
    #[arg(long, default_value_t = refresh_defaults().render.cell, value_parser = clap::value_parser!(u32).range(8..=1024))]
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
    pub fn options(&self) -> RefreshOptions {
        let defaults = RefreshOptions::for_engine(self.engine);
        RefreshOptions {
            out: self.out.clone(),
            degree: self.degree as usize,
            render: RenderSettings {
                cell: self.resolution,
                samples: self.spp.unwrap_or(defaults.render.samples),
                ..defaults.render
            },
            verify: !self.no_verify,
            blender: self.blender.options(self.json),
        }
    }
}

#[derive(Args, Debug)]
pub struct BenchArgs {
    /// Roughness values of the sweep, comma-separated (the default is verify's sweep).
    #[arg(long, short = 'r', value_delimiter = ',', value_parser = parse_roughness,
          default_values_t = BenchOptions::default().roughness)]
    pub roughness: Vec<Roughness>,

    /// Cycles samples per pixel.
    #[arg(long, default_value_t = BenchOptions::default().render.samples, value_parser = clap::value_parser!(u32).range(1..=65_536))]
    pub spp: u32,

    /// Time `audit` instead: on generated libraries of these many materials (e.g.
    /// 25,100,400), in one Blender process each, and its rules alone, beside one process
    /// per material on the smallest library.
    #[arg(long, value_name = "N,...", value_delimiter = ',', value_parser = clap::value_parser!(u64).range(1..=100_000))]
    pub audit: Vec<u64>,

    /// Time a sharded audit instead: a generated library of 4·N files audited as one run,
    /// then as N shards at once, and the farm cost model's numbers (a Blender start, a
    /// material).
    #[arg(long, value_name = "N", conflicts_with = "audit", value_parser = clap::value_parser!(u64).range(1..=64))]
    pub shards: Option<u64>,

    #[command(flatten)]
    pub blender: BlenderArgs,
}

impl BenchArgs {
    pub fn audit_options(&self) -> AuditBenchOptions {
        AuditBenchOptions {
            sizes: self.audit.iter().map(|&n| n as usize).collect(),
            render: RenderSettings {
                samples: self.spp,
                ..RenderSettings::default()
            },
            blender: self.blender.options(false),
        }
    }

    pub fn options(&self) -> BenchOptions {
        BenchOptions {
            roughness: self.roughness.clone(),
            render: RenderSettings {
                samples: self.spp,
                ..RenderSettings::default()
            },
            blender: self.blender.options(false),
        }
    }
}

/// `gloffuse lut`: write a split-sum or Kulla–Conty lookup table as EXR, DDS or KTX2.
///
/// Texel (x, y) holds roughness (x + ½)/n and N·V = (y + ½)/n; sample at uv = (roughness, N·V).
#[derive(Args, Debug, Clone, PartialEq)]
pub struct LutArgs {
    /// split-sum: GGX scale and bias (R, G); kulla-conty: scale, bias, ∫f_ms cos, E_avg (RGBA); albedo: E(μ, r), E_avg(r) (R, G); coat: A(μ, r, IOR), E(μ, r) (R, G) in 12 slices of IOR 1 to 3 side by side; anisotropic: E(μ, φ, αx, αy), E_avg(αx, αy) (R, G) in slices over the view azimuth and the bitangent width; glass: E(μ, r, η) of the Glass and Refraction BSDFs (R, G) in 12 slices of IOR 1 to 3, light entering (top row) and leaving (bottom row).
    #[arg(long, value_parser = one_of(KINDS, Kind::key), default_value = Kind::SplitSum.key())]
    pub kind: Kind,

    /// kulla-conty, albedo and coat: beckmann, ggx or ashikhmin-shirley; anisotropic and glass: beckmann or ggx [default: ggx].
    #[arg(long, short = 'd', value_parser = parse_distribution)]
    pub distribution: Option<Distribution>,

    /// kulla-conty, albedo, coat, anisotropic and glass: the Blender whose BSDF the table follows (masking: 3.0–3.4 separable, 3.5+ height-correlated; glass: 3.0–3.5 two closures, 3.6+ one) [default: 4.5].
    #[arg(long, value_parser = parse_version)]
    pub blender_version: Option<BlenderVersion>,

    /// Texels per side (per slice for coat, anisotropic and glass), 1 to 8192 (coat 1024, anisotropic 2 to 32, glass 256) [default: 512 for split-sum, 16 for anisotropic, 32 for glass, 64 otherwise].
    #[arg(long, value_name = "N")]
    pub size: Option<u32>,

    /// Hammersley samples per texel, 1 to 1048576, for kulla-conty [default: 4096] and split-sum --method classic [default: 2048]; split-sum's quadrature and albedo take none.
    #[arg(long, value_name = "N")]
    pub samples: Option<u32>,

    /// split-sum only: quadrature (deterministic, max error 5e-5) or classic (the textbook UE4 estimator verbatim, sampled) [default: quadrature].
    #[arg(long, value_parser = one_of(METHODS, Method::key))]
    pub method: Option<Method>,

    /// Bits per channel: 16 (half float) or 32 (float).
    #[arg(long, value_parser = one_of(BITS, Bits::key), default_value = Bits::Half.key())]
    pub bits: Bits,

    /// split-sum only: ue4 (Schlick-GGX, k = α/2) or height-correlated (Smith GGX) [default: ue4].
    #[arg(long, value_parser = one_of(G_MODELS, GModel::key))]
    pub g_model: Option<GModel>,

    /// exr, dds or ktx2 (KTX 2.0) [default: from the --out extension: .exr, .dds, .ktx2/.ktx].
    #[arg(long, value_parser = one_of(FORMATS, Format::key))]
    pub format: Option<Format>,

    /// The file to write (atomically: it appears complete or not at all).
    #[arg(long, short = 'o', value_name = "FILE")]
    pub out: PathBuf,

    /// Print the summary as JSON.
    #[arg(long)]
    pub json: bool,
}

impl LutArgs {
    pub fn options(&self) -> LutOptions {
        LutOptions {
            kind: self.kind,
            distribution: self.distribution,
            blender_version: self.blender_version,
            size: self.size,
            samples: self.samples,
            method: self.method,
            bits: self.bits,
            g_model: self.g_model,
            format: self.format,
            out: self.out.clone(),
        }
    }
}

#[derive(Subcommand, Debug)]
pub enum FarmCommand {
    /// Write (and with --submit, submit) a Slurm array job, one task per shard, and a merge
    /// job after it (--dependency=afterany, so it runs whatever the shards' exit codes and
    /// its own exit code is the verdict: 0 passed, 1 failed, 2 shards missing).
    Slurm(SlurmArgs),
    /// Write an Open Job Description template (jobtemplate-2023-09): step Audit with one
    /// task per shard, step Merge after it; run it with `openjd run`, or submit it to AWS
    /// Deadline Cloud. Shards exit 0 when materials fail (OpenJD runs a step only after every
    /// task of the one it depends on succeeded); the Merge step's exit code is the verdict.
    Openjd(FarmArgs),
}

const FARM_EXAMPLES: &str = "Examples:
  gloffuse farm slurm /shared/assets --shards 50 --out /shared/audit --submit
  gloffuse farm slurm /shared/assets --shards 8 --out /shared/audit --sbatch-arg=--partition=cpu \
      -- --blender /opt/blender-4.5/blender --spp 64
  gloffuse farm openjd /shared/assets --shards 20 --out /shared/audit
  openjd run /shared/audit/gloffuse-audit.template.json";

#[derive(Args, Debug)]
pub struct FarmArgs {
    /// The .blend files or folders to audit, as every node sees them.
    #[arg(value_name = "PATH", required = true)]
    pub paths: Vec<PathBuf>,

    /// How many shards (farm tasks) to split the files into.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=100_000))]
    pub shards: u32,

    /// The job's folder, shared by every node: the scripts or template, every shard's
    /// report and the merged one (made if missing; its parent must exist).
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,

    /// gloffuse on the nodes [default: this gloffuse's path].
    #[arg(long, value_name = "PROGRAM")]
    pub gloffuse: Option<String>,

    /// More `audit` flags for every shard, after `--` (e.g. -- --spp 64 --blender PATH).
    #[arg(last = true, value_name = "AUDIT FLAGS")]
    pub audit_flags: Vec<String>,
}

#[derive(Args, Debug)]
pub struct SlurmArgs {
    #[command(flatten)]
    pub farm: FarmArgs,

    /// An sbatch option for both jobs (repeatable), e.g. --sbatch-arg=--partition=cpu.
    #[arg(long, value_name = "OPTION", allow_hyphen_values = true)]
    pub sbatch_arg: Vec<String>,

    /// Also submit the jobs with sbatch (else run DIR/submit.sh yourself).
    #[arg(long)]
    pub submit: bool,

    /// With --submit: print the job ids as JSON.
    #[arg(long, requires = "submit")]
    pub json: bool,
}

#[derive(Subcommand, Debug)]
pub enum ReportCommand {
    /// Join the reports of a sharded `audit --shard K/N` into the report one run gives.
    ///
    /// Takes every shard's report.json (or the --report folder holding it), in any order,
    /// and writes the same verdict, counts, JSON, JUnit and HTML (with the shards' pictures)
    /// as an audit of all the files at once. Refuses a missing shard, a shard given twice,
    /// and shards of different runs (another Blender, gloffuse, setting or set of files).
    /// Exit code 0: passed; 1: some materials have a verdict in the run's --fail-on; 2: the
    /// shards cannot be merged.
    #[command(after_long_help = MERGE_EXAMPLES)]
    Merge(MergeArgs),
}

const MERGE_EXAMPLES: &str = "Examples:
  gloffuse audit assets/ --shard 1/2 --report out/shard-1     on one machine
  gloffuse audit assets/ --shard 2/2 --report out/shard-2     on another
  gloffuse report merge out/shard-1 out/shard-2 --report out/merged --junit out/merged.xml";

#[derive(Args, Debug)]
pub struct MergeArgs {
    /// Every shard's report.json, or the --report folder that holds it.
    #[arg(value_name = "SHARD", required = true)]
    pub shards: Vec<PathBuf>,

    /// Write the merged JSON report to this file (`-`: standard output, instead of the
    /// table).
    #[arg(long, value_name = "FILE")]
    pub json: Option<PathBuf>,

    /// Write the merged verdict as JUnit XML.
    #[arg(long, value_name = "FILE.xml")]
    pub junit: Option<PathBuf>,

    /// Write report.html, report.json and the materials' pictures (copied from the shards'
    /// report folders) into this folder.
    #[arg(long, value_name = "DIR")]
    pub report: Option<PathBuf>,

    /// Exit 0 even when materials fail the check (the verdict stays in the reports), for a
    /// farm that would retry a failed task; shards that cannot be merged still exit 2.
    #[arg(long)]
    pub exit_zero: bool,
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

/// The flag that sets a library input: how the CLI names a [`Field`] in messages. A field no
/// flag sets (a combination of inputs, a model's own parameter) keeps its own name.
pub fn flag(field: Field) -> String {
    let flag = match field {
        Field::Blender => "--blender",
        Field::BlenderVersion => "--blender-version",
        Field::Blend => "--blend",
        Field::Coefficients => "--coefficients",
        Field::Color => "--color",
        Field::ColorModel => "--color-model",
        Field::Anisotropy => "--anisotropy",
        Field::Degree => "--degree",
        Field::Distribution => "--distribution",
        Field::Engine => "--engine",
        Field::Extension => "--extension",
        Field::Force => "--force",
        Field::Format => "--format",
        Field::GModel => "--g-model",
        Field::Into => "--into",
        Field::AllowDowngrade => "--allow-downgrade",
        Field::AuditPath => "PATH",
        Field::FailOn => "--fail-on",
        Field::Fix => "--fix",
        Field::FixDir => "--fix-dir",
        Field::InPlace => "--in-place",
        Field::Ior => "--ior",
        Field::FitSource => "--from",
        Field::Kind => "--kind",
        Field::Method => "--method",
        Field::Mode => "--mode",
        Field::Model => "--model",
        Field::NoProvision => "--no-provision",
        Field::Out => "--out",
        Field::Point => "--point",
        Field::Report => "--report",
        Field::Shard => "--shard",
        Field::ShardReport => "SHARD",
        Field::Roughness => "--roughness",
        Field::Samples => "--samples",
        Field::Script => "--script",
        Field::Size => "--size",
        Field::Table => "--table",
        Field::Timeout => "--timeout",
        Field::ViewCosine => "--mu",
        Field::Arguments
        | Field::Catalogs
        | Field::ContactSheet
        | Field::ModelParameter(_)
        | Field::PointRoughness
        | Field::PointPercent => return field.name(),
    };
    flag.to_string()
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::CommandFactory;

    #[test]
    fn the_command_line_is_consistent() {
        Cli::command().debug_assert();
    }

    #[test]
    fn defaults_come_from_the_library() {
        let cli = Cli::try_parse_from(["gloffuse", "verify"]).unwrap();
        let Command::Verify(v) = cli.command else {
            panic!("verify parses as verify")
        };
        assert_eq!(
            v.options(),
            VerifyOptions {
                blender: BlenderOptions {
                    installer_output: InstallerOutput::Stderr,
                    cancel: super::super::cancel().clone(),
                    ..BlenderOptions::default()
                },
                ..VerifyOptions::default()
            }
        );
        let cli = Cli::try_parse_from(["gloffuse", "refresh"]).unwrap();
        let Command::Refresh(r) = cli.command else {
            panic!("refresh parses as refresh")
        };
        assert_eq!(
            r.options(),
            RefreshOptions {
                blender: BlenderOptions {
                    installer_output: InstallerOutput::Stderr,
                    cancel: super::super::cancel().clone(),
                    ..BlenderOptions::default()
                },
                ..RefreshOptions::default()
            }
        );
    }

    #[test]
    fn lut_flags_parse() {
        let cli = Cli::try_parse_from([
            "gloffuse",
            "lut",
            "--kind",
            "kulla-conty",
            "--distribution",
            "ASHIKHMIN_SHIRLEY",
            "--blender-version",
            "3.4.1",
            "--size",
            "32",
            "--samples",
            "100",
            "--bits",
            "32",
            "--format",
            "ktx",
            "--out",
            "x.ktx2",
        ])
        .unwrap();
        let Command::Lut(a) = cli.command else {
            panic!("lut parses as lut")
        };
        assert_eq!(a.kind, Kind::KullaConty);
        assert_eq!(a.distribution, Some(Distribution::AshikhminShirley));
        assert_eq!(
            (a.size, a.samples, a.bits),
            (Some(32), Some(100), Bits::Float)
        );
        assert_eq!(a.format, Some(Format::Ktx));
        let cli = Cli::try_parse_from([
            "gloffuse",
            "lut",
            "--g-model",
            "height-correlated",
            "--bits",
            "16",
            "--format",
            "dds",
            "-o",
            "y",
        ])
        .unwrap();
        let Command::Lut(a) = cli.command else {
            panic!("lut parses as lut")
        };
        assert_eq!(a.kind, Kind::SplitSum);
        assert_eq!(a.g_model, Some(GModel::HeightCorrelated));
        assert_eq!(a.format, Some(Format::Dds));
        assert!(Cli::try_parse_from(["gloffuse", "lut", "--bits", "8", "--out", "z.exr"]).is_err());
        assert!(
            Cli::try_parse_from(["gloffuse", "lut", "--kind", "split-sum"]).is_err(),
            "--out is required"
        );
    }

    /// Every flag of every command has real help: at least four words.
    #[test]
    fn every_flag_is_documented() {
        let cli = Cli::command();
        let mut checked = 0;
        for command in cli.get_subcommands() {
            let nested: Vec<_> = command.get_subcommands().collect();
            for c in std::iter::once(command).chain(nested) {
                for arg in c.get_arguments() {
                    let Some(long) = arg.get_long() else { continue };
                    let help = arg.get_help().map(|h| h.to_string()).unwrap_or_default();
                    assert!(
                        help.split_whitespace().count() >= 4,
                        "{} --{long} has no real help: {help:?}",
                        c.get_name()
                    );
                    checked += 1;
                }
            }
        }
        assert!(checked > 40, "only {checked} flags found");
    }
}
