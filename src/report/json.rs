//! The machine-readable twin of the verify report.

use crate::verify::VerifyReport;

/// The report as pretty JSON, ending in a newline.
pub fn render(report: &VerifyReport) -> String {
    serde_json::to_string_pretty(report).expect("reports serialise to JSON") + "\n"
}
