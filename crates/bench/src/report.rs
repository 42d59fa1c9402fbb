//! The report of the main matrix (`--preset quick`, `full` and `study`, with their knob
//! sweeps): its rows ([`Row`], [`SweepRow`]) and their columns, the [`Report`] itself
//! (serialized as `bench.json`, so its field names are the JSON keys), the fastest
//! technique per cell, the PNG plots, the Markdown printed and written as `bench.md`, the
//! CSV files, and the summary on stdout.

use std::collections::BTreeMap;
use std::path::Path;

use anyhow::{Context, Result};
use serde::Serialize;
use ssbvb_gpu::GpuContext;
use ssbvb_voxel::camera::Camera;

use super::args::BenchArgs;
use super::plot::{PlotInfo, Series, plot};
use super::table::{Column, Fmt, Table, Value, size};

/// One technique on one cell of the matrix.
#[derive(Debug)]
pub(crate) struct Row {
    pub(crate) technique: &'static str,
    pub(crate) model: String,
    /// Occupied cells at this level.
    pub(crate) level: u32,
    pub(crate) width: u32,
    pub(crate) height: u32,
    pub(crate) frames: usize,
    pub(crate) frame_ms_median: f64,
    pub(crate) frame_ms_min: f64,
    pub(crate) frame_ms_max: f64,
    /// Median GPU time of the frames timed by timestamps (`None` on software adapters).
    pub(crate) frame_gpu_ms_median: Option<f64>,
    pub(crate) passes: Vec<ssbvb_passes::PassTiming>,
    pub(crate) fill_count: Option<u32>,
    /// Pixels the reference covers (what the fill count is compared with).
    pub(crate) covered_pixels: usize,
    pub(crate) voxels: usize,
    pub(crate) gpu_memory_bytes: u64,
    pub(crate) coverage_iou: f64,
    /// `None` for techniques that keep no per-pixel voxel ids (all but the per-pixel
    /// SSBVB).
    pub(crate) same_voxel_rate: Option<f64>,
    pub(crate) depth_error_voxels_median: f64,
    pub(crate) normal_error_deg_median: f64,
    /// PSNR (dB) of the composite over the pixels either covers (`None`: identical).
    pub(crate) psnr_db: Option<f64>,
    /// Mean SSIM of the composite (see `harness::Measured::ssim`).
    pub(crate) ssim: Option<f64>,
    /// Mean FLIP of the composite against the supersampled reference (see
    /// `harness::Measured::flip_mean`).
    pub(crate) flip_mean: Option<f64>,
    /// Hardware-independent counts of the profiled frame.
    pub(crate) counters: ssbvb_passes::FrameCounters,
}

impl Row {
    /// Traversal steps per ray of the technique's ray walk: march steps of the filter,
    /// DDA cells or octree nodes of the ray casters (`None` for rasterizers).
    pub(crate) fn steps_per_ray(&self) -> Option<f64> {
        let c = &self.counters;
        c.march_steps_mean
            .or(c.dda_steps_per_ray)
            .or(c.octree_nodes_per_ray)
    }
}

