//! Everything about Blender itself: versions (and, in later modules, finding and running it).

pub mod script;
pub mod version;

pub use version::BlenderVersion;
