//! The verdict's notes in words: the one place their English lives (the table and the page
//! both print [`sentence`]).

use crate::measure::Engine;
use crate::verify::{Note, WorstSphere};

/// A note as an English sentence (or a few).
pub fn sentence(note: &Note) -> String {
    match note {
        Note::Lighting { engine, brightness } => format!(
            "{engine}'s lighting: a white Diffuse sphere renders at {:.2} % in this sweep (EEVEE Next's world probe loses about 0.8 %; EEVEE Legacy none), so no sphere can come out brighter than that.",
            100.0 * brightness
        ),
        Note::ForeignGroups {
            coefficients,
            groups_engine,
            engine,
            suggested,
        } => format!(
            "The coefficients '{coefficients}' correct {groups_engine}'s Glossy, rendered here in {engine}{}: the preset '{suggested}' holds {engine}'s own groups.",
            match engine {
                Engine::Eevee => ", which renders every distribution as its GGX",
                Engine::Cycles => "",
            },
        ),
        Note::MaskingMismatch {
            distribution,
            fitted,
            blender,
            masking,
            suggested,
        } => format!(
            "{}: the coefficients were fitted for {fitted} masking, but Blender {blender} uses {masking} masking; the preset '{suggested}' suits this Blender.",
            distribution.label(),
        ),
        Note::DisplayReferred {
            coefficients,
            under,
            over,
        } => {
            let mut s = format!(
                "The coefficients '{coefficients}' are display-referred: their percentages are sRGB-encoded brightness read off a screen (sRGB(0.305) ≈ 0.59 is GGX's centre at r = 1), but a shader gain acts on linear light, so 100/f(r) misses."
            );
            for (w, verb) in [(under, "Under-corrected"), (over, "Over-corrected")] {
                if let Some(w) = w {
                    s.push_str(&worst_sphere(verb, w));
                }
            }
            s
        }
        Note::WithinNoise {
            count,
            failing,
            samples,
        } => format!(
            "{count} of the {} miss{} by no more than three standard errors of {} own noise beyond the tolerance: more samples may pass {} (rendered with {samples} samples per pixel; four times as many, {}, would halve a sphere's noise and cut a solid glass sphere's by about a third).",
            crate::plural::count(*failing, "failing sphere", "failing spheres"),
            if *count == 1 { "es" } else { "" },
            if *count == 1 { "its" } else { "their" },
            if *count == 1 { "it" } else { "them" },
            samples.saturating_mul(4),
        ),
    }
}

/// ` Under-corrected: 8 spheres, worst GGX r = 1 at 69.4 % (gain 1.695; 1/E_avg = 2.444 is
/// needed).`
fn worst_sphere(verb: &str, w: &WorstSphere) -> String {
    format!(
        " {verb}: {}, worst {} r = {} at {:.1} % (gain {:.3}; 1/E_avg = {:.3} is needed).",
        crate::plural::count(w.count, "sphere", "spheres"),
        w.distribution.label(),
        w.roughness,
        100.0 * w.brightness,
        w.gain,
        w.needed_gain
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::measure::{BlenderVersion, Distribution, Masking, Roughness};

    #[test]
    fn no_sentence_names_a_flag() {
        let v: BlenderVersion = "3.4".parse().unwrap();
        let notes = [
            Note::ForeignGroups {
                coefficients: "blender-4".into(),
                groups_engine: Engine::Cycles,
                engine: Engine::Eevee,
                suggested: "eevee",
            },
            Note::MaskingMismatch {
                distribution: Distribution::Ggx,
                fitted: Masking::HeightCorrelated,
                blender: v,
                masking: Masking::Separable,
                suggested: "blender-3",
            },
        ];
        for n in &notes {
            let s = sentence(n);
            assert!(!s.contains("--"), "{s}");
            assert!(
                s.contains(&format!("'{}'", n.suggested_preset().unwrap())),
                "{s}"
            );
        }
        assert_eq!(
            sentence(&notes[1]),
            "GGX: the coefficients were fitted for height-correlated masking, but Blender 3.4 uses separable masking; the preset 'blender-3' suits this Blender."
        );
    }

    #[test]
    fn within_noise_counts_in_words() {
        assert_eq!(
            sentence(&Note::WithinNoise {
                count: 1,
                failing: 1,
                samples: 256
            }),
            "1 of the 1 failing sphere misses by no more than three standard errors of its own noise beyond the tolerance: more samples may pass it (rendered with 256 samples per pixel; four times as many, 1024, would halve a sphere's noise and cut a solid glass sphere's by about a third)."
        );
        let s = sentence(&Note::WithinNoise {
            count: 2,
            failing: 4,
            samples: 32,
        });
        assert!(s.starts_with("2 of the 4 failing spheres miss by no more than three standard errors of their own noise"), "{s}");
        assert!(s.contains("may pass them"), "{s}");
    }

    #[test]
    fn display_referred_words_each_side_present() {
        let worst = WorstSphere {
            count: 1,
            distribution: Distribution::Ggx,
            roughness: Roughness::new(0.4).unwrap(),
            brightness: 1.047,
            gain: 1.114,
            needed_gain: 1.063,
        };
        let s = sentence(&Note::DisplayReferred {
            coefficients: "seed".into(),
            under: None,
            over: Some(worst),
        });
        assert!(
            s.starts_with("The coefficients 'seed' are display-referred"),
            "{s}"
        );
        assert!(
            s.ends_with(" Over-corrected: 1 sphere, worst GGX r = 0.4 at 104.7 % (gain 1.114; 1/E_avg = 1.063 is needed)."),
            "{s}"
        );
        assert!(!s.contains("Under-corrected"), "{s}");
    }
}
