//! The verdict of a verify run, as data: what was rendered, what came out, what was
//! expected, and whether each sphere passes. `crate::report` renders it.

use serde::Serialize;

use super::plan::{Role, ior_slots};
use super::render::{RenderInfo, Rendered};
use super::stats::SphereStats;
use crate::Error;
use crate::fit::{Coefficients, ColorSpace, preset_for};
use crate::generate::{ColorModel, Mode};
use crate::measure::coat::{Coat, multiscatter_tint};
use crate::measure::{AlbedoIntegrator, BlenderVersion, Distribution, Engine, Roughness, fresnel};

/// Rings with fewer fully covered pixels than this are too noisy to judge flatness by (at
/// 64 px per sphere, the outermost ring, μ ∈ [0.3, 0.4), holds 72 pixels: at 32 spp its
/// mean scatters by ±2 % in multiscatter mode, while at 512 spp every ring is within 0.3 %).
pub const MIN_RING_PIXELS: usize = 150;

/// The thresholds a corrected sphere is judged by.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Judging {
    /// Allowed |mean − 100 %| of a corrected sphere, in percent.
    pub tolerance_percent: f64,
    /// In the view modes: allowed |ring mean − 100 %| of every view-cosine ring with at
    /// least [`MIN_RING_PIXELS`] pixels, in percent.
    pub ring_tolerance_percent: f64,
}

impl Default for Judging {
    fn default() -> Self {
        Judging::for_engine(Engine::Cycles)
    }
}

impl Judging {
    pub fn for_engine(engine: Engine) -> Self {
        match engine {
            Engine::Cycles => Judging {
                // 1 %: five times the largest standard error of a sphere's mean at 32 spp.
                tolerance_percent: 1.0,
                // 1.5 %: a ring holds fewer pixels than a sphere, so it is noisier.
                ring_tolerance_percent: 1.5,
            },
            // EEVEE has no noise but its own errors: Next's lighting is 0.8 % dark, and
            // its split-sum table is within 0.5 % of the integrator's.
            Engine::Eevee => Judging {
                tolerance_percent: 2.0,
                ring_tolerance_percent: 2.0,
            },
        }
    }
}

/// One distribution at one roughness: the plain Glossy sphere and the corrected one (layered
/// mode: at one index of refraction, the hand-made Mix Shader and the layered group).
#[derive(Clone, Debug, Serialize)]
pub struct Row {
    pub distribution: Distribution,
    pub roughness: f64,
    /// The coat's index of refraction (layered mode only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ior: Option<f64>,
    /// Where the uncorrected and the corrected sphere are in the plan's cells.
    #[serde(skip)]
    pub cells: [usize; 2],
    pub uncorrected: SphereStats,
    pub corrected: SphereStats,
    /// What the colour model promises the corrected sphere's mean is, per channel: the
    /// colour itself (exact), or the colour with multiple bounces tinted (physical).
    pub target: [f64; 3],
    /// The uncorrected sphere's mean relative to the colour (1 for a white sphere that lost
    /// nothing), the channels averaged.
    pub uncorrected_brightness: f64,
    /// The corrected sphere's mean relative to `target`, the channels averaged: 1 is right.
    pub brightness: f64,
    /// The worst channel's |mean / target − 1|.
    pub deviation: f64,
    /// What the integrator predicts for the uncorrected sphere: E_avg(r) of the BSDF the
    /// engine renders (0–1); in layered mode the Mix Shader's mean relative to `target`.
    pub predicted_uncorrected: f64,
    /// In an EEVEE sweep: what Cycles renders for the uncorrected sphere in this Blender
    /// (the integrator's E_avg(r) for its distribution and masking).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub cycles_uncorrected: Option<f64>,
    /// What the coefficients should give relative to `target` (gain(r) · E_avg(r) for a
    /// white sphere; 1 in the view modes, unless the groups are another engine's).
    pub predicted_corrected: f64,
    /// What the colour model promises each view-cosine ring of the corrected sphere (in the
    /// order of its rings), per channel: for a pixel-exact correction, every pixel's target.
    pub ring_targets: Vec<[f64; 3]>,
    /// Largest |ring mean / ring target − 1| of the corrected sphere over its view-cosine
    /// rings and channels.
    pub worst_ring: f64,
    /// Every channel's |mean / target − 1| ≤ tolerance (and, in the view modes, every ring
    /// within the ring tolerance).
    pub pass: bool,
}

