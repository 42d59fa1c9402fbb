//! PNG plots of `ssbvb bench` (plotters, bitmap backend). No text is drawn (plotters'
//! font features need system fonts): titles are the file names, and the axes, ranges,
//! grid spacing and series colours are written to the report (JSON and Markdown).

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
];

/// One line of points, drawn in order.
pub(crate) struct Series {
    pub name: String,
    pub points: Vec<(f64, f64)>,
}

/// What a written plot shows (the image itself has no text).
#[derive(Debug, Serialize)]
pub(crate) struct PlotInfo {
    pub file: String,
    pub title: String,
    pub x_axis: String,
    pub y_axis: String,
    /// Axis ranges as drawn (the plot frame's edges).
    pub x_range: [f64; 2],
    pub y_range: [f64; 2],
    /// Spacing of the grey grid lines (at multiples of it).
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

/// Draws `series` into `dir/file` and describes it.
pub(crate) fn plot(
    dir: &Path,
    file: &str,
    title: &str,
    (x_axis, y_axis): (&str, &str),
    series: &[Series],
) -> Result<PlotInfo> {
    let pts = || series.iter().flat_map(|s| s.points.iter().copied());
    let (xr, xs) = axis(pts().map(|p| p.0), false);
    let (yr, ys) = axis(pts().map(|p| p.1), true);
    let mut rgb = vec![0u8; (WIDTH * HEIGHT * 3) as usize];
    {
        let err = |e: &dyn std::fmt::Display| anyhow!("drawing {file}: {e}");
        let root = BitMapBackend::with_buffer(&mut rgb, (WIDTH, HEIGHT)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| err(&e))?;
        let mut chart = ChartBuilder::on(&root)
            .margin(24)
            .build_cartesian_2d(xr[0]..xr[1], yr[0]..yr[1])
            .map_err(|e| err(&e))?;
        let grid = RGBColor(215, 215, 215);
        let mut lines = Vec::new();
        let mut x = xr[0];
        while x <= xr[1] + xs * 1e-6 {
            lines.push(vec![(x, yr[0]), (x, yr[1])]);
            x += xs;
        }
        let mut y = yr[0];
        while y <= yr[1] + ys * 1e-6 {
            lines.push(vec![(xr[0], y), (xr[1], y)]);
            y += ys;
        }
        chart
            .draw_series(lines.into_iter().map(|l| PathElement::new(l, grid)))
            .map_err(|e| err(&e))?;
        // The frame.
        chart
            .draw_series(std::iter::once(PathElement::new(
                vec![
                    (xr[0], yr[0]),
                    (xr[1], yr[0]),
                    (xr[1], yr[1]),
                    (xr[0], yr[1]),
                    (xr[0], yr[0]),
                ],
                BLACK.stroke_width(2),
            )))
            .map_err(|e| err(&e))?;
        for (i, s) in series.iter().enumerate() {
            let c = PALETTE[i % PALETTE.len()].1;
            chart
                .draw_series(LineSeries::new(s.points.iter().copied(), c.stroke_width(2)))
                .map_err(|e| err(&e))?;
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
    let mut s = String::from(
        "\n## Plots\n\nThe PNGs carry no text; each series' first point is a square.\n",
    );
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
