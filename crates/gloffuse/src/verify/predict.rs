//! What the integrator predicts for one row of a verify sweep, before anything rendered is
//! looked at: what the colour model promises the spheres (as a whole and ring by ring), and
//! what the uncorrected and corrected spheres should render relative to that.

use super::modes::spec;
use super::plan::Block;
use crate::fit::Curve;
use crate::generate::{ColorModel, Mode};
use crate::measure::coat::{Coat, multiscatter_tint};
use crate::measure::{
    AlbedoIntegrator, AnisotropicIntegrator, AnisotropicLobe, Anisotropy, Distribution, Engine,
    Glossy, Masking, Roughness,
};

/// What a sweep's predictions depend on besides the row: the engines, the masking of the
/// Blender used, the correction mode and the colour.
pub struct Predictor {
    pub integrator: AlbedoIntegrator,
    /// The engine that renders.
    pub engine: Engine,
    /// The engine the groups are calibrated for.
    pub groups_engine: Engine,
    pub masking: Masking,
    pub mode: Mode,
    pub color: [f64; 3],
    pub color_model: ColorModel,
}

/// What the integrator predicts for one (distribution, roughness, block) row.
#[derive(Clone, Debug, PartialEq)]
pub struct Prediction {
    /// What the colour model promises the corrected sphere's mean, per channel.
    pub target: [f64; 3],
    /// What it promises each view-cosine ring, in the order of the rings given.
    pub ring_targets: Vec<[f64; 3]>,
    /// What the uncorrected sphere's brightness is measured against: the colour, or in
    /// layered mode `target`.
    pub uncorrected_base: [f64; 3],
    /// The uncorrected sphere relative to `uncorrected_base`'s promise: E_avg(r), or in
    /// layered mode the Mix Shader's mean relative to `target`; none in glass mode (a solid
    /// glass sphere's light crosses its surfaces many times, which the integrator of one
    /// interface does not follow).
    pub uncorrected: Option<f64>,
    /// The corrected sphere relative to `target`.
    pub corrected: f64,
    /// In an EEVEE sweep: E_avg(r) of what Cycles renders for the uncorrected sphere.
    pub cycles_uncorrected: Option<f64>,
}

impl Predictor {
    /// The prediction for `d` at `r` (and the block's coat index or anisotropy), with
    /// `curve` the coefficients' curve of `d` and `rings` the view-cosine intervals of the
    /// corrected sphere's rings.
    pub fn predict(
        &self,
        curve: &Curve,
        d: Distribution,
        r: Roughness,
        block: Option<Block>,
        rings: &[(f64, f64)],
    ) -> Prediction {
        if let Some(a) = block.and_then(Block::anisotropy) {
            return self.predict_anisotropic(d, r, a, rings.len());
        }
        if spec(self.mode).solid {
            return self.predict_glass(rings.len());
        }
        let ior = block.and_then(Block::ior);
        let i = &self.integrator;
        let glossy = self.engine.glossy(d, self.masking, r);
        let coat = ior.map(|n| Coat::new(i, glossy, n));
        let e_avg = match &coat {
            Some(coat) => coat.e_avg(),
            None => i.average_albedo(&glossy),
        };
        let (target, ring_targets, uncorrected_base, uncorrected) = match &coat {
            Some(coat) => {
                let target = layered_sphere_target(coat, self.color);
                let rings = rings
                    .iter()
                    .map(|&mu| layered_target(self.color, ring_mean(|m| coat.albedo(m), mu)))
                    .collect();
                // The hand-made Mix Shader: F E + (1 − F) C, averaged over the sphere.
                let mix = relative(coat.hand_mix_average(self.color), target).0;
                (target, rings, target, mix)
            }
            None => {
                let rings = rings
                    .iter()
                    .map(|&mu| {
                        let e = ring_mean(|m| i.directional_albedo(&glossy, m), mu);
                        target(self.color_model, self.color, e_avg, e)
                    })
                    .collect();
                let whole = target(self.color_model, self.color, e_avg, e_avg);
                (whole, rings, self.color, e_avg)
            }
        };
        let calibrated = self.groups_engine.glossy(d, self.masking, r);
        Prediction {
            corrected: self.corrected(curve, r, e_avg, target, &glossy, &calibrated),
            cycles_uncorrected: (self.engine != Engine::Cycles)
                .then(|| i.average_albedo(&Engine::Cycles.glossy(d, self.masking, r))),
            target,
            ring_targets,
            uncorrected_base,
            uncorrected: Some(uncorrected),
        }
    }