/// `GGX`, or in layered mode `GGX, IOR 1.5`: the name of a row's series.
fn series_name(name: &str, ior: Option<f64>) -> String {
    match ior {
        Some(n) => format!("{name}, IOR {n}"),
        None => name.to_string(),
    }
}

impl Row {
    /// The distribution, and the index of refraction in layered mode: `GGX, IOR 1.5`.
    pub fn series(&self) -> String {
        series_name(self.distribution.label(), self.ior)
    }
}

/// Blender's Multiscatter GGX at one roughness (the energy-conserving peer; layered mode:
/// Principled BSDF at one index of refraction).
#[derive(Clone, Debug, Serialize)]
pub struct ReferenceSphere {
    pub roughness: f64,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ior: Option<f64>,
    /// Where the sphere is in the plan's cells.
    #[serde(skip)]
    pub cell: usize,
    pub stats: SphereStats,
    /// Its mean relative to what the colour model promises a GGX sphere (layered mode: a
    /// layered GGX coat), channels averaged.
    pub brightness: f64,
}

impl ReferenceSphere {
    /// `Multiscatter GGX`, or in layered mode `Principled BSDF, IOR 1.5`.
    pub fn series(&self, mode: Mode) -> String {
        series_name(super::plan::reference_label(mode), self.ior)
    }
}

#[derive(Clone, Debug, Serialize)]
pub struct VerifyReport {
    pub coefficients: String,
    /// The engine that rendered the sweep.
    pub engine: Engine,
    /// The engine the coefficients (and so the corrected spheres' groups) are calibrated for.
    pub groups_engine: Engine,
    /// EEVEE: a white Diffuse sphere's mean relative to the colour (how bright the engine's
    /// lighting is; the corrections cannot do better).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lighting: Option<f64>,
    pub mode: Mode,
    /// The spheres' colour, and what the corrections promise for it.
    pub color: [f64; 3],
    pub color_model: ColorModel,
    /// Allowed |ring mean − 100 %| in the view modes, in percent.
    pub ring_tolerance_percent: f64,
    pub render: RenderInfo,
    /// Allowed |mean − 100 %| of a corrected sphere, in percent.
    pub tolerance_percent: f64,
    pub rows: Vec<Row>,
    pub reference: Vec<ReferenceSphere>,
    /// Explanations for the reader (display-referred coefficients, masking mismatch, …).
    pub notes: Vec<String>,
    pub pass: bool,
}

/// The largest |ring mean / its target − 1| over the view-cosine rings (with at least
/// [`MIN_RING_PIXELS`] pixels) and channels of a sphere.
fn worst_ring(s: &SphereStats, targets: &[[f64; 3]]) -> f64 {
    s.rings
        .iter()
        .zip(targets)
        .filter(|(r, _)| r.pixels >= MIN_RING_PIXELS)
        .map(|(r, &t)| relative(r.mean_rgb, t).1)
        .fold(0.0, f64::max)
}

/// What a verify sweep checks: the coefficients (and the name they were loaded by), the
/// distributions and roughness values rendered, and the correction mode.
pub struct Sweep<'a> {
    pub coefficients: &'a Coefficients,
    pub source: &'a str,
    pub distributions: &'a [Distribution],
    pub roughness: &'a [f64],
    /// Layered mode: the indices of refraction (else empty).
    pub ior: &'a [f64],
    pub mode: Mode,
    /// The spheres' colour and what a correction promises for it.
    pub color: [f64; 3],
    pub color_model: ColorModel,
}

