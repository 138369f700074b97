//! Infrastructure: running Blender. Layered bottom-up: `process` (spawning with process
//! groups, timeouts and logs), `environment` (what the search reads), `probe` (is this a
//! Blender, which version), `provision` (install bpy), `discover` (the search), `run`
//! (a script run headless, its result line read back), `log_progress` (a run's progress
//! from its log) and `runs` (where runs keep their files).

pub mod discover;
pub mod environment;
pub mod for_files;
pub mod log_progress;
pub mod probe;
pub mod process;
pub mod provision;
pub mod run;
pub mod runs;

pub use discover::{FindOptions, Need, find_blender};
pub use environment::BPY_VERSION;
pub use for_files::find_for_files;
pub use log_progress::{Estimate, Step, run_following_render, run_following_steps};
pub use probe::{Blender, BlenderKind, probe};
pub use process::Cancel;
pub use provision::InstallerOutput;
pub use run::{Run, RunOutput, command_line, run_script};

use std::path::PathBuf;
use std::time::Duration;

use crate::Error;
use crate::progress::Progress;

/// Where Blender comes from and how long it may run: shared by every command that runs it.
#[derive(Clone, Debug, PartialEq)]
pub struct BlenderOptions {
    /// A Blender executable, or a Python interpreter that imports bpy (else the search of
    /// [`find_blender`]).
    pub program: Option<PathBuf>,
    /// Install bpy into the cache when no Blender is found.
    pub provision: bool,
    /// Where pip's output goes if bpy is installed.
    pub installer_output: InstallerOutput,
    /// Kill Blender (and its children) after this long; the search for Blender (its version
    /// probes) also ends within it.
    pub timeout: Duration,
    /// Stops the Blender run in progress (and every later one) when requested.
    pub cancel: Cancel,
}

impl Default for BlenderOptions {
    fn default() -> Self {
        BlenderOptions {
            program: None,
            provision: true,
            installer_output: InstallerOutput::Log,
            timeout: Duration::from_secs(600),
            cancel: Cancel::default(),
        }
    }
}

impl BlenderOptions {
    /// Finds Blender as the options say and announces which one is used.
    pub fn find(&self, progress: &dyn Progress) -> Result<Blender, Error> {
        self.find_for(None, progress)
    }

    /// [`find`](Self::find) for a job that needs a Blender at least as new as `need` says:
    /// an older one the user did not name is passed over (with a notice) for the bpy cache,
    /// or bpy is installed if allowed; one the user named is refused.
    pub fn find_for(&self, need: Option<Need>, progress: &dyn Progress) -> Result<Blender, Error> {
        let blender = find_blender(
            &FindOptions {
                explicit: self.program.clone(),
                allow_provision: self.provision,
                installer_output: self.installer_output,
                timeout: self.timeout,
                cancel: self.cancel.clone(),
                need,
            },
            progress,
        )?;
        progress.notice(&format!("using {}", blender.describe()));
        if let Some(assumed) = blender.newer_than_known() {
            progress.advise(&assumed);
        }
        Ok(blender)
    }
}
