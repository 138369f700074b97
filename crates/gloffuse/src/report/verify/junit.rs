//! The verify report as JUnit XML, for CI servers: one test case per corrected sphere (its
//! mean), and in the view modes one per sphere's view-cosine rings, with what was measured,
//! predicted and allowed as properties and, on failure, the message and the commands to
//! rerun the check and the render. Paths and versions go through [`xml_attribute`] and
//! [`xml_text`] as the audit's names do, so the XML stays valid whatever they hold.

use quick_junit::{NonSuccessKind, Property, Report, TestCase, TestCaseStatus, TestSuite};

use crate::report::escape::{xml_attribute, xml_text};

use crate::verify::{Row, VerifyReport};

/// `rerun` is the command line that reproduces the whole check (the CLI passes its own).
pub fn render(report: &VerifyReport, rerun: &str) -> String {
    let suite_name = format!("gloffuse verify ({} mode)", report.mode.key());
    let mut suite = TestSuite::new(suite_name.as_str());
    add_suite_properties(&mut suite, report);
    for row in &report.rows {
        suite.add_test_case(mean_case(report, row, rerun));
        if report.mode.per_pixel() {
            suite.add_test_case(rings_case(report, row, rerun));
        }
    }
    let mut junit = Report::new("gloffuse");
    junit.add_test_suite(suite);
    junit.to_string().expect("a report serialises to XML")
}

/// How the sweep was rendered and judged, as the suite's properties.
fn add_suite_properties(suite: &mut TestSuite, report: &VerifyReport) {
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
        suite.add_property(Property::new(name, xml_attribute(&value)));
    }
}

/// The test case of a corrected sphere's mean.
fn mean_case(report: &VerifyReport, row: &Row, rerun: &str) -> TestCase {
    let sphere = sphere_name(row);
    let status = if row.deviation <= report.tolerance_percent / 100.0 {
        TestCaseStatus::success()
    } else {
        failure(
            report,
            rerun,
            format!(
                "{sphere}: the corrected sphere's mean is {:.2} % of what it should be (a channel {:.2} % off; allowed ±{} %)",
                100.0 * row.brightness,
                100.0 * row.deviation,
                report.tolerance_percent
            ),
        )
    };
    let mut case = TestCase::new(format!("{sphere} mean").as_str(), status);
    case.set_classname(classname(report).as_str());
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
    case
}

/// The test case of a corrected sphere's view-cosine rings.
fn rings_case(report: &VerifyReport, row: &Row, rerun: &str) -> TestCase {
    let sphere = sphere_name(row);
    let rings_ok = row.worst_ring <= report.ring_tolerance_percent / 100.0;
    let status = if rings_ok {
        TestCaseStatus::success()
    } else {
        failure(
            report,
            rerun,
            format!(
                "{sphere}: a view-cosine ring is {:.2} % off what it should be (allowed ±{} %)",
                100.0 * row.worst_ring,
                report.ring_tolerance_percent
            ),
        )
    };
    let mut case = TestCase::new(format!("{sphere} rings").as_str(), status);
    case.set_classname(classname(report).as_str());
    case.add_property(Property::new(
        "worst_ring_percent",
        format!("{:.4}", 100.0 * row.worst_ring),
    ));
    case.add_property(Property::new(
        "ring_tolerance_percent",
        report.ring_tolerance_percent.to_string(),
    ));
    case
}

/// A failed case's status: `message`, and in its description the commands to rerun the
/// check and the render, and the render's log.
fn failure(report: &VerifyReport, rerun: &str, message: String) -> TestCaseStatus {
    let info = &report.render;
    let mut status = TestCaseStatus::non_success(NonSuccessKind::Failure);
    status
        .set_message(xml_attribute(&message))
        .set_description(xml_text(&format!(
            "{message}\nrerun: {rerun}\nrender: {}\nlog: {}",
            info.command, info.log
        )));
    status
}

fn sphere_name(row: &Row) -> String {
    format!("{} r={}", row.series(), row.roughness)
}

fn classname(report: &VerifyReport) -> String {
    format!("gloffuse.verify.{}", report.mode.key())
}
