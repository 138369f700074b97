//! The verify verdict in words, shared by the terminal table, the page and the pictures:
//! what passed, what failed and against what. Written so a person needs no second
//! reading: the count that comes first is the count that failed. What each mode's spheres
//! are called and what it judges are in its spec ([`crate::verify::ModeSpec`]).

use crate::generate::ColorModel;
use crate::verify::{VerifyReport, spec};

/// The verdict line. `PASS: all 33 corrected spheres within ±1 % of their target`, or
/// `FAIL: 12 of 22 corrected spheres missed their target …; the other 10 passed`.
pub fn headline(report: &VerifyReport) -> String {
    let total = report.rows.len();
    let failed = report.rows.iter().filter(|r| !r.pass).count();
    let tolerance = report.tolerance_percent;
    let rings = report.ring_tolerance_percent;
    let per_pixel = report.mode.per_pixel();
    let mode = report.mode.key();
    if failed == 0 {
        let rings = if per_pixel {
            format!(", every view-cosine ring within ±{rings} %")
        } else {
            String::new()
        };
        format!(
            "PASS: all {total} corrected spheres ({mode} mode) within ±{tolerance} % of their target{rings}"
        )
    } else {
        let rings = if per_pixel {
            format!(" or a view-cosine ring by more than ±{rings} %")
        } else {
            String::new()
        };
        format!(
            "FAIL: {failed} of {total} corrected spheres ({mode} mode) missed their target by more than ±{tolerance} %{rings}; the other {} passed",
            total - failed
        )
    }
}

/// What "target" means in this report: the value every corrected sphere is judged against.
pub fn target(report: &VerifyReport) -> String {
    let white = report.color == [1.0; 3];
    if let Some(own) = spec(report.mode).own_target {
        return own.to_string();
    }
    match report.color_model {
        ColorModel::Exact if white => {
            "the target is 100 %: a white sphere in a white world that loses no energy".to_string()
        }
        ColorModel::Exact => "the target is 100 % of the sphere's colour".to_string(),
        ColorModel::Physical => "the target is the sphere's colour with its multiple \
             bounces tinted by the colour, as Blender's Multiscatter GGX renders it"
            .to_string(),
    }
}

/// What the "predicted" numbers are, and that the verdict does not compare with them.
pub const PREDICTED: &str = "what these coefficients should give, from the \
     integrator (a fitted curve can itself miss 100 % by a little); the verdict compares the \
     render with the target, not with this prediction";

/// Roughness mode's scope ([`crate::verify::ModeSpec::scope`]) in one line, for the
/// false-colour picture.
pub const ROUGHNESS_PICTURE: &str = "Roughness mode corrects only each sphere's mean: centres \
     and rims off target in opposite directions are expected, not judged (view mode corrects them)";
