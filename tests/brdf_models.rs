//! The classic BRDFs (`gloffuse::measure::brdf`) against independent oracles: reciprocity, the
//! horizon, the sampler against its own pdf, brute-force quadrature over the sphere with far
//! more points than the sampler uses, and closed-form albedos derived in the comments.
//!
//! Tier: fast (no Blender; `scripts/test.sh --fast` runs it).

use glam::DVec3;
use gloffuse::measure::brdf::{
    Brdf, CookTorrance, FresnelBlendDiffuse, Lambert, Model, ModelParams, ModifiedPhong, Shadowing,
    Ward, model_albedo,
};
use rayon::prelude::*;
use std::f64::consts::{FRAC_PI_2, PI};

/// View cosines the albedo tests sweep.
const MUS: [f64; 3] = [0.1, 0.5, 1.0];
/// Sampler grid for the albedo estimates: 256² draws.
const GRID: usize = 256;
/// Agreement between the sampler estimate and brute-force quadrature: the measured gap is
/// at most 9e-6 at n = 256 for every case here (see `Brdf::albedo`).
const ALBEDO_TOL: f64 = 3e-5;
/// Slack for "albedo ≤ 1": the brute-force quadrature overshoots by up to 5e-6 on the
/// narrowest lobes tested (Phong n = 200 at μ = 1, whose exact albedo is 1).
const FURNACE_SLACK: f64 = 1e-5;

type Named = (String, Box<dyn Brdf + Sync>);

/// SplitMix64: deterministic uniform numbers in [0, 1) without a `rand` dependency.
struct SplitMix(u64);

impl SplitMix {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform on the unit sphere.
    fn sphere(&mut self) -> DVec3 {
        let z = 2.0 * self.next() - 1.0;
        let r = (1.0 - z * z).max(0.0).sqrt();
        let (s, c) = (2.0 * PI * self.next()).sin_cos();
        DVec3::new(r * c, r * s, z)
    }

    /// Uniform on the upper hemisphere.
    fn hemisphere(&mut self) -> DVec3 {
        let w = self.sphere();
        DVec3::new(w.x, w.y, w.z.abs())
    }
}

fn view(mu: f64) -> DVec3 {
    DVec3::new((1.0 - mu * mu).sqrt(), 0.0, mu)
}

/// Every model with assorted parameters (coloured and white, narrow and broad).
fn all_models() -> Vec<Named> {
    let mut v: Vec<Named> = Vec::new();
    for rho in [0.3, 1.0] {
        v.push((
            format!("lambert {rho}"),
            Box::new(Lambert::new(rho).unwrap()),
        ));
    }
    for n in [0.0, 1.0, 20.0, 500.0] {
        v.push((
            format!("phong n={n}"),
            Box::new(ModifiedPhong::new(0.8, n).unwrap()),
        ));
    }
    for (ax, ay) in [(0.3, 0.3), (0.1, 0.4), (0.5, 0.05)] {
        v.push((
            format!("ward {ax}x{ay}"),
            Box::new(Ward::new(0.7, ax, ay).unwrap()),
        ));
    }
    for s in [Shadowing::VCavity, Shadowing::Smith] {
        for (f0, a) in [(0.04, 0.05), (0.9, 0.3), (1.0, 1.0)] {
            v.push((
                format!("cook-torrance {s:?} f0={f0} a={a}"),
                Box::new(CookTorrance::new(f0, a).unwrap().with_shadowing(s)),
            ));
        }
    }
    for (rd, rs) in [(0.5, 0.04), (1.0, 0.0)] {
        v.push((
            format!("fresnel-blend {rd} {rs}"),
            Box::new(FresnelBlendDiffuse::new(rd, rs).unwrap()),
        ));
    }
    v
}

