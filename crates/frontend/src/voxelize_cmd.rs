//! `ssbvb voxelize <model> --level N [-o out] [--json] [--no-cache]`: prepares a model
//! (voxelization, LOD chain, point clouds, sparse lookups, proxy meshes), through the asset
//! cache unless `--no-cache`, and reports per-level sizes and times.
//!
//! Output contract: a progress bar on stderr (only when stderr is a terminal and `--json`
//! is not given); then either a human-readable summary on stdout, or with `--json` exactly
//! one JSON object on stdout and nothing else there. `-o out` also writes the asset cache
//! file to `out` (atomically: temporary file in the same folder, then rename).

use std::io::IsTerminal;
use std::time::Instant;

use anyhow::Context;
use ssbvb_voxel::cache::{CacheStatus, hash_source, prepare_into_cache, read_cache, write_cache};
use ssbvb_voxel::load::load_model;
use ssbvb_voxel::prepare::{asset_level_stats, prepare_asset};

use crate::progress::BarProgress;
pub use crate::voxelize_report::VoxelizeArgs;
use crate::voxelize_report::{CacheReport, Report};

/// Runs `ssbvb voxelize`.
pub fn run(args: &VoxelizeArgs) -> anyhow::Result<()> {
    let start = Instant::now();
    if args.gpu {
        let report = crate::voxelize_gpu::run(args)?;
        return print_report(&report, args.json);
    }
    let progress = BarProgress::new(!args.json && std::io::stderr().is_terminal());

    let (asset, cache, stats, streamed) = if args.no_cache {
        let model = load_model(&args.model)?;
        let (asset, stats) = prepare_asset(&model, args.level, &progress)
            .with_context(|| format!("{}: preparation failed", args.model.display()))?;
        let cache = CacheReport {
            status: "disabled",
            reason: None,
            path: None,
            write_error: None,
        };
        (Some(asset), cache, Some(stats), None)
    } else {
        // A miss prepares a mesh straight into the cache file, never holding a level.
        let (asset, outcome) = prepare_into_cache(&args.model, args.level, None, &progress)?;
        let streamed = (asset.is_none() && args.out.is_some())
            .then(|| (outcome.cache_path.clone(), outcome.cache_key));
        let (status, reason) = match outcome.status {
            CacheStatus::Hit => ("hit", None),
            CacheStatus::AssetFile => ("asset_file", None),
            CacheStatus::Rebuilt { reason } => ("rebuilt", Some(reason)),
        };
        let cache = CacheReport {
            status,
            reason,
            path: Some(outcome.cache_path),
            write_error: outcome.cache_write_error,
        };
        (asset, cache, outcome.stats, streamed)
    };
    progress.finish();
    // Streamed into the cache and asked for a copy: read it back.
    let asset = match streamed {
        Some((path, key)) => Some(read_cache(&path, key, args.level)?),
        None => asset,
    };

    if let (Some(out), Some(asset)) = (&args.out, &asset) {
        let hash = hash_source(&args.model)?;
        write_cache(out, asset, hash, args.level)?;
    }

    let levels = match (&stats, &asset) {
        (Some(s), _) => s.levels.clone(),
        (None, Some(a)) => asset_level_stats(a),
        (None, None) => Vec::new(),
    };
    let (center, scale) = match (&stats, &asset) {
        (Some(s), _) => (s.object_space_center, s.object_space_scale),
        (None, Some(a)) => (a.object_space.center.to_array(), a.object_space.scale),
        (None, None) => ([0.0; 3], 1.0),
    };
    let report = Report {
        model: args.model.clone(),
        level: args.level,
        cache,
        output: args.out.clone(),
        object_space_center: center,
        object_space_scale: scale,
        stages: stats.as_ref().map(|s| s.stages.clone()),
        voxelize: stats.map(|s| s.voxelize),
        total_s: start.elapsed().as_secs_f64(),
        levels,
        differs_from_cpu: None,
        gpu: None,
    };
    if let Some(e) = &report.cache.write_error {
        eprintln!("warning: the asset cache could not be written: {e}");
    }
    print_report(&report, args.json)
}

