//! gloffuse's physics: the BSDFs Blender evaluates and their albedo by quadrature
//! ([`measure`]), the error type every gloffuse crate shares ([`error`]) and the way long
//! work reports itself ([`progress`]).
//!
//! This crate is numerics only: it runs no Blender, reads and writes no files and parses no
//! command line (its dependencies are the numeric crates, serde and thiserror). The library
//! `gloffuse` builds the stages on it. See `docs/ARCHITECTURE.md`.

pub mod error;
pub mod measure;
pub mod progress;

pub use error::{Error, Field, Hint, Result};
