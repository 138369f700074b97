//! `brightness.png` of `verify --report`: brightness against roughness, rendered and
//! predicted, with the pass band, and the corrected spheres zoomed below.

use std::path::Path;

use plotters::coord::Shift;
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use crate::error::Error;
use crate::generate::Mode;
use crate::measure::Distribution;
use crate::report::png::{FAMILY, backend, register_font, write_error, write_png};
use crate::verify::VerifyReport;
use crate::verify::plan::Block;
use crate::verify::spec;

/// Size of the brightness plot in pixels.
pub const PLOT_SIZE: (u32, u32) = (900, 820);

/// Colours of one distribution's series in the plot.
fn colour(d: Distribution) -> RGBColor {
    match d {
        Distribution::Beckmann => RGBColor(31, 119, 180),
        Distribution::Ggx => RGBColor(214, 39, 40),
        Distribution::AshikhminShirley => RGBColor(44, 160, 44),
    }
}

const REFERENCE_COLOUR: RGBColor = RGBColor(90, 90, 90);

/// (roughness, brightness %) points of one series.
type Points = Vec<(f64, f64)>;

/// `(x, 100·y)` for the finite points, sorted by x.
fn percent_points(points: impl Iterator<Item = (f64, f64)>) -> Points {
    let mut v: Points = points
        .filter(|(x, y)| x.is_finite() && y.is_finite())
        .map(|(x, y)| (x, 100.0 * y))
        .collect();
    v.sort_by(|a, b| a.0.total_cmp(&b.0));
    v
}

/// Plot of brightness (%) against roughness: per distribution the uncorrected and corrected
/// sphere means (hollow and filled circles) with the integrator's predictions for each
/// (dashed and solid lines), Blender's Multiscatter GGX reference (triangles), 100 % with the
/// tolerance band; legend, axis labels, and a title naming the Blender version and the
/// coefficients. [`PLOT_SIZE`] pixels, written as PNG atomically. NaN values are left out.
pub fn brightness_plot(report: &VerifyReport, out: &Path) -> Result<(), Error> {
    register_font().map_err(|m| write_error(out, m))?;
    let plot = PlotData::of(report);
    let (w, h) = PLOT_SIZE;
    let mut rgb = vec![255u8; (w * h * 3) as usize];
    {
        let root = backend(&mut rgb, (w, h), out)?.into_drawing_area();
        draw_plot(&root, &plot)
            .map_err(|e| write_error(out, format!("cannot draw the plot: {e}")))?;
    }
    write_png(&rgb, (w, h), out)
}

/// What the brightness plot shows, gathered from a report before anything is drawn.
struct PlotData {
    mode: Mode,
    title: String,
    /// Per distribution: uncorrected, its prediction, corrected, its prediction.
    series: Vec<(Distribution, [Points; 4])>,
    reference: Points,
    /// Per distribution: the corrected spheres' deviation (%), for the zoomed panel.
    zoom: Vec<(Distribution, Points)>,
    /// The pass band's half width in %, 0 when there is none.
    tolerance: f64,
    x: (f64, f64),
    y: (f64, f64),
    /// The zoomed panel's y axis runs from −zoom_half to zoom_half.
    zoom_half: f64,
}

impl PlotData {
    fn of(report: &VerifyReport) -> Self {
        let plotted = plotted_block(report);
        let mut distributions: Vec<Distribution> = Vec::new();
        for row in &report.rows {
            if !distributions.contains(&row.distribution) {
                distributions.push(row.distribution);
            }
        }
        let series: Vec<_> = distributions
            .iter()
            .map(|&d| (d, series_points(report, d, plotted)))
            .collect();
        let reference = percent_points(
            report
                .reference
                .iter()
                .filter(|s| s.block == plotted)
                .map(|s| (s.roughness.get(), s.brightness)),
        );
        let tolerance = if report.tolerance_percent.is_finite() {
            report.tolerance_percent.abs()
        } else {
            0.0
        };
        let zoom: Vec<_> = distributions
            .iter()
            .map(|&d| (d, zoom_points(report, d)))
            .collect();
        let zoom_half = zoom
            .iter()
            .flat_map(|(_, p)| p.iter().map(|(_, y)| y.abs() * 1.25))
            .fold((3.0 * tolerance).max(0.5), f64::max);
        let (x, y) = plot_ranges(&series, &reference, tolerance);
        PlotData {
            mode: report.mode,
            title: plot_title(report, plotted),
            series,
            reference,
            zoom,
            tolerance,
            x,
            y,
            zoom_half,
        }
    }
}

