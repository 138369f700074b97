//! Asset catalogs: where the groups show up in Blender's Asset Browser and, from 4.0, in
//! the shader editor's Add menu. Shader groups (a BSDF output) go in the catalog `Shader`,
//! next to Glossy BSDF; the helper groups in `Shader/Gloffuse Helpers`. Catalog ids are
//! UUIDv5 of the path, so every run gives the same ones.
//!
//! `blender_assets.cats.txt` (Blender's catalog definition file: a `VERSION 1` line, then
//! `UUID:path:simple name` lines) is merged, never clobbered: the user's lines stay as
//! they are, a catalog the user already has for one of our paths is used as it is, and only
//! the missing ones are added. A file Blender would ignore (no `VERSION 1` line) or misread
//! (a line whose id is not a UUID) is refused, never appended to. The file is read once
//! before the Blender run (bad input fails fast, and the groups get the user's ids), and
//! again under a lock just before it is replaced, so catalogs added meanwhile are kept.

use std::path::{Path, PathBuf};
use std::time::Duration;

use serde::Serialize;
use uuid::Uuid;

use crate::blender::Cancel;
use crate::error::{Error, Field, Hint};
use crate::file_lock::{FileLock, Wait};
use crate::output::staged;

/// The name of Blender's catalog definition file, beside the .blend (the library root).
pub const FILE_NAME: &str = "blender_assets.cats.txt";

/// One catalog: its id, its path, and the "simple name" Blender stores with it.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Catalog {
    pub uuid: String,
    pub path: String,
    pub simple_name: String,
}

impl Catalog {
    /// The catalog at `path`, with the id gloffuse gives it.
    pub fn at(path: &str) -> Self {
        let namespace = Uuid::new_v5(&Uuid::NAMESPACE_URL, b"gloffuse:asset-catalog");
        Catalog {
            uuid: Uuid::new_v5(&namespace, path.as_bytes()).to_string(),
            path: path.to_string(),
            simple_name: path.replace('/', "-"),
        }
    }

    /// Its line in a definition file.
    fn line(&self) -> String {
        format!("{}:{}:{}\n", self.uuid, self.path, self.simple_name)
    }
}

/// The catalogs of the two kinds of group.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Catalogs {
    /// Groups with a BSDF output.
    pub shader: Catalog,
    /// Groups the shader groups use (gains, the shading normal).
    pub helper: Catalog,
}

impl Default for Catalogs {
    fn default() -> Self {
        Catalogs {
            shader: Catalog::at("Shader"),
            helper: Catalog::at("Shader/Gloffuse Helpers"),
        }
    }
}

/// What Blender expects of a definition file, said once for every refusal.
const EXPECTED: &str = "Blender's asset catalog definition file: a `VERSION 1` line first \
    (after comments), then lines `UUID:catalog/path:simple name` with UUIDs like \
    9df742e7-f3ca-55de-8a87-d10e33fe9382 (fix or move the file, then run again)";

/// The catalog lines of a definition file, `(uuid, path)`, checked as Blender reads it: the
/// first line that is not blank or a comment is `VERSION 1`, and every line after it has a
/// UUID. `Err` is (1-based line number, or 0 for the file, and what is wrong).
fn parse(text: &str) -> Result<Vec<(&str, &str)>, (usize, String)> {
    let mut version = false;
    let mut lines = Vec::new();
    for (index, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        if !version {
            if line != "VERSION 1" {
                return Err((
                    index + 1,
                    format!("its first line is `{line}`, not `VERSION 1`"),
                ));
            }
            version = true;
            continue;
        }
        let mut parts = line.splitn(3, ':');
        let uuid = parts.next().unwrap_or_default();
        let path = parts.next();
        // Blender reads the hyphenated form only.
        let valid = uuid.len() == 36 && Uuid::try_parse(uuid).is_ok();
        match path {
            Some(path) if valid => lines.push((uuid, path)),
            _ => return Err((index + 1, format!("`{uuid}` is not a UUID"))),
        }
    }
    if !version {
        return Err((0, "it has no `VERSION 1` line".to_string()));
    }
    Ok(lines)
}

/// The definition file at `file`, checked (`None`: there is none, or it is empty).
pub fn read(file: &Path) -> Result<Option<String>, Error> {
    let text = match std::fs::read_to_string(file) {
        Ok(text) => text,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(source) => {
            return Err(Error::Read {
                path: file.to_path_buf(),
                source,
            });
        }
    };
    if text.trim().is_empty() {
        return Ok(None);
    }
    match parse(&text) {
        Ok(_) => Ok(Some(text)),
        Err((line, why)) => {
            let at = match line {
                0 => file.display().to_string(),
                n => format!("{}, line {n}", file.display()),
            };
            Err(Error::input(
                Field::Catalogs,
                at,
                Hint::text(format!("{EXPECTED}; {why}")),
            ))
        }
    }
}