/// The rows of `bench.csv`, `bench.md` and `bench.json`.
fn rows_table(rows: &[Row]) -> Table<'_, Row> {
    Table::new(
        rows,
        vec![
            Column::new("technique", |r: &Row| r.technique)
                .csv(Fmt::PLAIN)
                .md("technique", Fmt::PLAIN),
            Column::new("model", |r: &Row| r.model.clone())
                .csv(Fmt::PLAIN)
                .md("model", Fmt::PLAIN),
            Column::new("level", |r: &Row| r.level)
                .csv(Fmt::PLAIN)
                .md("level", Fmt::PLAIN),
            Column::new("width", |r: &Row| r.width).csv(Fmt::PLAIN),
            Column::new("height", |r: &Row| r.height).csv(Fmt::PLAIN),
            Column::md_only("size", |r: &Row| size(r.width, r.height)),
            Column::new("frames", |r: &Row| r.frames).csv(Fmt::PLAIN),
            Column::md_only("frame ms (median [min, max])", |r: &Row| {
                format!(
                    "{:.2} [{:.2}, {:.2}]",
                    r.frame_ms_median, r.frame_ms_min, r.frame_ms_max
                )
            }),
            Column::new("frame_ms_median", |r: &Row| r.frame_ms_median).csv(Fmt::fixed(4)),
            Column::new("frame_ms_min", |r: &Row| r.frame_ms_min).csv(Fmt::fixed(4)),
            Column::new("frame_ms_max", |r: &Row| r.frame_ms_max).csv(Fmt::fixed(4)),
            Column::new("frame_gpu_ms_median", |r: &Row| r.frame_gpu_ms_median)
                .csv(Fmt::fixed(4))
                .md("GPU ms (median)", Fmt::fixed(2).or("-")),
            Column::new("passes", |r: &Row| Value::json(&r.passes)),
            Column::new("fill_count", |r: &Row| r.fill_count).csv(Fmt::PLAIN),
            Column::md_only("fill / covered", |r: &Row| {
                r.fill_count.map_or("-".into(), |f| {
                    format!(
                        "{f} / {} = {:.3}",
                        r.covered_pixels,
                        f as f64 / r.covered_pixels.max(1) as f64
                    )
                })
            }),
            Column::new("covered_pixels", |r: &Row| r.covered_pixels).csv(Fmt::PLAIN),
            Column::new("voxels", |r: &Row| r.voxels)
                .csv(Fmt::PLAIN)
                .md("voxels", Fmt::PLAIN),
            Column::new("gpu_memory_bytes", |r: &Row| r.gpu_memory_bytes).csv(Fmt::PLAIN),
            Column::text("gpu_mib", |r: &Row| {
                r.gpu_memory_bytes as f64 / (1 << 20) as f64
            })
            .md("GPU MiB", Fmt::fixed(1)),
            Column::new("coverage_iou", |r: &Row| r.coverage_iou)
                .csv(Fmt::fixed(6))
                .md("IoU", Fmt::fixed(4)),
            Column::new("same_voxel_rate", |r: &Row| r.same_voxel_rate)
                .csv(Fmt::fixed(6))
                .md("same voxel", Fmt::fixed(4).or("-")),
            Column::new("depth_error_voxels_median", |r: &Row| {
                r.depth_error_voxels_median
            })
            .csv(Fmt::fixed(6))
            .md("depth err (vox)", Fmt::fixed(3)),
            Column::new("normal_error_deg_median", |r: &Row| {
                r.normal_error_deg_median
            })
            .csv(Fmt::fixed(4)),
            Column::new("psnr_db", |r: &Row| r.psnr_db)
                .csv(Fmt::fixed(4))
                .md("PSNR dB", Fmt::fixed(2).or("-")),
            Column::new("ssim", |r: &Row| r.ssim)
                .csv(Fmt::fixed(5))
                .md("SSIM", Fmt::fixed(4).or("-")),
            Column::new("flip_mean", |r: &Row| r.flip_mean)
                .csv(Fmt::fixed(5))
                .md("FLIP", Fmt::fixed(4).or("-")),
            Column::new("counters", |r: &Row| Value::json(&r.counters)),
            Column::text("steps_per_ray", Row::steps_per_ray)
                .csv(Fmt::fixed(3))
                .md("steps / ray", Fmt::fixed(1).or("-")),
            Column::text("node_words_per_step", |r: &Row| {
                r.counters.node_words_per_step
            })
            .csv(Fmt::fixed(3))
            .md("node words / step", Fmt::fixed(2).or("-")),
        ],
    )
}