/// White parameters (reflectance 1) with lobes broad enough for the brute-force grid.
fn white_models() -> Vec<Named> {
    let mut v: Vec<Named> = vec![
        ("lambert".into(), Box::new(Lambert::new(1.0).unwrap())),
        (
            "fresnel-blend".into(),
            Box::new(FresnelBlendDiffuse::new(1.0, 0.0).unwrap()),
        ),
    ];
    for n in [0.0, 1.0, 20.0, 200.0] {
        v.push((
            format!("phong n={n}"),
            Box::new(ModifiedPhong::new(1.0, n).unwrap()),
        ));
    }
    for (ax, ay) in [(0.1, 0.1), (0.2, 0.2), (0.1, 0.3)] {
        v.push((
            format!("ward {ax}x{ay}"),
            Box::new(Ward::new(1.0, ax, ay).unwrap()),
        ));
    }
    for s in [Shadowing::VCavity, Shadowing::Smith] {
        for a in [0.1, 0.3, 0.7, 1.5] {
            v.push((
                format!("cook-torrance {s:?} a={a}"),
                Box::new(CookTorrance::new(1.0, a).unwrap().with_shadowing(s)),
            ));
        }
    }
    v
}

/// Midpoint rule over (θ, φ) ∈ (0, θmax) × (0, 2π) of g(ω) sinθ, rows in parallel.
fn sphere_midpoint(theta_max: f64, n_theta: usize, g: impl Fn(DVec3) -> f64 + Sync) -> f64 {
    let n_phi = 2 * n_theta;
    let (dt, dp) = (theta_max / n_theta as f64, 2.0 * PI / n_phi as f64);
    (0..n_theta)
        .into_par_iter()
        .map(|i| {
            let (st, ct) = ((i as f64 + 0.5) * dt).sin_cos();
            let row: f64 = (0..n_phi)
                .map(|j| {
                    let (sp, cp) = ((j as f64 + 0.5) * dp).sin_cos();
                    g(DVec3::new(st * cp, st * sp, ct))
                })
                .sum();
            row * st
        })
        .sum::<f64>()
        * dt
        * dp
}

/// Brute-force `E(μ) = ∫ f cosθi dωi` over the hemisphere, 2000 × 4000 midpoints.
fn brute_albedo(b: &(dyn Brdf + Sync), mu: f64) -> f64 {
    let wo = view(mu);
    sphere_midpoint(FRAC_PI_2, 2000, |wi| b.eval(wo, wi) * wi.z)
}

/// Fraction of an n×n midpoint grid of u for which `sample` returns `Some`.
fn acceptance(b: &(dyn Brdf + Sync), wo: DVec3, n: usize) -> f64 {
    let mut hits = 0usize;
    for i in 0..n {
        for j in 0..n {
            let u = [(i as f64 + 0.5) / n as f64, (j as f64 + 0.5) / n as f64];
            hits += usize::from(b.sample(wo, u).is_some());
        }
    }
    hits as f64 / (n * n) as f64
}

#[test]
fn helmholtz_reciprocity() {
    let mut rng = SplitMix(1);
    for (name, b) in all_models() {
        for _ in 0..20_000 {
            let (wo, wi) = (rng.hemisphere(), rng.hemisphere());
            let (a, c) = (b.eval(wo, wi), b.eval(wi, wo));
            assert!(
                (a - c).abs() <= 1e-12 * a.abs().max(c.abs()),
                "{name}: f({wo}, {wi}) = {a} but f({wi}, {wo}) = {c}"
            );
        }
    }
}

#[test]
fn non_negative_and_zero_below_horizon() {
    let mut rng = SplitMix(2);
    for (name, b) in all_models() {
        for k in 0..20_000 {
            // Half the pairs over the whole sphere, half in the upper hemisphere.
            let (wo, wi) = if k % 2 == 0 {
                (rng.sphere(), rng.sphere())
            } else {
                (rng.hemisphere(), rng.hemisphere())
            };
            let (f, p) = (b.eval(wo, wi), b.pdf(wo, wi));
            assert!(f.is_finite() && f >= 0.0, "{name}: f({wo}, {wi}) = {f}");
            assert!(p.is_finite() && p >= 0.0, "{name}: pdf({wo}, {wi}) = {p}");
            if wo.z <= 0.0 || wi.z <= 0.0 {
                assert_eq!(f, 0.0, "{name}: f({wo}, {wi}) below the horizon");
                assert_eq!(p, 0.0, "{name}: pdf({wo}, {wi}) below the horizon");
            }
        }
        let below = DVec3::new(0.6, 0.0, -0.8);
        assert!(
            b.sample(below, [0.3, 0.7]).is_none(),
            "{name}: sampled from below"
        );
    }
}

