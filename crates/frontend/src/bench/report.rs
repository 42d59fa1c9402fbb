//! The reports of `ssbvb bench`: the [`Report`] itself (serialized as `bench.json`, so its
//! field names are the JSON keys), the fastest technique per cell, the Markdown tables
//! printed and written as `bench.md`, the CSV files, and the summary on stdout.

use std::path::Path;

use anyhow::{Context, Result};
use serde::Serialize;
use ssbvb_voxel::camera::Camera;

use super::plot::PlotInfo;
use super::run::Row;
use super::sweep::SweepRow;

/// Everything one run measured, as written to `bench.json`.
#[derive(Debug, Serialize)]
pub(super) struct Report {
    pub(super) adapter: String,
    pub(super) adapter_is_software: bool,
    pub(super) timing: &'static str,
    pub(super) preset: String,
    pub(super) camera: Camera,
    pub(super) rows: Vec<Row>,
    pub(super) skipped: Vec<String>,
    /// Knob sweeps (empty without `--sweep`).
    pub(super) sweeps: Vec<SweepRow>,
    /// Fastest technique per model, target size and level (the study's Table 11).
    pub(super) fastest: Vec<Fastest>,
    /// The PNG plots written next to the report.
    pub(super) plots: Vec<PlotInfo>,
}

/// The fastest technique of one (model, size, level) cell.
#[derive(Debug, Serialize)]
pub(super) struct Fastest {
    model: String,
    width: u32,
    height: u32,
    level: u32,
    technique: &'static str,
    frame_ms_median: f64,
    /// The runner-up, and how much slower it was (ratio of medians).
    runner_up: Option<(&'static str, f64)>,
}

/// How frame and per-pass times were taken on this adapter.
pub(super) fn timing(software: bool) -> &'static str {
    if software {
        "frame ms = wall time of submit + wait per frame; per-pass = wall time of each pass submitted alone (software adapter: timestamps unreliable)"
    } else {
        "frame ms = wall time of submit + wait per frame; per-pass = GPU timestamps"
    }
}

/// Prints the report: as JSON with `json`, else as Markdown followed by the files written.
pub(super) fn print(report: &Report, out: &Path, json: bool) -> Result<()> {
    if json {
        println!("{}", serde_json::to_string_pretty(report)?);
    } else {
        print!("{}", markdown(report));
        println!("wrote {}/bench.{{csv,json,md}}", out.display());
        if !report.sweeps.is_empty() {
            println!("wrote {}/sweeps.csv", out.display());
        }
        for p in &report.plots {
            println!("wrote {}/{}", out.display(), p.file);
        }
    }
    Ok(())
}

/// The fastest technique per (model, size, level) with more than one technique measured.
pub(super) fn fastest(rows: &[Row]) -> Vec<Fastest> {
    use std::collections::BTreeMap;
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
    let mut s = format!("adapter: {}\ntiming: {}\n\n", r.adapter, r.timing);
    s.push_str("| technique | model | level | size | frame ms (median [min, max]) | fill / covered | voxels | GPU MiB | IoU | same voxel | depth err (vox) | PSNR dB | SSIM | steps / ray |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    for x in &r.rows {
        s.push_str(&format!(
            "| {} | {} | {} | {}x{} | {:.2} [{:.2}, {:.2}] | {} | {} | {:.1} | {:.4} | {} | {:.3} | {} | {} | {} |\n",
            x.technique,
            x.model,
            x.level,
            x.width,
            x.height,
            x.frame_ms_median,
            x.frame_ms_min,
            x.frame_ms_max,
            x.fill_count.map_or("-".into(), |f| format!(
                "{f} / {} = {:.3}",
                x.covered_pixels,
                f as f64 / x.covered_pixels.max(1) as f64
            )),
            x.voxels,
            x.gpu_memory_bytes as f64 / (1 << 20) as f64,
            x.coverage_iou,
            x.same_voxel_rate.map_or("-".into(), |v| format!("{v:.4}")),
            x.depth_error_voxels_median,
            x.psnr_db.map_or("-".into(), |p| format!("{p:.2}")),
            x.ssim.map_or("-".into(), |v| format!("{v:.4}")),
            x.steps_per_ray().map_or("-".into(), |v| format!("{v:.1}"))
        ));
    }
    for k in &r.skipped {
        s.push_str(&format!("\nskipped: {k}"));
    }
    s.push('\n');
    s.push_str(&fastest_markdown(&r.fastest));
    s.push_str(&super::sweep::markdown(&r.sweeps));
    if !r.plots.is_empty() {
        s.push_str(&super::plot::markdown(&r.plots));
    }
    s
}

