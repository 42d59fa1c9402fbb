//! `ssbvb bench --preset quality`: image quality still and in motion, against ground
//! truth. Each view ([`mod@views`]: the 64-bunny grid along a path and hovering at an LOD
//! switch, one bunny along the path) is rendered by every technique and by the CPU
//! reference at `--flip-samples` samples per pixel (the supersampled ground truth), all
//! composited over black, at each of `--sizes`. The ground truth draws every instance at
//! the asset's finest level, so what Auto LOD changes (coarser voxels, a pop where an
//! instance switches level) counts as error and as flicker. Per technique and view:
//!
//! - `flip_still`: FLIP of the still frame (the view's first camera, held for a temporal
//!   pass's whole jitter sequence) against the ground truth's;
//! - `flip_mean`: FLIP of each frame against the ground truth's, averaged over the path;
//! - `flip_still_same_levels`, `flip_mean_same_levels`: the same against the supersampled
//!   reference at the levels the technique drew (what anti-aliasing can reach; LOD error
//!   left out);
//! - `flicker_ratio`: the mean FLIP between consecutive frames divided by the same for the
//!   ground truth's path (1.0: as stable as ground truth; above: shimmering, popping);
//! - `lod_switches`: instances drawn at another level than in the frame before;
//! - `frame_ms_median`: the median time of a path frame (submit and wait; the references'
//!   rows: the CPU's time);
//! - `history_rejected_share`: with a temporal pass, the share of pixels whose history it
//!   rejected per path frame (nothing to reproject, or its neighbourhood clamp moved the
//!   history by more than 1/16: it held another surface), averaged.
//!
//! Reference rows: `reference-1spp` (finest levels, one sample: what exact aliasing costs)
//! and `reference-auto-lod` (Auto LOD's levels with the renderer's hysteresis,
//! supersampled: what the LOD choice alone costs). Beside `ssbvb-unique`, the row
//! `ssbvb-unique-no-hysteresis` draws it with every frame choosing its levels afresh. The
//! still frame of each technique on the first size is written as a side-by-side crop
//! (technique | ground truth) and as its FLIP error map in NVIDIA's magma colours.

mod measure;
mod views;

use std::path::Path;

use anyhow::{Context, Result};
use serde::Serialize;
use ssbvb_gpu::scene::DEFAULT_LOD_HYSTERESIS;
use ssbvb_voxel::reference::{self, SampleGrid};

use crate::args::BenchArgs;
use crate::flip::{flip_map_rgb8, flip_rgb8};
use crate::harness::technique_pipeline;
use crate::harness::techniques::{self, Technique};
use crate::table::{Column, Fmt, Table, write_report};
use measure::{
    Drawn, ReferenceLevels, SameLevels, flicker, lod_switches, reference_frames, technique_frames,
};
use views::{INSTANCES, LEVEL, QualityView, views};

/// One technique's quality on one view.
#[derive(Debug)]
struct QualityRow {
    technique: String,
    view: &'static str,
    width: u32,
    height: u32,
    frames: usize,
    flip_still: f64,
    flip_mean: f64,
    flip_still_same_levels: f64,
    flip_mean_same_levels: f64,
    /// Mean FLIP between consecutive frames.
    flicker: f64,
    flicker_ratio: f64,
    /// Instance level changes between consecutive frames of the path.
    lod_switches: usize,
    frame_ms_median: f64,
    /// With a temporal pass: the share of pixels whose history was rejected (nothing to
    /// reproject, or clamped away), averaged over the path's frames.
    history_rejected_share: Option<f64>,
}

#[derive(Serialize)]
struct QualityReport<'a> {
    adapter: String,
    adapter_is_software: bool,
    instances: usize,
    level: u32,
    /// Samples per pixel of the ground truth.
    reference_samples: u32,
    /// Auto LOD's hysteresis in levels (`GpuScene::lod_hysteresis`) of the renderer's rows.
    lod_hysteresis: f64,
    rows: Table<'a, QualityRow>,
    /// Techniques not measured, and why.
    skipped: Vec<String>,
    /// The PNGs written (crops and error maps), relative to `--out`.
    images: Vec<String>,
}