fn print_report(report: &Report, json: bool) -> anyhow::Result<()> {
    if json {
        println!("{}", serde_json::to_string(report)?);
    } else {
        print!("{}", table(report));
    }
    Ok(())
}

fn mib(bytes: u64) -> String {
    format!("{:.2}", bytes as f64 / (1024.0 * 1024.0))
}

/// The human-readable summary.
fn table(r: &Report) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    let _ = writeln!(s, "model   {}", r.model.display());
    let cache = match (&r.cache.reason, &r.cache.path) {
        (Some(reason), Some(p)) => format!("{reason}, rebuilt ({})", p.display()),
        (None, Some(p)) => format!("hit ({})", p.display()),
        _ => "disabled".to_string(),
    };
    let _ = writeln!(s, "cache   {cache}");
    if let Some(out) = &r.output {
        let _ = writeln!(s, "output  {}", out.display());
    }
    let c = r.object_space_center;
    let _ = writeln!(
        s,
        "object  centre ({:.6}, {:.6}, {:.6}), scale {:.6e}",
        c[0], c[1], c[2], r.object_space_scale
    );
    if let Some(v) = &r.voxelize {
        let skipped = v.skipped_non_finite + v.skipped_bad_index;
        if v.triangles > 0 {
            let _ = writeln!(
                s,
                "input   {} triangles ({} skipped, {} degenerate)",
                v.triangles, skipped, v.degenerate
            );
        } else {
            let _ = writeln!(s, "input   {} voxels", v.source_voxels);
        }
    }
    if let Some(t) = &r.stages {
        let _ = writeln!(
            s,
            "stages  voxelize {:.3}s, octree {:.3}s, point clouds {:.3}s, lookups {:.3}s, proxies {:.3}s",
            t.voxelize_s, t.octree_s, t.point_clouds_s, t.lookups_s, t.proxies_s
        );
    }
    let _ = writeln!(s, "total   {:.3}s", r.total_s);
    if let Some(g) = &r.gpu {
        let _ = writeln!(
            s,
            "gpu     {} ({:?}): {:.3}s against {:.3}s on the CPU ({} fragments, {} pass(es))",
            g.adapter,
            g.method,
            g.gpu_seconds,
            g.cpu_seconds,
            g.stats.fragments,
            g.stats.raster_passes
        );
    }
    for d in r.differs_from_cpu.iter().flatten() {
        let _ = writeln!(
            s,
            "level {:>2}: GPU {} voxels, CPU {}: {} extra, {} missing",
            d.level, d.gpu_voxels, d.cpu_voxels, d.extra, d.missing
        );
    }
    let _ = writeln!(s);
    let _ = writeln!(
        s,
        "{:>5} {:>12} {:>8} {:>12} {:>11} {:>7} {:>10} {:>11} {:>9} {:>8}",
        "level",
        "voxels",
        "pages",
        "attrs MiB",
        "lookup MiB",
        "B/voxel",
        "% dense",
        "octree MiB",
        "proxy tri",
        "time s"
    );
    for l in &r.levels {
        let secs = l
            .seconds
            .map_or_else(|| "-".to_string(), |t| format!("{t:.3}"));
        let _ = writeln!(
            s,
            "{:>5} {:>12} {:>8} {:>12} {:>11} {:>7.2} {:>10.4} {:>11} {:>9} {:>8}",
            l.level,
            l.voxels,
            l.resident_pages,
            mib(l.point_cloud_bytes),
            mib(l.lookup_bytes),
            l.bytes_per_voxel,
            l.lookup_percent_of_dense,
            mib(l.octree_bytes),
            l.proxy_triangles,
            secs
        );
    }
    s
}
