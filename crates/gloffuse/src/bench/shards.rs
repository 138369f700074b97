//! `gloffuse bench --shards N`: what sharding buys on this machine. A generated library of
//! 4·N files is audited as one run, then as N shards at once (as N farm nodes would, here
//! sharing this machine's cores); and the farm cost model's two numbers are measured — a
//! Blender start (with the twins' tables) and a material — from the library's files and a
//! one-material file.

use std::path::PathBuf;
use std::time::Instant;

use serde::Serialize;

use super::audit::{AuditBenchOptions, library, options};
use crate::Error;
use crate::audit::{AuditOptions, audit_with};
use crate::blender::{Blender, runs};
use crate::progress::{Progress, Quiet};
use crate::shard::Shard;

/// Materials in each file of the library.
pub const MATERIALS_PER_FILE: usize = 20;

#[derive(Clone, Debug, Serialize)]
pub struct ShardBenchResult {
    pub blender_version: String,
    pub cell: u32,
    pub samples: u32,
    pub files: usize,
    pub materials_per_file: usize,
    pub shards: usize,
    /// The whole library in one run, wall time.
    pub one_run_seconds: f64,
    /// The N shards run at once: the wall time until the last one ended.
    pub sharded_seconds: f64,
    pub speedup: f64,
    /// The cost model: a file's audit is `start + materials × per_material` seconds.
    pub start_seconds: f64,
    pub per_material_seconds: f64,
}

/// Runs the benchmark with `shards` shards; `progress` counts the audits.
pub fn bench_shards(
    b: &AuditBenchOptions,
    shards: usize,
    progress: &dyn Progress,
) -> Result<ShardBenchResult, Error> {
    let blender = b.blender.find(progress)?;
    let dir = runs::new_run_dir("bench-shards")?;
    let files = 4 * shards.max(1);
    progress.begin("building and auditing the sharded library", 3);
    let folder = dir.join("library");
    std::fs::create_dir_all(&folder).map_err(|e| Error::Write {
        path: folder.clone(),
        message: e.to_string(),
    })?;
    let library_files = (0..files)
        .map(|i| {
            let path = folder.join(format!("file-{i:03}.blend"));
            let first = i * MATERIALS_PER_FILE;
            library(&blender, b, &path, first, MATERIALS_PER_FILE)
        })
        .collect::<Result<Vec<PathBuf>, Error>>()?;
    let single = library(&blender, b, &dir.join("single.blend"), 0, 1)?;
    let options = |paths: &[PathBuf], shard: Option<Shard>| AuditOptions {
        shard,
        ..options(b, paths, true)
    };
    let one_file = timed(|| run(&blender, &options(&[single], None)))?;
    progress.step();
    let one_run_seconds = timed(|| run(&blender, &options(&library_files, None)))?;
    progress.step();
    let sharded_seconds = timed(|| {
        std::thread::scope(|scope| {
            let runs: Vec<_> = (1..=shards)
                .map(|index| {
                    let o = options(
                        &library_files,
                        Some(Shard {
                            index,
                            count: shards,
                        }),
                    );
                    let blender = &blender;
                    scope.spawn(move || run(blender, &o))
                })
                .collect();
            runs.into_iter()
                .try_for_each(|r| r.join().expect("an audit thread does not panic"))
        })
    })?;
    progress.step();
    progress.end();
    let _ = std::fs::remove_dir_all(&dir);
    let per_file = one_run_seconds / files as f64;
    let per_material_seconds = (per_file - one_file) / (MATERIALS_PER_FILE - 1) as f64;
    Ok(ShardBenchResult {
        blender_version: blender.version_string.clone(),
        cell: b.render.cell,
        samples: b.render.samples,
        files,
        materials_per_file: MATERIALS_PER_FILE,
        shards,
        one_run_seconds,
        sharded_seconds,
        speedup: one_run_seconds / sharded_seconds,
        start_seconds: one_file - per_material_seconds,
        per_material_seconds,
    })
}

fn run(blender: &Blender, o: &AuditOptions) -> Result<(), Error> {
    audit_with(blender, o, &Quiet, &mut |_| Ok(())).map(|_| ())
}

/// The wall time of `f`.
fn timed(f: impl FnOnce() -> Result<(), Error>) -> Result<f64, Error> {
    let start = Instant::now();
    f()?;
    Ok(start.elapsed().as_secs_f64())
}