/// Layered and anisotropic sweeps plot one block (layered: glass, IOR 1.5, when it was
/// rendered; else the first): the table, report.json and the zoomed panel hold every block.
fn plotted_block(report: &VerifyReport) -> Option<Block> {
    report.rows.iter().find_map(|r| r.block).map(|first| {
        let glass = Block::Ior(1.5);
        if report.rows.iter().any(|r| r.block == Some(glass)) {
            glass
        } else {
            first
        }
    })
}

/// Distribution `d`'s points in `block`: uncorrected, its prediction, corrected, its
/// prediction.
fn series_points(report: &VerifyReport, d: Distribution, block: Option<Block>) -> [Points; 4] {
    // A value that is not there (glass mode predicts no uncorrected sphere) has no point.
    let pts = |f: fn(&crate::verify::Row) -> Option<f64>| {
        percent_points(
            report
                .rows
                .iter()
                .filter(|r| r.distribution == d && r.block == block)
                .filter_map(|r| Some((r.roughness.get(), f(r)?))),
        )
    };
    [
        pts(|r| Some(r.uncorrected_brightness)),
        pts(|r| r.predicted_uncorrected),
        pts(|r| Some(r.brightness)),
        pts(|r| Some(r.predicted_corrected)),
    ]
}

/// The zoomed panel's points of distribution `d`: corrected spheres' distance from what
/// they promise, in %, in every block.
fn zoom_points(report: &VerifyReport, d: Distribution) -> Points {
    let rows = report.rows.iter().filter(|r| r.distribution == d);
    let mut points: Points = rows
        .map(|r| (r.roughness.get(), 100.0 * (r.brightness - 1.0)))
        .filter(|(x, y)| x.is_finite() && y.is_finite())
        .collect();
    points.sort_by(|a, b| a.0.total_cmp(&b.0));
    points
}

/// The main panel's x and y ranges: every point and the pass band, y in whole multiples of
/// 5 % with some air and at least 20 % tall.
fn plot_ranges(
    series: &[(Distribution, [Points; 4])],
    reference: &Points,
    tolerance: f64,
) -> ((f64, f64), (f64, f64)) {
    let all = series
        .iter()
        .flat_map(|(_, s)| s.iter().flatten())
        .chain(reference.iter());
    let (mut y_lo, mut y_hi) = (100.0 - tolerance, 100.0 + tolerance);
    let (mut x_lo, mut x_hi) = (0.0f64, 1.0f64);
    for &(x, y) in all {
        (x_lo, x_hi) = (x_lo.min(x), x_hi.max(x));
        (y_lo, y_hi) = (y_lo.min(y), y_hi.max(y));
    }
    let y_lo = ((y_lo - 2.0) / 5.0).floor() * 5.0;
    let y_hi = (((y_hi + 2.0) / 5.0).ceil() * 5.0).max(y_lo + 20.0);
    let x_pad = 0.02 * (x_hi - x_lo);
    ((x_lo - x_pad, x_hi + x_pad), (y_lo, y_hi))
}

fn plot_title(report: &VerifyReport, plotted: Option<Block>) -> String {
    match plotted {
        Some(Block::Ior(n)) => format!(
            "{} furnace brightness · Blender {} · IOR {n} · {} spp",
            spec(report.mode).block_plot_title,
            report.render.blender_version,
            report.render.samples
        ),
        Some(Block::Anisotropy(a)) => format!(
            "{} furnace brightness · Blender {} · anisotropy {a} · {} spp",
            spec(report.mode).block_plot_title,
            report.render.blender_version,
            report.render.samples
        ),
        None => format!(
            "Furnace brightness · Blender {} · coefficients {} · {} spp",
            report.render.blender_version,
            shorten(&report.coefficients, 36),
            report.render.samples
        ),
    }
}

/// The plot's two panels: brightness against roughness with its axes and the legend panel
/// beside it; the corrected spheres zoomed below.
fn draw_plot<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    plot: &PlotData,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let (w, h) = PLOT_SIZE;
    root.fill(&WHITE)?;
    let below_title = root.titled(&plot.title, (FAMILY, 20))?;
    let (left_area, legend_area) = below_title.split_horizontally(w as i32 - LEGEND_WIDTH);
    let (plot_area, zoom_area) = left_area.split_vertically((h as f64 * 0.64) as i32);
    let legend = draw_brightness_panel(&plot_area, plot)?;
    draw_legend(&legend_area, &legend)?;
    draw_zoom_panel(&zoom_area, plot)?;
    root.present()
}

/// A panel of the plot: roughness across, f64 both ways.
type Chart<'a, DB> = ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>;
type Drawn<T, DB> = Result<T, DrawingAreaErrorKind<<DB as DrawingBackend>::ErrorType>>;

