//! gloffuse: measure, fit and correct the energy loss of Blender's glossy BSDFs.
//!
//! Data flows one way: [`microfacet`] (measure) → [`fit`] → [`coefficients`] → generate →
//! verify → report.

pub mod app;
pub mod blender;
pub mod brdf;
pub mod cli;
pub mod coefficients;
pub mod error;
pub mod fit;
pub mod furnace;
pub mod generate;
pub mod lut;
pub mod microfacet;
pub mod output;
pub mod refresh;
pub mod verify;

pub use error::{Error, Result};
