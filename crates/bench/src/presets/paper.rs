//! `ssbvb bench --preset paper`: the seed paper's comparison of SSBVB with SVO ray casting
//! (Jabłoński & Martyn, Table 2: the bunny at level 9, 720p, 2.59 ms against 9.32 ms for
//! ESVO; Figure 9: 4096 bunnies) reproduced on this renderer and adapter. It runs the main
//! matrix over every model of `assets/models/` at level 9, 1280x720 (`bench.*`), then the
//! scale grid at 4096 instances at the same size (`scale.*`), and writes `paper.*`: per
//! scene each technique's median frame time and each SSBVB frame over each ray caster's
//! of the same run, beside the paper's ratio where it has one; then the paper's third
//! scene (Figure 8: 21 objects at level 11 under a GPU budget, `figure8`) with every
//! technique that can draw it.

use anyhow::Result;
use serde::Serialize;

use crate::args::{BenchArgs, Preset};
use crate::harness::techniques::{PAPER_TECHNIQUES, REMOVED};
use crate::presets::figure8::{self, Figure8};
use crate::presets::{matrix, scale};
use crate::report;
use crate::table::{Column, Fmt, Table, write_report};

/// The paper's Table 2 bunny row at level 9, 720p: SSBVB render time over ESVO's
/// (2.59 ms / 9.32 ms).
const PAPER_BUNNY_L9_720P: f64 = 2.59 / 9.32;

/// Instances of the paper's Figure 9 scene.
const GRID_INSTANCES: usize = 4096;

/// One scene of the comparison: each technique's median frame time.
#[derive(Debug)]
struct PaperRow {
    scene: String,
    /// The level drawn (the grid: Auto LOD up to this level).
    level: u32,
    width: u32,
    height: u32,
    /// Median frame ms per technique of [`PAPER_TECHNIQUES`] (`None`: not measured).
    ms: Vec<Option<f64>>,
    /// Median GPU ms (timestamps) per technique (`None`: not measured, or a software
    /// adapter, or a scene measured by wall time only).
    gpu_ms: Vec<Option<f64>>,
    /// The paper's SSBVB / ESVO ratio for this scene, where it has one.
    paper_ssbvb_over_esvo: Option<f64>,
}

impl PaperRow {
    fn time(&self, technique: &str) -> Option<f64> {
        let i = PAPER_TECHNIQUES.iter().position(|t| *t == technique)?;
        self.ms[i]
    }

    fn gpu_time(&self, technique: &str) -> Option<f64> {
        let i = PAPER_TECHNIQUES.iter().position(|t| *t == technique)?;
        self.gpu_ms[i]
    }

    /// The time ratios compare: GPU time where every technique of the row that has a wall
    /// time has one, else wall time (one clock for the whole row).
    fn compared_time(&self, technique: &str) -> Option<f64> {
        let all_gpu = self
            .ms
            .iter()
            .zip(&self.gpu_ms)
            .all(|(w, g)| w.is_none() || g.is_some());
        if all_gpu {
            self.gpu_time(technique)
        } else {
            self.time(technique)
        }
    }

    fn ratio(&self, num: &str, den: &str) -> Option<f64> {
        Some(self.compared_time(num)? / self.compared_time(den)?)
    }

    /// The fastest of `techniques` that was measured.
    fn best_time(&self, techniques: &[&str]) -> Option<f64> {
        techniques
            .iter()
            .filter_map(|t| self.compared_time(t))
            .min_by(f64::total_cmp)
    }

    /// The fastest of `nums` over the fastest of `dens` that were measured (each side's
    /// strongest form).
    fn best_ratio(&self, nums: &[&str], dens: &[&str]) -> Option<f64> {
        Some(self.best_time(nums)? / self.best_time(dens)?)
    }
}

#[derive(Serialize)]
struct PaperReport<'a> {
    adapter: String,
    adapter_is_software: bool,
    rows: Table<'a, PaperRow>,
    /// The Figure 8 scene: what it holds and each technique's convergence and accuracy.
    figure8: Figure8Report,
    /// What was not measured, and why (from the matrix, the grid and Figure 8).
    skipped: Vec<String>,
}

/// `paper.json`'s `figure8`.
#[derive(Serialize)]
struct Figure8Report {
    objects: usize,
    level: u32,
    voxels: u64,
    budget_mib: u64,
    techniques: Vec<Figure8TechniqueReport>,
}

#[derive(Serialize)]
struct Figure8TechniqueReport {
    technique: &'static str,
    frame_ms_median: f64,
    frames_to_converge: usize,
    converged: bool,
    coverage_iou: f64,
}

