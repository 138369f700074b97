//! gloffuse's physics: the BSDFs Blender evaluates and their albedo by quadrature
//! ([`measure`]) and the one error they raise for a value out of their range ([`error`],
//! which the library wraps). Long work takes a `step` callback and calls it as it goes.
//!
//! This crate is numerics only: it runs no Blender, reads and writes no files and parses no
//! command line (its dependencies are the numeric crates, serde and thiserror). The library
//! `gloffuse` builds the stages on it. See `docs/ARCHITECTURE.md`.

pub mod error;
pub mod measure;

pub use error::{Error, Quantity, Result};
