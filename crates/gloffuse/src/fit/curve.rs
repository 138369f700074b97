//! Correction curves `f(r)` in percent, with `f(0) = 100` and `f'(0) = 0`, fitted by
//! constrained least squares; the gain a shader applies is `100 / f(r)`.

use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};

use crate::error::{Error, Field};

/// Highest polynomial degree a fit may use.
pub const MAX_DEGREE: usize = 8;

/// The curve's free variable. Fitting in `alpha = r²` keeps `f'(0) = 0` for every
/// coefficient, so the r¹ term that the constraint forbids never appears.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Variable {
    /// x = r (the node's Roughness, clamped to [0, 1]); powers r⁰ and r², r³, …
    Roughness,
    /// x = r² (Cycles' alpha); powers α⁰, α¹, α², …
    Alpha,
}

impl Variable {
    pub fn of(self, r: f64) -> f64 {
        let r = r.clamp(0.0, 1.0);
        match self {
            Variable::Roughness => r,
            Variable::Alpha => r * r,
        }
    }

    /// The powers a fit of this degree may use besides the constant term.
    fn free_powers(self, degree: usize) -> Vec<i32> {
        match self {
            Variable::Roughness => (2..=degree as i32).collect(),
            Variable::Alpha => (1..=degree as i32).collect(),
        }
    }
}

/// `f(x) = numerator(x) / denominator(x)` in percent; coefficients in ascending powers.
/// A polynomial has `denominator = [1]`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Curve {
    pub variable: Variable,
    pub numerator: Vec<f64>,
    pub denominator: Vec<f64>,
}

fn horner(coefficients: &[f64], x: f64) -> f64 {
    coefficients.iter().rev().fold(0.0, |acc, &c| acc * x + c)
}

impl Curve {
    /// The brightness `f(r)` in percent that the curve predicts for roughness `r`.
    ///
    /// ```
    /// use gloffuse::fit::{Curve, Variable};
    /// let seed_ggx = Curve::polynomial(Variable::Roughness, vec![100.0, 0.0, -79.0, 38.0]);
    /// assert_eq!(seed_ggx.percent(1.0), 59.0);
    /// ```
    pub fn percent(&self, r: f64) -> f64 {
        let x = self.variable.of(r);
        horner(&self.numerator, x) / horner(&self.denominator, x)
    }

    /// The gain `100 / f(r)` a shader multiplies its colour by.
    pub fn gain(&self, r: f64) -> f64 {
        100.0 / self.percent(r)
    }

    pub fn polynomial(variable: Variable, numerator: Vec<f64>) -> Self {
        Curve {
            variable,
            numerator,
            denominator: vec![1.0],
        }
    }

    /// Polynomial degree in r (alpha-curves count double).
    pub fn degree_in_r(&self) -> usize {
        let d = self
            .numerator
            .len()
            .max(self.denominator.len())
            .saturating_sub(1);
        match self.variable {
            Variable::Roughness => d,
            Variable::Alpha => 2 * d,
        }
    }
}

/// How the least-squares residuals are weighted.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Weighting {
    /// Minimise the error in brightness points.
    Absolute,
    /// Minimise the relative error `f/y − 1`, i.e. the gain error (right for a gain).
    Relative,
}

impl Weighting {
    pub const ALL: [Weighting; 2] = [Weighting::Absolute, Weighting::Relative];

    pub fn key(self) -> &'static str {
        match self {
            Weighting::Absolute => "absolute",
            Weighting::Relative => "relative",
        }
    }
}

/// One measured or computed brightness: roughness r and brightness in percent.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Point {
    pub roughness: f64,
    pub percent: f64,
}

impl std::str::FromStr for Point {
    type Err = Error;

    /// `ROUGHNESS:PERCENT`, e.g. `0.5:97`.
    fn from_str(s: &str) -> Result<Self, Error> {
        let bad = |why: &str| {
            Error::input(
                Field::Point,
                s,
                format!(
                    "ROUGHNESS:PERCENT with roughness in [0, 1] and a brightness above 0, e.g. 0.5:97 ({why})"
                ),
            )
        };
        let (r, p) = s.split_once(':').ok_or_else(|| bad("no ':'"))?;
        let roughness: f64 = r
            .trim()
            .parse()
            .map_err(|_| bad("roughness is not a number"))?;
        let percent: f64 = p
            .trim()
            .parse()
            .map_err(|_| bad("percent is not a number"))?;
        if !roughness.is_finite() || !(0.0..=1.0).contains(&roughness) {
            return Err(bad("roughness outside [0, 1]"));
        }
        if !percent.is_finite() || percent <= 0.0 {
            return Err(bad("percent must be a finite number above 0"));
        }
        Ok(Point { roughness, percent })
    }
}

