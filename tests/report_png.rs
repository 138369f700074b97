//! The PNG outputs of `verify --report`: the contact sheet's pixels are the exact sRGB
//! encoding of the composited render, the plot is drawn, and a failed write leaves no file.
//!
//! Set `GLOFFUSE_PNG_SAMPLES=DIR` to also keep the produced PNGs in DIR for a look.
//!
//! Tier: fast (no Blender; `scripts/test.sh --fast` runs it).

use std::path::{Path, PathBuf};

use gloffuse::measure::{Distribution, Roughness};
use gloffuse::report::verify::plot::{PLOT_SIZE, brightness_plot};
use gloffuse::report::verify::sheet::{contact_sheet, sheet_labels};
use gloffuse::verify::image::Rgba;
use gloffuse::verify::plan::{Plan, RenderSettings};
use gloffuse::verify::stats::{RINGS, SphereStats, sphere_stats};
use gloffuse::verify::{ReferenceSphere, RenderInfo, Row, VerifyReport};

const CELL: usize = 16;
const RADIUS_FRACTION: f64 = 0.9;

/// sRGB code values of the linear values the tests use (IEC 61966-2-1, rounded).
const SRGB_0_18: u8 = 118;
const SRGB_0_214: u8 = 128;
const SRGB_0_5: u8 = 188;

/// A grid of `columns` × `rows` cells of `cell` pixels, each a disc of `colour(col, row)`
/// (alpha 1) on transparent black (alpha 0), premultiplied like Blender's film.
fn grid(
    columns: usize,
    rows: usize,
    cell: usize,
    colour: impl Fn(usize, usize, f64) -> [f32; 3],
) -> Rgba {
    let (width, height) = (columns * cell, rows * cell);
    let radius = RADIUS_FRACTION * cell as f64 / 2.0;
    let pixels = (0..width * height)
        .map(|i| {
            let (x, y) = (i % width, i / width);
            let dx = (x % cell) as f64 + 0.5 - cell as f64 / 2.0;
            let dy = (y % cell) as f64 + 0.5 - cell as f64 / 2.0;
            let d = (dx * dx + dy * dy).sqrt() / radius;
            if d < 1.0 {
                let [r, g, b] = colour(x / cell, y / cell, (1.0 - d * d).sqrt());
                [r, g, b, 1.0]
            } else {
                [0.0; 4]
            }
        })
        .collect();
    Rgba {
        width,
        height,
        pixels,
    }
}

/// Linear colours of the 3 × 3 test grid: red is 0.5 everywhere; green steps by column and
/// blue by row, so a misplaced or flipped grid shows.
fn small_colour(col: usize, row: usize, _mu: f64) -> [f32; 3] {
    let steps = [0.0, 0.214, 0.5];
    [0.5, steps[col], [0.214, 1.0, 2.0][row]]
}

fn small_expected(col: usize, row: usize) -> [u8; 3] {
    [
        SRGB_0_5,
        [0, SRGB_0_214, SRGB_0_5][col],
        [SRGB_0_214, 255, 255][row],
    ]
}

fn labels(v: &[&str]) -> Vec<String> {
    v.iter().map(|s| s.to_string()).collect()
}

fn samples_dir() -> Option<PathBuf> {
    let dir = PathBuf::from(std::env::var_os("GLOFFUSE_PNG_SAMPLES")?);
    std::fs::create_dir_all(&dir).ok()?;
    Some(dir)
}

fn keep_sample(from: &Path, name: &str) {
    if let Some(dir) = samples_dir() {
        std::fs::copy(from, dir.join(name)).unwrap();
    }
}

fn render_info(cell: usize, columns: usize, rows: usize) -> RenderInfo {
    RenderInfo {
        blender_version: "4.5.3 LTS".into(),
        blender_program: "/opt/blender/blender".into(),
        masking: "smith".into(),
        cell: cell as u32,
        samples: 32,
        seed: 0,
        width: columns * cell,
        height: rows * cell,
        render_seconds: 12.5,
        log: "/tmp/verify.log".into(),
        command: "blender -b --factory-startup --python furnace.py".into(),
    }
}

