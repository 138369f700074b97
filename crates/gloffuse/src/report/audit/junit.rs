//! The audit verdict as JUnit XML: one test suite per file, one test case per material,
//! failing when it fails the check, skipped (with why) when its failing verdict is waived or
//! below error severity, each waived finding a `waived` property; a file that could not be
//! audited is one failing case of its own. Names come from users' files: each attribute goes through
//! [`xml_attribute`] and the failure's text through [`xml_text`], so the XML stays valid
//! and every name reads as the terminal shows it (the writer escapes `<`, `&` and quotes).

use quick_junit::{NonSuccessKind, Property, Report, TestCase, TestCaseStatus, TestSuite};

use crate::audit::waivers::{counts, said};
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
        // A file finding raised to error severity (gloffuse.toml), not waived.
        let counting: Vec<String> = file
            .findings
            .iter()
            .filter(|f| counts(f))
            .map(|f| format!("{} at {}: {}", f.rule, f.node, f.why))
            .collect();
        if !counting.is_empty() {
            let mut status = TestCaseStatus::non_success(NonSuccessKind::Failure);
            status.set_message(xml_attribute(&counting.join("; ")));
            suite.add_test_case(TestCase::new("(file findings)", status));
        }
        for m in report.materials.iter().filter(|m| m.file == file.file) {
            suite.add_test_case(case(m, rerun));
        }
        junit.add_test_suite(suite);
    }
    junit.to_string().expect("a report serialises to XML")
}

fn case(m: &AuditedMaterial, rerun: &str) -> TestCase {
    let status = if m.failing() {
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
    } else if let Some(why) = &m.suppressed {
        // A verdict that would fail, suppressed: skipped, with why.
        let mut status = TestCaseStatus::skipped();
        status.set_message(xml_attribute(why));
        status
    } else if m.fails == Some(true) {
        // A failure the baseline has: skipped, as a suppressed one is.
        let mut status = TestCaseStatus::skipped();
        status.set_message(xml_attribute(&format!(
            "{}: {} (in the baseline)",
            m.verdict.key(),
            m.reason
        )));
        status
    } else {
        TestCaseStatus::success()
    };
    let mut case = TestCase::new(xml_attribute(&m.material), status);
    for f in m.findings.iter().filter(|f| f.waived.is_some()) {
        let w = f.waived.as_ref().expect("filtered");
        case.add_property(Property::new(
            "waived",
            xml_attribute(&format!("{} at {}: {}", f.rule, f.node, said(w))),
        ));
    }
    case.set_classname(xml_attribute(&m.file));
    case.add_property(Property::new("verdict", m.verdict.key()));
    if let Some(state) = m.baseline {
        case.add_property(Property::new("baseline", state.key()));
    }
    for (name, value) in [("mean", m.mean), ("rim", m.rim), ("twin_mean", m.twin_mean)] {
        if let Some(v) = value {
            case.add_property(Property::new(name, format!("{v:.4}")));
        }
    }
    case
}