/// The main panel: the pass band, every distribution's series, the reference and the 100 %
/// line; returns the legend of what it drew.
fn draw_brightness_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    plot: &PlotData,
) -> Drawn<Vec<Legend>, DB> {
    let mut chart = ChartBuilder::on(area)
        .margin(12)
        .x_label_area_size(44)
        .y_label_area_size(60)
        .build_cartesian_2d(plot.x.0..plot.x.1, plot.y.0..plot.y.1)?;
    draw_mesh(&mut chart, "brightness (%)", 12, &|y| format!("{y:.0}"))?;
    let tolerance = plot.tolerance;
    if tolerance > 0.0 {
        draw_band(&mut chart, plot.x, (100.0 - tolerance, 100.0 + tolerance))?;
    }
    let mut legend = Vec::new();
    for (d, points) in &plot.series {
        legend.extend(draw_distribution(&mut chart, *d, points, plot.mode)?);
    }
    if !plot.reference.is_empty() {
        legend.extend(draw_reference(&mut chart, &plot.reference, plot.mode)?);
    }
    // On top, so it shows through curves that lie on it.
    draw_level(&mut chart, plot.x, 100.0)?;
    legend.push(Legend::Heading("Target".into(), BLACK));
    legend.push(Legend::Entry(Key::Dashed(BLACK.into(), 1), "100 %".into()));
    if tolerance > 0.0 {
        legend.push(Legend::Entry(
            Key::Band(PASS_BAND.mix(0.12)),
            format!("100 % ± {tolerance} % (pass)"),
        ));
    }
    Ok(legend)
}

/// The zoomed panel: each distribution's corrected spheres against 0 and the pass band.
fn draw_zoom_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    plot: &PlotData,
) -> Drawn<(), DB> {
    let half = plot.zoom_half;
    let mut chart = ChartBuilder::on(area)
        .margin(12)
        .caption(
            "corrected, zoomed: distance from what the correction promises",
            (FAMILY, 14),
        )
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(plot.x.0..plot.x.1, -half..half)?;
    draw_mesh(&mut chart, "deviation (%)", 9, &|y| format!("{y:+.1}"))?;
    if plot.tolerance > 0.0 {
        draw_band(&mut chart, plot.x, (-plot.tolerance, plot.tolerance))?;
    }
    draw_level(&mut chart, plot.x, 0.0)?;
    for (d, points) in &plot.zoom {
        let c = colour(*d);
        chart.draw_series(LineSeries::new(points.iter().copied(), c.stroke_width(1)))?;
        chart.draw_series(points.iter().map(|&p| Circle::new(p, 4, c.filled())))?;
    }
    Ok(())
}

/// A panel's grid and axes: roughness across, `y_desc` up with `y_labels` labels.
fn draw_mesh<DB: DrawingBackend>(
    chart: &mut Chart<'_, DB>,
    y_desc: &str,
    y_labels: usize,
    y_format: &dyn Fn(&f64) -> String,
) -> Drawn<(), DB> {
    chart
        .configure_mesh()
        .x_desc("roughness")
        .y_desc(y_desc)
        .axis_desc_style((FAMILY, 15))
        .label_style((FAMILY, 13))
        .x_labels(11)
        .y_labels(y_labels)
        .x_label_formatter(&|x| format!("{x:.1}"))
        .y_label_formatter(y_format)
        .light_line_style(RGBColor(242, 242, 242))
        .bold_line_style(RGBColor(215, 215, 215))
        .draw()
}

/// The pass band from `y.0` to `y.1` across the panel.
fn draw_band<DB: DrawingBackend>(
    chart: &mut Chart<'_, DB>,
    (x_lo, x_hi): (f64, f64),
    (y_lo, y_hi): (f64, f64),
) -> Drawn<(), DB> {
    chart.draw_series([Rectangle::new(
        [(x_lo, y_lo), (x_hi, y_hi)],
        PASS_BAND.mix(0.12).filled(),
    )])?;
    Ok(())
}

/// A dashed black line at `y` across the panel.
fn draw_level<DB: DrawingBackend>(
    chart: &mut Chart<'_, DB>,
    (x_lo, x_hi): (f64, f64),
    y: f64,
) -> Drawn<(), DB> {
    chart.draw_series(DashedLineSeries::new(
        [(x_lo, y), (x_hi, y)],
        8,
        5,
        BLACK.stroke_width(1),
    ))?;
    Ok(())
}

