//! The pictures of `report merge`: each merged material's picture copied from the folder
//! of the shard that audited it into the merged report's, never through a link.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use super::{PICTURES, ReportDir, picture_name};
use crate::Error;
use crate::audit::merge::{Merged, report_json};
use crate::blender::Cancel;

/// A picture a merge left out, and why; in the order met.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Skipped {
    /// A shard's `materials/`, or a picture in it, that is a symbolic link or not a regular
    /// file: never copied, so a merge publishes no file a link points to.
    NotRegular(PathBuf),
    /// Shard `k` (from 1) audited rendered materials but has no pictures beside its
    /// report.json (it ran without a report folder).
    NoPictures(usize),
}

/// Makes the merged report's folder `dir` and copies into it, in the merged order, every
/// material's picture from its shard's folder (the one holding its report.json); returns
/// the folder, to finish with the merged report, and what was left out. `cancel` is checked
/// before each picture.
pub fn copy_pictures(
    dir: &Path,
    merged: &Merged,
    cancel: &Cancel,
) -> Result<(ReportDir, Vec<Skipped>), Error> {
    let mut folder = ReportDir::create(dir)?;
    let mut skipped = Vec::new();
    // None for a shard whose materials/ is refused: none of its pictures is copied.
    let pictures: Vec<Option<ShardPictures>> = (merged.shards.iter())
        .map(|s| {
            let json = report_json(s);
            ShardPictures::open(json.parent().unwrap_or(Path::new(".")))
                .map_err(|folder| skipped.push(Skipped::NotRegular(folder)))
                .ok()
        })
        .collect();
    let mut unpictured = BTreeSet::new();
    for (&(k, i), material) in merged.sources.iter().zip(&merged.report.materials) {
        cancel.check()?;
        let Some(shard) = &pictures[k] else {
            folder.add_copy(None)?;
            continue;
        };
        let copy = match shard.picture(i) {
            ShardPicture::File(path, file) => Some((path, file)),
            ShardPicture::Missing => {
                if material.mean.is_some() {
                    unpictured.insert(k + 1);
                }
                None
            }
            ShardPicture::Refused(path) => {
                skipped.push(Skipped::NotRegular(path));
                None
            }
        };
        folder.add_copy(copy)?;
    }
    skipped.extend(unpictured.into_iter().map(Skipped::NoPictures));
    Ok((folder, skipped))
}

/// A shard's pictures, as `report merge` copies them: only regular files in a `materials/`
/// that is a folder, neither being a symbolic link. A shard's folder is on storage others
/// can write, and a link there would have the merge publish whatever file it points to.
/// The folder is opened once and each picture opened inside it without following links,
/// so a link put in place after the checks is refused as well.
struct ShardPictures {
    folder: PathBuf,
    dir: Option<std::fs::File>,
}

/// A shard's picture of one material.
enum ShardPicture {
    /// A regular file, open to copy; its path.
    File(PathBuf, std::fs::File),
    /// None: the material was not rendered, or its shard ran without `--report`.
    Missing,
    /// A symbolic link or another file that is not a regular one (a FIFO, a device): not
    /// copied.
    Refused(PathBuf),
}

impl ShardPictures {
    /// The pictures of the shard whose report is in `dir`; `Err` names its `materials/` if
    /// that is a symbolic link or no folder.
    fn open(dir: &Path) -> Result<Self, PathBuf> {
        use std::os::unix::fs::OpenOptionsExt;
        let folder = dir.join(PICTURES);
        let meta = match std::fs::symlink_metadata(&folder) {
            Ok(meta) => meta,
            Err(_) => return Ok(ShardPictures { folder, dir: None }),
        };
        if !meta.is_dir() {
            return Err(folder);
        }
        let dir = std::fs::OpenOptions::new()
            .read(true)
            .custom_flags(libc::O_DIRECTORY | libc::O_NOFOLLOW)
            .open(&folder)
            .map_err(|_| folder.clone())?;
        Ok(ShardPictures {
            folder,
            dir: Some(dir),
        })
    }

    /// The picture of the material at `index` of the shard's report.
    fn picture(&self, index: usize) -> ShardPicture {
        use std::os::fd::{AsRawFd, FromRawFd};
        let Some(dir) = &self.dir else {
            return ShardPicture::Missing;
        };
        let name = picture_name(index);
        let path = self.folder.join(&name);
        let c_name = std::ffi::CString::new(name).expect("a picture's name has no NUL");
        // SAFETY: `dir` is an open folder and `c_name` a NUL-terminated name; a descriptor
        // returned is owned by the File made of it alone.
        let fd = unsafe {
            libc::openat(
                dir.as_raw_fd(),
                c_name.as_ptr(),
                libc::O_RDONLY | libc::O_NOFOLLOW | libc::O_NONBLOCK | libc::O_CLOEXEC,
            )
        };
        if fd < 0 {
            return match std::io::Error::last_os_error().raw_os_error() {
                Some(libc::ENOENT) => ShardPicture::Missing,
                _ => ShardPicture::Refused(path),
            };
        }
        // SAFETY: `fd` was just opened and is owned by nothing else.
        let file = unsafe { std::fs::File::from_raw_fd(fd) };
        match file.metadata() {
            Ok(meta) if meta.is_file() => ShardPicture::File(path, file),
            _ => ShardPicture::Refused(path),
        }
    }
}