impl Catalogs {
    /// Merges these catalogs into the definition file `existing` (if there is one): returns
    /// the catalogs to assign (the user's own id where they already have one of our paths)
    /// and the file's new text.
    pub fn merge(&self, existing: Option<&str>) -> (Catalogs, String) {
        // The caller checked the file (`read`); unreadable lines would only be kept as text.
        let lines: Vec<(&str, &str)> = existing
            .and_then(|text| parse(text).ok())
            .unwrap_or_default();
        let mut text = match existing {
            Some(t) if !t.trim().is_empty() => {
                let mut t = t.to_string();
                if !t.ends_with('\n') {
                    t.push('\n');
                }
                t
            }
            _ => HEADER.to_string(),
        };
        let mut resolve = |ours: &Catalog| match lines.iter().find(|(_, path)| *path == ours.path) {
            Some((uuid, _)) => Catalog {
                uuid: uuid.to_string(),
                ..ours.clone()
            },
            None => {
                text.push_str(&ours.line());
                ours.clone()
            }
        };
        let shader = resolve(&self.shader);
        let helper = resolve(&self.helper);
        (Catalogs { shader, helper }, text)
    }

    /// A definition file of these catalogs alone (the one an extension bundles).
    pub fn definition_file(&self) -> String {
        let mut text = HEADER.to_string();
        for c in [&self.shader, &self.helper] {
            text.push_str(&c.line());
        }
        text
    }
}

/// The merged definition file, written beside `file` under a temporary name while the lock
/// is held: [`Staged::commit`] renames it into place; dropped, it leaves the folder as it
/// was.
pub struct Staged {
    file: PathBuf,
    tmp: tempfile::TempPath,
    _lock: FileLock,
}

/// Re-reads the definition file `file` under its lock, merges the catalogs `ours` (already
/// resolved against the file as it was before the run) into it, and stages the result.
pub fn stage(file: &Path, ours: &Catalogs) -> Result<Staged, Error> {
    let lock = FileLock::take(
        file,
        &Wait {
            limit: Some(LOCK_WAIT),
            cancel: &Cancel::default(),
            progress: None,
        },
    )?;
    let existing = read(file)?;
    let (_, text) = ours.merge(existing.as_deref());
    let tmp = staged(file, text.as_bytes())?;
    Ok(Staged {
        file: file.to_path_buf(),
        tmp,
        _lock: lock,
    })
}

impl Staged {
    /// Renames the staged file into place, then releases the lock.
    pub fn commit(self) -> Result<PathBuf, Error> {
        let Staged { file, tmp, _lock } = self;
        tmp.persist(&file).map_err(|e| Error::Write {
            path: file.clone(),
            message: e.error.to_string(),
        })?;
        Ok(file)
    }
}

/// How long to wait for another run's lock on the definition file (it holds it for a
/// merge and a rename).
const LOCK_WAIT: Duration = Duration::from_secs(30);