    /// An anisotropic row (exact colour, Cycles): the corrected sphere and every ring at the
    /// colour, the uncorrected sphere at the mean of E(μ, φ) over its disk.
    fn predict_anisotropic(
        &self,
        d: Distribution,
        r: Roughness,
        anisotropy: f64,
        rings: usize,
    ) -> Prediction {
        let a = Anisotropy::new(anisotropy).expect("verify checks the anisotropy");
        let lobe = AnisotropicLobe::from_glossy_node(d, self.masking, r, a)
            .expect("verify sweeps the distributions with an anisotropic lobe");
        let e_avg = AnisotropicIntegrator::default().constant_tangent_sphere_mean(&lobe);
        Prediction {
            target: self.color,
            ring_targets: vec![self.color; rings],
            uncorrected_base: self.color,
            uncorrected: Some(e_avg),
            corrected: 1.0,
            cycles_uncorrected: None,
        }
    }

    /// A glass row (white, Cycles): the corrected solid sphere and every ring at the
    /// colour; the uncorrected sphere unpredicted.
    fn predict_glass(&self, rings: usize) -> Prediction {
        Prediction {
            target: self.color,
            ring_targets: vec![self.color; rings],
            uncorrected_base: self.color,
            uncorrected: None,
            corrected: 1.0,
            cycles_uncorrected: None,
        }
    }

    /// What the corrected sphere renders relative to `target`: the roughness-only gain's
    /// result, or in the view modes 1 unless the groups are calibrated for another engine's
    /// BSDF (`calibrated`) than the one rendered (`glossy`).
    fn corrected(
        &self,
        curve: &Curve,
        r: Roughness,
        e_avg: f64,
        target: [f64; 3],
        glossy: &Glossy,
        calibrated: &Glossy,
    ) -> f64 {
        let i = &self.integrator;
        match self.mode {
            Mode::Roughness => {
                // What the roughness-only gain g gives: C g E_avg (exact), or
                // C E_avg / (1 − C (1 − 1/g)) (physical).
                let g = curve.gain(r.get());
                let achieved = |c: f64| match self.color_model {
                    ColorModel::Exact => c * g * e_avg,
                    ColorModel::Physical => c * e_avg / (1.0 - c * (1.0 - 1.0 / g)),
                };
                relative(self.color.map(achieved), target).0
            }
            _ if calibrated == glossy => 1.0,
            // Another engine's table: gain E/E' per pixel, or E + (1 − E').
            Mode::View => i.hemispherical_average(|mu| {
                i.directional_albedo(glossy, mu) / i.directional_albedo(calibrated, mu)
            }),
            Mode::Multiscatter => 1.0 + e_avg - i.average_albedo(calibrated),
            Mode::Layered | Mode::Anisotropic | Mode::Glass => 1.0,
        }
    }

    /// What the reference sphere at `r` promises: Multiscatter GGX (at any anisotropy)
    /// what a corrected GGX sphere does, Principled BSDF (at the block's index) what a
    /// layered GGX coat does, Multiscatter GGX glass (white) all the light.
    pub fn reference_target(&self, r: Roughness, block: Option<Block>) -> [f64; 3] {
        if spec(self.mode).solid {
            return self.color;
        }
        let ggx = self.engine.glossy(Distribution::Ggx, self.masking, r);
        match block.and_then(Block::ior) {
            Some(n) => layered_sphere_target(&Coat::new(&self.integrator, ggx, n), self.color),
            None => {
                let e_avg = self.integrator.average_albedo(&ggx);
                target(self.color_model, self.color, e_avg, e_avg)
            }
        }
    }
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
pub fn relative(measured: [f64; 3], target: [f64; 3]) -> (f64, f64) {
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
