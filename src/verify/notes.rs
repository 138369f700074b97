//! Which notes a verdict carries: each a check of the sweep and its outcome that returns a
//! [`Note`] (data; `crate::report::notes` words it).

use super::verdict::{Note, Row, Sweep, WorstSphere};
use crate::fit::{ColorSpace, preset_for};
use crate::measure::{BlenderVersion, Engine, fresnel};

/// The notes for a sweep rendered in `engine` of Blender `version`, with the white Diffuse
/// sphere's brightness `lighting` (EEVEE) and the judged `rows`, in a fixed order.
pub fn notes(
    sweep: &Sweep,
    engine: Engine,
    version: BlenderVersion,
    lighting: Option<f64>,
    rows: &[Row],
) -> Vec<Note> {
    let lighting = lighting.map(|brightness| Note::Lighting { engine, brightness });
    lighting
        .into_iter()
        .chain(foreign_groups(sweep, engine, version))
        .chain(masking_mismatches(sweep, engine, version))
        .chain(principled_capped(sweep.ior, version))
        .chain(display_referred(sweep, rows))
        .collect()
}

/// The groups are calibrated for another engine than the one rendering.
fn foreign_groups(sweep: &Sweep, engine: Engine, version: BlenderVersion) -> Option<Note> {
    let groups_engine = sweep.coefficients.engine();
    (groups_engine != engine).then(|| Note::ForeignGroups {
        coefficients: sweep.source.to_string(),
        groups_engine,
        engine,
        suggested: preset_for(engine, version),
    })
}

/// Every checked distribution whose linear Cycles curve was fitted for the other masking
/// family than `version`'s (judged in Cycles only: EEVEE renders its own GGX).
fn masking_mismatches(sweep: &Sweep, engine: Engine, version: BlenderVersion) -> Vec<Note> {
    let masking = version.masking();
    sweep
        .coefficients
        .distributions
        .iter()
        .filter(|(d, e)| {
            e.masking != masking
                && e.engine == Engine::Cycles
                && engine == Engine::Cycles
                && e.color_space == ColorSpace::Linear
                && sweep.distributions.contains(d)
        })
        .map(|(&distribution, e)| Note::MaskingMismatch {
            distribution,
            fitted: e.masking,
            blender: version,
            masking,
            suggested: preset_for(engine, version),
        })
        .collect()
}

/// Before 4.0 Principled's specular F0 is 0.08 × Specular, and Specular stops at 1: the
/// indices whose coat reflects more.
fn principled_capped(ior: &[f64], version: BlenderVersion) -> Option<Note> {
    let iors: Vec<f64> = ior
        .iter()
        .copied()
        .filter(|&n| version.major < 4 && fresnel::f0(n) > 0.08 + 1e-12)
        .collect();
    (!iors.is_empty()).then_some(Note::PrincipledSpecularCapped {
        blender: version,
        iors,
    })
}

/// Display-referred coefficients: the worst failing sphere on each side of 100 % (the
/// display-referred curve over-corrects some roughness values and under-corrects others).
fn display_referred(sweep: &Sweep, rows: &[Row]) -> Option<Note> {
    let c = sweep.coefficients;
    if !c.distributions.values().any(|e| e.color_space == ColorSpace::Display) {
        return None;
    }
    let worst = |under: bool| {
        let failing = rows
            .iter()
            .filter(|r| !r.pass && (r.brightness < 1.0) == under);
        let count = failing.clone().count();
        let w = failing.max_by(|a, b| {
            (a.brightness - 1.0)
                .abs()
                .total_cmp(&(b.brightness - 1.0).abs())
        })?;
        Some(WorstSphere {
            count,
            distribution: w.distribution,
            roughness: w.roughness,
            brightness: w.brightness,
            gain: c.distributions[&w.distribution]
                .curve
                .gain(w.roughness.get()),
            needed_gain: 1.0 / w.predicted_uncorrected,
        })
    };
    Some(Note::DisplayReferred {
        coefficients: sweep.source.to_string(),
        under: worst(true),
        over: worst(false),
    })
}