impl Figure8Report {
    fn of(f: &Figure8) -> Self {
        Self {
            objects: f.objects,
            level: f.level,
            voxels: f.voxels,
            budget_mib: f.budget_mib,
            techniques: f
                .times
                .iter()
                .map(|t| Figure8TechniqueReport {
                    technique: t.technique,
                    frame_ms_median: t.frame_ms_median,
                    frames_to_converge: t.frames_to_converge,
                    converged: t.converged,
                    coverage_iou: t.coverage_iou,
                })
                .collect(),
        }
    }
}

/// Runs the preset: the matrix, the grid, and the comparison.
pub(crate) fn run(args: &BenchArgs) -> Result<()> {
    let m = matrix::run(args)?;
    report::write(args, &m.ctx, m.camera, &m.results, &[], false)?;
    let (width, height) = args.first_size((1280, 720));
    let grid_args = BenchArgs {
        preset: Preset::Scale,
        instances: Some(vec![GRID_INSTANCES]),
        sizes: Some(vec![(width, height)]),
        techniques: Some(args.techniques.clone().unwrap_or_else(|| {
            PAPER_TECHNIQUES
                .iter()
                .filter(|t| !REMOVED.contains(t))
                .map(|t| t.to_string())
                .collect()
        })),
        ..args.clone()
    };
    let grid = scale::run_with(&grid_args, false)?;
    let mut rows: Vec<PaperRow> = Vec::new();
    for r in &m.results.rows {
        let i = match rows
            .iter()
            .position(|p| p.scene == r.model && p.level == r.level && p.width == r.width)
        {
            Some(i) => i,
            None => {
                let paper = (r.model == "bunny.obj" && r.level == 9 && r.height == 720)
                    .then_some(PAPER_BUNNY_L9_720P);
                rows.push(PaperRow {
                    scene: r.model.clone(),
                    level: r.level,
                    width: r.width,
                    height: r.height,
                    ms: vec![None; PAPER_TECHNIQUES.len()],
                    gpu_ms: vec![None; PAPER_TECHNIQUES.len()],
                    paper_ssbvb_over_esvo: paper,
                });
                rows.len() - 1
            }
        };
        if let Some(k) = PAPER_TECHNIQUES.iter().position(|t| *t == r.technique) {
            rows[i].ms[k] = Some(r.frame_ms_median);
            rows[i].gpu_ms[k] = r.frame_gpu_ms_median;
        }
    }
    let mut grid_row = PaperRow {
        scene: format!("{GRID_INSTANCES} bunnies (grid)"),
        level: 8,
        width,
        height,
        ms: vec![None; PAPER_TECHNIQUES.len()],
        gpu_ms: vec![None; PAPER_TECHNIQUES.len()],
        paper_ssbvb_over_esvo: None,
    };
    for g in grid
        .iter()
        .filter(|g| g.view == "grid" && g.instances == GRID_INSTANCES)
    {
        if let Some(k) = PAPER_TECHNIQUES.iter().position(|t| *t == g.technique) {
            grid_row.ms[k] = Some(g.frame_ms_median);
            grid_row.gpu_ms[k] = g.frame_gpu_ms_median;
        }
    }
    rows.push(grid_row);
    let techniques = crate::harness::techniques::select(args)?;
    let fig = figure8::run(args, &m.ctx, matrix::PAPER_MODELS, &techniques)?;
    let mut fig_row = PaperRow {
        scene: format!(
            "Figure 8: {} objects ({} MiB budget)",
            fig.objects, fig.budget_mib
        ),
        level: fig.level,
        width,
        height,
        ms: vec![None; PAPER_TECHNIQUES.len()],
        gpu_ms: vec![None; PAPER_TECHNIQUES.len()],
        paper_ssbvb_over_esvo: None,
    };
    for t in &fig.times {
        if let Some(k) = PAPER_TECHNIQUES.iter().position(|p| *p == t.technique) {
            fig_row.ms[k] = Some(t.frame_ms_median);
        }
    }
    rows.push(fig_row);
    let mut skipped = m.results.skipped.clone();
    skipped.dedup();
    // Rows that lost the device are not measured either; say so where the ratios are.
    skipped.extend(m.results.failed.iter().map(|f| format!("failed: {f}")));
    skipped.extend(fig.skipped.iter().cloned());
    let report = PaperReport {
        adapter: m.ctx.report().to_string(),
        adapter_is_software: m.ctx.report().is_software,
        rows: table(&rows),
        figure8: Figure8Report::of(&fig),
        skipped,
    };
    let md = markdown(&report, &rows);
    write_report(&args.out, "paper", report.rows.csv(), &report, md.clone())?;
    if args.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        println!("{md}");
        println!(
            "wrote {0}/paper.{{csv,json,md}}, {0}/bench.{{csv,json,md}}, {0}/scale.{{csv,json,md}}",
            args.out.display()
        );
    }
    Ok(())
}

