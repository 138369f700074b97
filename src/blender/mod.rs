//! Everything about Blender itself: versions, finding (or installing) it, and running
//! scripts in it headless.

pub mod discover;
pub mod run;
pub mod runs;
pub mod script;
pub mod version;

pub use discover::{Blender, BlenderKind, FindOptions, find_blender};
pub use run::{Run, RunOutput, command_line, run_script};
pub use version::BlenderVersion;
