//! The one safe path for changing a .blend the user owns (`generate --into`, and any later
//! command that edits a user's file in place). A user's file is never downgraded,
//! truncated, re-moded or silently rewritten:
//!
//! 1. [`UserBlend::open`] reads the file's header before Blender starts: the version that
//!    saved it and whether it is compressed. A file saved by a newer Blender than the one
//!    that would open it is refused (opening loses what the older one does not know)
//!    unless a downgrade is allowed.
//! 2. [`UserBlend::lock`] takes the lock every gloffuse writer of the file takes
//!    (`file_lock`), waiting while another gloffuse writes it, and checks the file again:
//!    two gloffuse runs on one file take turns, and the later one edits what the earlier
//!    one wrote.
//! 3. Blender opens the canonical path (every link followed), so the file's `//` relative
//!    paths resolve from the folder the file really is in, and saves beside that real file
//!    ([`LockedBlend::temp`]), compressed exactly when the user's file is.
//! 4. [`LockedBlend::install`] refuses if the file is no longer the one Blender read
//!    (another program saved it meanwhile), then gives the new file the old one's
//!    permission bits, hard-links the old file to a temporary name beside it (a copy where
//!    links are not supported), renames the new file over the old one and only then
//!    renames the link to `FILE.blend1`. A failure before the main rename removes the link and leaves the file
//!    and any earlier `.blend1` untouched; the backup is never a partial copy. A `.blend1`
//!    made since the command began (another gloffuse replaced the file while this one
//!    waited) stays: it is what the user had before either run.

use std::os::unix::fs::PermissionsExt;
use std::path::{Path, PathBuf};
use std::time::SystemTime;

use crate::blend_file::{BlendHeader, Compression, read_header};
use crate::file_lock::{FileLock, Wait};
use crate::measure::BlenderVersion;
use crate::{Error, Field, Hint};

/// A user's .blend, checked and ready to be changed in place.
#[derive(Clone, Debug)]
pub struct UserBlend {
    /// The path as the user gave it (maybe a link).
    pub given: PathBuf,
    /// The file itself, every link followed: what Blender opens and what is replaced.
    pub real: PathBuf,
    pub header: BlendHeader,
    /// Its permission bits, given to the new file.
    mode: u32,
    /// How it was checked, so that it can be checked again under the lock.
    field: Field,
    blender: BlenderVersion,
    allow_downgrade: bool,
}

/// Which file a path holds, and whether it was written since: its inode and its size and
/// modification time. (Not the change time: linking the file as the backup changes it.)
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Identity {
    dev: u64,
    ino: u64,
    len: u64,
    mtime: (i64, i64),
}

impl Identity {
    fn of(meta: &std::fs::Metadata) -> Identity {
        use std::os::unix::fs::MetadataExt;
        Identity {
            dev: meta.dev(),
            ino: meta.ino(),
            len: meta.len(),
            mtime: (meta.mtime(), meta.mtime_nsec()),
        }
    }

    fn read(path: &Path) -> std::io::Result<Identity> {
        std::fs::metadata(path).map(|m| Identity::of(&m))
    }
}

impl UserBlend {
    /// Checks `path` before Blender starts: it must be a .blend, and not newer than
    /// `blender` unless `allow_downgrade`. `field` names the input in errors.
    pub fn open(
        path: &Path,
        field: Field,
        blender: BlenderVersion,
        allow_downgrade: bool,
    ) -> Result<UserBlend, Error> {
        let meta = std::fs::metadata(path)
            .ok()
            .filter(|m| m.is_file())
            .ok_or_else(|| Error::input(field, path.display(), "an existing .blend file"))?;
        let header = read_header(path).map_err(|why| {
            Error::input(
                field,
                path.display(),
                Hint::text(format!("an existing .blend file (this file {why})")),
            )
        })?;
        if let Some(saved_by) = header.version
            && newer(saved_by, blender)
            && !allow_downgrade
        {
            return Err(Error::input(
                field,
                path.display(),
                downgrade_hint(saved_by, blender),
            ));
        }
        let real = std::fs::canonicalize(path).map_err(|e| Error::Read {
            path: path.to_path_buf(),
            source: e,
        })?;
        Ok(UserBlend {
            given: path.to_path_buf(),
            real,
            header,
            mode: meta.permissions().mode() & 0o7777,
            field,
            blender,
            allow_downgrade,
        })
    }

    /// Whether Blender should save the new file compressed.
    pub fn compressed(&self) -> bool {
        self.header.compression != Compression::None
    }

    /// `FILE.blend1`, beside the real file: Blender's own name for the previous version.
    pub fn backup_path(&self) -> PathBuf {
        let mut backup = self.real.clone().into_os_string();
        backup.push("1");
        PathBuf::from(backup)
    }

    /// Takes the lock every gloffuse writer of the file takes (waiting while another
    /// holds it), then checks the file again as [`UserBlend::open`] did: another writer may
    /// have replaced it meanwhile. Blender must read the file only after this. `began`:
    /// when the command began (see [`LockedBlend::install`]).
    pub fn lock(&self, wait: &Wait, began: SystemTime) -> Result<LockedBlend, Error> {
        let lock = FileLock::take(&self.real, wait)?;
        let mut now = UserBlend::open(&self.real, self.field, self.blender, self.allow_downgrade)?;
        now.given = self.given.clone();
        let read = Identity::read(&now.real).map_err(|source| Error::Read {
            path: now.real.clone(),
            source,
        })?;
        Ok(LockedBlend {
            blend: now,
            read,
            began,
            _lock: lock,
        })
    }
}