/// How far a curve is from its points.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Residuals {
    /// max |f(r) − y| in brightness points.
    pub max_points: f64,
    pub rms_points: f64,
    /// max |(100/f) / (100/y) − 1| = max |y/f − 1|: the gain's relative error.
    pub max_gain_error: f64,
    pub rms_gain_error: f64,
}

impl Residuals {
    pub fn of(curve: &Curve, points: &[Point]) -> Self {
        let n = points.len().max(1) as f64;
        let (mut maxp, mut sump, mut maxg, mut sumg) = (0.0f64, 0.0, 0.0f64, 0.0);
        for p in points {
            let f = curve.percent(p.roughness);
            let dp = (f - p.percent).abs();
            let dg = (p.percent / f - 1.0).abs();
            maxp = maxp.max(dp);
            maxg = maxg.max(dg);
            sump += dp * dp;
            sumg += dg * dg;
        }
        Residuals {
            max_points: maxp,
            rms_points: (sump / n).sqrt(),
            max_gain_error: maxg,
            rms_gain_error: (sumg / n).sqrt(),
        }
    }
}

/// A fitted curve with its residuals on the points it was fitted to.
#[derive(Clone, Debug, PartialEq)]
pub struct Fit {
    pub curve: Curve,
    pub residuals: Residuals,
}

/// Fits `f = 100 + Σ c_k x^k` (k ≥ 2 in r, k ≥ 1 in alpha) through `points` by least
/// squares. With as many points as free coefficients the fit is exact (the seed's
/// two-point solve). `degree` counts powers of the variable.
pub fn fit_polynomial(
    points: &[Point],
    variable: Variable,
    degree: usize,
    weighting: Weighting,
) -> Result<Fit, Error> {
    let min_degree = match variable {
        Variable::Roughness => 2,
        Variable::Alpha => 1,
    };
    if degree < min_degree || degree > MAX_DEGREE {
        return Err(Error::input(
            Field::Degree,
            degree,
            format!("a degree from {min_degree} to {MAX_DEGREE}"),
        ));
    }
    check_points(points)?;
    let powers = variable.free_powers(degree);
    if points.len() < powers.len() {
        return Err(Error::Fit(format!(
            "a degree-{degree} fit has {} free coefficients and needs at least {} points with distinct roughness; got {}",
            powers.len(),
            powers.len(),
            points.len()
        )));
    }
    if points
        .iter()
        .any(|p| p.roughness == 0.0 && p.percent != 100.0)
    {
        return Err(Error::Fit(
            "a point at roughness 0 must be 100 % (the curve is pinned to f(0) = 100)".into(),
        ));
    }
    let rows = points.len();
    let a = DMatrix::from_fn(rows, powers.len(), |i, j| {
        weight(weighting, points[i]) * variable.of(points[i].roughness).powi(powers[j])
    });
    let b = DVector::from_fn(rows, |i, _| {
        weight(weighting, points[i]) * (points[i].percent - 100.0)
    });
    let svd = a.svd(true, true);
    let smallest = svd
        .singular_values
        .iter()
        .cloned()
        .fold(f64::INFINITY, f64::min);
    let largest = svd.singular_values.iter().cloned().fold(0.0, f64::max);
    if smallest.is_nan() || smallest <= largest * 1e-13 {
        return Err(Error::Fit(
            "the points do not determine the coefficients (too few distinct non-zero roughness values for this degree)".into(),
        ));
    }
    let c = svd
        .solve(&b, 0.0)
        .map_err(|e| Error::Fit(format!("least-squares solve failed: {e}")))?;
    let mut numerator = vec![0.0; degree + 1];
    numerator[0] = 100.0;
    for (j, &p) in powers.iter().enumerate() {
        numerator[p as usize] = c[j];
    }
    let curve = Curve::polynomial(variable, numerator);
    let residuals = Residuals::of(&curve, points);
    Ok(Fit { curve, residuals })
}

