//! gloffuse: measure, fit and correct the energy loss of Blender's glossy BSDFs.
//!
//! Data flows one way, and the module names say where: [`measure`] (the physics, from the
//! `gloffuse-physics` crate) → [`fit`] (curves and the coefficients file) → [`generate`]
//! (the node groups) → [`verify`] (furnace renders and the verdict) → [`report`] (renderers
//! of the verdict). [`albedo`], [`lut`], [`refresh`] and [`bench`] are commands composed of
//! those stages; [`blender`] runs Blender, [`output`] writes the files the user names,
//! [`user_blend`] changes a user's .blend in place and [`plural`] says counts in words. The
//! library returns data and never prints or parses flags: long work reports through
//! [`progress::Progress`], and errors name their input by a typed [`Field`]. See
//! `docs/ARCHITECTURE.md`.

pub use gloffuse_physics::measure;

pub mod albedo;
pub mod audit;
pub mod bench;
pub mod blend_file;
pub mod blender;
#[cfg(test)]
mod contract;
pub mod error;
pub mod file_lock;
pub mod fit;
pub mod generate;
pub mod lut;
pub mod output;
pub mod plural;
pub mod progress;
pub mod refresh;
pub mod report;
pub mod shard;
pub mod user_blend;
pub mod verify;

pub use error::{Error, Field, Hint, Result};
