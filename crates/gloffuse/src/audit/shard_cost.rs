//! What a file costs a shard: its materials and a Blender start; the split of a run's files
//! by those costs (`audit --shard`), and the shard's place in the whole run for its report.

use std::path::PathBuf;

use super::{ShardInput, ShardRun};
use crate::shard::Shard;

/// What a Blender start costs, in materials' audit time: the split balances each file's
/// materials plus one start. Measured (docs/FARM.md): 19 materials in Blender 3.4, 7 in
/// bpy 4.5; one constant for every Blender, between the two.
const START_COST: u64 = 12;

/// Each file's cost to the split: its materials and a Blender start.
pub(super) fn file_costs(materials: &[usize]) -> Vec<u64> {
    materials.iter().map(|&m| m as u64 + START_COST).collect()
}

/// A shard's place in the run: every file of the run, with its material count.
pub(super) fn shard_run(shard: Shard, files: &[PathBuf], counts: &[usize]) -> ShardRun {
    ShardRun {
        shard,
        inputs: files
            .iter()
            .zip(counts)
            .map(|(f, &materials)| ShardInput {
                file: f.display().to_string(),
                materials,
            })
            .collect(),
    }
}

/// The files (and their material counts) `shard` audits.
pub(super) fn shard_part(
    shard: Shard,
    files: &[PathBuf],
    counts: Vec<usize>,
) -> (Vec<PathBuf>, Vec<usize>) {
    let costs = file_costs(&counts);
    files
        .iter()
        .cloned()
        .zip(counts)
        .zip(shard.takes(&costs))
        .filter_map(|(kept, takes)| takes.then_some(kept))
        .unzip()
}
