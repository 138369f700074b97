//! The machine-readable twin of the verify report.

use crate::verify::VerifyReport;

/// The report as pretty JSON, ending in a newline.
pub fn render(report: &VerifyReport) -> String {
    serde_json::to_string_pretty(report).expect("reports serialise to JSON") + "\n"
}

#[cfg(test)]
mod tests {
    use serde_json::json;

    use crate::measure::{Distribution, Masking};
    use crate::verify::Note;

    /// Notes are objects tagged by `kind`, their fields plain JSON values.
    #[test]
    fn notes_are_tagged_objects() {
        let note = Note::MaskingMismatch {
            distribution: Distribution::AshikhminShirley,
            fitted: Masking::Separable,
            blender: "4.5".parse().unwrap(),
            masking: Masking::HeightCorrelated,
            suggested: "blender-4",
        };
        assert_eq!(
            serde_json::to_value(&note).unwrap(),
            json!({
                "kind": "masking-mismatch",
                "distribution": "ashikhmin-shirley",
                "fitted": "separable",
                "blender": "4.5",
                "masking": "height-correlated",
                "suggested": "blender-4",
            })
        );
        let display = Note::DisplayReferred {
            coefficients: "seed".into(),
            under: None,
            over: None,
        };
        assert_eq!(
            serde_json::to_value(&display).unwrap(),
            json!({"kind": "display-referred", "coefficients": "seed"})
        );
    }
}
