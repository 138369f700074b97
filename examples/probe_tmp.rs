use gloffuse::microfacet::*;
use gloffuse::fit::*;
fn main() {
    let q = AlbedoIntegrator::default();
    for m in [Masking::HeightCorrelated, Masking::Separable] {
    for d in Distribution::ALL {
        let rs: Vec<f64> = (0..=200).map(|i| i as f64 / 200.0).collect();
        let e = q.average_table(|r| Glossy::new(d, m, Roughness::new(r).unwrap()), &rs);
        let pts: Vec<Point> = rs.iter().zip(&e).map(|(&r, &e)| Point { roughness: r, percent: 100.0 * e }).collect();
        for var in [Variable::Roughness, Variable::Alpha] {
            let degs: Vec<usize> = if var == Variable::Roughness { (3..=8).collect() } else { (1..=4).collect() };
            for deg in degs {
                let mut s = String::new();
                for w in [Weighting::Absolute, Weighting::Relative] {
                    let f = fit_polynomial(&pts, var, deg, w).unwrap();
                    s += &format!(" {:?}: maxgain {:.4}% ", w, 100.0 * f.residuals.max_gain_error);
                }
                println!("{m} {d} {var:?} deg {deg}: {s}");
            }
        }
        println!("  Eavg(1) = {:.5}", e[200]);
    }}
}