/// A row of white spheres: brightness is the rendered mean (the target is white).
fn white_row(
    id: usize,
    distribution: Distribution,
    roughness: f64,
    uncorrected: SphereStats,
    corrected: SphereStats,
    predicted_uncorrected: f64,
    pass: bool,
) -> Row {
    Row {
        id,
        distribution,
        roughness: Roughness::new(roughness).unwrap(),
        block: None,
        cycles_uncorrected: None,
        target: [1.0; 3],
        uncorrected_brightness: uncorrected.mean,
        brightness: corrected.mean,
        deviation: (corrected.mean - 1.0).abs(),
        uncorrected,
        corrected,
        predicted_uncorrected: Some(predicted_uncorrected),
        predicted_corrected: 1.0,
        ring_targets: vec![[1.0; 3]; RINGS],
        worst_ring: 0.0,
        pass,
        within_noise: false,
    }
}

fn reference_sphere(roughness: f64, stats: SphereStats) -> ReferenceSphere {
    ReferenceSphere {
        roughness: Roughness::new(roughness).unwrap(),
        block: None,
        cell: 0,
        brightness: stats.mean,
        stats,
    }
}

fn with_mean(stats: &SphereStats, mean: f64) -> SphereStats {
    let mut s = stats.clone();
    s.mean = mean;
    s
}

/// The 3 × 3 grid as a report: GGX uncorrected, GGX corrected, the reference row; one
/// prediction and one rendered mean are NaN, which the plot must skip.
fn small_report(img: &Rgba) -> VerifyReport {
    let roughness = [0.1, 0.5, 0.9];
    let stats = |i| sphere_stats(img, i, 3, CELL, RADIUS_FRACTION);
    let rows = (0..3)
        .map(|c| {
            let corrected = if c == 1 {
                with_mean(&stats(3 + c), f64::NAN)
            } else {
                stats(3 + c)
            };
            let predicted = if c == 2 {
                f64::NAN
            } else {
                0.9 - 0.2 * c as f64
            };
            white_row(
                c,
                Distribution::Ggx,
                roughness[c],
                stats(c),
                corrected,
                predicted,
                false,
            )
        })
        .collect();
    let reference = (0..3)
        .map(|c| reference_sphere(roughness[c], stats(6 + c)))
        .collect();
    VerifyReport {
        engine: gloffuse::measure::Engine::Cycles,
        groups_engine: gloffuse::measure::Engine::Cycles,
        lighting: None,
        mode: gloffuse::generate::Mode::Roughness,
        color: [1.0; 3],
        color_model: gloffuse::generate::ColorModel::Exact,
        ring_tolerance_percent: 1.5,
        coefficients: "cycles-4.x".into(),
        render: render_info(CELL, 3, 3),
        tolerance_percent: 2.0,
        rows,
        reference,
        notes: vec![],
        pass: false,
    }
}

#[test]
fn contact_sheet_pixels_are_the_srgb_encoding_of_the_composite() {
    let img = grid(3, 3, CELL, small_colour);
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("sheet.png");
    let rows = labels(&["GGX uncorrected", "GGX corrected", "Multiscatter GGX"]);
    let cols = labels(&["0.1", "0.5", "0.9"]);
    contact_sheet(&img, CELL, &rows, &cols, &out).unwrap();
    keep_sample(&out, "sheet-small.png");

    let sheet = image::open(&out).unwrap().to_rgb8();
    let (w, h) = (sheet.width() as usize, sheet.height() as usize);
    // The grid sits in the bottom-right corner, one sheet pixel per image pixel; the label
    // column must hold "Multiscatter GGX" and the header a line of text.
    let (left, top) = (w - img.width, h - img.height);
    assert!(left >= 80, "label column only {left} px wide");
    assert!((12..=60).contains(&top), "header {top} px tall");

    let close = |got: [u8; 3], want: [u8; 3], what: &str| {
        for k in 0..3 {
            assert!(
                got[k].abs_diff(want[k]) <= 1,
                "{what}: got {got:?}, want {want:?}"
            );
        }
    };
    for row in 0..3 {
        for col in 0..3 {
            let (x0, y0) = (left + col * CELL, top + row * CELL);
            let centre = sheet
                .get_pixel((x0 + CELL / 2) as u32, (y0 + CELL / 2) as u32)
                .0;
            close(
                centre,
                small_expected(col, row),
                &format!("centre of cell ({col}, {row})"),
            );
            let corner = sheet.get_pixel(x0 as u32, y0 as u32).0;
            close(
                corner,
                [SRGB_0_18; 3],
                &format!("background of cell ({col}, {row})"),
            );
        }
    }

    // Labels are drawn: light text on the dark label column, in every row's band.
    for row in 0..3 {
        let band = top + row * CELL..top + (row + 1) * CELL;
        let lit = band
            .flat_map(|y| (0..left).map(move |x| (x, y)))
            .filter(|&(x, y)| sheet.get_pixel(x as u32, y as u32).0[0] > 150)
            .count();
        assert!(lit > 10, "row {row}: no label text ({lit} light pixels)");
    }
    let header_lit = (0..top)
        .flat_map(|y| (left..w).map(move |x| (x, y)))
        .filter(|&(x, y)| sheet.get_pixel(x as u32, y as u32).0[0] > 150)
        .count();
    assert!(
        header_lit > 10,
        "no column labels ({header_lit} light pixels)"
    );
}

