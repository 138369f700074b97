//! Renderers of the audit's verdict: `table` (terminal), `junit` (CI servers), `sarif`
//! (code-scanning services), `html` (a page for people, each material as authored beside
//! its twin and their difference), and the report folder, whose pictures are made file by
//! file while the audit streams, or copied from the shards' folders by `merge`.

pub mod html;
pub mod junit;
pub mod merge;
pub mod sarif;
pub mod table;

use std::path::{Path, PathBuf};

use super::false_colour::colour;
use super::png::{cell_image, encode_png};
use crate::Error;
use crate::audit::{AuditReport, FileDone};
use crate::output::{self, write_output};
use crate::verify::image::Rgba;

/// The folder of material pictures, inside the report folder.
const PICTURES: &str = "materials";

/// The report folder while the audit runs: each file's pictures are written as it is done,
/// into a temporary folder inside it that becomes `materials/` when the report is finished
/// (an audit stopped half-way leaves no pictures behind, and no report folder it made).
pub struct ReportDir {
    dir: PathBuf,
    /// Whether this run made `dir` (then an unfinished report removes it again).
    made: bool,
    /// Taken by [`ReportDir::finish`]; still here when dropped unfinished.
    staging: Option<tempfile::TempDir>,
    /// Per material, in report order: its picture's path relative to the folder, if rendered.
    pictures: Vec<Option<String>>,
}

impl ReportDir {
    /// Makes `dir` (its parent must exist) and the temporary picture folder in it.
    pub fn create(dir: &Path) -> Result<Self, Error> {
        let made = !dir.exists();
        output::make_report_dir(dir)?;
        let staging = tempfile::Builder::new()
            .prefix(".gloffuse-materials-")
            .tempdir_in(dir)
            .map_err(|e| Error::Write {
                path: dir.to_path_buf(),
                message: e.to_string(),
            })?;
        Ok(ReportDir {
            dir: dir.to_path_buf(),
            made,
            staging: Some(staging),
            pictures: Vec::new(),
        })
    }

    fn staging(&self) -> &Path {
        self.staging.as_ref().expect("taken only by finish").path()
    }

    /// Writes one PNG per rendered material of `done`: as authored | twin | difference.
    pub fn add(&mut self, done: &FileDone) -> Result<(), Error> {
        for m in done.materials {
            let rgb = match (done.image, done.file.grid, m.cells) {
                (Some(image), Some((columns, cell)), Some((own, twin))) => {
                    strip(image, columns, cell, own, twin).map(|rgb| (rgb, cell))
                }
                _ => None,
            };
            let picture = match rgb {
                Some((rgb, cell)) => {
                    let file = picture_name(self.pictures.len());
                    let path = self.staging().join(&file);
                    let bytes =
                        encode_png(&rgb, ((3 * cell) as u32, cell as u32)).map_err(|message| {
                            Error::Write {
                                path: path.clone(),
                                message,
                            }
                        })?;
                    write_output(&path, &bytes)?;
                    Some(format!("{PICTURES}/{file}"))
                }
                _ => None,
            };
            self.pictures.push(picture);
        }
        Ok(())
    }

    /// Adds the next material's picture as a copy of `from` (a shard's picture, opened by
    /// [`merge::ShardPictures::picture`]), if any.
    fn add_copy(&mut self, from: Option<(PathBuf, std::fs::File)>) -> Result<(), Error> {
        let picture = match from {
            Some((from, mut source)) => {
                let file = picture_name(self.pictures.len());
                let path = self.staging().join(&file);
                let failed = |e: std::io::Error| Error::Write {
                    path: path.clone(),
                    message: format!("copying {}: {e}", from.display()),
                };
                let mut copy = std::fs::File::create(&path).map_err(failed)?;
                std::io::copy(&mut source, &mut copy).map_err(failed)?;
                Some(format!("{PICTURES}/{file}"))
            }
            None => None,
        };
        self.pictures.push(picture);
        Ok(())
    }

    /// Puts the pictures in place as `materials/` (replacing an earlier report's), writes
    /// report.json and report.html; returns every path written at the top.
    pub fn finish(mut self, report: &AuditReport, rerun: &str) -> Result<Vec<PathBuf>, Error> {
        let pictures = self.dir.join(PICTURES);
        let fail = |e: std::io::Error| Error::Write {
            path: pictures.clone(),
            message: e.to_string(),
        };
        let staged = self.staging.take().expect("taken only here").keep();
        if pictures.is_dir() {
            // The old folder moves aside, the new one takes its name, then the old goes.
            let old = staged.with_extension("old");
            std::fs::rename(&pictures, &old).map_err(fail)?;
            std::fs::rename(&staged, &pictures).map_err(fail)?;
            std::fs::remove_dir_all(&old).map_err(fail)?;
        } else {
            std::fs::rename(&staged, &pictures).map_err(fail)?;
        }
        let json = self.dir.join("report.json");
        let text = serde_json::to_string_pretty(report).expect("reports serialise to JSON");
        write_output(&json, text.as_bytes())?;
        let page = self.dir.join("report.html");
        write_output(
            &page,
            html::render(report, &self.pictures, rerun).as_bytes(),
        )?;
        Ok(vec![json, page, self.dir.join(PICTURES)])
    }
}

