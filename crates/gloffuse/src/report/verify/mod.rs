//! Renderers of the verify verdict, one file each: `table` (terminal), `json` (machines),
//! `junit` (CI servers), `html` (a page for people), `sheet` (the contact sheet), `plot`
//! (the brightness plot), `deviation` (the false-colour view), `notes` (the verdict's notes
//! in words), `words` (the verdict and the mode in words); and the report folder that holds
//! them with the rendered EXR.

pub mod deviation;
pub mod html;
pub mod json;
pub mod junit;
pub mod notes;
pub mod plot;
pub mod sheet;
pub mod table;
pub mod words;

use std::path::{Path, PathBuf};

use crate::Error;
use crate::output::{self, write_output};
use crate::verify::Verification;

/// Writes report.json, sweep.exr, contact-sheet.png, brightness.png, deviation.png and
/// report.html into `dir` (made if missing; its parent must exist); returns the paths
/// written. `rerun` is the command line of the check, for the page.
pub fn write_files(
    dir: &Path,
    verification: &Verification,
    rerun: &str,
) -> Result<Vec<PathBuf>, Error> {
    let Verification { report, rendered } = verification;
    output::make_report_dir(dir)?;
    let json_path = dir.join("report.json");
    write_output(&json_path, json::render(report).as_bytes())?;
    let exr_path = dir.join("sweep.exr");
    let bytes = std::fs::read(&rendered.exr).map_err(|source| Error::Read {
        path: rendered.exr.clone(),
        source,
    })?;
    write_output(&exr_path, &bytes)?;
    let sheet_path = dir.join("contact-sheet.png");
    let (rows, columns) = sheet::sheet_labels(&rendered.plan, report.mode);
    sheet::contact_sheet(
        &rendered.image,
        rendered.plan.settings.cell as usize,
        &rows,
        &columns,
        &sheet_path,
    )?;
    let plot_path = dir.join(html::PLOT);
    plot::brightness_plot(report, &plot_path)?;
    let false_colour = dir.join("deviation.png");
    deviation::sheet(report, rendered, &false_colour)?;
    let mut written = vec![json_path, exr_path, sheet_path, plot_path, false_colour];
    let names: Vec<String> = written
        .iter()
        .filter_map(|p| p.file_name().map(|n| n.to_string_lossy().into_owned()))
        .collect();
    let page = dir.join("report.html");
    write_output(
        &page,
        html::render(report, rendered, rerun, &names).as_bytes(),
    )?;
    written.push(page);
    Ok(written)
}