#[test]
fn sample_returns_the_pdf_that_pdf_computes() {
    for (name, b) in all_models() {
        for mu in [0.05, 0.3, 0.7, 1.0] {
            let wo = view(mu);
            let n = 64;
            let mut some = 0;
            for i in 0..n {
                for j in 0..n {
                    let u = [(i as f64 + 0.5) / n as f64, (j as f64 + 0.5) / n as f64];
                    let Some((wi, p)) = b.sample(wo, u) else {
                        continue;
                    };
                    some += 1;
                    assert!(
                        (wi.length() - 1.0).abs() < 1e-12,
                        "{name}: |wi| = {}",
                        wi.length()
                    );
                    assert!(wi.z > 0.0 && p > 0.0, "{name}: wi {wi}, pdf {p}");
                    let q = b.pdf(wo, wi);
                    assert!(
                        (p - q).abs() <= 1e-9 * p,
                        "{name} μ={mu} u={u:?}: sample pdf {p}, pdf() {q}"
                    );
                }
            }
            assert!(some > 0, "{name} μ={mu}: no sample above the horizon");
        }
    }
}

/// `∫ pdf dωi` over the whole sphere (1000 × 2000 midpoints, 2e-4 from the limit at worst) equals the fraction of draws
/// `sample` returns: exactly 1 for the cosine samplers (Lambert, Fresnel blend); below 1 for
/// the lobes (Phong, Ward, Cook–Torrance), whose draws can land below the horizon (or, for
/// the half-vector samplers, have h facing away from ωo) and come back `None`. The sampled
/// fraction on a 1024² grid is within 1/2048 of its limit where the cut is a line in u.
#[test]
fn pdf_integrates_to_the_sampler_acceptance() {
    for (name, b) in all_models() {
        for mu in [0.2, 0.6, 1.0] {
            let wo = view(mu);
            let integral = sphere_midpoint(PI, 1000, |wi| b.pdf(wo, wi));
            let accepted = acceptance(b.as_ref(), wo, 1024);
            assert!(integral <= 1.0 + 1e-3, "{name} μ={mu}: ∫pdf = {integral}");
            assert!(
                (integral - accepted).abs() < 1e-3,
                "{name} μ={mu}: ∫pdf = {integral}, fraction sampled {accepted}"
            );
            if name.starts_with("lambert") || name.starts_with("fresnel") {
                assert_eq!(accepted, 1.0, "{name}");
                assert!(
                    (integral - 1.0).abs() < 1e-5,
                    "{name} μ={mu}: ∫pdf = {integral}"
                );
            }
        }
    }
}

/// White furnace: the sampler estimate and brute-force quadrature agree, and neither
/// exceeds 1 (Lambert: equals 1). Also the convergence `Brdf::albedo` documents: max
/// |error| 1.8e-4 at n = 64 (asserted with a margin), 9e-6 at n = 256.
#[test]
fn white_furnace_two_methods() {
    for (name, b) in white_models() {
        for mu in MUS {
            let sampled = b.albedo(mu, GRID);
            let brute = brute_albedo(b.as_ref(), mu);
            let coarse = b.albedo(mu, 64);
            assert!(
                (coarse - brute).abs() < 2.5e-4,
                "{name} μ={mu}: sampler at n = 64 {coarse}, quadrature {brute}"
            );
            assert!(
                (sampled - brute).abs() < ALBEDO_TOL,
                "{name} μ={mu}: sampler {sampled}, quadrature {brute}"
            );
            assert!(
                sampled <= 1.0 + FURNACE_SLACK,
                "{name} μ={mu}: sampler albedo {sampled} > 1"
            );
            assert!(
                brute <= 1.0 + FURNACE_SLACK,
                "{name} μ={mu}: quadrature albedo {brute} > 1"
            );
            if name == "lambert" {
                assert!(
                    (sampled - 1.0).abs() < 1e-3 && (brute - 1.0).abs() < 1e-3,
                    "{name}"
                );
            }
        }
    }
}