/// What a correction promises a surface whose (mean) directional albedo is `e`, of a
/// distribution and roughness with hemispherical albedo `e_avg`: `C` (exact), or
/// `C (E + Fms (1 − E))` (physical).
fn target(model: ColorModel, color: [f64; 3], e_avg: f64, e: f64) -> [f64; 3] {
    match model {
        ColorModel::Exact => color,
        ColorModel::Physical => {
            // Kulla and Conty's tint, as Cycles' Multiscatter GGX applies it per channel.
            let fms = color.map(|c| multiscatter_tint(c, e_avg));
            [0, 1, 2].map(|c| color[c] * (e + fms[c] * (1.0 - e)))
        }
    }
}

/// `measured / target` per channel, averaged; and the worst channel's |ratio − 1|.
fn relative(measured: [f64; 3], target: [f64; 3]) -> (f64, f64) {
    let ratios = [0, 1, 2].map(|c| measured[c] / target[c]);
    let worst = ratios.iter().map(|q| (q - 1.0).abs()).fold(0.0, f64::max);
    (ratios.iter().sum::<f64>() / 3.0, worst)
}

/// What a layered surface of base colour `C` reflects where its coat reflects `a`:
/// `a + C (1 − a)` per channel.
fn layered_target(color: [f64; 3], a: f64) -> [f64; 3] {
    color.map(|c| a + c * (1.0 - a))
}

/// What a layered sphere of base colour `C` promises as a whole: `A_avg + C (1 − A_avg)`.
fn layered_sphere_target(coat: &Coat, color: [f64; 3]) -> [f64; 3] {
    layered_target(color, coat.average())
}

/// The mean of an albedo `f(μ)` over a view-cosine ring [lo, hi) of an orthographic sphere,
/// whose pixels have view-cosine density ∝ μ: `∫ f μ dμ / ∫ μ dμ` by 4-point Gauss–Legendre.
fn ring_mean(f: impl Fn(f64) -> f64, (lo, hi): (f64, f64)) -> f64 {
    const NODES: [(f64, f64); 4] = [
        (0.069_431_844_202_973_7, 0.173_927_422_568_726_9),
        (0.330_009_478_207_571_9, 0.326_072_577_431_273_1),
        (0.669_990_521_792_428_1, 0.326_072_577_431_273_1),
        (0.930_568_155_797_026_3, 0.173_927_422_568_726_9),
    ];
    let (mut num, mut den) = (0.0, 0.0);
    for (x, w) in NODES {
        let mu = lo + (hi - lo) * x;
        num += w * mu * f(mu.max(1e-4));
        den += w * mu;
    }
    num / den
}