/// One sweep point.
#[derive(Debug)]
pub(crate) struct SweepRow {
    /// `max_steps`, `size_scale`, `max_i`, `min_dist`, `resolution_scale` or `lod_bias`.
    pub(crate) knob: &'static str,
    pub(crate) value: f64,
    /// Whether this is the value of the default pipeline.
    pub(crate) is_default: bool,
    pub(crate) level: u32,
    pub(crate) width: u32,
    pub(crate) height: u32,
    pub(crate) frames: usize,
    pub(crate) frame_ms_median: f64,
    pub(crate) fill_count: Option<u32>,
    pub(crate) coverage_iou: f64,
    pub(crate) depth_error_voxels_median: f64,
    /// PSNR (dB) of the composite against the reference over the pixels either covers;
    /// `None` (null) when identical (infinite) or when neither covers any pixel.
    pub(crate) psnr_db: Option<f64>,
    pub(crate) psnr_pixels: usize,
    /// Mean SSIM of the composite against the reference (see `harness::Measured::ssim`).
    pub(crate) ssim: Option<f64>,
}

/// The rows of `sweeps.csv`, the sweep section of `bench.md` and `sweeps` in `bench.json`.
fn sweeps_table(rows: &[SweepRow]) -> Table<'_, SweepRow> {
    Table::new(
        rows,
        vec![
            Column::new("knob", |r: &SweepRow| r.knob)
                .csv(Fmt::PLAIN)
                .md("knob", Fmt::PLAIN),
            Column::new("value", |r: &SweepRow| r.value).csv(Fmt::PLAIN),
            Column::md_only("value", |r: &SweepRow| {
                format!(
                    "{}{}",
                    r.value,
                    if r.is_default { " (default)" } else { "" }
                )
            }),
            Column::new("is_default", |r: &SweepRow| r.is_default).csv(Fmt::PLAIN),
            Column::new("level", |r: &SweepRow| r.level)
                .csv(Fmt::PLAIN)
                .md("level", Fmt::PLAIN),
            Column::new("width", |r: &SweepRow| r.width).csv(Fmt::PLAIN),
            Column::new("height", |r: &SweepRow| r.height).csv(Fmt::PLAIN),
            Column::md_only("size", |r: &SweepRow| size(r.width, r.height)),
            Column::new("frames", |r: &SweepRow| r.frames).csv(Fmt::PLAIN),
            Column::new("frame_ms_median", |r: &SweepRow| r.frame_ms_median)
                .csv(Fmt::fixed(4))
                .md("frame ms (median)", Fmt::fixed(2)),
            Column::new("fill_count", |r: &SweepRow| r.fill_count)
                .csv(Fmt::PLAIN)
                .md("fill", Fmt::PLAIN.or("-")),
            Column::new("coverage_iou", |r: &SweepRow| r.coverage_iou)
                .csv(Fmt::fixed(6))
                .md("IoU", Fmt::fixed(4)),
            Column::new("depth_error_voxels_median", |r: &SweepRow| {
                r.depth_error_voxels_median
            })
            .csv(Fmt::fixed(6))
            .md("depth err (vox)", Fmt::fixed(3)),
            Column::new("psnr_db", |r: &SweepRow| r.psnr_db)
                .csv(Fmt::fixed(4))
                .md("PSNR dB", Fmt::fixed(2).or("-")),
            Column::new("psnr_pixels", |r: &SweepRow| r.psnr_pixels).csv(Fmt::PLAIN),
            Column::new("ssim", |r: &SweepRow| r.ssim)
                .csv(Fmt::fixed(5))
                .md("SSIM", Fmt::fixed(4).or("-")),
        ],
    )
}

/// The Markdown section of the sweeps (empty without sweeps).
fn sweeps_markdown(sweeps: &Table<SweepRow>) -> String {
    if sweeps.rows().is_empty() {
        return String::new();
    }
    String::from(
        "\n## Knob sweeps (default SSBVB pipeline, one knob changed at a time)\n\n\
         PSNR: composite output (sRGB RGBA8) vs the CPU reference colours over the pixels either covers (a hole or an extra pixel counts as object against background).\n\n",
    ) + &sweeps.markdown()
}

/// What the main matrix measured.
#[derive(Default)]
pub(crate) struct Results {
    /// One row per measured cell and technique, in measuring order.
    pub(crate) rows: Vec<Row>,
    /// Why cells were not measured.
    pub(crate) skipped: Vec<String>,
    /// Rows that failed because the GPU device was lost (the run went on with a new one).
    pub(crate) failed: Vec<String>,
}

