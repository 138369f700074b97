//! `gloffuse report merge`.

use clap::{Args, Subcommand};
use std::path::PathBuf;

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

pub(super) const MERGE_EXAMPLES: &str = "Examples:
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

    /// Write the merged verdict as a SARIF 2.1.0 log.
    #[arg(long, value_name = "FILE.sarif")]
    pub sarif: Option<PathBuf>,

    /// Write report.html, report.json and the materials' pictures (copied from the shards'
    /// report folders) into this folder.
    #[arg(long, value_name = "DIR")]
    pub report: Option<PathBuf>,

    /// Exit 0 even when materials fail the check (the verdict stays in the reports), for a
    /// farm that would retry a failed task; shards that cannot be merged still exit 2.
    #[arg(long)]
    pub exit_zero: bool,
}
