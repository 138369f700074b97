//! The normal a glossy BSDF really shades with. Cycles never hands a bump or normal-map
//! normal straight to a specular lobe: where the mirror reflection about the shading normal
//! N would dip below `t = min(0.9 (Ng·I), 0.01)` above the true surface, it raises N towards
//! the geometric normal Ng, in the plane of the two, until the reflection sits at height t
//! (`docs/PHYSICS.md` §7). A view gain `1/E(μ, r)` must read μ from the raised normal.
//!
//! This is the reference the node groups' version of the same rule (`Gloffuse Shading
//! Normal`, built by `blender/gloffuse_blender/normal_group.py`) is tested against.

use glam::DVec3;

use super::version::BlenderVersion;

/// Which of Cycles' two rules a Blender version uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ReflectionRule {
    /// 3.0–3.5, `ensure_valid_reflection`: for every BSDF, two candidate roots checked.
    Checked,
    /// 3.6 and later, `ensure_valid_specular_reflection`: for specular lobes, one root in
    /// closed form (from 4.1 only while the material's Bump Map Correction is on).
    ClosedForm,
}

impl ReflectionRule {
    pub fn of(version: BlenderVersion) -> Self {
        if version >= (BlenderVersion { major: 3, minor: 6 }) {
            ReflectionRule::ClosedForm
        } else {
            ReflectionRule::Checked
        }
    }

    /// The normal the BSDF shades with, for the geometric normal `ng`, the direction to the
    /// viewer `i` and the shading normal `n` (all unit vectors).
    pub fn shading_normal(self, ng: DVec3, i: DVec3, n: DVec3) -> DVec3 {
        let iz = i.dot(ng);
        let t = (0.9 * iz).min(0.01);
        // The mirror reflection's height above the surface: (2 (N·I) N − I)·Ng.
        if 2.0 * n.dot(i) * n.dot(ng) - iz >= t {
            return n;
        }
        // The frame X (N's part across Ng), Z = Ng; N' = N'x X + N'z Ng with
        // 2 (N'x Ix + N'z Iz) N'z − Iz = t.
        let x = (n - n.dot(ng) * ng).normalize_or_zero();
        let ix = i.dot(x);
        let a = ix * ix + iz * iz;
        let raised = |nz2: f64| (1.0 - nz2).max(0.0).sqrt() * x + nz2.max(0.0).sqrt() * ng;
        match self {
            ReflectionRule::ClosedForm => {
                let b = 2.0 * (a + iz * t);
                let c = (t + iz) * (t + iz);
                let root = (b * b - 4.0 * a * c).max(0.0).sqrt();
                let nz2 = if ix < 0.0 { b + root } else { b - root } / (4.0 * a);
                raised(nz2)
            }
            ReflectionRule::Checked => {
                let b = (ix * ix * (a - t * t)).max(0.0).sqrt();
                let c = iz * t + a;
                let candidates = [(c + b) / (2.0 * a), (c - b) / (2.0 * a)];
                let valid = |z2: f64| z2 > 1e-5 && z2 <= 1.0 + 1e-5;
                let height = |z2: f64| {
                    let (nx, nz) = ((1.0 - z2).max(0.0).sqrt(), z2.max(0.0).sqrt());
                    2.0 * (nx * ix + nz * iz) * nz - iz
                };
                match candidates.map(valid) {
                    [true, true] => {
                        let [r1, r2] = candidates.map(height);
                        let first = if r1 >= 1e-5 && r2 >= 1e-5 {
                            r1 < r2
                        } else {
                            r1 > r2
                        };
                        raised(candidates[if first { 0 } else { 1 }])
                    }
                    [true, false] => raised(candidates[0]),
                    [false, true] => raised(candidates[1]),
                    [false, false] => ng,
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A normal tilted away from the viewer enough that its mirror reflection dips below
    /// the surface is raised until the reflection sits at height t exactly; one that does
    /// not dip is kept.
    #[test]
    fn raised_normals_put_the_reflection_at_the_threshold() {
        let ng = DVec3::Z;
        for rule in [ReflectionRule::Checked, ReflectionRule::ClosedForm] {
            for (view, tilt) in [(70.0f64, 40.0f64), (80.0, 20.0), (50.0, 60.0), (85.0, 5.0)] {
                let (v, b) = (view.to_radians(), tilt.to_radians());
                let i = DVec3::new(v.sin(), 0.0, v.cos());
                let n = DVec3::new(-b.sin(), 0.0, b.cos());
                let iz = i.dot(ng);
                let t = (0.9 * iz).min(0.01);
                let before = 2.0 * n.dot(i) * n.dot(ng) - iz;
                let m = rule.shading_normal(ng, i, n);
                assert!((m.length() - 1.0).abs() < 1e-12, "{rule:?} {view} {tilt}");
                let after = 2.0 * m.dot(i) * m.dot(ng) - iz;
                if before >= t {
                    assert_eq!(m, n, "{rule:?} {view} {tilt}: kept");
                } else {
                    assert!(
                        (after - t).abs() < 1e-9,
                        "{rule:?} {view} {tilt}: {after} vs {t}"
                    );
                    assert!(m.z > n.z, "{rule:?}: raised towards Ng");
                }
            }
            let kept = DVec3::new(0.1, 0.0, 0.995).normalize();
            assert_eq!(rule.shading_normal(ng, DVec3::Z, kept), kept);
        }
    }

    #[test]
    fn versions_pick_their_rule() {
        let v = |s: &str| s.parse::<BlenderVersion>().unwrap();
        assert_eq!(ReflectionRule::of(v("3.4")), ReflectionRule::Checked);
        assert_eq!(ReflectionRule::of(v("3.5")), ReflectionRule::Checked);
        assert_eq!(ReflectionRule::of(v("3.6")), ReflectionRule::ClosedForm);
        assert_eq!(ReflectionRule::of(v("5.0")), ReflectionRule::ClosedForm);
    }
}