/// Everything one run measured, as written to `bench.json`.
#[derive(Serialize)]
struct Report<'a> {
    adapter: String,
    adapter_is_software: bool,
    timing: &'static str,
    /// The pipeline of technique `ssbvb` (the SSBVB form `render` chooses on this adapter)
    /// and why; `null` where the run has no `ssbvb` row.
    pipeline_choice: Option<ssbvb_engine::PipelineChoice>,
    preset: String,
    camera: Camera,
    rows: Table<'a, Row>,
    skipped: &'a [String],
    /// Rows that failed with the device lost, and why.
    failed: &'a [String],
    /// Knob sweeps (empty without `--sweep`).
    sweeps: Table<'a, SweepRow>,
    /// Fastest technique per model, target size and level (the study's Table 11).
    fastest: Vec<Fastest>,
    /// The PNG plots written next to the report.
    plots: Vec<PlotInfo>,
}

/// The fastest technique of one (model, size, level) cell.
#[derive(Debug, Serialize)]
struct Fastest {
    model: String,
    width: u32,
    height: u32,
    level: u32,
    technique: &'static str,
    frame_ms_median: f64,
    /// The runner-up, and how much slower it was (ratio of medians).
    runner_up: Option<(&'static str, f64)>,
}

/// Writes the report of the main matrix (`results`, seen from `camera`, and `sweeps`)
/// into `--out`: bench.csv, bench.json, bench.md, sweeps.csv with sweeps, and the plots;
/// then prints it.
pub(crate) fn write(
    args: &BenchArgs,
    ctx: &GpuContext,
    camera: Camera,
    results: &Results,
    sweeps: &[SweepRow],
    print_report: bool,
) -> Result<()> {
    let software = ctx.report().is_software;
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("creating {}", args.out.display()))?;
    let plots = write_plots(&args.out, &results.rows, sweeps)?;
    let report = Report {
        adapter: ctx.report().to_string(),
        adapter_is_software: software,
        timing: timing(software),
        pipeline_choice: if results.rows.iter().any(|r| r.technique == "ssbvb") {
            Some(crate::harness::engine::default_form()?)
        } else {
            None
        },
        preset: format!("{:?}", args.preset),
        camera,
        rows: rows_table(&results.rows),
        skipped: &results.skipped,
        failed: &results.failed,
        sweeps: sweeps_table(sweeps),
        fastest: fastest(&results.rows),
        plots,
    };
    write_outputs(&args.out, &report)?;
    if !print_report {
        return Ok(());
    }
    print(&report, &args.out, args.json)
}

/// How frame and per-pass times were taken on this adapter.
fn timing(software: bool) -> &'static str {
    if software {
        "frame ms = wall time of submit + wait per frame; per-pass = wall time of each pass submitted alone (software adapter: timestamps unreliable)"
    } else {
        "frame ms = wall time of submit + wait per frame; per-pass = GPU timestamps"
    }
}

/// Prints the report: as JSON with `json`, else as Markdown followed by the files written.
fn print(report: &Report, out: &Path, json: bool) -> Result<()> {
    if json {
        println!("{}", serde_json::to_string_pretty(report)?);
    } else {
        print!("{}", markdown(report));
        println!("wrote {}/bench.{{csv,json,md}}", out.display());
        if !report.sweeps.rows().is_empty() {
            println!("wrote {}/sweeps.csv", out.display());
        }
        for p in &report.plots {
            println!("wrote {}/{}", out.display(), p.file);
        }
    }
    Ok(())
}

