//! Dielectric Fresnel reflectance, as Cycles computes it (`fresnel_dielectric_cos` in
//! `kernel/closure/bsdf_util.h`, the same from 3.4 to 5.0; see `docs/PHYSICS.md` §13).

/// Unpolarised reflectance of a smooth dielectric of relative index `eta` (inside over
/// outside) for light arriving at cosine `cos` to its normal: with `c = |cos|` and
/// `g² = η² − 1 + c²`, `F = ½ ((g − c)/(g + c))² (1 + ((c(g + c) − 1)/(c(g − c) + 1))²)`;
/// 1 under total internal reflection (`g² ≤ 0`).
pub fn dielectric(cos: f64, eta: f64) -> f64 {
    let c = cos.abs();
    let g2 = eta * eta - 1.0 + c * c;
    if g2 <= 0.0 {
        return 1.0;
    }
    let g = g2.sqrt();
    let a = (g - c) / (g + c);
    let b = (c * (g + c) - 1.0) / (c * (g - c) + 1.0);
    0.5 * a * a * (1.0 + b * b)
}

/// Reflectance at normal incidence, `((η − 1)/(η + 1))²`.
pub fn f0(eta: f64) -> f64 {
    ((eta - 1.0) / (eta + 1.0)).powi(2)
}

/// The index whose normal-incidence reflectance is `f0` ∈ [0, 1): `(1 + √F0)/(1 − √F0)`.
pub fn ior_from_f0(f0: f64) -> f64 {
    let s = f0.clamp(0.0, 1.0 - 1e-12).sqrt();
    (1.0 + s) / (1.0 - s)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normal_incidence_and_grazing() {
        for eta in [1.0, 1.33, 1.5, 2.0, 3.0] {
            assert!((dielectric(1.0, eta) - f0(eta)).abs() < 1e-15, "{eta}");
            assert!((dielectric(1e-9, eta) - 1.0).abs() < 1e-6 || eta == 1.0);
            assert!((ior_from_f0(f0(eta)) - eta).abs() < 1e-12);
        }
        // A matched index reflects nothing; glass at 45°: the s and p textbook values.
        assert_eq!(dielectric(0.7, 1.0), 0.0);
        let c = std::f64::consts::FRAC_1_SQRT_2;
        let (eta, s) = (1.5f64, (1.0f64 - 0.5 / 2.25).sqrt()); // cos of the refracted angle
        let rs = ((c - eta * s) / (c + eta * s)).powi(2);
        let rp = ((s - eta * c) / (s + eta * c)).powi(2);
        assert!((dielectric(c, eta) - 0.5 * (rs + rp)).abs() < 1e-15);
        // Inside glass beyond the critical angle: total internal reflection.
        assert_eq!(dielectric(0.5, 1.0 / 1.5), 1.0);
    }
}
