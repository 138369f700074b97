//! The glass tables' view-cosine axes: crowded toward grazing, and about the critical
//! cosine of light leaving. The integrator splits its quadrature at the critical cosine and
//! the table builder lays its rows on these axes, so both read them from here.

/// The view cosine below which light leaving a glass of index `ior` reflects totally at
/// the normal: `√(1 − 1/IOR²)` (0 for an index of 1).
pub fn critical_cosine(ior: f64) -> f64 {
    (1.0 - 1.0 / (ior * ior)).max(0.0).sqrt()
}

/// The view-cosine axis of the leaving Refraction tables: `s` in [0, 1] is `μ = μc +
/// (1 − μc)(2s − 1)²` above the critical cosine `μc` (s ≥ ½) and `μ = μc − μc (1 − 2s)²`
/// below it, so μc sits at s = ½ in every slice and the grid points crowd there from both
/// sides. Leaving a nearly smooth glass the refraction lobe falls from most of the light to
/// almost none within a few hundredths of μ at μc (past it most microfacets reflect
/// totally, and a refraction closure ends their paths); a grid even in μ blurs that fall
/// (by over 100 % at r 0.1–0.5) and this one resolves it.
pub fn critical_crowded(s: f64, ior: f64) -> f64 {
    let c = critical_cosine(ior);
    let d = 2.0 * s - 1.0;
    if d >= 0.0 {
        c + (1.0 - c) * d * d
    } else {
        c - c * d * d
    }
}

/// [`critical_crowded`]'s inverse: the `s` of view cosine `mu` leaving a glass of `ior`.
pub fn critical_crowded_coordinate(mu: f64, ior: f64) -> f64 {
    let c = critical_cosine(ior);
    let mu = mu.clamp(0.0, 1.0);
    if mu >= c {
        0.5 + 0.5 * ((mu - c) / (1.0 - c)).sqrt()
    } else {
        0.5 - 0.5 * ((c - mu) / c).sqrt()
    }
}

/// The view-cosine axis of the groups' glass tables: `t` in [0, 1] is `μ = t^1.5`. Toward
/// grazing E falls about as √μ (at r 1, IOR 1.1, from 0.98 at μ 0 to 0.77 at 0.07), which
/// a grid even in μ cuts with one cell and misses by up to 14 %; this grid puts four rows
/// below μ 0.1. Crowding harder (μ = t²) reads the rim a little better but leaves the cells
/// near μ = 1 at 0.13 instead of 0.10, and leaving glass has a kink there at the critical
/// angle: read over t², a Beckmann r 1, IOR 1.5 sphere rendered 0.8 % bright.
pub fn grazing_crowded(t: f64) -> f64 {
    t.powf(1.5)
}

/// [`grazing_crowded`]'s inverse: the `t` of view cosine `mu`.
pub fn grazing_crowded_coordinate(mu: f64) -> f64 {
    mu.clamp(0.0, 1.0).powf(2.0 / 3.0)
}