/// Judges a rendered verify sweep: every corrected sphere against 100 % (and, in the view
/// modes, ring by ring), next to the integrator's prediction for `version`'s masking, with
/// notes where the coefficients do not suit this Blender.
pub fn judge(
    rendered: &Rendered,
    sweep: &Sweep,
    judging: Judging,
    version: BlenderVersion,
) -> Result<VerifyReport, Error> {
    let Sweep {
        coefficients,
        source,
        distributions,
        roughness,
        ior,
        mode,
        color,
        color_model,
    } = *sweep;
    let plan = &rendered.plan;
    let masking = version.masking();
    // What renders, and what the groups were calibrated for (Cycles groups may be rendered
    // in EEVEE to show what they do there).
    let engine = plan.settings.engine;
    let groups_engine = coefficients.engine();
    let integrator = AlbedoIntegrator::default();
    let tolerance = judging.tolerance_percent / 100.0;
    let find = |role: Role, r: f64, ior: Option<f64>| {
        plan.find(role, r, ior)
            .expect("the plan holds every role at every roughness and index")
    };
    let iors = ior_slots(ior);
    let mut rows = Vec::new();
    for &ior in &iors {
        for &d in distributions {
            let curve = &coefficients.distributions[&d].curve;
            for &r in roughness {
                let roughness = Roughness::new(r)?;
                let glossy = engine.glossy(d, masking, roughness);
                let calibrated = groups_engine.glossy(d, masking, roughness);
                let coat = ior.map(|n| Coat::new(&integrator, glossy, n));
                let e_avg = match &coat {
                    Some(coat) => coat.e_avg(),
                    None => integrator.average_albedo(&glossy),
                };
                let cells = [
                    find(Role::Uncorrected(d), r, ior),
                    find(Role::Corrected(d), r, ior),
                ];
                let [uncorrected, corrected] = cells.map(|i| rendered.stats[i].clone());
                // What the sphere promises as a whole and ring by ring (every pixel's target:
                // shown in every mode, judged in the per-pixel modes).
                let (target, ring_targets): ([f64; 3], Vec<[f64; 3]>) = match &coat {
                    Some(coat) => (
                        layered_sphere_target(coat, color),
                        corrected
                            .rings
                            .iter()
                            .map(|ring| {
                                layered_target(color, ring_mean(|mu| coat.albedo(mu), ring.mu))
                            })
                            .collect(),
                    ),
                    None => (
                        target(color_model, color, e_avg, e_avg),
                        corrected
                            .rings
                            .iter()
                            .map(|ring| {
                                let e = ring_mean(
                                    |mu| integrator.directional_albedo(&glossy, mu),
                                    ring.mu,
                                );
                                self::target(color_model, color, e_avg, e)
                            })
                            .collect(),
                    ),
                };
                let (brightness, deviation) = relative(corrected.mean_rgb, target);
                let worst_ring = worst_ring(&corrected, &ring_targets);
                let rings_flat =
                    !mode.per_pixel() || worst_ring <= judging.ring_tolerance_percent / 100.0;
                // What the roughness-only gain g gives: C g E_avg (exact), or
                // C E_avg / (1 − C (1 − 1/g)) (physical).
                let achieved = |c: f64| match color_model {
                    ColorModel::Exact => c * curve.gain(r) * e_avg,
                    ColorModel::Physical => c * e_avg / (1.0 - c * (1.0 - 1.0 / curve.gain(r))),
                };
                let predicted_uncorrected = match &coat {
                    // The hand-made Mix Shader: F E + (1 − F) C, averaged over the sphere.
                    Some(coat) => relative(coat.hand_mix_average(color), target).0,
                    None => e_avg,
                };
                rows.push(Row {
                    distribution: d,
                    roughness: r,
                    ior,
                    cells,
                    cycles_uncorrected: (engine != Engine::Cycles).then(|| {
                        integrator.average_albedo(&Engine::Cycles.glossy(d, masking, roughness))
                    }),
                    uncorrected_brightness: relative(
                        uncorrected.mean_rgb,
                        if coat.is_some() { target } else { color },
                    )
                    .0,
                    uncorrected,
                    pass: deviation <= tolerance && rings_flat,
                    deviation,
                    worst_ring,
                    ring_targets,
                    brightness,
                    target,
                    corrected,
                    predicted_uncorrected,
                    predicted_corrected: match mode {
                        Mode::Roughness => relative(color.map(achieved), target).0,
                        _ if calibrated == glossy => 1.0,
                        // Another engine's table: gain E/E' per pixel, or E + (1 − E').
                        Mode::View => integrator.hemispherical_average(|mu| {
                            integrator.directional_albedo(&glossy, mu)
                                / integrator.directional_albedo(&calibrated, mu)
                        }),
                        Mode::Multiscatter => 1.0 + e_avg - integrator.average_albedo(&calibrated),
                        Mode::Layered => 1.0,
                    },
                });
            }
        }
    }
    let mut reference = Vec::new();
    for &ior in &iors {
        for &r in roughness {
            let ggx = engine.glossy(Distribution::Ggx, masking, Roughness::new(r)?);
            // Multiscatter GGX promises what a corrected GGX sphere does; Principled BSDF
            // what a layered GGX coat does.
            let promise = match ior {
                Some(n) => layered_sphere_target(&Coat::new(&integrator, ggx, n), color),
                None => {
                    let e_avg = integrator.average_albedo(&ggx);
                    target(color_model, color, e_avg, e_avg)
                }
            };
            let cell = find(Role::Reference, r, ior);
            let stats = rendered.stats[cell].clone();
            reference.push(ReferenceSphere {
                roughness: r,
                ior,
                cell,
                brightness: relative(stats.mean_rgb, promise).0,
                stats,
            });
        }
    }
    let pass = rows.iter().all(|r| r.pass);
    let lighting = plan
        .lighting()
        .map(|cell| relative(rendered.stats[cell].mean_rgb, color).0);
    let mut notes = Vec::new();
    if let Some(l) = lighting {
        notes.push(format!(
            "{engine}'s lighting: a white Diffuse sphere renders at {:.2} % in this sweep (EEVEE Next's world probe loses about 0.8 %; EEVEE Legacy none), so no sphere can come out brighter than that.",
            100.0 * l
        ));
    }
    if groups_engine != engine {
        notes.push(format!(
            "The coefficients '{source}' correct {groups_engine}'s Glossy, rendered here in {engine}{}: use --coefficients {} for {engine}'s own groups.",
            match engine {
                Engine::Eevee => ", which renders every distribution as its GGX",
                Engine::Cycles => "",
            },
            preset_for(engine, version)
        ));
    }
    for (d, e) in &coefficients.distributions {
        if e.masking != masking
            && e.engine == Engine::Cycles
            && engine == Engine::Cycles
            && e.color_space == ColorSpace::Linear
            && distributions.contains(d)
        {
            notes.push(format!(
                "{}: the coefficients were fitted for {} masking, but Blender {} uses {} masking; use --coefficients {}.",
                d.label(),
                e.masking,
                version,
                masking,
                preset_for(engine, version)
            ));
        }
    }
    // Before 4.0 Principled's specular F0 is 0.08 × Specular, and Specular stops at 1.
    let capped: Vec<String> = ior
        .iter()
        .filter(|&&n| version.major < 4 && fresnel::f0(n) > 0.08 + 1e-12)
        .map(|n| n.to_string())
        .collect();
    if !capped.is_empty() {
        notes.push(format!(
            "Blender {version}'s Principled BSDF cannot reflect like a coat of IOR {}: its specular F0 is 0.08 × Specular and Specular stops at 1 (F0 0.08, IOR 1.79), so those reference spheres use Specular 1.",
            capped.join(", ")
        ));
    }
    if coefficients
        .distributions
        .values()
        .any(|e| e.color_space == ColorSpace::Display)
    {
        // The worst failing sphere on each side of 100 %: the display-referred curve
        // over-corrects some roughness values and under-corrects others.
        let worst = |under: bool| {
            rows.iter()
                .filter(|r| !r.pass && (r.brightness < 1.0) == under)
                .max_by(|a, b| {
                    (a.brightness - 1.0)
                        .abs()
                        .total_cmp(&(b.brightness - 1.0).abs())
                })
        };
        let mut note = format!(
            "The coefficients '{source}' are display-referred: their percentages are sRGB-encoded brightness read off a screen (sRGB(0.305) ≈ 0.59 is GGX's centre at r = 1), but a shader gain acts on linear light, so 100/f(r) misses."
        );
        for (under, verb) in [(true, "Under-corrected"), (false, "Over-corrected")] {
            if let Some(w) = worst(under) {
                let count = rows
                    .iter()
                    .filter(|r| !r.pass && (r.brightness < 1.0) == under)
                    .count();
                note.push_str(&format!(
                    " {verb}: {count} sphere{}, worst {} r = {} at {:.1} % (gain {:.3}; 1/E_avg = {:.3} is needed).",
                    if count == 1 { "" } else { "s" },
                    w.distribution.label(),
                    w.roughness,
                    100.0 * w.brightness,
                    coefficients.distributions[&w.distribution]
                        .curve
                        .gain(w.roughness),
                    1.0 / w.predicted_uncorrected
                ));
            }
        }
        notes.push(note);
    }
    Ok(VerifyReport {
        coefficients: source.to_string(),
        engine,
        groups_engine,
        lighting,
        mode,
        color,
        color_model,
        ring_tolerance_percent: judging.ring_tolerance_percent,
        render: rendered.info.clone(),
        tolerance_percent: judging.tolerance_percent,
        rows,
        reference,
        notes,
        pass,
    })
}
