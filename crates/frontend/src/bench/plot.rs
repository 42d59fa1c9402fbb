//! PNG plots of `ssbvb bench` (plotters, bitmap backend, text in an embedded font): title,
//! labelled axes and a legend in the image; the same description (axes, ranges, grid
//! spacing, series colours) also goes into the report (JSON and Markdown). Which plots a
//! run writes ([`write_plots`]) is decided here too.

use std::collections::BTreeMap;
use std::path::Path;

use anyhow::{Result, anyhow};
use plotters::prelude::*;
use serde::Serialize;

use super::run::Row;
use super::sweep::SweepRow;

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

/// time_vs_level.png, time_vs_resolution.png (main matrix) and `trade_<knob>.png` (sweeps).
pub(super) fn write_plots(dir: &Path, rows: &[Row], sweeps: &[SweepRow]) -> Result<Vec<PlotInfo>> {
    let mut plots = Vec::new();
    let mut models: Vec<&str> = rows.iter().map(|r| r.model.as_str()).collect();
    models.sort_unstable();
    models.dedup();
    for model in &models {
        let suffix = if models.len() > 1 {
            format!(
                "_{}",
                model.replace(|c: char| !c.is_ascii_alphanumeric(), "_")
            )
        } else {
            String::new()
        };
        plots.extend(model_plots(dir, model, rows, &suffix)?);
    }
    let mut knobs: Vec<&str> = sweeps.iter().map(|r| r.knob).collect();
    knobs.dedup();
    for knob in knobs {
        plots.push(trade_plot(dir, knob, sweeps)?);
    }
    Ok(plots)
}

/// Points sorted by x.
fn sorted(mut p: Vec<(f64, f64)>) -> Vec<(f64, f64)> {
    p.sort_by(|a, b| a.0.total_cmp(&b.0));
    p
}

/// One model's frame time against level and against resolution, each technique one series
/// per extreme size (or level).
fn model_plots(dir: &Path, model: &str, rows: &[Row], suffix: &str) -> Result<[PlotInfo; 2]> {
    type Points = Vec<(f64, f64)>;
    let rows: Vec<&Row> = rows.iter().filter(|r| r.model == *model).collect();
    // Only the extreme sizes and levels, so that a study's plots stay readable.
    let mut sizes: Vec<(u32, u32)> = rows.iter().map(|r| (r.width, r.height)).collect();
    sizes.sort_by_key(|&(w, h)| (w * h, w));
    sizes.dedup();
    let sizes = [sizes[0], sizes[sizes.len() - 1]];
    let levels = (
        rows.iter().map(|r| r.level).min().unwrap_or(0),
        rows.iter().map(|r| r.level).max().unwrap_or(0),
    );
    let mut by_size: BTreeMap<(&str, u32, u32), Points> = BTreeMap::new();
    let mut by_level: BTreeMap<(&str, u32), Points> = BTreeMap::new();
    for r in &rows {
        if sizes.contains(&(r.width, r.height)) {
            by_size
                .entry((r.technique, r.width, r.height))
                .or_default()
                .push((r.level as f64, r.frame_ms_median));
        }
        if r.level == levels.0 || r.level == levels.1 {
            by_level
                .entry((r.technique, r.level))
                .or_default()
                .push(((r.width * r.height) as f64 / 1e6, r.frame_ms_median));
        }
    }
    let series: Vec<Series> = by_size
        .into_iter()
        .map(|((t, w, h), p)| Series {
            name: format!("{t} {w}x{h}"),
            points: sorted(p),
        })
        .collect();
    let vs_level = plot(
        dir,
        &format!("time_vs_level{suffix}.png"),
        &format!("{model}: frame time vs level"),
        ("level (2^level cells per axis)", "frame ms (median)"),
        &series,
    )?;
    let series: Vec<Series> = by_level
        .into_iter()
        .map(|((t, l), p)| Series {
            name: format!("{t} level {l}"),
            points: sorted(p),
        })
        .collect();
    let vs_resolution = plot(
        dir,
        &format!("time_vs_resolution{suffix}.png"),
        &format!("{model}: frame time vs resolution"),
        ("megapixels", "frame ms (median)"),
        &series,
    )?;
    Ok([vs_level, vs_resolution])
}

/// One knob's sweep: shaded error against frame time, a point per value.
fn trade_plot(dir: &Path, knob: &str, sweeps: &[SweepRow]) -> Result<PlotInfo> {
    let pts: Vec<&SweepRow> = sweeps
        .iter()
        .filter(|r| r.knob == knob && r.psnr_pixels > 0)
        .collect();
    let values: Vec<String> = pts.iter().map(|r| r.value.to_string()).collect();
    // RMSE in 8-bit levels from the PSNR (0 where the images are identical).
    let points = pts
        .iter()
        .map(|r| {
            let rmse = r.psnr_db.map_or(0.0, |p| 255.0 * 10f64.powf(-p / 20.0));
            (r.frame_ms_median, rmse)
        })
        .collect();
    plot(
        dir,
        &format!("trade_{knob}.png"),
        &format!("Shaded error vs frame time, {knob} swept"),
        (
            "frame ms (median)",
            "composite RMSE vs reference (8-bit levels, pixels either covers)",
        ),
        &[Series {
            name: format!("{knob} = {} (in this order)", values.join(", ")),
            points,
        }],
    )
}
