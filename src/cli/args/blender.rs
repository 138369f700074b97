//! The flags of every command that runs Blender.

use clap::Args;
use std::path::PathBuf;
use std::time::Duration;

use gloffuse::blender::{BlenderOptions, InstallerOutput};

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
            cancel: super::super::cancel().clone(),
        }
    }
}
