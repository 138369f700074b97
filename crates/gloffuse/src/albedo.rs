//! `albedo`: how much light one surface reflects — a Glossy BSDF as Cycles evaluates it, or a
//! classic BRDF model — at one view cosine and averaged over the hemisphere; or a grid of a
//! distribution's directional albedo written as a CSV table.

use std::path::PathBuf;

use serde::Serialize;

use crate::error::{Error, Field, Hint};
use crate::measure::brdf::{Model, ModelParams, model_albedo, model_average_albedo};
use crate::measure::{AlbedoIntegrator, BlenderVersion, Distribution, Glossy, Masking, Roughness};
use crate::output::{check_destination, write_output};
use crate::progress::Progress;

/// What to integrate: one of `distribution` (a Glossy BSDF) and `model` (a classic BRDF).
#[derive(Clone, Debug, PartialEq)]
pub struct AlbedoOptions {
    pub distribution: Option<Distribution>,
    pub model: Option<Model>,
    /// The model's parameters (with `model` only).
    pub params: ModelParams,
    /// The Glossy BSDF's roughness (needed unless `table` is given).
    pub roughness: Option<Roughness>,
    /// The view cosine of the directional albedo, in (0, 1].
    pub mu: f64,
    /// The Blender whose masking the Glossy BSDF uses.
    pub blender_version: BlenderVersion,
    /// Write a `grid`×`grid` table of the distribution's albedo over (roughness, μ) here.
    pub table: Option<PathBuf>,
    pub grid: usize,
}

/// One surface's albedo (JSON keys in alphabetical order, as the command has always printed).
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(untagged)]
pub enum Albedo {
    Glossy {
        alpha: f64,
        average_albedo: f64,
        blender_version: String,
        directional_albedo: f64,
        distribution: Distribution,
        masking: Masking,
        mu: f64,
        roughness: f64,
    },
    Model {
        average_albedo: f64,
        directional_albedo: f64,
        model: Model,
        mu: f64,
        parameters: Parameters,
    },
}

/// A model's parameters as the JSON names them.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Parameters {
    pub alpha_x: f64,
    pub alpha_y: f64,
    pub exponent: f64,
    pub rho: f64,
    pub rs: f64,
}

/// What `albedo` gave: one surface's albedo, or the table it wrote.
#[derive(Clone, Debug, PartialEq)]
pub enum AlbedoOutput {
    Point(Albedo),
    Table {
        path: PathBuf,
        grid: usize,
        masking: Masking,
        blender_version: BlenderVersion,
    },
}

/// Integrates what `options` asks for (a table reports its rows through `progress`).
pub fn albedo(options: &AlbedoOptions, progress: &dyn Progress) -> Result<AlbedoOutput, Error> {
    if let Some(model) = options.model {
        return model_point(options, model).map(AlbedoOutput::Point);
    }
    let Some(distribution) = options.distribution else {
        return Err(Error::input(
            Field::Arguments,
            "(none)",
            Hint::new("{} or {}", [Field::Distribution, Field::Model]),
        ));
    };
    if let Some(path) = &options.table {
        return table(options, distribution, path.clone(), progress);
    }
    let Some(roughness) = options.roughness else {
        return Err(Error::input(
            Field::Arguments,
            "(none)",
            Hint::new(
                "{} R (0 to 1), or {} FILE for a grid",
                [Field::Roughness, Field::Table],
            ),
        ));
    };
    let masking = options.blender_version.masking();
    let integrator = AlbedoIntegrator::default();
    let glossy = Glossy::new(distribution, masking, roughness);
    Ok(AlbedoOutput::Point(Albedo::Glossy {
        alpha: roughness.alpha(),
        average_albedo: integrator.average_albedo(&glossy),
        blender_version: options.blender_version.to_string(),
        directional_albedo: integrator.directional_albedo(&glossy, options.mu),
        distribution,
        masking,
        mu: options.mu,
        roughness: roughness.get(),
    }))
}

fn model_point(options: &AlbedoOptions, model: Model) -> Result<Albedo, Error> {
    let p = options.params;
    Ok(Albedo::Model {
        average_albedo: model_average_albedo(model, &p)?,
        directional_albedo: model_albedo(model, &p, options.mu)?,
        model,
        mu: options.mu,
        parameters: Parameters {
            alpha_x: p.alpha_x,
            alpha_y: p.alpha_y,
            exponent: p.exponent,
            rho: p.rho,
            rs: p.rs,
        },
    })
}

fn table(
    options: &AlbedoOptions,
    distribution: Distribution,
    path: PathBuf,
    progress: &dyn Progress,
) -> Result<AlbedoOutput, Error> {
    // A bad destination fails before minutes of integration, not after.
    check_destination(&path)?;
    let n = options.grid;
    let masking = options.blender_version.masking();
    let mus: Vec<f64> = (0..n).map(|i| (i as f64 + 0.5) / n as f64).collect();
    let grid =
        AlbedoIntegrator::default().grid(distribution, masking, &Roughness::grid(n), &mus, &|| {
            progress.step()
        });
    write_output(&path, grid.csv().as_bytes())?;
    Ok(AlbedoOutput::Table {
        path,
        grid: n,
        masking,
        blender_version: options.blender_version,
    })
}
