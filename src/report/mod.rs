//! ⑤ Report: renderers of the verify verdict, one file each — `table` (terminal), `json`
//! (machines), `png` (the contact sheet and the brightness plot) — and the report folder
//! that holds them with the rendered EXR.

pub mod json;
pub mod png;
pub mod table;

use std::path::{Path, PathBuf};

use crate::Error;
use crate::output::write_atomic;
use crate::verify::Verification;

/// Checks that `dir` can become a report folder: it is made if needed, so the nearest part
/// of it that exists must be a directory. Called before any slow work.
pub fn check_dir(dir: &Path) -> Result<(), Error> {
    let Some(file) = dir.ancestors().find(|a| a.exists() && !a.is_dir()) else {
        return Ok(());
    };
    Err(Error::Write {
        path: dir.to_path_buf(),
        message: if file == dir {
            "--report needs a directory, and this is a file".into()
        } else {
            format!(
                "--report needs a directory, but {} is a file",
                file.display()
            )
        },
    })
}

/// Writes report.json, sweep.exr, contact-sheet.png and brightness.png into `dir`
/// (created if needed); returns the paths written.
pub fn write_files(dir: &Path, verification: &Verification) -> Result<Vec<PathBuf>, Error> {
    let Verification { report, rendered } = verification;
    std::fs::create_dir_all(dir).map_err(|e| Error::Write {
        path: dir.to_path_buf(),
        message: e.to_string(),
    })?;
    let json_path = dir.join("report.json");
    write_atomic(&json_path, json::render(report).as_bytes())?;
    let exr_path = dir.join("sweep.exr");
    let bytes = std::fs::read(&rendered.exr).map_err(|source| Error::Read {
        path: rendered.exr.clone(),
        source,
    })?;
    write_atomic(&exr_path, &bytes)?;
    let sheet = dir.join("contact-sheet.png");
    let (rows, columns) = png::sheet_labels(&rendered.plan);
    png::contact_sheet(
        &rendered.image,
        rendered.plan.settings.cell as usize,
        &rows,
        &columns,
        &sheet,
    )?;
    let plot = dir.join("brightness.png");
    png::brightness_plot(report, &plot)?;
    Ok(vec![json_path, exr_path, sheet, plot])
}
