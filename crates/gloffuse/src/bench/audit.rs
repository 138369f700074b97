//! `gloffuse bench --audit N,…`: the audit's cost, measured. For each N, a generated file
//! of N varied materials is audited in one Blender process (rules and furnace), and its
//! rules alone; beside it, the smallest library is audited as one file, and one Blender
//! process, per material. Materials per second, side by side, show that the cost is
//! linear in the materials and what one process per file saves.

use std::path::{Path, PathBuf};
use std::time::Instant;

use serde::Serialize;

use crate::Error;
use crate::audit::{AuditOptions, AuditReport, audit_with};
use crate::blender::{Blender, BlenderOptions, Run, run_script, runs};
use crate::generate::{Job, assemble};
use crate::output::write_output;
use crate::progress::{Progress, Quiet};
use crate::verify::RenderSettings;

#[derive(Clone, Debug, PartialEq)]
pub struct AuditBenchOptions {
    /// Library sizes, in materials.
    pub sizes: Vec<usize>,
    pub render: RenderSettings,
    pub blender: BlenderOptions,
}

/// One library size, timed.
#[derive(Clone, Debug, Serialize)]
pub struct AuditTiming {
    pub materials: usize,
    /// Wall time of the whole audit in one process, Blender's start included.
    pub seconds: f64,
    pub materials_per_second: f64,
    /// The rules alone (`--no-render`), wall time.
    pub rules_seconds: f64,
    /// The rule scan inside Blender, per 1,000 materials.
    pub scan_seconds_per_1000: f64,
}

#[derive(Clone, Debug, Serialize)]
pub struct AuditBenchResult {
    pub blender_version: String,
    pub cell: u32,
    pub samples: u32,
    pub sizes: Vec<AuditTiming>,
    /// One process per material, on the smallest library.
    pub per_material: AuditTiming,
}

/// Runs the benchmark; `progress` counts the audits.
pub fn bench_audit(
    b: &AuditBenchOptions,
    progress: &dyn Progress,
) -> Result<AuditBenchResult, Error> {
    let blender = b.blender.find(progress)?;
    let dir = runs::new_run_dir("bench-audit")?;
    let smallest = b.sizes.iter().copied().min().unwrap_or(1).max(1);
    progress.begin(
        "auditing the benchmark libraries",
        (b.sizes.len() * 2 + smallest) as u64,
    );
    let mut sizes = Vec::new();
    for &n in &b.sizes {
        let file = library(&blender, b, &dir.join(format!("library-{n}.blend")), 0, n)?;
        let (seconds, _) = timed(&blender, b, std::slice::from_ref(&file), true)?;
        progress.step();
        let (rules_seconds, report) = timed(&blender, b, &[file], false)?;
        progress.step();
        let scan: f64 = report.files.iter().filter_map(|f| f.scan_seconds).sum();
        sizes.push(AuditTiming {
            materials: n,
            seconds,
            materials_per_second: n as f64 / seconds,
            rules_seconds,
            scan_seconds_per_1000: 1000.0 * scan / n.max(1) as f64,
        });
    }
    let singles: Vec<PathBuf> = (0..smallest)
        .map(|i| library(&blender, b, &dir.join(format!("single-{i:04}.blend")), i, 1))
        .collect::<Result<_, _>>()?;
    let mut seconds = 0.0;
    let mut rules_seconds = 0.0;
    for file in &singles {
        seconds += timed(&blender, b, std::slice::from_ref(file), true)?.0;
        rules_seconds += timed(&blender, b, std::slice::from_ref(file), false)?.0;
        progress.step();
    }
    progress.end();
    let _ = std::fs::remove_dir_all(&dir);
    Ok(AuditBenchResult {
        blender_version: blender.version_string.clone(),
        cell: b.render.cell,
        samples: b.render.samples,
        sizes,
        per_material: AuditTiming {
            materials: smallest,
            seconds,
            materials_per_second: smallest as f64 / seconds,
            rules_seconds,
            scan_seconds_per_1000: f64::NAN,
        },
    })
}

/// The wall time of one audit of `files` (rules and furnace, or the rules alone).
fn timed(
    blender: &Blender,
    b: &AuditBenchOptions,
    files: &[PathBuf],
    render: bool,
) -> Result<(f64, AuditReport), Error> {
    let options = options(b, files, render);
    let start = Instant::now();
    let report = audit_with(blender, &options, &Quiet, &mut |_| Ok(()))?;
    Ok((start.elapsed().as_secs_f64(), report))
}

/// The benchmark's audit of `files`: its render settings and Blender, rendered or the rules
/// alone.
pub(crate) fn options(b: &AuditBenchOptions, files: &[PathBuf], render: bool) -> AuditOptions {
    AuditOptions {
        paths: files.to_vec(),
        render,
        settings: b.render,
        blender: b.blender.clone(),
        ..AuditOptions::default()
    }
}

/// The `bench_library` job's parameter document.
pub fn library_document(path: &Path, first: usize, count: usize) -> serde_json::Value {
    serde_json::json!({
        "bench_library": {"output": path, "count": count, "first": first}
    })
}

/// Saves a library of `count` materials numbered from `first` at `path`.
pub(crate) fn library(
    blender: &Blender,
    b: &AuditBenchOptions,
    path: &Path,
    first: usize,
    count: usize,
) -> Result<PathBuf, Error> {
    let params = library_document(path, first, count);
    let script = path.with_extension("py");
    write_output(&script, assemble(&params, Job::BenchLibrary).as_bytes())?;
    run_script(&Run {
        blender,
        script: &script,
        args: Vec::new(),
        timeout: b.blender.timeout,
        cancel: b.blender.cancel.clone(),
        log: path.with_extension("log"),
    })?;
    Ok(path.to_path_buf())
}