/// JSON and CSV key of each technique's time, in [`PAPER_TECHNIQUES`] order.
const MS_KEYS: [&str; 10] = [
    "ssbvb_unique_ms",
    "ssbvb_exact_ms",
    "esvo_ms",
    "octree_ms",
    "dense_dda_ms",
    "esvo_compute_ms",
    "octree_compute_ms",
    "ssbvb_splat_ms",
    "ssbvb_ms",
    "esvo_all_compute_ms",
];

/// JSON and CSV key of each technique's GPU time, in [`PAPER_TECHNIQUES`] order.
const GPU_MS_KEYS: [&str; 10] = [
    "ssbvb_unique_gpu_ms",
    "ssbvb_exact_gpu_ms",
    "esvo_gpu_ms",
    "octree_gpu_ms",
    "dense_dda_gpu_ms",
    "esvo_compute_gpu_ms",
    "octree_compute_gpu_ms",
    "ssbvb_splat_gpu_ms",
    "ssbvb_gpu_ms",
    "esvo_all_compute_gpu_ms",
];

/// The GPU-time table of `paper.md` (where the adapter has timestamps).
fn gpu_table(rows: &[PaperRow]) -> Table<'_, PaperRow> {
    let mut columns = vec![
        Column::md_only("scene", |r: &PaperRow| r.scene.clone()),
        Column::md_only("level", |r: &PaperRow| r.level),
    ];
    for (k, technique) in PAPER_TECHNIQUES.iter().enumerate() {
        columns.push(Column::md_only(
            format!("{technique} GPU ms"),
            move |r: &PaperRow| r.gpu_ms[k].map_or("-".to_string(), |v| format!("{v:.2}")),
        ));
    }
    Table::new(rows, columns)
}

/// The ratios reported: (key, SSBVB technique, ray caster).
const RATIOS: [(&str, &str, &str); 5] = [
    ("ssbvb_unique_over_esvo", "ssbvb-unique", "esvo"),
    ("ssbvb_exact_over_esvo", "ssbvb-exact", "esvo"),
    ("ssbvb_unique_over_octree", "ssbvb-unique", "octree"),
    ("ssbvb_exact_over_octree", "ssbvb-exact", "octree"),
    ("ssbvb_splat_over_esvo", "ssbvb-splat", "esvo"),
];

/// The forms of ESVO (fragment, compute, compute with the shared stages in compute too) and
/// of the octree caster (fragment, compute).
const ESVO_FORMS: &[&str] = &["esvo", "esvo-compute", "esvo-all-compute"];
const OCTREE_FORMS: &[&str] = &["octree", "octree-compute"];
/// The SSBVB frames that draw the same image with the fast march: billboards rasterized
/// (the default pipeline) or splatted in compute.
const SSBVB_FORMS: &[&str] = &["ssbvb-unique", "ssbvb-splat"];

/// The ratios of the faster of some SSBVB forms over the fastest form of a ray caster
/// measured (fragment or compute): (key, SSBVB forms, the caster's forms, Markdown name).
const BEST_RATIOS: [(&str, &[&str], &[&str], &str); 5] = [
    (
        "ssbvb_over_best_esvo",
        &["ssbvb"],
        ESVO_FORMS,
        "**default `ssbvb` / best ESVO**",
    ),
    (
        "ssbvb_unique_over_best_esvo",
        &["ssbvb-unique"],
        ESVO_FORMS,
        "ssbvb-unique / best ESVO",
    ),
    (
        "ssbvb_unique_over_best_octree",
        &["ssbvb-unique"],
        OCTREE_FORMS,
        "ssbvb-unique / best octree",
    ),
    (
        "best_ssbvb_over_best_esvo",
        SSBVB_FORMS,
        ESVO_FORMS,
        "**best SSBVB / best ESVO**",
    ),
    (
        "best_ssbvb_over_best_octree",
        SSBVB_FORMS,
        OCTREE_FORMS,
        "best SSBVB / best octree",
    ),
];

