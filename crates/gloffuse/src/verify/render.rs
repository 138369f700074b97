//! Rendering a furnace plan in one Blender process and reading the EXR back.

use std::path::{Path, PathBuf};

use super::image::{Rgba, read_rgba};
use super::plan::Plan;
use super::stats::{SphereStats, sphere_stats};
use crate::Error;
use crate::blender::{
    Blender, BlenderOptions, Run, RunOutput, command_line, run_following_render, runs,
};
use crate::generate::{GenerateParams, Job, Mode, assemble};
use crate::output::write_output;
use crate::plural::count;
use crate::progress::Progress;

/// How a sweep was rendered: which Blender, the settings, and how to rerun it.
#[derive(Clone, Debug, serde::Serialize)]
pub struct RenderInfo {
    pub blender_version: String,
    pub blender_program: String,
    pub masking: String,
    pub cell: u32,
    pub samples: u32,
    pub seed: u32,
    pub width: usize,
    pub height: usize,
    pub render_seconds: f64,
    pub log: String,
    pub command: String,
}

/// A rendered sweep: the image, per-cell statistics (in plan order) and how it was made.
pub struct Rendered {
    pub image: Rgba,
    pub stats: Vec<SphereStats>,
    pub info: RenderInfo,
    /// The EXR, in the run's directory beside its script and log.
    pub exr: PathBuf,
    pub plan: Plan,
}

/// Renders `plan` in one Blender process, every sphere of colour `color`; `progress`
/// follows the samples Cycles logs.
pub fn render(
    blender: &Blender,
    plan: &Plan,
    groups: &GenerateParams,
    mode: Mode,
    color: [f64; 3],
    options: &BlenderOptions,
    progress: &dyn Progress,
) -> Result<Rendered, Error> {
    let run_dir = runs::new_run_dir("verify")?;
    let exr = run_dir.join("sweep.exr");
    let params = plan.params(groups, mode, color, &exr);
    let script = run_dir.join("gloffuse-furnace.py");
    write_output(&script, assemble(&params, Job::Furnace).as_bytes())?;
    let log = run_dir.join("blender.log");
    let run = Run {
        blender,
        script: &script,
        args: Vec::new(),
        timeout: options.timeout,
        cancel: options.cancel.clone(),
        log: log.clone(),
    };
    let command = command_line(&run);
    let out = run_followed(&run, plan, progress)?;
    let image = read_sweep(&exr, plan, &log, &command)?;
    let cell = plan.settings.cell as usize;
    let stats = (0..plan.cells.len())
        .map(|i| sphere_stats(&image, i, plan.columns, cell, plan.settings.radius_fraction))
        .collect();
    let info = RenderInfo {
        blender_version: blender.version_string.clone(),
        blender_program: blender.program.display().to_string(),
        masking: blender.version.masking().to_string(),
        cell: plan.settings.cell,
        samples: plan.settings.samples,
        seed: plan.settings.seed,
        width: image.width,
        height: image.height,
        render_seconds: out.result["render_seconds"].as_f64().unwrap_or(out.seconds),
        log: log.display().to_string(),
        command,
    };
    Ok(Rendered {
        image,
        stats,
        info,
        exr,
        plan: plan.clone(),
    })
}

/// Runs the render while `progress` follows it by Cycles' own estimate.
fn run_followed(run: &Run, plan: &Plan, progress: &dyn Progress) -> Result<RunOutput, Error> {
    progress.begin_estimated(&format!(
        "rendering {} in Blender {}",
        count(plan.cells.len(), "sphere", "spheres"),
        run.blender.version_string
    ));
    let outcome = run_following_render(run, &|e| progress.estimate(e.done, e.seconds_left));
    progress.end();
    outcome
}

/// The rendered EXR, which must be as large as `plan` needs; a failure names the render's
/// log and command.
fn read_sweep(exr: &Path, plan: &Plan, log: &Path, command: &str) -> Result<Rgba, Error> {
    let image = read_rgba(exr).map_err(|e| Error::Blender {
        message: e.to_string().into(),
        log: Some(log.to_path_buf()),
        command: Some(command.to_string()),
    })?;
    let cell = plan.settings.cell as usize;
    let want = (plan.columns * cell, plan.image_rows() * cell);
    if (image.width, image.height) != want {
        return Err(Error::Blender {
            message: format!(
                "{} is {}×{} pixels; the plan needs {}×{}",
                exr.display(),
                image.width,
                image.height,
                want.0,
                want.1
            )
            .into(),
            log: Some(log.to_path_buf()),
            command: Some(command.to_string()),
        });
    }
    Ok(image)
}
