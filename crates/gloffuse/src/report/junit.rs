//! The verify report as JUnit XML, for CI servers: one test case per corrected sphere (its
//! mean), and in the view modes one per sphere's view-cosine rings, with what was measured,
//! predicted and allowed as properties and, on failure, the message and the commands to
//! rerun the check and the render.

use quick_junit::{NonSuccessKind, Property, Report, TestCase, TestCaseStatus, TestSuite};

use crate::generate::Mode;
use crate::verify::VerifyReport;

/// `rerun` is the command line that reproduces the whole check (the CLI passes its own).
pub fn render(report: &VerifyReport, rerun: &str) -> String {
    let suite_name = format!("gloffuse verify ({} mode)", report.mode.key());
    let mut suite = TestSuite::new(suite_name.as_str());
    let info = &report.render;
    for (name, value) in [
        ("blender", info.blender_version.clone()),
        ("coefficients", report.coefficients.clone()),
        ("samples", info.samples.to_string()),
        ("resolution", info.cell.to_string()),
        ("color_model", report.color_model.key().to_string()),
        ("tolerance_percent", report.tolerance_percent.to_string()),
        (
            "ring_tolerance_percent",
            report.ring_tolerance_percent.to_string(),
        ),
    ] {
        suite.add_property(Property::new(name, value));
    }
    let classname = format!("gloffuse.verify.{}", report.mode.key());
    let failure = |message: String| {
        let mut status = TestCaseStatus::non_success(NonSuccessKind::Failure);
        status
            .set_message(message.as_str())
            .set_description(format!(
                "{message}\nrerun: {rerun}\nrender: {}\nlog: {}",
                info.command, info.log
            ));
        status
    };
    for row in &report.rows {
        let sphere = format!("{} r={}", row.series(), row.roughness);
        let status = if row.deviation <= report.tolerance_percent / 100.0 {
            TestCaseStatus::success()
        } else {
            failure(format!(
                "{sphere}: the corrected sphere's mean is {:.2} % of what it should be (a channel {:.2} % off; allowed ±{} %)",
                100.0 * row.brightness,
                100.0 * row.deviation,
                report.tolerance_percent
            ))
        };
        let mut case = TestCase::new(format!("{sphere} mean").as_str(), status);
        case.set_classname(classname.as_str());
        for (name, value) in [
            ("measured_percent", 100.0 * row.brightness),
            ("predicted_percent", 100.0 * row.predicted_corrected),
            ("uncorrected_percent", 100.0 * row.uncorrected_brightness),
            (
                "standard_error_percent",
                100.0 * row.corrected.standard_error,
            ),
            ("tolerance_percent", report.tolerance_percent),
        ] {
            case.add_property(Property::new(name, format!("{value:.4}")));
        }
        suite.add_test_case(case);
        if mode_rings(report.mode) {
            let rings_ok = row.worst_ring <= report.ring_tolerance_percent / 100.0;
            let status = if rings_ok {
                TestCaseStatus::success()
            } else {
                failure(format!(
                    "{sphere}: a view-cosine ring is {:.2} % off what it should be (allowed ±{} %)",
                    100.0 * row.worst_ring,
                    report.ring_tolerance_percent
                ))
            };
            let mut case = TestCase::new(format!("{sphere} rings").as_str(), status);
            case.set_classname(classname.as_str());
            case.add_property(Property::new(
                "worst_ring_percent",
                format!("{:.4}", 100.0 * row.worst_ring),
            ));
            case.add_property(Property::new(
                "ring_tolerance_percent",
                report.ring_tolerance_percent.to_string(),
            ));
            suite.add_test_case(case);
        }
    }
    let mut junit = Report::new("gloffuse");
    junit.add_test_suite(suite);
    junit.to_string().expect("a report serialises to XML")
}

/// The view modes judge rings as well as means.
fn mode_rings(mode: Mode) -> bool {
    mode != Mode::Roughness
}
