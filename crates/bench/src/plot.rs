//! PNG plots of `ssbvb bench` (plotters, bitmap backend, text in an embedded font): title,
//! labelled axes and a legend in the image; the same description (axes, ranges, grid
//! spacing, series colours) also goes into the report (JSON and Markdown). Which plots a
//! run writes is its report's or preset's business.

use std::path::Path;

use anyhow::{Result, anyhow};
use plotters::prelude::*;
use serde::Serialize;

const WIDTH: u32 = 800;
const HEIGHT: u32 = 600;

const PALETTE: &[(&str, RGBColor)] = &[
    ("blue", RGBColor(31, 119, 180)),
    ("orange", RGBColor(255, 127, 14)),
    ("green", RGBColor(44, 160, 44)),
    ("red", RGBColor(214, 39, 40)),
    ("purple", RGBColor(148, 103, 189)),
    ("brown", RGBColor(140, 86, 75)),
    ("pink", RGBColor(227, 119, 194)),
    ("olive", RGBColor(188, 189, 34)),
    ("cyan", RGBColor(23, 190, 207)),
    ("grey", RGBColor(127, 127, 127)),
    ("navy", RGBColor(0, 0, 128)),
    ("dark orange", RGBColor(166, 86, 0)),
    ("lime", RGBColor(120, 220, 40)),
    ("maroon", RGBColor(110, 0, 20)),
    ("black", RGBColor(0, 0, 0)),
    ("gold", RGBColor(230, 190, 0)),
];

/// One line of points, drawn in order.
pub(crate) struct Series {
    pub name: String,
    pub points: Vec<(f64, f64)>,
}

/// What a written plot shows.
#[derive(Debug, Serialize)]
pub(crate) struct PlotInfo {
    pub file: String,
    pub title: String,
    pub x_axis: String,
    pub y_axis: String,
    /// Axis ranges as drawn (the plot frame's edges).
    pub x_range: [f64; 2],
    pub y_range: [f64; 2],
    /// Spacing of the labelled grid lines (at multiples of it).
    pub x_grid: f64,
    pub y_grid: f64,
    /// `(series, colour)`; the first point of each series is a square, the rest circles.
    pub series: Vec<(String, String)>,
}

/// A 1-2-5 step giving about five intervals over `span`.
fn nice_step(span: f64) -> f64 {
    let raw = (span / 5.0).max(1e-12);
    let p = 10f64.powf(raw.log10().floor());
    let m = raw / p;
    p * if m <= 1.0 {
        1.0
    } else if m <= 2.0 {
        2.0
    } else if m <= 5.0 {
        5.0
    } else {
        10.0
    }
}

/// Range covering `v` with a margin, and a grid step; starts at 0 when `from_zero`.
fn axis(v: impl Iterator<Item = f64> + Clone, from_zero: bool) -> ([f64; 2], f64) {
    let (mut lo, mut hi) = v.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
        (a.min(x), b.max(x))
    });
    if !lo.is_finite() || !hi.is_finite() {
        (lo, hi) = (0.0, 1.0);
    }
    if from_zero {
        lo = lo.min(0.0);
    }
    if hi - lo < 1e-9 {
        let pad = (hi.abs() * 0.1).max(0.5);
        // Keep a non-negative quantity's axis non-negative.
        lo = if lo >= 0.0 {
            (lo - pad).max(0.0)
        } else {
            lo - pad
        };
        hi += pad;
    }
    let step = nice_step(hi - lo);
    let lo = if from_zero && lo >= 0.0 {
        0.0
    } else {
        (lo / step).floor() * step
    };
    let hi = (hi / step).ceil() * step;
    // Drop float noise such as 0.6000000000000001 from the reported numbers.
    let clean = |v: f64| (v * 1e9).round() / 1e9;
    ([clean(lo), clean(hi)], clean(step))
}

/// Registers the plot font once: Hack, embedded by `epaint_default_fonts` (no system
/// fonts are needed, so CI machines draw the same text).
fn register_font() -> Result<()> {
    static RESULT: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    let ok = *RESULT.get_or_init(|| {
        plotters::style::register_font(
            "sans-serif",
            FontStyle::Normal,
            epaint_default_fonts::HACK_REGULAR,
        )
        .is_ok()
    });
    if ok {
        Ok(())
    } else {
        Err(anyhow!("the embedded plot font could not be loaded"))
    }
}

