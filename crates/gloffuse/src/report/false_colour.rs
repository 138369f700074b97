//! The diverging colour scale of the false-colour pictures (verify's deviation view and
//! the audit's difference of a material from its twin).

use super::png::{BACKGROUND, srgb8};

/// The deviation at which the scale saturates: ±5 %.
pub const SCALE: f64 = 0.05;

/// The diverging colour of a deviation `d` (RdBu: blue at −[`SCALE`], near-white at 0,
/// red at +[`SCALE`]; clamped beyond); NaN is the background grey.
///
/// ```
/// use gloffuse::report::false_colour::colour;
/// assert_eq!(colour(0.0), [247, 247, 247]);
/// assert_eq!(colour(-1.0), [33, 102, 172]);
/// assert_eq!(colour(1.0), [178, 24, 43]);
/// ```
pub fn colour(d: f64) -> [u8; 3] {
    const LOW: [f64; 3] = [33.0, 102.0, 172.0];
    const MID: [f64; 3] = [247.0, 247.0, 247.0];
    const HIGH: [f64; 3] = [178.0, 24.0, 43.0];
    if d.is_nan() {
        let g = srgb8(BACKGROUND);
        return [g, g, g];
    }
    let t = (d / SCALE).clamp(-1.0, 1.0);
    let (from, to, f) = if t < 0.0 {
        (MID, LOW, -t)
    } else {
        (MID, HIGH, t)
    };
    [0, 1, 2].map(|c| (from[c] + (to[c] - from[c]) * f).round() as u8)
}
