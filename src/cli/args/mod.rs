//! The command line: clap definitions (each flag documented once, in the file of its
//! command) and the one place that turns typed flags into the library's option structs.
//! Every default is taken from the library's `Default`s, so it is written once. `parse`
//! holds the value parsers and the choices' help; each other file one command or family.

mod albedo;
mod audit;
mod bench;
mod blender;
mod farm;
mod fit;
mod generate;
mod lut;
mod parse;
mod refresh;
mod report;
mod verify;

use clap::{Parser, Subcommand};

use gloffuse::Field;

use audit::AUDIT_EXAMPLES;
use farm::FARM_EXAMPLES;
use generate::GENERATE_EXAMPLES;

pub use albedo::AlbedoArgs;
pub use audit::AuditArgs;
pub use bench::BenchArgs;
pub use farm::{FarmArgs, FarmCommand, SlurmArgs};
pub use fit::{CoefficientsCommand, FitArgs};
pub use generate::GenerateArgs;
pub use lut::LutArgs;
pub use refresh::RefreshArgs;
pub use report::{MergeArgs, ReportCommand};
pub use verify::VerifyArgs;

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
    /// Exit code 0: no material fails the check (a verdict in --fail-on that no waiver or
    /// severity suppresses; with a fix, counted after it); 1: some do; 2: bad input.
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
        Field::Addon => "--addon",
        Field::Force => "--force",
        Field::Format => "--format",
        Field::GModel => "--g-model",
        Field::Into => "--into",
        Field::AllowDowngrade => "--allow-downgrade",
        Field::AuditPath => "PATH",
        Field::AuditConfig => "gloffuse.toml",
        Field::Baseline => "--baseline",
        Field::Select => "--select",
        Field::Ignore => "--ignore",
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
    use gloffuse::blender::{BlenderOptions, InstallerOutput};
    use gloffuse::generate::Mode;
    use gloffuse::measure::Engine;
    use gloffuse::refresh::RefreshOptions;
    use gloffuse::verify::VerifyOptions;

    #[test]
    fn the_command_line_is_consistent() {
        Cli::command().debug_assert();
    }

    /// Without flags, the CLI passes no default of its own: each mode and engine reaches the
    /// library unset, and the library resolves it (`VerifyOptions::resolve`,
    /// `RefreshOptions::render`), so a library caller gets the same sweep.
    #[test]
    fn defaults_come_from_the_library() {
        let blender = BlenderOptions {
            installer_output: InstallerOutput::Stderr,
            cancel: super::super::cancel().clone(),
            ..BlenderOptions::default()
        };
        for mode in Mode::ALL {
            for engine in [Engine::Cycles, Engine::Eevee] {
                let cli = Cli::try_parse_from([
                    "gloffuse",
                    "verify",
                    "--mode",
                    mode.key(),
                    "--engine",
                    engine.key(),
                ])
                .unwrap();
                let Command::Verify(v) = cli.command else {
                    panic!("verify parses as verify")
                };
                let library = VerifyOptions {
                    mode,
                    engine,
                    blender: blender.clone(),
                    ..VerifyOptions::default()
                };
                assert_eq!(v.options(), library, "{} in {}", mode.key(), engine.key());
            }
        }
        let cli = Cli::try_parse_from(["gloffuse", "verify"]).unwrap();
        let Command::Verify(v) = cli.command else {
            panic!("verify parses as verify")
        };
        let library = VerifyOptions {
            blender: blender.clone(),
            ..VerifyOptions::default()
        };
        assert_eq!(v.options(), library);
        for engine in [Engine::Cycles, Engine::Eevee] {
            let cli =
                Cli::try_parse_from(["gloffuse", "refresh", "--engine", engine.key()]).unwrap();
            let Command::Refresh(r) = cli.command else {
                panic!("refresh parses as refresh")
            };
            let library = RefreshOptions {
                engine,
                blender: blender.clone(),
                ..RefreshOptions::default()
            };
            assert_eq!(r.options(), library, "{}", engine.key());
        }
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