/// Draws `series` into `dir/file` (title, axis labels and a legend included) and
/// describes it.
pub(crate) fn plot(
    dir: &Path,
    file: &str,
    title: &str,
    (x_axis, y_axis): (&str, &str),
    series: &[Series],
) -> Result<PlotInfo> {
    register_font()?;
    let pts = || series.iter().flat_map(|s| s.points.iter().copied());
    let (xr, xs) = axis(pts().map(|p| p.0), false);
    let (yr, ys) = axis(pts().map(|p| p.1), true);
    let mut rgb = vec![0u8; (WIDTH * HEIGHT * 3) as usize];
    {
        let err = |e: &dyn std::fmt::Display| anyhow!("drawing {file}: {e}");
        let root = BitMapBackend::with_buffer(&mut rgb, (WIDTH, HEIGHT)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| err(&e))?;
        let mut chart = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 20))
            .margin(16)
            .x_label_area_size(44)
            .y_label_area_size(72)
            .build_cartesian_2d(xr[0]..xr[1], yr[0]..yr[1])
            .map_err(|e| err(&e))?;
        // One label per grid step of `axis` (1-2-5 steps).
        let steps = |r: [f64; 2], s: f64| ((r[1] - r[0]) / s).round() as usize + 1;
        chart
            .configure_mesh()
            .x_labels(steps(xr, xs))
            .y_labels(steps(yr, ys))
            .x_desc(x_axis)
            .y_desc(y_axis)
            .label_style(("sans-serif", 13))
            .axis_desc_style(("sans-serif", 15))
            .light_line_style(TRANSPARENT)
            .bold_line_style(RGBColor(205, 205, 205))
            .draw()
            .map_err(|e| err(&e))?;
        for (i, s) in series.iter().enumerate() {
            let c = PALETTE[i % PALETTE.len()].1;
            chart
                .draw_series(LineSeries::new(s.points.iter().copied(), c.stroke_width(2)))
                .map_err(|e| err(&e))?
                .label(s.name.clone())
                .legend(move |(x, y)| Rectangle::new([(x, y - 5), (x + 16, y + 5)], c.filled()));
            chart
                .draw_series(
                    s.points.first().map(|&p| {
                        EmptyElement::at(p) + Rectangle::new([(-6, -6), (6, 6)], c.filled())
                    }),
                )
                .map_err(|e| err(&e))?;
            chart
                .draw_series(
                    s.points
                        .iter()
                        .skip(1)
                        .map(|&p| Circle::new(p, 5, c.filled())),
                )
                .map_err(|e| err(&e))?;
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperLeft)
            .label_font(("sans-serif", 12))
            .background_style(WHITE.mix(0.85))
            .border_style(RGBColor(120, 120, 120))
            .draw()
            .map_err(|e| err(&e))?;
        root.present().map_err(|e| err(&e))?;
    }
    let rgba: Vec<u8> = rgb
        .chunks_exact(3)
        .flat_map(|p| [p[0], p[1], p[2], 255])
        .collect();
    ssbvb_gpu::readback::write_png_rgba8(&dir.join(file), WIDTH, HEIGHT, &rgba)?;
    Ok(PlotInfo {
        file: file.into(),
        title: title.into(),
        x_axis: x_axis.into(),
        y_axis: y_axis.into(),
        x_range: xr,
        y_range: yr,
        x_grid: xs,
        y_grid: ys,
        series: series
            .iter()
            .enumerate()
            .map(|(i, s)| (s.name.clone(), PALETTE[i % PALETTE.len()].0.to_string()))
            .collect(),
    })
}

/// The Markdown section describing the plots.
pub(crate) fn markdown(plots: &[PlotInfo]) -> String {
    let mut s = String::from("\n## Plots\n\nEach series' first point is a square.\n");
    for p in plots {
        s.push_str(&format!(
            "\n### {} (`{}`)\n\nx: {} from {} to {} (grid every {}); y: {} from {} to {} (grid every {}).\n\n",
            p.title,
            p.file,
            p.x_axis,
            p.x_range[0],
            p.x_range[1],
            p.x_grid,
            p.y_axis,
            p.y_range[0],
            p.y_range[1],
            p.y_grid
        ));
        for (name, colour) in &p.series {
            s.push_str(&format!("- {colour}: {name}\n"));
        }
    }
    s
}