/// A user's .blend under the writers' lock: what Blender reads, and the one way to replace
/// it. The lock is released when it is dropped (after [`LockedBlend::install`]).
#[derive(Debug)]
pub struct LockedBlend {
    pub blend: UserBlend,
    /// The file as it was when the lock was taken: what Blender read.
    read: Identity,
    began: SystemTime,
    _lock: FileLock,
}

impl LockedBlend {
    /// A temporary file beside the real file, for Blender to save into.
    pub fn temp(&self) -> Result<tempfile::TempPath, Error> {
        crate::output::temp_beside(&self.blend.real, ".blend")
    }

    /// Puts the new file `new` (beside the real file) in place, keeping the old one as
    /// `FILE.blend1` (see the module docs for the order), and returns the backup's path.
    /// Refused, with nothing replaced, when the file is no longer the one Blender read
    /// (another program saved it meanwhile). A `.blend1` made since the command began
    /// (another gloffuse replaced the file while this one waited for the lock) stays: the
    /// new file holds both runs' changes, and the `.blend1` what the user had before either.
    pub fn install(self, new: tempfile::TempPath) -> Result<PathBuf, Error> {
        let b = &self.blend;
        let fail = |path: &Path, what: &str, e: std::io::Error| Error::Write {
            path: path.to_path_buf(),
            message: format!("{what}: {e}; {} is unchanged", b.given.display()),
        };
        let now = Identity::read(&b.real).map_err(|e| {
            fail(
                &b.given,
                "cannot read the file again before replacing it",
                e,
            )
        })?;
        if now != self.read {
            return Err(Error::Write {
                path: b.given.clone(),
                message: "the file was changed by another program while gloffuse worked on \
                          it; it is left as that program saved it, and gloffuse's change was \
                          not written (run again)"
                    .to_string(),
            });
        }
        std::fs::set_permissions(&new, std::fs::Permissions::from_mode(b.mode))
            .map_err(|e| fail(&b.given, "cannot give the new file the old one's mode", e))?;
        let backup = b.backup_path();
        let kept_already = std::fs::metadata(&backup).is_ok_and(|m| changed_since(&m, self.began));
        if kept_already {
            std::fs::rename(&new, &b.real)
                .map_err(|e| fail(&b.given, "cannot replace the file", e))?;
            drop(new);
            return Ok(backup);
        }
        let old = crate::output::keep_beside(&b.real, ".blend1").map_err(|e| Error::Write {
            path: backup.clone(),
            message: format!(
                "cannot keep the previous version: {e}; {} is unchanged",
                b.given.display()
            ),
        })?;
        std::fs::rename(&new, &b.real).map_err(|e| fail(&b.given, "cannot replace the file", e))?;
        // The new file is in place under the old name: nothing is left to clean up.
        drop(new);
        if let Err(e) = old.persist(&backup) {
            // The previous version must survive: keep it under its temporary name.
            let mut link = e.path;
            link.disable_cleanup(true);
            let kept = link.to_path_buf();
            return Err(Error::Write {
                path: backup,
                message: format!(
                    "{} was updated, but its previous version could not be renamed to this \
                     name ({}); it is kept as {}",
                    b.given.display(),
                    e.error,
                    kept.display()
                ),
            });
        }
        Ok(backup)
    }
}

/// Whether the inode `meta` was made or renamed (its change time) at or after `when`.
fn changed_since(meta: &std::fs::Metadata, when: SystemTime) -> bool {
    use std::os::unix::fs::MetadataExt;
    let Ok(since) = when.duration_since(SystemTime::UNIX_EPOCH) else {
        return true;
    };
    let changed = (meta.ctime(), meta.ctime_nsec());
    changed >= (since.as_secs() as i64, i64::from(since.subsec_nanos()))
}

/// What a file newer than the Blender that would save it needs: a Blender as new, which
/// gloffuse has itself for a file up to its own bpy's series (found unless a Blender is
/// named or installing is off), or accepting the loss.
fn downgrade_hint(saved_by: BlenderVersion, blender: BlenderVersion) -> Hint {
    let bpy = crate::blender::BPY_VERSION;
    let (own, own_fields) = if newer(saved_by, bpy) {
        (String::new(), vec![])
    } else {
        (
            format!(
                "gloffuse's own bpy {bpy} reads it: leave out {{}} and {{}} to have it found \
                 or installed; or "
            ),
            vec![Field::Blender, Field::NoProvision],
        )
    };
    Hint::new(
        format!(
            "a file saved by Blender {blender} or older: this one was saved by Blender \
             {saved_by}, and saving it from {blender} would lose what {blender} does not know \
             ({own}run a Blender {saved_by} or newer with {{}}, or accept the loss with {{}})"
        ),
        own_fields
            .into_iter()
            .chain([Field::Blender, Field::AllowDowngrade]),
    )
}

/// Whether a file saved by `saved_by` is newer (by major.minor) than `blender`.
fn newer(saved_by: BlenderVersion, blender: BlenderVersion) -> bool {
    (saved_by.major, saved_by.minor) > (blender.major, blender.minor)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_a_newer_major_or_minor_is_newer() {
        let at = |major, minor| BlenderVersion { major, minor };
        assert!(newer(at(5, 0), at(4, 5)));
        assert!(newer(at(4, 5), at(3, 4)));
        assert!(!newer(at(4, 5), at(4, 5)));
        assert!(!newer(at(3, 4), at(5, 0)));
    }
}
