//! The audit verdict as JUnit XML: one test suite per file, one test case per material,
//! failing when its verdict is one the check fails on; a file that could not be audited is
//! one failing case of its own. Names come from users' files: each attribute goes through
//! [`xml_attribute`] and the failure's text through [`xml_text`], so the XML stays valid
//! and every name reads as the terminal shows it (the writer escapes `<`, `&` and quotes).

use quick_junit::{NonSuccessKind, Property, Report, TestCase, TestCaseStatus, TestSuite};

use crate::audit::{AuditReport, AuditedMaterial};
use crate::report::escape::{xml_attribute, xml_text};

/// `rerun` is the command line that reproduces the check.
pub fn render(report: &AuditReport, rerun: &str) -> String {
    let mut junit = Report::new("gloffuse audit");
    for file in &report.files {
        let mut suite = TestSuite::new(xml_attribute(&file.file));
        suite.add_property(Property::new(
            "blender",
            xml_attribute(&report.blender_version),
        ));
        suite.add_property(Property::new(
            "samples",
            report.settings.samples.to_string(),
        ));
        if let Some(error) = &file.error {
            let mut status = TestCaseStatus::non_success(NonSuccessKind::Error);
            status.set_message(xml_attribute(error));
            suite.add_test_case(TestCase::new("(file)", status));
        }
        for m in report.materials.iter().filter(|m| m.file == file.file) {
            suite.add_test_case(case(report, m, rerun));
        }
        junit.add_test_suite(suite);
    }
    junit.to_string().expect("a report serialises to XML")
}

fn case(report: &AuditReport, m: &AuditedMaterial, rerun: &str) -> TestCase {
    let status = if report.settings.fail_on.contains(&m.verdict) {
        let mut status = TestCaseStatus::non_success(NonSuccessKind::Failure);
        status.set_message(xml_attribute(&format!("{}: {}", m.verdict.key(), m.reason)));
        let findings: Vec<String> = m
            .findings
            .iter()
            .map(|f| format!("{} at {}: {}. Fix: {}.", f.rule, f.node, f.why, f.fix))
            .collect();
        status.set_description(xml_text(&format!(
            "{}\nrerun: {rerun}",
            findings.join("\n")
        )));
        status
    } else {
        TestCaseStatus::success()
    };
    let mut case = TestCase::new(xml_attribute(&m.material), status);
    case.set_classname(xml_attribute(&m.file));
    case.add_property(Property::new("verdict", m.verdict.key()));
    for (name, value) in [("mean", m.mean), ("rim", m.rim), ("twin_mean", m.twin_mean)] {
        if let Some(v) = value {
            case.add_property(Property::new(name, format!("{v:.4}")));
        }
    }
    case
}