impl Drop for ReportDir {
    /// Unfinished (an error, a stop): the pictures go, and the folder too if this run made
    /// it and nothing else is in it.
    fn drop(&mut self) {
        if let Some(staging) = self.staging.take() {
            drop(staging);
            if self.made {
                let _ = std::fs::remove_dir(&self.dir);
            }
        }
    }
}

fn picture_name(index: usize) -> String {
    format!("{index:05}.png")
}

/// Three cells side by side, row by row: the material, its twin, and the relative
/// difference (material − twin) / twin in false colour; `None` if the image does not hold
/// both cells.
fn strip(image: &Rgba, columns: usize, cell: usize, own: usize, twin: usize) -> Option<Vec<u8>> {
    let a = cell_image(image, columns, cell, own)?;
    let b = cell_image(image, columns, cell, twin)?;
    let diff = difference(image, columns, cell, own, twin)?;
    let mut rgb = Vec::with_capacity(a.len() * 3);
    for y in 0..cell {
        let row = y * cell * 3..(y + 1) * cell * 3;
        rgb.extend_from_slice(&a[row.clone()]);
        rgb.extend_from_slice(&b[row.clone()]);
        rgb.extend_from_slice(&diff[row]);
    }
    Some(rgb)
}

fn difference(
    image: &Rgba,
    columns: usize,
    cell: usize,
    own: usize,
    twin: usize,
) -> Option<Vec<u8>> {
    let (ox, oy) = image.cell_origin(columns, cell, own)?;
    let (tx, ty) = image.cell_origin(columns, cell, twin)?;
    let luminance = |p: [f32; 4]| f64::from(p[0] + p[1] + p[2]) / 3.0;
    let mut rgb = Vec::with_capacity(cell * cell * 3);
    for y in 0..cell {
        for x in 0..cell {
            let p = image.pixels[(oy + y) * image.width + ox + x];
            let q = image.pixels[(ty + y) * image.width + tx + x];
            let d = if p[3] < 0.5 || q[3] < 0.5 || luminance(q) <= 0.0 {
                f64::NAN
            } else {
                luminance(p) / luminance(q) - 1.0
            };
            rgb.extend_from_slice(&colour(d));
        }
    }
    Some(rgb)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::audit::{AuditedFile, AuditedMaterial};

    /// A grid and an image that disagree (a job that said more cells, or columns, than its
    /// render holds) give no picture, never a panic.
    #[test]
    fn a_grid_the_image_does_not_hold_gives_no_picture() {
        let image = Rgba {
            width: 32,
            height: 16,
            pixels: vec![[0.5, 0.5, 0.5, 1.0]; 32 * 16],
        };
        let file: AuditedFile = serde_json::from_value(serde_json::json!({
            "file": "big.blend", "saved_by": null, "error": null, "findings": [],
            "materials": 4, "log": null, "render_seconds": 1.0, "scan_seconds": 1.0,
            "fixed": null
        }))
        .unwrap();
        let material = |cells| {
            let mut m: AuditedMaterial = serde_json::from_value(serde_json::json!({
                "file": "big.blend", "material": "m", "verdict": "ok", "reason": "",
                "mean": null, "center": null, "rim": null, "twin_mean": null,
                "twin_center": null, "twin_rim": null, "replaced": 0, "findings": [],
                "library": null, "after": null
            }))
            .unwrap();
            m.cells = Some(cells);
            m
        };
        // Cells (0, 1) fit; (2, 3) lie in a row the image lacks; 7 lies past it.
        let materials = [material((0, 1)), material((2, 3)), material((0, 7))];
        let dir = tempfile::tempdir().unwrap();
        for (grid, pictures) in [
            ((2, 16), [true, false, false]),
            ((0, 16), [false; 3]),
            ((2, 0), [false; 3]),
            ((1, 32), [false; 3]),
            ((usize::MAX, usize::MAX), [false; 3]),
        ] {
            let mut report = ReportDir::create(&dir.path().join(format!("{grid:?}"))).unwrap();
            let file = AuditedFile {
                grid: Some(grid),
                ..file.clone()
            };
            report
                .add(&FileDone {
                    file: &file,
                    materials: &materials,
                    image: Some(&image),
                })
                .unwrap();
            let made: Vec<bool> = report.pictures.iter().map(Option::is_some).collect();
            assert_eq!(made, pictures, "grid {grid:?}");
        }
        assert!(cell_image(&image, 2, 16, 2).is_none());
        assert_eq!(
            cell_image(&image, 2, 16, 1).map(|c| c.len()),
            Some(16 * 16 * 3)
        );
    }
}