fn weight(weighting: Weighting, p: Point) -> f64 {
    match weighting {
        Weighting::Absolute => 1.0,
        Weighting::Relative => 1.0 / p.percent,
    }
}

fn check_points(points: &[Point]) -> Result<(), Error> {
    for (i, p) in points.iter().enumerate() {
        if !p.roughness.is_finite() || !(0.0..=1.0).contains(&p.roughness) {
            return Err(Error::input(
                Field::PointRoughness,
                p.roughness,
                "a number from 0 to 1",
            ));
        }
        if !p.percent.is_finite() || p.percent <= 0.0 {
            return Err(Error::input(
                Field::PointPercent,
                p.percent,
                "a finite brightness above 0",
            ));
        }
        if let Some(q) = points[..i].iter().find(|q| q.roughness == p.roughness) {
            return Err(Error::Fit(format!(
                "duplicate roughness {}: points {}:{} and {}:{} (give each roughness once)",
                p.roughness, q.roughness, q.percent, p.roughness, p.percent
            )));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pts(v: &[(f64, f64)]) -> Vec<Point> {
        v.iter()
            .map(|&(roughness, percent)| Point { roughness, percent })
            .collect()
    }

    #[test]
    fn seed_two_point_solves_are_exact() {
        // Solved by hand: f(0.5) = 100 + b/4 + a/8, f(1) = 100 + a + b.
        let b = fit_polynomial(
            &pts(&[(0.5, 97.0), (1.0, 71.0)]),
            Variable::Roughness,
            3,
            Weighting::Absolute,
        )
        .unwrap();
        assert!((b.curve.numerator[3] - -34.0).abs() < 1e-9);
        assert!((b.curve.numerator[2] - 5.0).abs() < 1e-9);
        assert_eq!(b.curve.numerator[1], 0.0);
        assert_eq!(b.curve.numerator[0], 100.0);
        assert!(b.residuals.max_points < 1e-9);
        let g = fit_polynomial(
            &pts(&[(0.5, 85.0), (1.0, 59.0)]),
            Variable::Roughness,
            3,
            Weighting::Absolute,
        )
        .unwrap();
        assert!((g.curve.numerator[3] - 38.0).abs() < 1e-9);
        assert!((g.curve.numerator[2] - -79.0).abs() < 1e-9);
    }

    #[test]
    fn least_squares_recovers_a_known_polynomial() {
        // Points on 100 − 20 r² + 7 r⁴ − 3 r⁵, fitted at degree 5: exact recovery.
        let f = |r: f64| 100.0 - 20.0 * r * r + 7.0 * r.powi(4) - 3.0 * r.powi(5);
        let p: Vec<Point> = (1..=12)
            .map(|i| i as f64 / 12.0)
            .map(|r| Point {
                roughness: r,
                percent: f(r),
            })
            .collect();
        for w in [Weighting::Absolute, Weighting::Relative] {
            let fit = fit_polynomial(&p, Variable::Roughness, 5, w).unwrap();
            let want = [100.0, 0.0, -20.0, 0.0, 7.0, -3.0];
            for (c, w) in fit.curve.numerator.iter().zip(want) {
                assert!((c - w).abs() < 1e-8, "{:?}", fit.curve.numerator);
            }
        }
    }

    #[test]
    fn refuses_bad_point_sets() {
        // Too few points, a repeated roughness, degree above 8, degree below 2.
        let cases: [(&[(f64, f64)], usize); 4] = [
            (&[(0.5, 97.0)], 3),
            (&[(0.5, 97.0), (0.5, 90.0)], 3),
            (&[(0.5, 97.0), (1.0, 71.0)], 9),
            (&[(0.5, 97.0), (1.0, 71.0)], 1),
        ];
        for (points, degree) in cases {
            let fitted = fit_polynomial(
                &pts(points),
                Variable::Roughness,
                degree,
                Weighting::Absolute,
            );
            assert!(fitted.is_err(), "{points:?} at degree {degree}");
        }
        assert!("0.5".parse::<Point>().is_err());
        assert!("x:97".parse::<Point>().is_err());
        assert!("1.5:97".parse::<Point>().is_err());
        assert!("0.5:NaN".parse::<Point>().is_err());
        assert!("0.5:-3".parse::<Point>().is_err());
        assert_eq!(
            "0.5:97".parse::<Point>().unwrap(),
            Point {
                roughness: 0.5,
                percent: 97.0
            }
        );
    }
}
