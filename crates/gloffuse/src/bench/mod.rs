//! `gloffuse bench`: the verify sweep rendered as one Blender process against one process
//! per sphere, the measurement behind "one Blender process renders a whole sweep".

pub mod audit;
pub mod shards;

use serde::Serialize;
use std::time::Instant;

use crate::Error;
use crate::blender::BlenderOptions;
use crate::generate::{ColorModel, Curves, GenerateParams, Mode};
use crate::measure::{Distribution, Engine, Roughness};
use crate::plural::count;
use crate::progress::{Progress, Quiet};
use crate::verify::{Plan, RenderSettings, default_roughness, render};

/// The sweep to time.
#[derive(Clone, Debug, PartialEq)]
pub struct BenchOptions {
    pub roughness: Vec<Roughness>,
    pub render: RenderSettings,
    pub blender: BlenderOptions,
}

impl Default for BenchOptions {
    fn default() -> Self {
        BenchOptions {
            roughness: default_roughness(),
            render: RenderSettings::default(),
            blender: BlenderOptions::default(),
        }
    }
}

#[derive(Debug, Serialize)]
pub struct BenchResult {
    pub spheres: usize,
    pub one_process_seconds: f64,
    pub per_sphere_seconds: f64,
    pub ratio: f64,
}

/// Renders the sweep once as one Blender process and once as one process per sphere;
/// `progress` counts the per-sphere runs.
pub fn bench(b: &BenchOptions, progress: &dyn Progress) -> Result<BenchResult, Error> {
    let blender = b.blender.find(progress)?;
    let groups = GenerateParams::new(
        Curves::Presets(&[Engine::Cycles]),
        &[blender.version.masking()],
        &[Mode::Roughness],
        ColorModel::Exact,
    )?;
    let plan = Plan::verify(&Distribution::ALL, &b.roughness, &[], b.render);
    let start = Instant::now();
    render(
        &blender,
        &plan,
        &groups,
        Mode::Roughness,
        [1.0; 3],
        &b.blender,
        &Quiet,
    )?;
    let one = start.elapsed().as_secs_f64();
    progress.notice(&format!(
        "one process: {} in {one:.1} s",
        count(plan.cells.len(), "sphere", "spheres")
    ));
    progress.begin("one process per sphere", plan.cells.len() as u64);
    let start = Instant::now();
    for cell in &plan.cells {
        let single = Plan::of(vec![cell.clone()], 1, b.render);
        let rendered = render(
            &blender,
            &single,
            &groups,
            Mode::Roughness,
            [1.0; 3],
            &b.blender,
            &Quiet,
        );
        if let Err(e) = rendered {
            progress.end();
            return Err(e);
        }
        progress.step();
    }
    progress.end();
    let per = start.elapsed().as_secs_f64();
    Ok(BenchResult {
        spheres: plan.cells.len(),
        one_process_seconds: one,
        per_sphere_seconds: per,
        ratio: per / one,
    })
}
