//! Which Blenders a library suits. Two things bound it: the Blender that saved it (an older
//! one loses what it does not know, so the library suits that Blender and later), and the
//! masking family its Cycles corrections were fitted to (3.0–3.4 shadow microfacets apart,
//! 3.5 and later together: a correction fitted to one makes rough lobes too bright or too
//! dark in the other).

use crate::fit::preset_for_masking;
use crate::measure::{BlenderVersion, Engine, Masking};

/// What the Cycles corrections of a library were fitted to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Fitted<'a> {
    /// One masking family (a preset fitted to it, or the preset of the Blender that built it).
    Masking(Masking),
    /// Coefficients of that name, which say nothing of the masking they fit (`seed`, a file).
    Unknown(&'a str),
    /// No Cycles groups (EEVEE only): nothing depends on the masking.
    NoCycles,
}

/// The Blenders a library of `engines` suits, built by `built_by` from the coefficients
/// `pinned` (else that Blender's preset), in words.
pub fn library(pinned: Option<&str>, engines: &[Engine], built_by: BlenderVersion) -> String {
    suited_blenders(built_by, fitted(pinned, engines, built_by))
}

/// What the Cycles corrections of pinned coefficients `name` (or, unpinned, the preset of
/// the Blender `built_by`) were fitted to, for the `engines` built.
pub fn fitted<'a>(
    pinned: Option<&'a str>,
    engines: &[Engine],
    built_by: BlenderVersion,
) -> Fitted<'a> {
    if !engines.contains(&Engine::Cycles) {
        return Fitted::NoCycles;
    }
    let Some(name) = pinned else {
        return Fitted::Masking(built_by.masking());
    };
    Masking::ALL
        .into_iter()
        .find(|&m| preset_for_masking(Engine::Cycles, m) == name)
        .map_or(Fitted::Unknown(name), Fitted::Masking)
}

/// The Blenders a library saved by `built_by` suits, in words.
pub fn suited_blenders(built_by: BlenderVersion, fitted: Fitted) -> String {
    let last_separable = BlenderVersion { major: 3, minor: 4 };
    let first_correlated = BlenderVersion::HEIGHT_CORRELATED_FROM;
    match fitted {
        Fitted::Masking(Masking::Separable) if built_by <= last_separable => {
            let which = if built_by == last_separable {
                format!("Blender {built_by}")
            } else {
                format!("Blender {built_by} to {last_separable}")
            };
            format!(
                "{which} (its Cycles corrections fit the masking of 3.0–{last_separable}; from \
                 {first_correlated} on they make rough lobes too bright: build the library in \
                 the Blender it is for)"
            )
        }
        Fitted::Masking(Masking::Separable) => format!(
            "no Blender well: its Cycles corrections fit the masking of 3.0–{last_separable}, \
             which lose what Blender {built_by} saved (build the library in the Blender it is \
             for)"
        ),
        Fitted::Masking(Masking::HeightCorrelated) => {
            let from = built_by.max(first_correlated);
            format!(
                "Blender {from} and later (its Cycles corrections fit the masking of \
                 {first_correlated} and later; it is saved by {built_by})"
            )
        }
        Fitted::Unknown(name) => format!(
            "Blender {built_by} and later (it is saved by {built_by}); the coefficients \
             '{name}' are fitted to no one masking, so check them with verify in the Blender \
             you render with"
        ),
        Fitted::NoCycles => format!("Blender {built_by} and later (it is saved by {built_by})"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn v(major: u32, minor: u32) -> BlenderVersion {
        BlenderVersion { major, minor }
    }

    #[test]
    fn a_library_suits_its_blender_and_the_later_ones_of_its_masking() {
        let cycles = [Engine::Cycles];
        let in_34 = suited_blenders(v(3, 4), fitted(None, &cycles, v(3, 4)));
        assert!(in_34.starts_with("Blender 3.4 (its Cycles"), "{in_34}");
        let in_32 = suited_blenders(v(3, 2), fitted(None, &cycles, v(3, 2)));
        assert!(in_32.starts_with("Blender 3.2 to 3.4 "), "{in_32}");
        assert!(in_34.contains("from 3.5 on they make rough lobes too bright"));
        let in_45 = suited_blenders(v(4, 5), fitted(None, &cycles, v(4, 5)));
        assert!(in_45.starts_with("Blender 4.5 and later "), "{in_45}");
        let old_preset = suited_blenders(v(4, 5), fitted(Some("blender-3"), &cycles, v(4, 5)));
        assert!(old_preset.starts_with("no Blender well"), "{old_preset}");
        let new_preset = suited_blenders(v(3, 4), fitted(Some("blender-4"), &cycles, v(3, 4)));
        assert!(
            new_preset.starts_with("Blender 3.5 and later "),
            "{new_preset}"
        );
        let seed = suited_blenders(v(4, 5), fitted(Some("seed"), &cycles, v(4, 5)));
        assert!(
            seed.contains("'seed' are fitted to no one masking"),
            "{seed}"
        );
        let eevee = fitted(None, &[Engine::Eevee], v(3, 4));
        assert_eq!(eevee, Fitted::NoCycles);
        assert!(suited_blenders(v(3, 4), eevee).starts_with("Blender 3.4 and later"));
    }
}
