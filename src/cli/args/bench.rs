//! `gloffuse bench`.

use clap::Args;

use super::blender::BlenderArgs;
use super::parse::parse_roughness;
use gloffuse::bench::BenchOptions;
use gloffuse::bench::audit::AuditBenchOptions;
use gloffuse::measure::Roughness;
use gloffuse::verify::RenderSettings;

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
