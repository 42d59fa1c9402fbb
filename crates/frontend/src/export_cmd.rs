//! `ssbvb export MODEL --level N --format vox|raw|npy|obj [--sparse] -o OUT`: a model's
//! voxels at a level, through the asset cache, written where other tools open them
//! ([`ssbvb_voxel::export`]). An export over a format's limit is refused before the model
//! is voxelized. Prints what it wrote (`--json`: one JSON object).

use std::io::IsTerminal;
use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use clap::{Args, ValueEnum};
use serde::Serialize;
use ssbvb_voxel::export::{self, ExportFormat};

use crate::progress::BarProgress;

/// The formats, as written on the command line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum FormatArg {
    /// MagicaVoxel `.vox` (palette of the closest 255 colours; past level 8, 256³ models
    /// placed by the scene graph, up to level 12).
    Vox,
    /// The project's dense raw grid (grey levels).
    Raw,
    /// NumPy `.npy`: dense `uint8` RGBA `(X, Y, Z, 4)`, or with `--sparse` one record per
    /// voxel (position, colour, normal).
    Npy,
    /// Wavefront OBJ: the voxels' exposed faces, merged, with vertex colours.
    Obj,
}

/// Arguments of `ssbvb export`.
#[derive(Debug, Args)]
pub struct ExportArgs {
    /// A model file (OBJ, PLY, glTF/GLB, VOX, raw grid), voxelized at `--level` (cached),
    /// or a prepared asset file (`voxelize -o`, the viewer's save), read as it is.
    pub model: PathBuf,
    /// The level to export (2^level cells per axis).
    #[arg(long)]
    pub level: u32,
    /// The file format.
    #[arg(long, value_enum)]
    pub format: FormatArg,
    /// With `--format npy`: one record per voxel instead of the dense grid.
    #[arg(long)]
    pub sparse: bool,
    /// The file to write (written to a temporary file, then renamed).
    #[arg(short = 'o', long)]
    pub output: PathBuf,
    /// Print the report as one JSON object on stdout.
    #[arg(long)]
    pub json: bool,
}

/// What `export` reports.
#[derive(Debug, Serialize)]
struct Report {
    output: String,
    format: &'static str,
    level: u32,
    voxels: usize,
    rectangles: Option<usize>,
    bytes: u64,
    prepare_ms: f64,
    write_ms: f64,
    /// What the model's load could not do (a missing material or texture), naming the file.
    warnings: Vec<String>,
}

/// Runs `ssbvb export`.
pub fn run(args: &ExportArgs) -> Result<()> {
    let format = match (args.format, args.sparse) {
        (FormatArg::Npy, sparse) => ExportFormat::Npy { sparse },
        (_, true) => bail!("--sparse applies to --format npy only"),
        (FormatArg::Vox, false) => ExportFormat::Vox,
        (FormatArg::Raw, false) => ExportFormat::Raw,
        (FormatArg::Obj, false) => ExportFormat::Obj,
    };
    if args.level > 16 {
        bail!("--level {}: levels go up to 16", args.level);
    }
    export::check_size(format, 1 << args.level)?;
    let t0 = Instant::now();
    let progress = BarProgress::new(!args.json && std::io::stderr().is_terminal());
    // The model through the engine, as `render` opens it (a scene file is refused: it
    // holds several objects).
    if args
        .model
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("ron"))
    {
        bail!(
            "{}: export writes one model; give a model file, not a scene",
            args.model.display()
        );
    }
    let content = ssbvb_engine::Content::open(&args.model, Some(args.level), &progress)
        .with_context(|| {
            format!(
                "{}: cannot prepare it at level {}",
                args.model.display(),
                args.level
            )
        })?;
    let warnings = content.warning_lines();
    for w in &warnings {
        eprintln!("warning: {w}");
    }
    let asset = content
        .scene
        .objects
        .first()
        .map(|o| o.asset.clone())
        .context("the model holds no voxel object")?;
    let prepare_ms = t0.elapsed().as_secs_f64() * 1e3;
    let t1 = Instant::now();
    let written = export::write(format, &args.output, &asset, args.level)
        .with_context(|| format!("cannot export to {}", args.output.display()))?;
    let report = Report {
        output: args.output.display().to_string(),
        format: match args.format {
            FormatArg::Vox => "vox",
            FormatArg::Raw => "raw",
            FormatArg::Npy if args.sparse => "npy-sparse",
            FormatArg::Npy => "npy",
            FormatArg::Obj => "obj",
        },
        level: args.level,
        voxels: written.voxels,
        rectangles: written.rectangles,
        bytes: std::fs::metadata(&args.output).map_or(0, |m| m.len()),
        prepare_ms,
        write_ms: t1.elapsed().as_secs_f64() * 1e3,
        warnings,
    };
    if args.json {
        println!("{}", serde_json::to_string(&report)?);
    } else {
        println!(
            "wrote {} ({}, level {}, {} voxels{}, {} bytes) in {:.0} ms (model prepared in {:.0} ms)",
            report.output,
            report.format,
            report.level,
            report.voxels,
            report
                .rectangles
                .map_or(String::new(), |r| format!(", {r} rectangles")),
            report.bytes,
            report.write_ms,
            report.prepare_ms
        );
    }
    Ok(())
}