/// Ward's 1/√(cosθi cosθo) lifts grazing reflection for wide lobes (E(0.02) rises from
/// 0.05 at α = 0.05 to 0.50 at α = 0.7) but, for every width scanned, stays below 1;
/// the largest value is at normal incidence with the narrowest lobe.
#[test]
fn ward_white_furnace_scan_stays_below_one() {
    let mut largest: f64 = 0.0;
    for a in [0.05, 0.2, 0.7, 1.0, 2.0] {
        let b = Ward::new(1.0, a, a).unwrap();
        for mu in [0.02, 0.1, 0.3, 0.6, 1.0] {
            let e = b.albedo(mu, 128);
            assert!(e > 0.0 && e < 1.0, "Ward α={a} μ={mu}: {e}");
            largest = largest.max(e);
        }
    }
    let narrow_normal = Ward::new(1.0, 0.05, 0.05).unwrap().albedo(1.0, 128);
    assert_eq!(largest, narrow_normal);
    let wide_grazing = Ward::new(1.0, 0.7, 0.7).unwrap().albedo(0.02, 128);
    let narrow_grazing = Ward::new(1.0, 0.05, 0.05).unwrap().albedo(0.02, 128);
    assert!(
        wide_grazing > 5.0 * narrow_grazing,
        "{wide_grazing} vs {narrow_grazing}"
    );
}

#[test]
fn lambert_albedo_is_rho() {
    for rho in [0.0, 0.25, 1.0] {
        let b = Lambert::new(rho).unwrap();
        for mu in [0.01, 0.1, 0.5, 0.9, 1.0] {
            let e = b.albedo(mu, 16);
            assert!((e - rho).abs() < 1e-12, "ρ={rho} μ={mu}: {e}");
        }
    }
}

/// `2π ∫₀¹ (1 − (1 − c/2)⁵) c dc = 2π (1/2 − 5/56) = 23π/28`, so
/// `E(μ) = Rd (1 − Rs)(1 − (1 − μ/2)⁵)`.
#[test]
fn fresnel_blend_albedo_closed_form() {
    for (rd, rs) in [(1.0, 0.0), (0.6, 0.04), (0.3, 0.5)] {
        let b = FresnelBlendDiffuse::new(rd, rs).unwrap();
        for mu in [0.05f64, 0.1, 0.5, 0.8, 1.0] {
            let exact = rd * (1.0 - rs) * (1.0 - (1.0 - 0.5 * mu).powi(5));
            let e = b.albedo(mu, GRID);
            assert!(
                (e - exact).abs() < 1e-5,
                "Rd={rd} Rs={rs} μ={mu}: {e} vs {exact}"
            );
        }
    }
}