/// The fastest technique per (model, size, level) with more than one technique measured.
fn fastest(rows: &[Row]) -> Vec<Fastest> {
    let mut cells: BTreeMap<(String, u32, u32, u32), Vec<&Row>> = BTreeMap::new();
    for r in rows {
        cells
            .entry((r.model.clone(), r.width * r.height, r.width, r.level))
            .or_default()
            .push(r);
    }
    cells
        .into_values()
        .filter(|c| c.len() > 1)
        .map(|mut c| {
            c.sort_by(|a, b| a.frame_ms_median.total_cmp(&b.frame_ms_median));
            Fastest {
                model: c[0].model.clone(),
                width: c[0].width,
                height: c[0].height,
                level: c[0].level,
                technique: c[0].technique,
                frame_ms_median: c[0].frame_ms_median,
                runner_up: c
                    .get(1)
                    .map(|r| (r.technique, r.frame_ms_median / c[0].frame_ms_median)),
            }
        })
        .collect()
}

/// `bench.md`: the results table, the skipped cells, the fastest technique per cell, the
/// sweeps and the plots.
fn markdown(r: &Report) -> String {
    let mut s = format!("adapter: {}\ntiming: {}\n", r.adapter, r.timing);
    if let Some(c) = &r.pipeline_choice {
        s.push_str(&format!("technique `ssbvb`: {}\n", c.line()));
    }
    s.push('\n');
    s.push_str(&r.rows.markdown());
    for k in r.skipped {
        s.push_str(&format!("\nskipped: {k}"));
    }
    for k in r.failed {
        s.push_str(&format!("\nfailed: {k}"));
    }
    s.push('\n');
    s.push_str(&fastest_markdown(&r.fastest));
    s.push_str(&sweeps_markdown(&r.sweeps));
    if !r.plots.is_empty() {
        s.push_str(&super::plot::markdown(&r.plots));
    }
    s
}

/// Per model, a table of the fastest technique: rows are target sizes, columns levels
/// (model resolution 2^level), like Table 11 of the ray casting against cube
/// rasterization study.
fn fastest_markdown(f: &[Fastest]) -> String {
    let mut models: Vec<&str> = f.iter().map(|x| x.model.as_str()).collect();
    models.dedup();
    let mut s = String::new();
    for model in models {
        let cells: Vec<&Fastest> = f.iter().filter(|x| x.model == model).collect();
        let mut levels: Vec<u32> = cells.iter().map(|x| x.level).collect();
        levels.sort_unstable();
        levels.dedup();
        let mut sizes: Vec<(u32, u32)> = cells.iter().map(|x| (x.width, x.height)).collect();
        sizes.sort_by_key(|&(w, h)| (w * h, w));
        sizes.dedup();
        s.push_str(&format!(
            "\n## Fastest technique per cell: {model}\n\nms of the median frame; in brackets the runner-up and how much slower it was.\n\n"
        ));
        let cells = &cells;
        let mut columns = vec![Column::md_only("target", |&(w, h): &(u32, u32)| size(w, h))];
        for &l in &levels {
            columns.push(Column::md_only(
                format!("{} (L{l})", 1u64 << l),
                move |&(w, h): &(u32, u32)| match cells
                    .iter()
                    .find(|x| x.width == w && x.height == h && x.level == l)
                {
                    Some(x) => format!(
                        "{} {:.2}{}",
                        x.technique,
                        x.frame_ms_median,
                        x.runner_up
                            .map_or(String::new(), |(t, r)| format!(" ({t} ×{r:.2})"))
                    ),
                    None => "-".into(),
                },
            ));
        }
        s.push_str(&Table::new(&sizes, columns).markdown());
    }
    s
}

/// Writes bench.csv, bench.json and bench.md (and sweeps.csv with sweeps) atomically
/// into `dir`.
fn write_outputs(dir: &Path, r: &Report) -> Result<()> {
    let mut files = vec![
        ("bench.csv", r.rows.csv()),
        ("bench.json", serde_json::to_string_pretty(r)?),
        ("bench.md", markdown(r)),
    ];
    if !r.sweeps.rows().is_empty() {
        files.push(("sweeps.csv", r.sweeps.csv()));
    }
    super::table::write_files(dir, files)
}

/// time_vs_level.png, time_vs_resolution.png (main matrix) and `trade_<knob>.png` (sweeps).
fn write_plots(dir: &Path, rows: &[Row], sweeps: &[SweepRow]) -> Result<Vec<PlotInfo>> {
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
