//! `gloffuse farm slurm` and `gloffuse farm openjd`.

use clap::{Args, Subcommand};
use std::path::PathBuf;

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

pub(super) const FARM_EXAMPLES: &str = "Examples:
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