/// Modified Phong, `f = ρs (n+2)/(2π) cosⁿα` (cosα > 0), in closed form:
/// - μ = 1: the mirror direction is the normal, α = θi, so
///   `E = ρs (n+2)/(2π) · 2π ∫₀¹ cⁿ⁺¹ dc = ρs` for every n.
/// - Any μ: over the whole lobe cosα > 0 (which reaches below the horizon),
///   `∫ (n+2)/(2π) cosⁿα (ωi·n) dωi = (r·n) (n+2)/(2π) ∫ cosⁿ⁺¹α dω = μ` (the sinα part
///   averages out in azimuth); the horizon removes only the negative part, so E ≥ ρs μ,
///   and E → ρs μ as n → ∞ (the lobe leaves the horizon).
/// - n = 0: f = ρs/π on {cosα > 0, cosθi > 0}, whose projected area is a half disc plus a
///   half ellipse with semi-axes 1 and μ: `E = ρs (1 + μ)/2`.
/// - n = 1: `∫ ⟨a·ω⟩⟨b·ω⟩ dω = (2/3)((π − γ) cosγ + sinγ)` for unit a, b at angle γ = θo,
///   so `E = ρs ((π − θo) μ + sinθo) / π`.
#[test]
fn phong_albedo_closed_forms() {
    let rho = 0.9;
    for n in [0.0, 1.0, 5.0, 50.0, 1000.0] {
        let e = ModifiedPhong::new(rho, n).unwrap().albedo(1.0, GRID);
        assert!((e - rho).abs() < 1e-5, "n={n}: E(1) = {e}");
    }
    for mu in [0.05, 0.1, 0.3, 0.5, 0.8, 1.0] {
        let theta = f64::acos(mu);
        let e0 = ModifiedPhong::new(rho, 0.0).unwrap().albedo(mu, GRID);
        let exact0 = rho * (1.0 + mu) / 2.0;
        assert!((e0 - exact0).abs() < 2e-5, "n=0 μ={mu}: {e0} vs {exact0}");
        let e1 = ModifiedPhong::new(rho, 1.0).unwrap().albedo(mu, GRID);
        let exact1 = rho * ((PI - theta) * mu + theta.sin()) / PI;
        assert!((e1 - exact1).abs() < 2e-5, "n=1 μ={mu}: {e1} vs {exact1}");
        // The same two closed forms by brute-force quadrature, independent of the sampler.
        let b1 = ModifiedPhong::new(rho, 1.0).unwrap();
        let q1 = brute_albedo(&b1, mu);
        assert!(
            (q1 - exact1).abs() < 1e-5,
            "n=1 μ={mu}: quadrature {q1} vs {exact1}"
        );
    }
    for n in [2.0, 10.0, 100.0, 1000.0] {
        for mu in [0.05, 0.2, 0.5, 0.9] {
            let e = ModifiedPhong::new(rho, n).unwrap().albedo(mu, GRID);
            assert!(e >= rho * mu - 1e-4 && e <= rho + 1e-4, "n={n} μ={mu}: {e}");
        }
    }
    let e = ModifiedPhong::new(rho, 1e4).unwrap().albedo(0.5, GRID);
    assert!((e - rho * 0.5).abs() < 1e-4, "n=1e4 μ=0.5: {e}");
}

/// As α → 0, G → 1 and h → n, so Cook–Torrance reflects the Schlick Fresnel at the mirror
/// angle: E(μ) → f0 + (1 − f0)(1 − μ)⁵. Ward's narrow lobe tends to ρs μ instead:
/// f cosθi dωi = ρs √(cosθi/cosθo) · 4(ωo·h) · exp(…)/(4π α²) dωh → ρs μ at h = n.
#[test]
fn narrow_lobe_limits() {
    for s in [Shadowing::VCavity, Shadowing::Smith] {
        for (f0, mu) in [(0.04, 0.5), (0.5, 0.3), (1.0, 0.8)] {
            let b = CookTorrance::new(f0, 1e-3).unwrap().with_shadowing(s);
            let e = b.albedo(mu, GRID);
            let exact = f0 + (1.0 - f0) * (1.0 - mu).powi(5);
            assert!(
                (e - exact).abs() < 1e-3,
                "{s:?} f0={f0} μ={mu}: {e} vs {exact}"
            );
        }
    }
    for mu in [0.3, 0.6, 1.0] {
        let e = Ward::new(0.8, 1e-3, 2e-3).unwrap().albedo(mu, GRID);
        assert!((e - 0.8 * mu).abs() < 1e-3, "Ward μ={mu}: {e}");
    }
}