/// Per model, a table of the fastest technique: rows are target sizes, columns levels
/// (model resolution 2^level), like Table 11 of the seed-002 study.
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
            "\n## Fastest technique per cell: {model}\n\nms of the median frame; in brackets the runner-up and how much slower it was.\n\n| target |"
        ));
        for l in &levels {
            s.push_str(&format!(" {} (L{l}) |", 1u64 << l));
        }
        s.push_str("\n|---|");
        s.push_str(&"---|".repeat(levels.len()));
        s.push('\n');
        for (w, h) in sizes {
            s.push_str(&format!("| {w}x{h} |"));
            for l in &levels {
                match cells
                    .iter()
                    .find(|x| x.width == w && x.height == h && x.level == *l)
                {
                    Some(x) => s.push_str(&format!(
                        " {} {:.2}{} |",
                        x.technique,
                        x.frame_ms_median,
                        x.runner_up
                            .map_or(String::new(), |(t, r)| format!(" ({t} ×{r:.2})"))
                    )),
                    None => s.push_str(" - |"),
                }
            }
            s.push('\n');
        }
    }
    s
}

/// Writes bench.csv, bench.json and bench.md atomically into `dir`.
pub(super) fn write_outputs(dir: &Path, r: &Report) -> Result<()> {
    let mut csv = String::from(
        "technique,model,level,width,height,frames,frame_ms_median,frame_ms_min,frame_ms_max,fill_count,covered_pixels,voxels,gpu_memory_bytes,coverage_iou,same_voxel_rate,depth_error_voxels_median,normal_error_deg_median,psnr_db,ssim,steps_per_ray\n",
    );
    for x in &r.rows {
        csv.push_str(&format!(
            "{},{},{},{},{},{},{:.4},{:.4},{:.4},{},{},{},{},{:.6},{},{:.6},{:.4},{},{},{}\n",
            x.technique,
            x.model,
            x.level,
            x.width,
            x.height,
            x.frames,
            x.frame_ms_median,
            x.frame_ms_min,
            x.frame_ms_max,
            x.fill_count.map_or(String::new(), |f| f.to_string()),
            x.covered_pixels,
            x.voxels,
            x.gpu_memory_bytes,
            x.coverage_iou,
            x.same_voxel_rate
                .map_or(String::new(), |v| format!("{v:.6}")),
            x.depth_error_voxels_median,
            x.normal_error_deg_median,
            x.psnr_db.map_or(String::new(), |p| format!("{p:.4}")),
            x.ssim.map_or(String::new(), |v| format!("{v:.5}")),
            x.steps_per_ray()
                .map_or(String::new(), |v| format!("{v:.3}"))
        ));
    }
    let mut files = vec![
        ("bench.csv", csv),
        ("bench.json", serde_json::to_string_pretty(r)?),
        ("bench.md", markdown(r)),
    ];
    if !r.sweeps.is_empty() {
        files.push(("sweeps.csv", super::sweep::csv(&r.sweeps)));
    }
    write_files(dir, files)
}

/// Writes each `(name, body)` into `dir` (created if missing) atomically: a temporary
/// file, then a rename, so a reader never sees half a report.
pub(super) fn write_files(dir: &Path, files: Vec<(&str, String)>) -> Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    for (name, body) in files {
        let path = dir.join(name);
        let tmp = dir.join(format!(".{name}.tmp"));
        std::fs::write(&tmp, body).with_context(|| format!("writing {}", tmp.display()))?;
        std::fs::rename(&tmp, &path).with_context(|| format!("writing {}", path.display()))?;
    }
    Ok(())
}
