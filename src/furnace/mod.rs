//! Furnace verification: render plans, EXR read-back, sphere statistics.

pub mod image;
pub mod plan;
pub mod stats;