/// αx runs along the tangent x: turning both directions by 90° about the normal is the
/// same as swapping αx and αy.
#[test]
fn ward_anisotropy_follows_the_tangent() {
    let (a, b) = (
        Ward::new(0.7, 0.1, 0.4).unwrap(),
        Ward::new(0.7, 0.4, 0.1).unwrap(),
    );
    let turn = |w: DVec3| DVec3::new(-w.y, w.x, w.z);
    let mut rng = SplitMix(3);
    for _ in 0..1000 {
        let (wo, wi) = (rng.hemisphere(), rng.hemisphere());
        let (x, y) = (a.eval(wo, wi), b.eval(turn(wo), turn(wi)));
        assert!((x - y).abs() <= 1e-12 * x.max(y), "{x} vs {y}");
    }
    // A lobe stretched along x reflects a view along x differently from one along y.
    assert!((a.albedo(0.3, 64) - b.albedo(0.3, 64)).abs() > 1e-3);
}

#[test]
fn constructors_reject_bad_values() {
    for bad in [-0.1, 1.1, f64::NAN, f64::INFINITY] {
        assert!(Lambert::new(bad).is_err(), "Lambert ρ={bad}");
        assert!(ModifiedPhong::new(bad, 10.0).is_err(), "Phong ρs={bad}");
        assert!(Ward::new(bad, 0.2, 0.2).is_err(), "Ward ρs={bad}");
        assert!(CookTorrance::new(bad, 0.2).is_err(), "CT f0={bad}");
        assert!(FresnelBlendDiffuse::new(bad, 0.0).is_err(), "FB Rd={bad}");
        assert!(FresnelBlendDiffuse::new(0.5, bad).is_err(), "FB Rs={bad}");
    }
    for bad in [-1.0, f64::NAN, f64::INFINITY] {
        assert!(ModifiedPhong::new(0.5, bad).is_err(), "Phong n={bad}");
    }
    for bad in [0.0, -0.2, f64::NAN, f64::INFINITY] {
        assert!(Ward::new(0.5, bad, 0.2).is_err(), "Ward αx={bad}");
        assert!(Ward::new(0.5, 0.2, bad).is_err(), "Ward αy={bad}");
        assert!(CookTorrance::new(0.5, bad).is_err(), "CT α={bad}");
    }
    assert!(ModifiedPhong::new(0.5, 0.0).is_ok());
    let msg = Ward::new(0.5, 0.0, 0.2).unwrap_err().to_string();
    assert!(msg.contains("alpha_x") && msg.contains("> 0"), "{msg}");
}

#[test]
fn model_names_and_model_albedo() {
    for (s, m) in [
        ("lambert", Model::Lambert),
        ("Phong", Model::Phong),
        ("WARD", Model::Ward),
        ("cook-torrance", Model::CookTorrance),
        ("Cook_Torrance", Model::CookTorrance),
        ("fresnel-blend", Model::FresnelBlend),
    ] {
        assert_eq!(s.parse::<Model>().unwrap(), m, "{s}");
        assert_eq!(m.to_string().parse::<Model>().unwrap(), m);
    }
    assert!("blinn".parse::<Model>().is_err());

    let p = ModelParams {
        rho: 0.6,
        rs: 0.1,
        ..ModelParams::default()
    };
    let e = model_albedo(Model::FresnelBlend, &p, 0.5).unwrap();
    let exact = 0.6 * 0.9 * (1.0 - 0.75f64.powi(5));
    assert!((e - exact).abs() < 1e-6, "{e} vs {exact}");
    for m in Model::ALL {
        let e = model_albedo(m, &ModelParams::default(), 1.0).unwrap();
        assert!(e > 0.0 && e <= 1.0 + 1e-6, "{m}: {e}");
    }
    for mu in [0.0, -0.5, 1.5, f64::NAN] {
        assert!(model_albedo(Model::Lambert, &p, mu).is_err(), "μ={mu}");
    }
    let bad = ModelParams {
        alpha_x: 0.0,
        ..ModelParams::default()
    };
    assert!(model_albedo(Model::Ward, &bad, 0.5).is_err());
    assert!(
        model_albedo(Model::Lambert, &bad, 0.5).is_ok(),
        "unused parameters are not read"
    );
}
