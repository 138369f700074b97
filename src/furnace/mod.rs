//! Furnace verification: render plans, EXR read-back, sphere statistics.

pub mod image;
pub mod plan;
pub mod png;
pub mod report;
pub mod stats;