/// The row that draws `ssbvb-unique` without LOD hysteresis.
const NO_HYSTERESIS: &str = "ssbvb-unique-no-hysteresis";

/// The techniques of `--techniques`, else the SSBVB variants and the ray casters that draw
/// many instances.
fn quality_techniques(args: &BenchArgs) -> Result<Vec<&'static Technique>> {
    techniques::select_or(
        args,
        &["ssbvb-unique", "ssbvb-aa", "ssbvb-flat", "octree", "esvo"],
    )
}

/// Runs the quality preset and writes `quality.{csv,json,md}` and the PNGs to `--out`.
pub(crate) fn run(args: &BenchArgs) -> Result<()> {
    let chosen = quality_techniques(args)?;
    let pipelines = chosen
        .iter()
        .map(|t| technique_pipeline(t))
        .collect::<Result<Vec<_>>>()?;
    let ctx = ssbvb_engine::choice::headless_context(&pipelines.iter().collect::<Vec<_>>())?;
    let sizes = args.sizes.clone().unwrap_or_else(|| vec![(320, 240)]);
    let n = args.frames.unwrap_or(12).max(2);
    let grid = args.flip_samples_grid();
    let wanted = |name: &str| {
        args.views
            .as_ref()
            .is_none_or(|v| v.iter().any(|w| w == name))
    };
    if let Some(bad) = args
        .views
        .iter()
        .flatten()
        .find(|v| !["path", "hover", "bunny"].contains(&v.as_str()))
    {
        anyhow::bail!("--views: unknown view `{bad}`; the quality views are path, hover, bunny");
    }
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("creating {}", args.out.display()))?;
    let mut rows = Vec::new();
    let mut skipped = Vec::new();
    let mut images = Vec::new();
    for (k, &size) in sizes.iter().enumerate() {
        for view in views(n, size)?.into_iter().filter(|v| wanted(v.name)) {
            // The renderer's rows: each chosen technique, and ssbvb-unique without hysteresis.
            let mut runs: Vec<(String, &Technique, f64)> = Vec::new();
            for t in &chosen {
                runs.push((t.name.to_string(), t, DEFAULT_LOD_HYSTERESIS));
                if t.name == "ssbvb-unique" {
                    runs.push((NO_HYSTERESIS.to_string(), t, 0.0));
                }
            }
            let mut drawn = vec![
                (
                    "reference-1spp".to_string(),
                    reference_frames(&view, size, SampleGrid::CENTRE, ReferenceLevels::Finest),
                ),
                (
                    "reference-auto-lod".to_string(),
                    reference_frames(
                        &view,
                        size,
                        grid,
                        ReferenceLevels::Auto {
                            hysteresis: DEFAULT_LOD_HYSTERESIS,
                        },
                    ),
                ),
            ];
            for (name, t, hysteresis) in runs {
                let p = technique_pipeline(t)?;
                match technique_frames(&ctx, &view, p, size, hysteresis) {
                    Ok(d) => drawn.push((name, d)),
                    Err(e) if techniques::refused(&e) => {
                        if k == 0 && view.name == "path" {
                            skipped.push(format!("{name}: {e:#}"));
                        }
                    }
                    Err(e) => return Err(e.context(name)),
                }
            }
            let truth = reference_frames(&view, size, grid, ReferenceLevels::Finest);
            let mut same = SameLevels::new(&view, size, grid);
            for (name, d) in &drawn {
                let row = quality_row(name, &view, d, &truth, &mut same)?;
                if k == 0 {
                    images.extend(write_images(
                        &args.out,
                        &view,
                        name,
                        &d.still,
                        &truth.still,
                        size,
                    )?);
                }
                if !args.json {
                    eprintln!(
                        "{}x{} {} {name}: FLIP still {:.4} (same levels {:.4}), path {:.4}, \
                         flicker ratio {:.2}, {} LOD switches",
                        size.0,
                        size.1,
                        view.name,
                        row.flip_still,
                        row.flip_still_same_levels,
                        row.flip_mean,
                        row.flicker_ratio,
                        row.lod_switches
                    );
                }
                rows.push(row);
            }
        }
    }
    let report = QualityReport {
        adapter: ctx.report().to_string(),
        adapter_is_software: ctx.report().is_software,
        instances: INSTANCES,
        level: LEVEL,
        reference_samples: grid.count(),
        lod_hysteresis: DEFAULT_LOD_HYSTERESIS,
        rows: table(&rows),
        skipped,
        images,
    };
    let md = markdown(&report);
    write_report(&args.out, "quality", report.rows.csv(), &report, md.clone())?;
    if args.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        println!("{md}");
        println!("wrote {}/quality.{{csv,json,md}}", args.out.display());
    }
    Ok(())
}

