//! Writing the files the user names, so that a failure never leaves a partial file and
//! nothing the user pointed at is replaced behind their back:
//!
//! - a regular file (or a new one) is written to a temporary file in its directory and
//!   renamed over it, so it appears complete or not at all;
//! - a symbolic link is followed: its target is written that way, and the link stays;
//! - a FIFO, a character device, a socket, or a path into `/dev` or `/proc` (`/dev/stdout`)
//!   is opened and written in place, as a stream;
//! - `-` is standard output.
//!
//! One rule for folders: the folder an output goes in must exist; gloffuse makes none but
//! the report folder itself.

use std::io::Write;
use std::os::unix::fs::FileTypeExt;
use std::path::{Path, PathBuf};

use crate::Error;

/// Where the bytes for a path end up (see the module docs).
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Destination {
    /// `-`.
    Stdout,
    /// Opened and written in place.
    Stream(PathBuf),
    /// Written beside and renamed over: the path after following any links.
    File(PathBuf),
}

fn fail(path: &Path, message: impl Into<String>) -> Error {
    Error::Write {
        path: path.to_path_buf(),
        message: message.into(),
    }
}

/// How links are followed before giving up: the kernel's own limit.
const MAX_LINKS: usize = 40;

/// The path a chain of symbolic links ends at (it need not exist).
fn follow_links(path: &Path) -> Result<PathBuf, Error> {
    let mut at = path.to_path_buf();
    for _ in 0..MAX_LINKS {
        match std::fs::read_link(&at) {
            Ok(target) => {
                at = match at.parent() {
                    Some(dir) if target.is_relative() => dir.join(target),
                    _ => target,
                };
            }
            Err(_) => return Ok(at),
        }
    }
    Err(fail(path, "too many levels of symbolic links"))
}

/// Checks that `path` can be an output and says how it will be written. Commands call it
/// before slow work (finding Blender, rendering), so that bad input fails fast.
pub fn check_destination(path: &Path) -> Result<Destination, Error> {
    if path.as_os_str() == "-" {
        return Ok(Destination::Stdout);
    }
    match std::fs::metadata(path) {
        Ok(meta) => {
            let kind = meta.file_type();
            if kind.is_dir() {
                return Err(fail(path, "it is a directory; give a file name"));
            }
            if kind.is_block_device() {
                return Err(fail(path, "it is a block device; give a file name"));
            }
            // Paths into /dev and /proc (/dev/stdout, /dev/fd/3) name open files: stream.
            let special = path.starts_with("/dev") || path.starts_with("/proc");
            if kind.is_fifo() || kind.is_char_device() || kind.is_socket() || special {
                return Ok(Destination::Stream(path.to_path_buf()));
            }
            let real = std::fs::canonicalize(path).map_err(|e| fail(path, e.to_string()))?;
            Ok(Destination::File(real))
        }
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            // A new file, or a dangling link: the file it names is made.
            let real = follow_links(path)?;
            let dir = match real.parent() {
                Some(d) if !d.as_os_str().is_empty() => d,
                _ => Path::new("."),
            };
            if !dir.is_dir() {
                return Err(fail(
                    path,
                    format!("the directory {} does not exist", dir.display()),
                ));
            }
            Ok(Destination::File(real))
        }
        Err(e) => Err(fail(path, e.to_string())),
    }
}

/// Whether `path` is standard output: `-`, or the very file standard output is open on
/// (`/dev/stdout`, `/proc/self/fd/1`, or the file it is redirected to).
pub fn is_stdout(path: &Path) -> bool {
    use std::os::fd::AsFd;
    use std::os::unix::fs::MetadataExt;
    if path.as_os_str() == "-" {
        return true;
    }
    let stdout = std::io::stdout()
        .as_fd()
        .try_clone_to_owned()
        .and_then(|fd| std::fs::File::from(fd).metadata());
    match (stdout, std::fs::metadata(path)) {
        (Ok(a), Ok(b)) => (a.dev(), a.ino()) == (b.dev(), b.ino()),
        _ => false,
    }
}

/// Writes `bytes` to `path` as [`check_destination`] says. A pipe whose reader has gone
/// (`-` or `/dev/stdout` piped into `head`, a FIFO whose reader quit) is not an error: the
/// reader has seen enough, and the command's own outcome stands.
pub fn write_output(path: &Path, bytes: &[u8]) -> Result<(), Error> {
    let written = match check_destination(path)? {
        Destination::Stdout => {
            let mut out = std::io::stdout().lock();
            out.write_all(bytes).and_then(|()| out.flush())
        }
        Destination::Stream(p) => std::fs::OpenOptions::new()
            .write(true)
            .open(&p)
            .and_then(|mut f| f.write_all(bytes)),
        Destination::File(real) => {
            return write_atomic(&real, bytes).map_err(|e| match e {
                Error::Write { message, .. } => fail(path, message),
                other => other,
            });
        }
    };
    match written {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => Err(fail(path, e.to_string())),
        _ => Ok(()),
    }
}