fn table(rows: &[PaperRow]) -> Table<'_, PaperRow> {
    let mut columns = vec![
        Column::new("scene", |r: &PaperRow| r.scene.clone())
            .csv(Fmt::PLAIN)
            .md("scene", Fmt::PLAIN),
        Column::new("level", |r: &PaperRow| r.level)
            .csv(Fmt::PLAIN)
            .md("level", Fmt::PLAIN),
        Column::new("width", |r: &PaperRow| r.width).csv(Fmt::PLAIN),
        Column::new("height", |r: &PaperRow| r.height).csv(Fmt::PLAIN),
    ];
    for (k, (key, technique)) in MS_KEYS.iter().zip(PAPER_TECHNIQUES).enumerate() {
        columns.push(
            Column::new(key, move |r: &PaperRow| r.ms[k])
                .csv(Fmt::fixed(3))
                .md(format!("{technique} ms"), Fmt::fixed(1).or("-")),
        );
    }
    for (k, key) in GPU_MS_KEYS.iter().enumerate() {
        columns.push(Column::new(key, move |r: &PaperRow| r.gpu_ms[k]).csv(Fmt::fixed(3)));
    }
    for (key, num, den) in RATIOS {
        columns.push(
            Column::new(key, move |r: &PaperRow| r.ratio(num, den))
                .csv(Fmt::fixed(4))
                .md(format!("{num} / {den}"), Fmt::fixed(2).or("-")),
        );
    }
    for (key, nums, dens, name) in BEST_RATIOS {
        columns.push(
            Column::new(key, move |r: &PaperRow| r.best_ratio(nums, dens))
                .csv(Fmt::fixed(4))
                .md(name, Fmt::fixed(2).or("-")),
        );
    }
    columns.push(
        Column::new("paper_ssbvb_over_esvo", |r: &PaperRow| {
            r.paper_ssbvb_over_esvo
        })
        .csv(Fmt::fixed(4))
        .md("paper SSBVB / ESVO", Fmt::fixed(2).or("-")),
    );
    Table::new(rows, columns)
}

