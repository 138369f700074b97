//! gloffuse: measure, fit and correct the energy loss of Blender's glossy BSDFs.
//!
//! Data flows one way, and the module names say where: [`measure`] (the physics) →
//! [`fit`] (curves and the coefficients file) → [`generate`] (the node groups) →
//! [`verify`] (furnace renders and the verdict) → [`report`] (renderers of the verdict).
//! [`refresh`] and [`bench`] compose those stages; [`lut`] writes tables from [`measure`];
//! [`blender`] runs Blender. The library returns data and never prints: long work reports
//! through [`progress::Progress`]. See `docs/ARCHITECTURE.md`.

pub mod albedo;
pub mod bench;
pub mod blender;
pub mod error;
pub mod fit;
pub mod generate;
pub mod lut;
pub mod measure;
pub mod output;
pub mod progress;
pub mod refresh;
pub mod report;
pub mod verify;

pub use error::{Error, Field, Hint, Result};