/// Writes `bytes` to the regular file `path` atomically (temporary file + rename in the
/// same directory), keeping the permissions of a file it replaces.
fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), Error> {
    let tmp = staged(path, bytes)?;
    tmp.persist(path)
        .map_err(|e| fail(path, e.error.to_string()))?;
    Ok(())
}

/// `bytes` written and synced to a temporary file beside the regular file `path`, with the
/// permissions of the file it will replace: renaming it over `path` is the atomic write.
/// Dropped unrenamed, it is removed.
pub fn staged(path: &Path, bytes: &[u8]) -> Result<tempfile::TempPath, Error> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    if !dir.is_dir() {
        return Err(fail(
            path,
            format!("the directory {} does not exist", dir.display()),
        ));
    }
    let err = |e: std::io::Error| fail(path, e.to_string());
    let mut tmp = tempfile::Builder::new()
        .prefix(".gloffuse-")
        .suffix(".tmp")
        .tempfile_in(dir)
        .map_err(err)?;
    tmp.write_all(bytes).map_err(err)?;
    // Temporary files are created private (0600); an output file should be as readable as
    // any other file the user writes.
    {
        use std::os::unix::fs::PermissionsExt;
        let mode = std::fs::metadata(path)
            .map(|m| m.permissions().mode())
            .unwrap_or(0o644);
        tmp.as_file()
            .set_permissions(std::fs::Permissions::from_mode(mode))
            .map_err(err)?;
    }
    tmp.as_file().sync_all().map_err(err)?;
    Ok(tmp.into_temp_path())
}

/// Makes the report folder `dir` if it does not exist (its parent must), and checks that
/// what is there is a folder.
pub fn report_dir(dir: &Path) -> Result<(), Error> {
    match std::fs::metadata(dir) {
        Ok(m) if m.is_dir() => Ok(()),
        Ok(_) => Err(fail(dir, "a report needs a directory, and this is a file")),
        Err(_) => {
            let parent = match dir.parent() {
                Some(d) if !d.as_os_str().is_empty() => d,
                _ => Path::new("."),
            };
            match std::fs::metadata(parent) {
                Ok(m) if m.is_dir() => Ok(()),
                Ok(_) => Err(fail(
                    dir,
                    format!(
                        "a report needs a directory, but {} is a file",
                        parent.display()
                    ),
                )),
                Err(_) => Err(fail(
                    dir,
                    format!("the directory {} does not exist", parent.display()),
                )),
            }
        }
    }
}

/// [`report_dir`], then makes the folder.
pub fn make_report_dir(dir: &Path) -> Result<(), Error> {
    report_dir(dir)?;
    match std::fs::create_dir(dir) {
        Err(e) if e.kind() != std::io::ErrorKind::AlreadyExists => Err(fail(dir, e.to_string())),
        _ => Ok(()),
    }
}

/// `file` kept under a temporary name beside it, removed on drop unless persisted: a hard
/// link (the very bytes, no copy to fail half-way), or a synced copy with its mode where
/// the filesystem has no links. The io error says why it could not be kept.
pub fn keep_beside(file: &Path, suffix: &str) -> Result<tempfile::TempPath, String> {
    let slot = temp_beside(file, suffix).map_err(|e| e.to_string())?;
    std::fs::remove_file(&slot).map_err(|e| e.to_string())?;
    if std::fs::hard_link(file, &slot).is_err() {
        // fs::copy gives the copy the file's permission bits.
        std::fs::copy(file, &slot).map_err(|e| e.to_string())?;
        std::fs::File::open(&slot)
            .and_then(|f| f.sync_all())
            .map_err(|e| e.to_string())?;
    }
    Ok(slot)
}

/// A temporary file next to `dest`, removed on drop unless persisted.
pub fn temp_beside(dest: &Path, suffix: &str) -> Result<tempfile::TempPath, Error> {
    let dir = match dest.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    if !dir.is_dir() {
        return Err(Error::Write {
            path: dest.to_path_buf(),
            message: format!("the directory {} does not exist", dir.display()),
        });
    }
    tempfile::Builder::new()
        .prefix(".gloffuse-")
        .suffix(suffix)
        .tempfile_in(dir)
        .map(|f| f.into_temp_path())
        .map_err(|e| Error::Write {
            path: dest.to_path_buf(),
            message: e.to_string(),
        })
}