fn markdown(r: &PaperReport, rows: &[PaperRow]) -> String {
    let mut s = format!(
        "## The paper's comparison (Table 2, Figure 9), {}\n\n",
        r.adapter
    );
    s.push_str(&r.rows.markdown());
    if rows
        .iter()
        .any(|row| row.gpu_ms.iter().any(Option::is_some))
    {
        s.push_str("\nGPU time of the same frames (median over the timed frames of the sum of each frame's pass timestamps; the host's submission and wait left out):\n\n");
        s.push_str(&gpu_table(rows).markdown());
        s.push_str(
            "\nRatios of a row whose every measured technique has a GPU time compare GPU \
             times; other rows (software adapters, the grid's wall-timed row) compare wall \
             times.\n",
        );
    }
    s.push_str(
        "\nMedian frame ms of each technique's whole frame in the same run; ratios are SSBVB \
         frame over ray-caster frame (below 1: SSBVB faster); \"best\" is the fastest of a \
         caster's fragment and compute forms (for ESVO also `esvo-all-compute`, with the \
         smoothing and the composite in compute), and of the SSBVB frame's rasterized \
         (`ssbvb-unique`) and splatted (`ssbvb-splat`) billboards, which draw the same \
         G-buffer; `ssbvb` is the SSBVB form `render` chooses on this adapter (what a user \
         gets by default). The paper's ratio is its render times (GTX 660).\n",
    );
    let f = &r.figure8;
    s.push_str(&format!(
        "\nFigure 8: {} objects, {:.1} M voxels at level {}, under {} MiB (the paper: 21 \
         objects, 402 M voxels at level 11, 22 FPS at 720p on a GTX 980).\n",
        f.objects,
        f.voxels as f64 / 1e6,
        f.level,
        f.budget_mib
    ));
    for t in &f.techniques {
        s.push_str(&format!(
            "- {}: {:.1} ms, {} frames to converge{}, coverage IoU {:.4}\n",
            t.technique,
            t.frame_ms_median,
            t.frames_to_converge,
            if t.converged { "" } else { " (not converged)" },
            t.coverage_iou
        ));
    }
    for k in &r.skipped {
        s.push_str(&format!("\nSkipped: {k}\n"));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_follow_the_techniques_and_ratios_divide_their_times() {
        assert_eq!(MS_KEYS.len(), PAPER_TECHNIQUES.len());
        for (key, t) in MS_KEYS.iter().zip(PAPER_TECHNIQUES) {
            assert_eq!(*key, format!("{}_ms", t.replace('-', "_")));
        }
        let row = PaperRow {
            scene: "bunny.obj".into(),
            level: 9,
            width: 1280,
            height: 720,
            ms: vec![
                Some(3.0),
                Some(2.0),
                Some(8.0),
                Some(4.0),
                None,
                Some(6.0),
                None,
                Some(2.5),
                Some(2.75),
                Some(5.5),
            ],
            gpu_ms: vec![None; 10],
            paper_ssbvb_over_esvo: Some(PAPER_BUNNY_L9_720P),
        };
        assert_eq!(row.ratio("ssbvb-exact", "esvo"), Some(0.25));
        assert_eq!(row.ratio("ssbvb-unique", "octree"), Some(0.75));
        assert_eq!(row.ratio("ssbvb-unique", "dense-dda"), None);
        // The faster form of ESVO (compute, 6 ms) and the only octree form measured.
        assert_eq!(
            row.best_ratio(&["ssbvb-unique"], &["esvo", "esvo-compute"]),
            Some(0.5)
        );
        assert_eq!(
            row.best_ratio(&["ssbvb-unique"], &["octree", "octree-compute"]),
            Some(0.75)
        );
        assert_eq!(row.best_ratio(&["ssbvb-unique"], &["dense-dda"]), None);
        // The faster SSBVB form (splat, 2.5 ms) over the fastest ESVO form (its compute form
        // with the shared stages in compute, 5.5 ms).
        assert_eq!(row.best_ratio(SSBVB_FORMS, ESVO_FORMS), Some(2.5 / 5.5));
        assert_eq!(row.best_ratio(SSBVB_FORMS, OCTREE_FORMS), Some(2.5 / 4.0));
        assert_eq!(row.ratio("ssbvb-splat", "esvo"), Some(2.5 / 8.0));
        // The default form (2.75 ms) over the fastest ESVO form (5.5 ms).
        assert_eq!(row.best_ratio(&["ssbvb"], ESVO_FORMS), Some(2.75 / 5.5));
        let csv = table(std::slice::from_ref(&row)).csv();
        assert!(
            csv.starts_with("scene,level,width,height,ssbvb_unique_ms"),
            "{csv}"
        );
        let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
        let values: Vec<&str> = csv.lines().nth(1).unwrap().split(',').collect();
        let value = |key: &str| values[header.iter().position(|h| *h == key).unwrap()];
        assert_eq!(value("ssbvb_ms"), "2.750");
        assert_eq!(value("ssbvb_over_best_esvo"), "0.5000");
        assert_eq!(value("esvo_all_compute_ms"), "5.500");
        assert!(header.contains(&"ssbvb_gpu_ms"), "{csv}");
        assert!(csv.contains(",0.2500,"), "{csv}");
        assert!((PAPER_BUNNY_L9_720P - 0.2779).abs() < 1e-4);
    }

    #[test]
    fn ratios_compare_gpu_times_only_when_the_whole_row_has_them() {
        let row = |esvo_gpu: Option<f64>| PaperRow {
            scene: "bunny.obj".into(),
            level: 9,
            width: 1280,
            height: 720,
            ms: vec![
                Some(3.0),
                None,
                Some(8.0),
                None,
                None,
                Some(5.0),
                None,
                None,
                None,
                None,
            ],
            gpu_ms: vec![
                Some(1.0),
                None,
                esvo_gpu,
                None,
                None,
                Some(2.0),
                None,
                None,
                None,
                None,
            ],
            paper_ssbvb_over_esvo: None,
        };
        let gpu = row(Some(4.0));
        assert_eq!(gpu.ratio("ssbvb-unique", "esvo"), Some(0.25));
        assert_eq!(
            gpu.best_ratio(&["ssbvb-unique"], &["esvo", "esvo-compute"]),
            Some(0.5)
        );
        // ESVO's frame has no GPU time: the whole row compares wall times.
        let wall = row(None);
        assert_eq!(wall.ratio("ssbvb-unique", "esvo"), Some(3.0 / 8.0));
        assert_eq!(
            wall.best_ratio(&["ssbvb-unique"], &["esvo", "esvo-compute"]),
            Some(0.6)
        );
        let csv = table(std::slice::from_ref(&gpu)).csv();
        assert!(
            csv.lines().next().unwrap().contains("esvo_compute_gpu_ms"),
            "{csv}"
        );
        let md = gpu_table(std::slice::from_ref(&gpu)).markdown();
        assert!(
            md.contains("esvo-compute GPU ms") && md.contains("2.00"),
            "{md}"
        );
    }
}