/// The opening of a new definition file, as Blender writes it.
const HEADER: &str = "# This is an Asset Catalog Definition file for Blender.\n#\n\
    # Empty lines and lines starting with `#` will be ignored.\n\
    # The first non-ignored line should be the version indicator.\n\
    # Other lines are of the format \"UUID:catalog/path/for/assets:simple catalog name\"\n\n\
    VERSION 1\n\n";

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ids_are_uuid_v5_and_stable() {
        let a = Catalog::at("Shader");
        assert_eq!(a, Catalog::at("Shader"));
        let id = Uuid::parse_str(&a.uuid).unwrap();
        assert_eq!(id.get_version_num(), 5);
        assert_ne!(a.uuid, Catalog::at("Shader/Gloffuse Helpers").uuid);
    }

    #[test]
    fn merging_keeps_the_users_catalogs() {
        let ours = Catalogs::default();
        let (fresh, text) = ours.merge(None);
        assert_eq!(fresh, ours);
        assert_eq!(text, ours.definition_file());
        assert!(text.contains("\nVERSION 1\n"));
        assert!(text.contains(&format!("{}:Shader:Shader\n", ours.shader.uuid)));
        // Merging again adds nothing.
        assert_eq!(ours.merge(Some(&text)).1, text);
        // A user's file: their lines stay, their "Shader" catalog is used.
        let user = "VERSION 1\n\n# mine\n0e5a7f27-7e0e-4a11-9a35-1f4b2a7c9d01:Shader:My shaders\n\
                    1b2c3d4e-0000-4000-8000-000000000001:Props/Chairs:Props-Chairs";
        let (merged, text) = ours.merge(Some(user));
        assert!(text.starts_with(user));
        assert_eq!(merged.shader.uuid, "0e5a7f27-7e0e-4a11-9a35-1f4b2a7c9d01");
        assert_eq!(merged.helper, ours.helper);
        assert_eq!(text.matches(":Shader:").count(), 1);
        assert!(text.ends_with(&format!(
            "{}:Shader/Gloffuse Helpers:Shader-Gloffuse Helpers\n",
            ours.helper.uuid
        )));
    }

    #[test]
    fn files_blender_would_ignore_or_misread_are_refused() {
        let ok = "# mine\n\nVERSION 1\n\n0e5a7f27-7e0e-4a11-9a35-1f4b2a7c9d01:A/B:A-B\n";
        assert_eq!(
            parse(ok),
            Ok(vec![("0e5a7f27-7e0e-4a11-9a35-1f4b2a7c9d01", "A/B")])
        );
        let refused = |text: &str| parse(text).unwrap_err();
        assert_eq!(refused("# only comments\n").0, 0);
        assert_eq!(refused("VERSION 2\n").0, 1);
        assert_eq!(
            refused("0e5a7f27-7e0e-4a11-9a35-1f4b2a7c9d01:A:A\nVERSION 1\n").0,
            1
        );
        // Ids Blender does not read: not hex, a UUID's other spellings, no path.
        for bad in [
            "zzzzzzzz-7e0e-4a11-9a35-1f4b2a7c9d01:A:A",
            "0e5a7f277e0e4a119a351f4b2a7c9d01:A:A",
            "{0e5a7f27-7e0e-4a11-9a35-1f4b2a7c9d01}:A:A",
            "0e5a7f27-7e0e-4a11-9a35-1f4b2a7c9d01",
            "Shader",
        ] {
            let (line, why) = refused(&format!("VERSION 1\n\n{bad}\n"));
            assert_eq!(line, 3, "{bad}");
            assert!(why.contains("is not a UUID"), "{why}");
        }
    }

    #[test]
    fn read_names_the_file_and_the_line() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join(FILE_NAME);
        assert_eq!(read(&file).unwrap(), None, "no file");
        std::fs::write(&file, "  \n").unwrap();
        assert_eq!(read(&file).unwrap(), None, "an empty file is a new one");
        std::fs::write(&file, "VERSION 1\nnot-a-uuid:A:A\n").unwrap();
        let message = read(&file).unwrap_err().to_string();
        let at = format!("{}, line 2", file.display());
        assert!(message.contains(&at), "{message}");
        assert!(message.contains("`not-a-uuid` is not a UUID"), "{message}");
        std::fs::write(&file, "# mine\n").unwrap();
        let message = read(&file).unwrap_err().to_string();
        assert!(message.contains("has no `VERSION 1` line"), "{message}");
        std::fs::remove_file(&file).unwrap();
        std::fs::create_dir(&file).unwrap();
        assert!(matches!(read(&file), Err(Error::Read { .. })), "a folder");
    }

    #[test]
    fn staging_merges_the_file_as_it_is_then_and_leaves_nothing_behind() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join(FILE_NAME);
        let ours = Catalogs::default();
        // Read before the run: none. Meanwhile the user writes one with a catalog.
        let user = "VERSION 1\n1b2c3d4e-0000-4000-8000-000000000001:Props:Props\n";
        std::fs::write(&file, user).unwrap();
        let staged = stage(&file, &ours).unwrap();
        let lock = dir.path().join(format!(".{FILE_NAME}.gloffuse-lock"));
        assert!(lock.exists(), "held while staged");
        assert_eq!(std::fs::read_to_string(&file).unwrap(), user, "not yet");
        assert_eq!(staged.commit().unwrap(), file);
        let text = std::fs::read_to_string(&file).unwrap();
        assert!(text.starts_with(user), "{text}");
        assert!(text.ends_with(&ours.helper.line()), "{text}");
        let names: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
        assert_eq!(names.len(), 1, "no lock or temporary file left");
        // Dropped unrenamed: the folder as it was.
        std::fs::write(&file, user).unwrap();
        drop(stage(&file, &ours).unwrap());
        assert_eq!(std::fs::read_to_string(&file).unwrap(), user);
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
        // A bad file is refused under the lock too, and the lock released.
        std::fs::write(&file, "VERSION 2\n").unwrap();
        assert!(stage(&file, &ours).is_err());
        assert!(!lock.exists());
    }

    #[test]
    fn a_second_stager_waits_for_the_first() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join(FILE_NAME);
        let ours = Catalogs::default();
        let first = stage(&file, &ours).unwrap();
        let (file2, ours2) = (file.clone(), ours.clone());
        let waiter = std::thread::spawn(move || {
            let started = std::time::Instant::now();
            let second = stage(&file2, &ours2).unwrap();
            (started.elapsed(), second.commit().unwrap())
        });
        std::thread::sleep(Duration::from_millis(300));
        first.commit().unwrap();
        let (waited, _) = waiter.join().unwrap();
        assert!(waited >= Duration::from_millis(250), "{waited:?}");
        // The second saw the first's file: nothing added twice.
        let text = std::fs::read_to_string(&file).unwrap();
        assert_eq!(text, ours.definition_file());
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }
}
