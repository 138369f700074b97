//! The Glass and Refraction BSDFs as Cycles samples them: which node, the form of each
//! Blender version, how it draws a microfacet normal, and one sample's weight by lobe.

use glam::DVec3;

use crate::measure::fresnel;
use crate::measure::microfacet::{Distribution, Masking, Microfacet, Roughness};
use crate::measure::version::BlenderVersion;

/// Which node.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[repr(usize)]
pub enum DielectricNode {
    /// Glass BSDF: reflection and refraction.
    Glass,
    /// Refraction BSDF: the refracted lobe alone.
    Refraction,
}

/// How Cycles builds and samples a rough dielectric (Blender version dependent).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum GlassForm {
    /// Blender 3.0–3.5: Glass is two closures weighted by the Fresnel at the shading
    /// normal; the refraction sampler keeps a direction that leaves upwards.
    TwoClosures,
    /// Blender 3.6 on: one closure with the Fresnel of each microfacet; a refraction that
    /// leaves upwards ends the path.
    OneClosure,
}

impl GlassForm {
    /// The first Blender whose Glass node is one closure with a per-microfacet Fresnel
    /// (Cycles v3.6.0; v3.5.0 still allocates two in `svm/closure.h`).
    pub const ONE_CLOSURE_FROM: BlenderVersion = BlenderVersion { major: 3, minor: 6 };

    pub fn of(version: BlenderVersion) -> Self {
        if version >= Self::ONE_CLOSURE_FROM {
            GlassForm::OneClosure
        } else {
            GlassForm::TwoClosures
        }
    }
}

/// One Glass or Refraction BSDF configuration of a Blender version, white.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Dielectric {
    pub node: DielectricNode,
    pub microfacet: Microfacet,
    pub masking: Masking,
    pub form: GlassForm,
    pub sampler: Sampler,
}

/// How Cycles draws a visible microfacet normal.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Sampler {
    /// From the visible normals' own distribution.
    Exact,
    /// Beckmann in 3.0–3.4: the slope along the view from Cycles' table
    /// ([`beckmann_table`](crate::measure::beckmann_table)), which returns up to 2.4 % more
    /// than the lobe (docs/PHYSICS.md §15).
    BeckmannTable,
}

impl Sampler {
    /// The first Blender that draws a Beckmann slope without the table (by Newton's method,
    /// Cycles v3.5.0).
    pub const BECKMANN_EXACT_FROM: BlenderVersion = BlenderVersion { major: 3, minor: 5 };

    pub fn of(distribution: Distribution, version: BlenderVersion) -> Self {
        if distribution == Distribution::Beckmann && version < Self::BECKMANN_EXACT_FROM {
            Sampler::BeckmannTable
        } else {
            Sampler::Exact
        }
    }
}

/// How one direction leaves a microfacet of the sampler.
enum Scatter {
    /// Away from the surface (reflection) or into it (refraction): its `G2/G1(v)`.
    Kept(f64),
    /// To the wrong side of the surface: the path ends.
    Lost,
}

impl Dielectric {
    /// The node of `distribution` (GGX or Beckmann) at `roughness` as Blender `version`
    /// renders it.
    pub fn new(
        node: DielectricNode,
        distribution: Distribution,
        roughness: Roughness,
        version: BlenderVersion,
    ) -> Self {
        Dielectric {
            node,
            microfacet: Microfacet::new(distribution, roughness),
            masking: version.masking(),
            form: GlassForm::of(version),
            sampler: Sampler::of(distribution, version),
        }
    }

    /// Cycles samples a lobe this narrow as a perfect interface (`αx αy ≤ 1e-7` before the
    /// 3.6 rewrite, `≤ 2e-10` after).
    pub(super) fn is_smooth(&self) -> bool {
        let a2 = self.microfacet.alpha * self.microfacet.alpha;
        a2 <= match self.form {
            GlassForm::TwoClosures => 1e-7,
            GlassForm::OneClosure => 2e-10,
        }
    }

    /// `G2(v, l) / G1(v)` for the direction `l` leaving a microfacet, if the sampler keeps
    /// it: a reflection above the surface; a refraction below it, or from Blender 3.0–3.5's
    /// sampler, which does not check the side of a refracted direction, anywhere (one that
    /// leaves upwards goes on as it is).
    fn leave(&self, lambda_v: f64, l: DVec3, reflected: bool) -> Scatter {
        let wrong_side = if reflected {
            l.z <= 0.0
        } else {
            l.z >= 0.0 && self.form == GlassForm::OneClosure
        };
        if wrong_side || l.z == 0.0 {
            return Scatter::Lost;
        }
        let lambda_l = self.microfacet.lambda(l.z.abs());
        Scatter::Kept(self.masking.g2(lambda_v, lambda_l) * (1.0 + lambda_v))
    }

    /// The weight of a sample through the microfacet `h` (unit, `h.z > 0`, `v·h > 0`) for
    /// the view `v` at index `eta`, by lobe: `(reflection, refraction)`, each without the
    /// macro Fresnel of [`GlassForm::TwoClosures`] (the caller weights the two lobes).
    pub(super) fn lobes(&self, v: DVec3, h: DVec3, eta: f64, lambda_v: f64) -> (f64, f64) {
        let c = v.dot(h);
        let kept = |s: Scatter| match s {
            Scatter::Kept(g) => g,
            Scatter::Lost => 0.0,
        };
        let reflection = || kept(self.leave(lambda_v, 2.0 * c * h - v, true));
        // Snell at the microfacet: sin²θt = (1 − c²)/η²; none when that exceeds 1.
        let sin2_t = (1.0 - c * c) / (eta * eta);
        let refraction = || {
            if sin2_t >= 1.0 {
                return 0.0;
            }
            let cos_t = (1.0 - sin2_t).sqrt();
            let t = (c / eta - cos_t) * h - v / eta;
            kept(self.leave(lambda_v, t, false))
        };
        match (self.node, self.form) {
            (DielectricNode::Refraction, _) => (0.0, refraction()),
            (DielectricNode::Glass, GlassForm::TwoClosures) => (reflection(), refraction()),
            (DielectricNode::Glass, GlassForm::OneClosure) => {
                let f = fresnel::dielectric(c, eta);
                (f * reflection(), (1.0 - f) * refraction())
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn v(version: &str) -> BlenderVersion {
        version.parse().unwrap()
    }

    #[test]
    fn the_glass_form_changes_in_3_6() {
        assert_eq!(GlassForm::of(v("3.4")), GlassForm::TwoClosures);
        assert_eq!(GlassForm::of(v("3.5")), GlassForm::TwoClosures);
        assert_eq!(GlassForm::of(v("3.6")), GlassForm::OneClosure);
        assert_eq!(GlassForm::of(v("5.0")), GlassForm::OneClosure);
    }
}