/// One distribution's predictions (lines) and rendered means (circles), with their legend.
fn draw_distribution<DB: DrawingBackend>(
    chart: &mut Chart<'_, DB>,
    d: Distribution,
    [uncorrected, predicted_u, corrected, predicted_c]: &[Points; 4],
    mode: Mode,
) -> Drawn<Vec<Legend>, DB> {
    let c = colour(d);
    chart.draw_series(DashedLineSeries::new(
        predicted_u.iter().copied(),
        6,
        4,
        c.mix(0.6).stroke_width(2),
    ))?;
    chart.draw_series(LineSeries::new(
        predicted_c.iter().copied(),
        c.stroke_width(2),
    ))?;
    chart.draw_series(
        uncorrected
            .iter()
            .map(|&p| Circle::new(p, 4, c.stroke_width(2))),
    )?;
    chart.draw_series(corrected.iter().map(|&p| Circle::new(p, 4, c.filled())))?;
    let (uncorrected_name, corrected_name) = (spec(mode).uncorrected, spec(mode).corrected);
    let mut legend = vec![
        Legend::Heading(d.label().to_string(), c),
        Legend::Entry(Key::Hollow(c), format!("{uncorrected_name}, rendered")),
    ];
    // Glass mode predicts no uncorrected sphere: no line, so no key for one.
    if !predicted_u.is_empty() {
        legend.push(Legend::Entry(
            Key::Dashed(c.mix(0.6), 2),
            format!("{uncorrected_name}, predicted"),
        ));
    }
    legend.extend([
        Legend::Entry(Key::Filled(c), format!("{corrected_name}, rendered")),
        Legend::Entry(Key::Solid(c.into()), format!("{corrected_name}, predicted")),
    ]);
    Ok(legend)
}

/// The reference's line and triangles, with their legend.
fn draw_reference<DB: DrawingBackend>(
    chart: &mut Chart<'_, DB>,
    reference: &Points,
    mode: Mode,
) -> Drawn<[Legend; 2], DB> {
    chart.draw_series(LineSeries::new(
        reference.iter().copied(),
        REFERENCE_COLOUR.stroke_width(1),
    ))?;
    chart.draw_series(
        reference
            .iter()
            .map(|&p| TriangleMarker::new(p, 5, REFERENCE_COLOUR.filled())),
    )?;
    Ok([
        Legend::Heading("Reference".into(), REFERENCE_COLOUR),
        Legend::Entry(Key::Triangle(REFERENCE_COLOUR), spec(mode).reference.into()),
    ])
}

/// Width of the legend panel to the right of the plot.
const LEGEND_WIDTH: i32 = 215;
const PASS_BAND: RGBColor = RGBColor(0, 150, 0);

/// One line of the plot's legend.
enum Legend {
    Heading(String, RGBColor),
    Entry(Key, String),
}

/// The sample drawn in front of a legend entry.
enum Key {
    Hollow(RGBColor),
    Filled(RGBColor),
    Triangle(RGBColor),
    Solid(RGBAColor),
    Dashed(RGBAColor, u32),
    Band(RGBAColor),
}

/// The legend as a column of headed groups in its own panel, so it never hides a point.
fn draw_legend<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    items: &[Legend],
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let line = 19;
    let left = Pos::new(HPos::Left, VPos::Center);
    let mut y = 24;
    for item in items {
        match item {
            Legend::Heading(text, c) => {
                y += 6;
                let style = TextStyle::from((FAMILY, 14).into_font()).color(c).pos(left);
                area.draw_text(text, &style, (8, y))?;
            }
            Legend::Entry(key, text) => {
                let (x0, x1, xm) = (14, 36, 25);
                match *key {
                    Key::Hollow(c) => area.draw(&Circle::new((xm, y), 4, c.stroke_width(2)))?,
                    Key::Filled(c) => area.draw(&Circle::new((xm, y), 4, c.filled()))?,
                    Key::Triangle(c) => {
                        area.draw(&PathElement::new([(x0, y), (x1, y)], c.stroke_width(1)))?;
                        area.draw(&TriangleMarker::new((xm, y), 5, c.filled()))?;
                    }
                    Key::Solid(c) => {
                        area.draw(&PathElement::new([(x0, y), (x1, y)], c.stroke_width(2)))?
                    }
                    Key::Dashed(c, width) => {
                        let s = c.stroke_width(width);
                        area.draw(&PathElement::new([(x0, y), (x0 + 8, y)], s))?;
                        area.draw(&PathElement::new([(x1 - 8, y), (x1, y)], s))?;
                    }
                    Key::Band(c) => {
                        area.draw(&Rectangle::new([(x0, y - 5), (x1, y + 5)], c.filled()))?
                    }
                }
                let style = TextStyle::from((FAMILY, 13).into_font())
                    .color(&BLACK)
                    .pos(left);
                area.draw_text(text, &style, (44, y))?;
            }
        }
        y += line;
    }
    Ok(())
}

/// `text` if it has at most `max` characters, else `…` and its last `max − 1`.
fn shorten(text: &str, max: usize) -> String {
    let n = text.chars().count();
    if n <= max {
        text.to_string()
    } else {
        let tail: String = text.chars().skip(n + 1 - max).collect();
        format!("…{tail}")
    }
}
