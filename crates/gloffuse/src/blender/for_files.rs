//! Which Blender opens a user's files. A file is read as its own Blender or a newer one
//! reads it; an older Blender reads newer nodes as it knows them (a 4.x Principled BSDF as
//! 3.x's) or crashes on them, and saving from it loses what it does not know. So the
//! search asks for a Blender at least as new as the newest file, up to the bpy series
//! gloffuse can install itself: an older one found first is passed over, with a notice,
//! for the cached or installed bpy. Where none is that new (bpy may not be installed, or
//! the files are newer than any Blender here), the Blender found as usual is used, and the
//! caller says which files it is older than (the audit) or refuses to save them (`into`).

use std::path::PathBuf;

use super::{BPY_VERSION, Blender, BlenderOptions, Need};
use crate::blend_file::read_header;
use crate::measure::BlenderVersion;
use crate::progress::Progress;
use crate::{Error, Field};

/// The Blender for `files` under `options` (a Blender the user named is used as named),
/// at least as new as `also` asks if it asks more; `by` is the input that names the files.
pub fn find_for_files(
    options: &BlenderOptions,
    files: &[PathBuf],
    by: Field,
    also: Option<Need>,
    progress: &dyn Progress,
) -> Result<Blender, Error> {
    let newest = files
        .iter()
        .filter_map(|f| read_header(f).ok()?.version)
        .max();
    let need = newest.and_then(|v| wanted(v, by, options.program.is_some()));
    let need = match (need, also) {
        (Some(n), Some(a)) if n.version > a.version => Some(n),
        (n, None) => n,
        (_, a) => a,
    };
    match options.find_for(need, progress) {
        // Only the files asked for it: the search without them.
        Err(Error::BlenderNotFound(_)) if need.is_some() && need != also => {
            options.find_for(also, progress)
        }
        found => found,
    }
}

/// What the newest file asks of the search: a Blender as new as it, capped at the bpy
/// series gloffuse installs; nothing where the user named the Blender, or where any Blender
/// gloffuse supports reads it.
fn wanted(newest: BlenderVersion, by: Field, named: bool) -> Option<Need> {
    let version = newest.min(BPY_VERSION);
    (!named && version > BlenderVersion::OLDEST).then_some(Need {
        version,
        by,
        why: "a file is opened in the Blender that saved it or a newer one",
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn v(major: u32, minor: u32) -> BlenderVersion {
        BlenderVersion { major, minor }
    }

    #[test]
    fn the_newest_file_asks_for_its_blender_up_to_the_installable_bpy() {
        assert_eq!(
            wanted(v(4, 2), Field::AuditPath, false).map(|n| n.version),
            Some(v(4, 2))
        );
        assert_eq!(
            wanted(v(5, 2), Field::AuditPath, false).map(|n| n.version),
            Some(BPY_VERSION)
        );
        assert!(
            wanted(v(4, 2), Field::AuditPath, true).is_none(),
            "a named Blender is used as named"
        );
        assert!(wanted(v(2, 93), Field::AuditPath, false).is_none());
    }

    #[test]
    fn the_installable_bpy_is_one_version() {
        let series = crate::blender::environment::BPY_SERIES;
        assert_eq!(
            format!("{}.{}", BPY_VERSION.major, BPY_VERSION.minor),
            series
        );
    }
}