/// The row of one technique's frames `d` of `view` against the ground truth's, and against
/// the supersampled reference at the levels it drew (`same`).
fn quality_row(
    name: &str,
    view: &QualityView,
    d: &Drawn,
    truth: &Drawn,
    same: &mut SameLevels,
) -> Result<QualityRow> {
    let size = same.size;
    let mut flips = Vec::with_capacity(d.frames.len());
    let mut same_flips = Vec::with_capacity(d.frames.len());
    for (i, (f, r)) in d.frames.iter().zip(&truth.frames).enumerate() {
        flips.push(flip_rgb8(r, f, size)?);
        same_flips.push(flip_rgb8(same.get(i, &d.levels[i]), f, size)?);
    }
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let truth_flicker = flicker(&truth.frames, size)?;
    let own = flicker(&d.frames, size)?;
    Ok(QualityRow {
        technique: name.to_string(),
        view: view.name,
        width: size.0,
        height: size.1,
        frames: d.frames.len(),
        flip_still: flip_rgb8(&truth.still, &d.still, size)?,
        flip_mean: mean(&flips),
        flip_still_same_levels: flip_rgb8(same.get(0, &d.still_levels), &d.still, size)?,
        flip_mean_same_levels: mean(&same_flips),
        flicker: own,
        flicker_ratio: if truth_flicker > 0.0 {
            own / truth_flicker
        } else {
            f64::NAN
        },
        lod_switches: lod_switches(&d.levels),
        frame_ms_median: d.frame_ms_median,
        history_rejected_share: d
            .rejected
            .iter()
            .copied()
            .collect::<Option<Vec<f64>>>()
            .filter(|v| !v.is_empty())
            .map(|v| mean(&v)),
    })
}

/// `quality_<view>_<name>_crop.png` (the centre half of the still frame beside the ground
/// truth's) and `quality_<view>_<name>_flip.png` (its FLIP error map); returns their names.
fn write_images(
    dir: &Path,
    view: &QualityView,
    name: &str,
    frame: &[u8],
    truth: &[u8],
    size: (u32, u32),
) -> Result<Vec<String>> {
    let (w, h) = (size.0 as usize, size.1 as usize);
    let (cw, ch) = ((w / 2).max(1), (h / 2).max(1));
    let (x0, y0) = ((w - cw) / 2, (h - ch) / 2);
    let mut crop = Vec::with_capacity(cw * 2 * ch * 4);
    for y in y0..y0 + ch {
        for img in [frame, truth] {
            for x in x0..x0 + cw {
                let i = (y * w + x) * 3;
                crop.extend_from_slice(&[img[i], img[i + 1], img[i + 2], 255]);
            }
        }
    }
    let (_, magma) = flip_map_rgb8(truth, frame, size)?;
    let magma: Vec<u8> = magma
        .chunks_exact(3)
        .flat_map(|p| [p[0], p[1], p[2], 255])
        .collect();
    let crop_name = format!("quality_{}_{name}_crop.png", view.name);
    let map_name = format!("quality_{}_{name}_flip.png", view.name);
    reference::write_png_atomic(&dir.join(&crop_name), (cw * 2) as u32, ch as u32, &crop)
        .with_context(|| format!("writing {}", dir.join(&crop_name).display()))?;
    reference::write_png_atomic(&dir.join(&map_name), size.0, size.1, &magma)
        .with_context(|| format!("writing {}", dir.join(&map_name).display()))?;
    Ok(vec![crop_name, map_name])
}

