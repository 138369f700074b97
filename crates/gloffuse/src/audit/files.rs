//! Which .blend files an audit reads: the files named, and every `*.blend` below the
//! folders named (hidden entries and linked folders skipped, so a link cannot loop), in
//! path order, each once.

use std::path::{Path, PathBuf};

use crate::{Error, Field};

/// The .blend files under `paths`, sorted and each once (by its real path). A path that
/// does not exist, a file that is not a `.blend`, or nothing found at all is bad input.
pub fn blend_files(paths: &[PathBuf]) -> Result<Vec<PathBuf>, Error> {
    let mut found = Vec::new();
    for path in paths {
        let meta = std::fs::metadata(path).map_err(|_| {
            Error::input(
                Field::AuditPath,
                path.display(),
                "an existing .blend file or folder",
            )
        })?;
        if meta.is_dir() {
            walk(path, &mut found)?;
        } else if is_blend(path) && meta.is_file() {
            found.push(path.clone());
        } else {
            return Err(Error::input(
                Field::AuditPath,
                path.display(),
                "a .blend file (a name ending in .blend) or a folder",
            ));
        }
    }
    let mut seen = std::collections::HashSet::new();
    found.sort();
    found.retain(|p| seen.insert(std::fs::canonicalize(p).unwrap_or_else(|_| p.clone())));
    if found.is_empty() {
        let shown: Vec<String> = paths.iter().map(|p| p.display().to_string()).collect();
        return Err(Error::input(
            Field::AuditPath,
            shown.join(" "),
            "a .blend file, or a folder with .blend files in it or below it",
        ));
    }
    Ok(found)
}

fn is_blend(path: &Path) -> bool {
    path.extension().is_some_and(|e| e == "blend")
}

fn walk(dir: &Path, found: &mut Vec<PathBuf>) -> Result<(), Error> {
    let entries = std::fs::read_dir(dir).map_err(|source| Error::Read {
        path: dir.to_path_buf(),
        source,
    })?;
    for entry in entries {
        let entry = entry.map_err(|source| Error::Read {
            path: dir.to_path_buf(),
            source,
        })?;
        let path = entry.path();
        if entry.file_name().to_string_lossy().starts_with('.') {
            continue;
        }
        // file_type does not follow links: a linked folder is skipped, a linked file kept.
        let kind = entry.file_type().map_err(|source| Error::Read {
            path: path.clone(),
            source,
        })?;
        if kind.is_dir() {
            walk(&path, found)?;
        } else if is_blend(&path) && std::fs::metadata(&path).is_ok_and(|m| m.is_file()) {
            found.push(path);
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn folders_are_searched_below_and_each_file_counts_once() {
        let dir = tempfile::tempdir().unwrap();
        let root = dir.path();
        std::fs::create_dir_all(root.join("a/b")).unwrap();
        std::fs::create_dir_all(root.join(".hidden")).unwrap();
        for f in [
            "a/b/deep.blend",
            "top.blend",
            "top.blend1",
            ".hidden/x.blend",
            "a/notes.txt",
        ] {
            std::fs::write(root.join(f), b"x").unwrap();
        }
        std::os::unix::fs::symlink(root.join("a"), root.join("loop")).unwrap();
        let files = blend_files(&[root.to_path_buf(), root.join("top.blend")]).unwrap();
        assert_eq!(
            files,
            vec![root.join("a/b/deep.blend"), root.join("top.blend")]
        );
    }

    #[test]
    fn a_missing_path_a_non_blend_and_an_empty_folder_are_bad_input() {
        let dir = tempfile::tempdir().unwrap();
        let text = dir.path().join("notes.txt");
        std::fs::write(&text, b"x").unwrap();
        for bad in [
            dir.path().join("missing.blend"),
            text,
            dir.path().to_path_buf(),
        ] {
            let e = blend_files(std::slice::from_ref(&bad))
                .unwrap_err()
                .to_string();
            assert!(e.contains(&bad.display().to_string()), "{e}");
        }
    }
}