#[test]
fn partial_coverage_is_composited_and_out_of_range_values_clamp() {
    // One cell: premultiplied (0.25, 0.25, 0.25, 0.5) over 0.18 → 0.25 + 0.5 · 0.18 = 0.34;
    // a NaN pixel and a negative one must not panic.
    let mut img = grid(1, 1, CELL, |_, _, _| [0.5; 3]);
    img.pixels[8 * CELL + 8] = [0.25, 0.25, 0.25, 0.5];
    img.pixels[8 * CELL + 9] = [f32::NAN, -1.0, 5.0, 1.0];
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("one.png");
    contact_sheet(
        &img,
        CELL,
        &labels(&["GGX uncorrected"]),
        &labels(&["0.5"]),
        &out,
    )
    .unwrap();
    let sheet = image::open(&out).unwrap().to_rgb8();
    let (left, top) = (sheet.width() - CELL as u32, sheet.height() - CELL as u32);
    let srgb_0_34 = 158; // 1.055 · 0.34^(1/2.4) − 0.055 = 0.6200 → 158.1
    let half = sheet.get_pixel(left + 8, top + 8).0;
    assert!(half.iter().all(|v| v.abs_diff(srgb_0_34) <= 1), "{half:?}");
    assert_eq!(sheet.get_pixel(left + 9, top + 8).0, [0, 0, 255]);
}

#[test]
fn contact_sheet_rejects_labels_that_do_not_match_the_grid() {
    let img = grid(3, 3, CELL, small_colour);
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("sheet.png");
    let err = contact_sheet(
        &img,
        CELL,
        &labels(&["a", "b"]),
        &labels(&["1", "2", "3"]),
        &out,
    )
    .unwrap_err()
    .to_string();
    assert!(err.contains("2 row and 3 column labels"), "{err}");
    assert!(!out.exists());
}

#[test]
fn brightness_plot_is_drawn_and_skips_nan() {
    let img = grid(3, 3, CELL, small_colour);
    let report = small_report(&img);
    assert!(report.rows[1].corrected.mean.is_nan());
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("plot.png");
    brightness_plot(&report, &out).unwrap();
    keep_sample(&out, "plot-small.png");

    let plot = image::open(&out).unwrap().to_rgb8();
    assert_eq!((plot.width(), plot.height()), PLOT_SIZE);
    let mut colours: Vec<[u8; 3]> = plot.pixels().map(|p| p.0).collect();
    colours.sort_unstable();
    colours.dedup();
    assert!(
        colours.len() > 50,
        "only {} distinct colours",
        colours.len()
    );
    // GGX's series colour is there (markers, lines, legend).
    let ggx = plot.pixels().filter(|p| p.0 == [214, 39, 40]).count();
    assert!(ggx > 100, "only {ggx} GGX-coloured pixels");
}

#[test]
fn brightness_plot_of_only_nan_values_still_draws() {
    let img = grid(3, 3, CELL, small_colour);
    let mut report = small_report(&img);
    for row in &mut report.rows {
        row.uncorrected_brightness = f64::NAN;
        row.brightness = f64::NAN;
        row.predicted_uncorrected = Some(f64::NAN);
        row.predicted_corrected = f64::NAN;
    }
    report.reference.clear();
    report.tolerance_percent = f64::NAN;
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("empty.png");
    brightness_plot(&report, &out).unwrap();
    let plot = image::open(&out).unwrap().to_rgb8();
    assert_eq!((plot.width(), plot.height()), PLOT_SIZE);
}

