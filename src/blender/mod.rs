//! Everything about Blender itself: versions (and, in later modules, finding and running it).

pub mod version;

pub use version::BlenderVersion;
