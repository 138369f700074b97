//! The lock every gloffuse writer of a file takes: an advisory `flock` on a hidden file
//! beside it (`.NAME.gloffuse-lock`), so two gloffuse runs that write one file (two
//! `audit --in-place` of one folder, `generate --into` beside an audit, two libraries
//! replaced at once) take turns instead of losing each other's work.
//!
//! Why a file beside, not the file itself: the writers replace the file by renaming a new
//! one over it, and a lock on the old inode would not stop a run that opens the new one.
//! The lock file is removed while still locked; a waiter that then wins a removed file
//! sees that it no longer has the path and locks again. Nothing is left behind but after a
//! SIGKILL, and a stale lock file locks nothing (the kernel released it).

use std::fs::File;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use crate::Error;
use crate::blender::Cancel;
use crate::progress::Progress;

/// A held lock on a file's writers; released (and its file removed) when dropped.
#[derive(Debug)]
pub struct FileLock {
    path: PathBuf,
    _file: File,
}

/// How a writer waits for another's lock.
pub struct Wait<'a> {
    /// Give up after this long (`None`: wait as long as the other writer works).
    pub limit: Option<Duration>,
    /// Stop waiting when a stop is requested.
    pub cancel: &'a Cancel,
    /// Told (once) that the lock is held by another process, if given.
    pub progress: Option<&'a dyn Progress>,
}

/// The lock file of `target`: hidden, beside it.
pub fn lock_path(target: &Path) -> PathBuf {
    // Built from the name's bytes: a name that is not UTF-8 gets a lock of its own.
    let mut name = std::ffi::OsString::from(".");
    name.push(target.file_name().unwrap_or_default());
    name.push(".gloffuse-lock");
    target.parent().unwrap_or(Path::new(".")).join(name)
}

impl FileLock {
    /// Locks `target` (its real path: links followed by the caller) for writing.
    pub fn take(target: &Path, wait: &Wait) -> Result<FileLock, Error> {
        use std::os::unix::fs::MetadataExt;
        let path = lock_path(target);
        let fail = |message: String| Error::Write {
            path: path.clone(),
            message,
        };
        let start = Instant::now();
        let mut told = false;
        loop {
            let handle = std::fs::OpenOptions::new()
                .create(true)
                .truncate(false)
                .write(true)
                .open(&path)
                .map_err(|e| {
                    fail(format!(
                        "cannot make the lock file for {}: {e}",
                        target.display()
                    ))
                })?;
            match handle.try_lock() {
                Ok(()) => {
                    let held = handle.metadata().map_err(|e| fail(e.to_string()))?;
                    let current = std::fs::metadata(&path);
                    if current.is_ok_and(|m| m.ino() == held.ino() && m.dev() == held.dev()) {
                        return Ok(FileLock {
                            path,
                            _file: handle,
                        });
                    }
                }
                Err(std::fs::TryLockError::WouldBlock) => {
                    if let (false, Some(progress)) = (told, wait.progress) {
                        progress.notice(&format!(
                            "waiting for another gloffuse that is writing {}",
                            target.display()
                        ));
                        told = true;
                    }
                }
                Err(std::fs::TryLockError::Error(e)) => return Err(fail(e.to_string())),
            }
            if wait.cancel.is_requested() {
                return Err(Error::Interrupted {
                    log: None,
                    written: Vec::new(),
                });
            }
            if let Some(limit) = wait.limit
                && start.elapsed() > limit
            {
                return Err(fail(format!(
                    "another process has held this lock on {} for over {} s; if none is \
                     running, remove the lock file",
                    target.display(),
                    limit.as_secs()
                )));
            }
            std::thread::sleep(Duration::from_millis(50));
        }
    }
}

impl Drop for FileLock {
    fn drop(&mut self) {
        // Removed before the handle (and so the lock) is released: see the module docs.
        let _ = std::fs::remove_file(&self.path);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Mutex;

    /// A progress that keeps its notices.
    #[derive(Default)]
    struct Told(Mutex<Vec<String>>);

    impl Progress for Told {
        fn notice(&self, message: &str) {
            self.0.lock().unwrap().push(message.to_string());
        }
    }

    fn no_wait(cancel: &Cancel) -> Wait<'_> {
        Wait {
            limit: Some(Duration::from_millis(200)),
            cancel,
            progress: None,
        }
    }

    #[test]
    fn a_second_writer_waits_and_nothing_is_left_behind() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("scene.blend");
        let cancel = Cancel::default();
        let first = FileLock::take(&target, &no_wait(&cancel)).unwrap();
        assert!(lock_path(&target).exists());
        let told = Told::default();
        let second = FileLock::take(
            &target,
            &Wait {
                limit: Some(Duration::from_millis(200)),
                cancel: &cancel,
                progress: Some(&told),
            },
        );
        assert!(matches!(second, Err(Error::Write { .. })), "{second:?}");
        let notices = told.0.lock().unwrap().clone();
        assert_eq!(notices.len(), 1, "said once: {notices:?}");
        assert!(notices[0].contains("scene.blend"), "{notices:?}");
        drop(first);
        assert!(!lock_path(&target).exists());
        // Free again: taken at once.
        let again = FileLock::take(&target, &no_wait(&cancel)).unwrap();
        drop(again);
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    }

    #[test]
    fn a_waiter_stops_when_asked() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("scene.blend");
        let cancel = Cancel::default();
        let _held = FileLock::take(&target, &no_wait(&cancel)).unwrap();
        cancel.request();
        let waiting = FileLock::take(
            &target,
            &Wait {
                limit: None,
                cancel: &cancel,
                progress: None,
            },
        );
        assert!(matches!(waiting, Err(Error::Interrupted { .. })));
    }
}