#[test]
fn a_missing_output_directory_is_an_error_naming_the_path_and_leaves_no_file() {
    let img = grid(3, 3, CELL, small_colour);
    let report = small_report(&img);
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("no-such-dir");
    let rows = labels(&["GGX uncorrected", "GGX corrected", "Multiscatter GGX"]);
    let cols = labels(&["0.1", "0.5", "0.9"]);

    let sheet = missing.join("sheet.png");
    let err = contact_sheet(&img, CELL, &rows, &cols, &sheet).unwrap_err();
    assert!(matches!(err, gloffuse::Error::Write { ref path, .. } if path == &sheet));
    assert!(
        err.to_string().contains(&sheet.display().to_string()),
        "{err}"
    );

    let plot = missing.join("plot.png");
    let err = brightness_plot(&report, &plot).unwrap_err();
    assert!(matches!(err, gloffuse::Error::Write { ref path, .. } if path == &plot));
    assert!(
        err.to_string().contains(&plot.display().to_string()),
        "{err}"
    );

    assert!(!missing.exists());
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
}

/// A verify-sized sweep (three distributions, eleven roughness values, 64-pixel cells) with
/// labels from the plan: the layout holds the longest label, and the samples look real.
#[test]
fn full_sweep_sheet_and_plot() {
    let roughness: Vec<f64> = (0..=10).map(|i| i as f64 / 10.0).collect();
    let settings = RenderSettings::default();
    let cell = settings.cell as usize;
    let typed: Vec<Roughness> = roughness
        .iter()
        .map(|&r| Roughness::new(r).unwrap())
        .collect();
    let plan = Plan::verify(&Distribution::ALL, &typed, &[], settings);
    let (row_labels, column_labels) = sheet_labels(&plan, gloffuse::generate::Mode::Roughness);
    assert_eq!(row_labels.len(), 7);
    assert_eq!(row_labels[4], "Ashikhmin-Shirley uncorrected");
    assert_eq!(row_labels[6], "Multiscatter GGX");
    assert_eq!(column_labels[..3], ["0", "0.1", "0.2"]);

    // Uncorrected spheres lose energy with roughness (more at grazing view), corrected
    // ones stay near 1, the reference near 1.
    let loss = |d: usize, r: f64| 1.0 - (0.12 + 0.05 * d as f64) * r * r;
    let colour = |col: usize, row: usize, mu: f64| {
        let r = roughness[col];
        let v = match row {
            6 => 0.99,
            _ if row.is_multiple_of(2) => loss(row / 2, r) * (0.9 + 0.1 * mu),
            _ => 1.0 + 0.01 * (r - 0.5),
        } as f32;
        [v * 0.98, v, v * 1.02]
    };
    let img = grid(roughness.len(), plan.image_rows(), cell, colour);
    let dir = tempfile::tempdir().unwrap();
    let sheet_path = dir.path().join("sheet.png");
    contact_sheet(&img, cell, &row_labels, &column_labels, &sheet_path).unwrap();
    keep_sample(&sheet_path, "sheet-full.png");
    let sheet = image::open(&sheet_path).unwrap().to_rgb8();
    assert!(sheet.width() as usize > img.width + 150);
    assert!(sheet.height() as usize > img.height);

    let columns = roughness.len();
    let stats = |i| sphere_stats(&img, i, columns, cell, settings.radius_fraction);
    let rows = Distribution::ALL
        .iter()
        .enumerate()
        .flat_map(|(k, &d)| {
            roughness
                .iter()
                .enumerate()
                .map(move |(c, &r)| (k, d, c, r))
        })
        .map(|(k, d, c, r)| {
            white_row(
                k * columns + c,
                d,
                r,
                stats(2 * k * columns + c),
                stats((2 * k + 1) * columns + c),
                loss(k, r) * 0.9667,
                true,
            )
        })
        .collect();
    let reference = roughness
        .iter()
        .enumerate()
        .map(|(c, &r)| reference_sphere(r, stats(6 * columns + c)))
        .collect();
    let report = VerifyReport {
        engine: gloffuse::measure::Engine::Cycles,
        groups_engine: gloffuse::measure::Engine::Cycles,
        lighting: None,
        mode: gloffuse::generate::Mode::Roughness,
        color: [1.0; 3],
        color_model: gloffuse::generate::ColorModel::Exact,
        ring_tolerance_percent: 1.5,
        coefficients: "presets/cycles-4.x.json".into(),
        render: render_info(cell, columns, 7),
        tolerance_percent: 1.5,
        rows,
        reference,
        notes: vec![],
        pass: true,
    };
    let plot_path = dir.path().join("plot.png");
    brightness_plot(&report, &plot_path).unwrap();
    keep_sample(&plot_path, "plot-full.png");
    let plot = image::open(&plot_path).unwrap().to_rgb8();
    assert_eq!((plot.width(), plot.height()), PLOT_SIZE);
}
