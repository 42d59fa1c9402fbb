//! Preparation benchmark: model file → cached asset, per level, with wall time and peak
//! memory.
//!
//! ```text
//! cargo run --release -p ssbvb-voxel --example prepare_bench -- <model> <level>...
//! ```
//!
//! Each level runs in a fresh child process (this same executable with `--child`), so its
//! peak resident set size (`VmHWM` from `/proc/self/status`, the same number as
//! `/usr/bin/time -v`'s "Maximum resident set size") belongs to that level alone. A child
//! does what `ssbvb voxelize` does with a cold cache: load the model, prepare the asset,
//! write the cache file (into a temporary folder). The parent prints a Markdown table of
//! the runs, then the per-level statistics of the finest run.

use std::path::Path;
use std::process::Command;
use std::time::Instant;

use ssbvb_voxel::cache::{hash_source, write_cache};
use ssbvb_voxel::load::load_model;
use ssbvb_voxel::prepare::{PrepareOptions, prepare_asset_with};
use ssbvb_voxel::progress::NoProgress;

/// Peak resident set size of this process in KiB (Linux), if known.
fn peak_rss_kib() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

/// One level, in this process: prints one JSON line on stdout.
fn child(model: &Path, level: u32) -> Result<(), String> {
    let start = Instant::now();
    let source_hash = hash_source(model).map_err(|e| e.to_string())?;
    let loaded = load_model(model).map_err(|e| e.to_string())?;
    let load_s = start.elapsed().as_secs_f64();
    let options = PrepareOptions {
        max_level: 16,
        ..Default::default()
    };
    let (asset, stats) =
        prepare_asset_with(&loaded, level, &options, &NoProgress).map_err(|e| e.to_string())?;
    drop(loaded);
    let t = Instant::now();
    let dir = tempfile::tempdir().map_err(|e| e.to_string())?;
    let path = dir.path().join("bench.ssbvbast");
    write_cache(&path, &asset, source_hash, level).map_err(|e| e.to_string())?;
    let write_s = t.elapsed().as_secs_f64();
    let file_bytes = std::fs::metadata(&path).map(|m| m.len()).unwrap_or(0);
    let wall_s = start.elapsed().as_secs_f64();
    let line = serde_json::json!({
        "level": level,
        "wall_s": wall_s,
        "load_s": load_s,
        "write_s": write_s,
        "cache_file_bytes": file_bytes,
        "peak_rss_kib": peak_rss_kib(),
        "stats": stats,
    });
    println!("{line}");
    Ok(())
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if args.len() >= 4 && args[1] == "--child" {
        let level = args[3].parse().unwrap_or(u32::MAX);
        if let Err(e) = child(Path::new(&args[2]), level) {
            eprintln!("error: {e}");
            std::process::exit(1);
        }
        return;
    }
    if args.len() < 3 {
        eprintln!("usage: prepare_bench <model> <level>...");
        std::process::exit(2);
    }
    let exe = std::env::current_exe().unwrap_or_else(|_| args[0].clone().into());
    println!(
        "model: {}, threads: {}",
        args[1],
        rayon::current_num_threads()
    );
    println!();
    println!(
        "| level | voxels | wall s | voxelize s | octree s | point clouds s | lookups s | proxies s | load s | write s | peak RSS MiB | cache file MiB |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|");
    let mut last: Option<serde_json::Value> = None;
    for level in &args[2..] {
        let out = Command::new(&exe)
            .args(["--child", &args[1], level])
            .output();
        let out = match out {
            Ok(o) if o.status.success() => o,
            Ok(o) => {
                eprintln!(
                    "level {level}: {}",
                    String::from_utf8_lossy(&o.stderr).trim()
                );
                continue;
            }
            Err(e) => {
                eprintln!("level {level}: {e}");
                continue;
            }
        };
        let v: serde_json::Value = match serde_json::from_slice(&out.stdout) {
            Ok(v) => v,
            Err(e) => {
                eprintln!("level {level}: bad child output: {e}");
                continue;
            }
        };
        let f = |k: &str| v[k].as_f64().unwrap_or(f64::NAN);
        let st = &v["stats"]["stages"];
        let s = |k: &str| st[k].as_f64().unwrap_or(f64::NAN);
        let finest = v["stats"]["levels"]
            .as_array()
            .and_then(|l| l.last().cloned());
        let voxels = finest
            .as_ref()
            .and_then(|l| l["voxels"].as_u64())
            .unwrap_or(0);
        println!(
            "| {level} | {voxels} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {:.0} | {:.1} |",
            f("wall_s"),
            s("voxelize_s"),
            s("octree_s"),
            s("point_clouds_s"),
            s("lookups_s"),
            s("proxies_s"),
            f("load_s"),
            f("write_s"),
            f("peak_rss_kib") / 1024.0,
            f("cache_file_bytes") / (1024.0 * 1024.0),
        );
        last = Some(v);
    }
    if let Some(v) = &last {
        levels_table(v);
    }
}

/// Prints the per-level statistics of one run as a Markdown table.
fn levels_table(v: &serde_json::Value) {
    let Some(levels) = v["stats"]["levels"].as_array() else {
        return;
    };
    println!();
    println!(
        "| level | voxels | resident pages | point cloud MiB | lookup MiB | % of dense | octree MiB |"
    );
    println!("|---|---|---|---|---|---|---|");
    for l in levels {
        let u = |k: &str| l[k].as_u64().unwrap_or(0);
        let mib = |k: &str| u(k) as f64 / (1024.0 * 1024.0);
        println!(
            "| {} | {} | {} | {:.2} | {:.2} | {:.3} | {:.2} |",
            u("level"),
            u("voxels"),
            u("resident_pages"),
            mib("point_cloud_bytes"),
            mib("lookup_bytes"),
            l["lookup_percent_of_dense"].as_f64().unwrap_or(f64::NAN),
            mib("octree_bytes"),
        );
    }
}
