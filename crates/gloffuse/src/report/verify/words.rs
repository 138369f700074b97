//! The verify verdict in words, shared by the terminal table, the page and the pictures:
//! what passed, what failed and against what, and what the sweep's mode judges. Written so
//! a person needs no second reading: the count that comes first is the count that failed.

use crate::generate::{ColorModel, Mode};
use crate::verify::VerifyReport;

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

/// What a report calls a row's two spheres in `mode`: (the plain one, the corrected one).
pub fn sphere_names(mode: Mode) -> (&'static str, &'static str) {
    match mode {
        Mode::Layered => ("Mix Shader", "layered"),
        Mode::Glass => ("Glass BSDF", "corrected"),
        _ => ("uncorrected", "corrected"),
    }
}

/// What "target" means in this report: the value every corrected sphere is judged against.
pub fn target(report: &VerifyReport) -> String {
    let white = report.color == [1.0; 3];
    match (report.mode, report.color_model) {
        (Mode::Layered, _) => "the target is what the layered coat promises: A + Base Color × \
             (1 − A), with A the coat's albedo, averaged over the sphere (100 % for a white base)"
            .to_string(),
        (_, ColorModel::Exact) if white => {
            "the target is 100 %: a white sphere in a white world that loses no energy".to_string()
        }
        (_, ColorModel::Exact) => "the target is 100 % of the sphere's colour".to_string(),
        (_, ColorModel::Physical) => "the target is the sphere's colour with its multiple \
             bounces tinted by the colour, as Blender's Multiscatter GGX renders it"
            .to_string(),
    }
}

/// What the mode corrects and so what is judged; in roughness mode, why the rings and
/// false-colour pictures are off target on a sphere that passes.
pub fn scope(mode: Mode) -> &'static str {
    match mode {
        Mode::Roughness => {
            "Roughness mode corrects only each sphere's mean brightness (one gain per \
             roughness), not how brightness changes with the view direction: a corrected \
             sphere's centre and rim stay off target in opposite directions (which is \
             brighter depends on the roughness). So only the mean is judged; the rings are \
             shown, not judged, and red and blue rings in the false colour are expected. \
             View mode corrects every view direction."
        }
        Mode::View | Mode::Multiscatter | Mode::Anisotropic => {
            "This mode corrects every view direction, so both the sphere's mean and every \
             view-cosine ring are judged."
        }
        Mode::Layered => {
            "Layered mode corrects the coat at every view direction, so both the sphere's \
             mean and every view-cosine ring are judged."
        }
        Mode::Glass => {
            "Glass mode corrects the interface at every view direction, light entering and \
             leaving, so both a solid sphere's mean and every view-cosine ring are judged. \
             Light crosses a solid sphere's surfaces many times (1,024 bounces are rendered), \
             so the plain Glass BSDF's sphere has no prediction, and the renders are noisier \
             than a glossy sphere's: hence the wider default tolerances."
        }
    }
}

/// What the "predicted" numbers are, and that the verdict does not compare with them.
pub const PREDICTED: &str = "what these coefficients should give, from the \
     integrator (a fitted curve can itself miss 100 % by a little); the verdict compares the \
     render with the target, not with this prediction";

/// [`scope`]'s roughness mode in one line, for the false-colour picture.
pub const ROUGHNESS_PICTURE: &str = "Roughness mode corrects only each sphere's mean: centres \
     and rims off target in opposite directions are expected, not judged (view mode corrects them)";