fn table(rows: &[QualityRow]) -> Table<'_, QualityRow> {
    Table::new(
        rows,
        vec![
            Column::new("technique", |r: &QualityRow| r.technique.clone())
                .csv(Fmt::PLAIN)
                .md("technique", Fmt::PLAIN),
            Column::new("view", |r: &QualityRow| r.view)
                .csv(Fmt::PLAIN)
                .md("view", Fmt::PLAIN),
            Column::new("width", |r: &QualityRow| r.width).csv(Fmt::PLAIN),
            Column::new("height", |r: &QualityRow| r.height).csv(Fmt::PLAIN),
            Column::new("size", |r: &QualityRow| format!("{}x{}", r.width, r.height))
                .md("size", Fmt::PLAIN),
            Column::new("frames", |r: &QualityRow| r.frames)
                .csv(Fmt::PLAIN)
                .md("frames", Fmt::PLAIN),
            Column::new("flip_still", |r: &QualityRow| r.flip_still)
                .csv(Fmt::fixed(5))
                .md("FLIP still", Fmt::fixed(4)),
            Column::new("flip_mean", |r: &QualityRow| r.flip_mean)
                .csv(Fmt::fixed(5))
                .md("FLIP path", Fmt::fixed(4)),
            Column::new("flip_still_same_levels", |r: &QualityRow| {
                r.flip_still_same_levels
            })
            .csv(Fmt::fixed(5))
            .md("FLIP still, same levels", Fmt::fixed(4)),
            Column::new("flip_mean_same_levels", |r: &QualityRow| {
                r.flip_mean_same_levels
            })
            .csv(Fmt::fixed(5))
            .md("FLIP path, same levels", Fmt::fixed(4)),
            Column::new("flicker", |r: &QualityRow| r.flicker)
                .csv(Fmt::fixed(5))
                .md("frame-to-frame FLIP", Fmt::fixed(4)),
            Column::new("flicker_ratio", |r: &QualityRow| r.flicker_ratio)
                .csv(Fmt::fixed(4))
                .md("flicker ratio", Fmt::fixed(2)),
            Column::new("lod_switches", |r: &QualityRow| r.lod_switches)
                .csv(Fmt::PLAIN)
                .md("LOD switches", Fmt::PLAIN),
            Column::new("frame_ms_median", |r: &QualityRow| r.frame_ms_median)
                .csv(Fmt::fixed(3))
                .md("frame ms", Fmt::fixed(1)),
            Column::new("history_rejected_share", |r: &QualityRow| {
                r.history_rejected_share
            })
            .csv(Fmt::fixed(5))
            .md("history rejected", Fmt::fixed(4).or("-")),
        ],
    )
}

fn markdown(r: &QualityReport) -> String {
    format!(
        "# Image quality in motion ({} bunnies, Auto LOD to level {}; adapter {})\n\n\
         Ground truth: the CPU reference at {} samples per pixel, every instance at the \
         finest level. Auto LOD hysteresis: {} levels.\n\n{}",
        r.instances,
        r.level,
        r.adapter,
        r.reference_samples,
        r.lod_hysteresis,
        r.rows.markdown()
    )
}
