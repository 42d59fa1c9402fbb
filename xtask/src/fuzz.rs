//! `cargo xtask fuzz`: coverage-guided fuzzing of every parser on the stable toolchain.
//!
//! The targets live in `crates/voxel/fuzz` (its own workspace and lock file). They are built
//! in release with LLVM's sanitizer-coverage passes (what `cargo fuzz` adds on nightly,
//! minus the address sanitizer, which needs nightly), debug assertions and overflow checks
//! on, and `--cfg fuzzing` (the cache reader then skips checksum comparisons so the fuzzer
//! reaches the structure checks). `--target` keeps those flags away from build scripts and
//! proc macros. Each target runs libFuzzer on a working corpus under
//! `target/fuzz/corpus/TARGET`, seeded from `crates/voxel/fuzz/seeds/TARGET` (small files
//! kept in the repository), the bundled models and pipelines that fit its `-max_len`, and,
//! for the cache, a cache file written here from the bundled knight. A crash, a timeout or
//! an allocation beyond libFuzzer's malloc limit writes its input to the artifacts folder
//! and fails the command.

use std::path::{Path, PathBuf};
use std::process::Command;

use anyhow::{Context, Result, bail};

/// A fuzz target: its binary name and the longest input tried.
struct Target {
    name: &'static str,
    max_len: usize,
}

/// Every target. The longest inputs are per format: mesh formats need room for a header and
/// some elements; pipelines and scenes are short text; the voxelizer gets a few hundred triangles.
const TARGETS: &[Target] = &[
    Target {
        name: "obj",
        max_len: 64 << 10,
    },
    Target {
        name: "ply",
        max_len: 64 << 10,
    },
    Target {
        name: "gltf",
        max_len: 64 << 10,
    },
    Target {
        name: "vox",
        max_len: 64 << 10,
    },
    Target {
        name: "raw",
        max_len: 16 << 10,
    },
    Target {
        name: "cache",
        max_len: 128 << 10,
    },
    Target {
        name: "pipeline",
        max_len: 8 << 10,
    },
    Target {
        name: "scene",
        max_len: 8 << 10,
    },
    Target {
        name: "voxelize",
        max_len: 4 << 10,
    },
];

const USAGE: &str = "usage: cargo xtask fuzz [TARGET ...] [--seconds N] [--runs N] [--artifacts DIR] [--report FILE]
  targets: obj ply gltf vox raw cache pipeline scene voxelize (default: all)
  --seconds N      time per target (default 60)
  --runs N         stop a target after N executions (default: no limit)
  --artifacts DIR  where crashing inputs go (default target/fuzz/artifacts)
  --report FILE    also write the results as a Markdown table";

/// What one target's run did.
#[derive(Debug, Default, Clone, PartialEq)]
pub struct Outcome {
    /// Target name.
    pub target: String,
    /// Inputs executed.
    pub executions: u64,
    /// Coverage (libFuzzer's `cov`: edges reached) at the end.
    pub coverage: u64,
    /// Corpus inputs at the end.
    pub corpus: u64,
    /// Peak resident memory in MB.
    pub peak_rss_mb: u64,
    /// Whether libFuzzer stopped on a crash, timeout or memory limit.
    pub crashed: bool,
}

/// Runs the fuzz task with the command-line arguments after `fuzz`.
pub fn run(root: &Path, args: &[String]) -> Result<bool> {
    let mut names = Vec::new();
    let mut seconds = 60u64;
    let mut runs: Option<u64> = None;
    let mut artifacts = root.join("target/fuzz/artifacts");
    let mut report: Option<PathBuf> = None;
    let mut it = args.iter();
    while let Some(a) = it.next() {
        let mut value = |flag: &str| {
            it.next()
                .cloned()
                .with_context(|| format!("{flag} needs a value\n{USAGE}"))
        };
        match a.as_str() {
            "--seconds" => seconds = value("--seconds")?.parse().context("--seconds")?,
            "--runs" => runs = Some(value("--runs")?.parse().context("--runs")?),
            "--artifacts" => artifacts = PathBuf::from(value("--artifacts")?),
            "--report" => report = Some(PathBuf::from(value("--report")?)),
            "-h" | "--help" => {
                println!("{USAGE}");
                return Ok(true);
            }
            t if TARGETS.iter().any(|x| x.name == t) => names.push(t.to_string()),
            other => bail!("unknown fuzz target or flag `{other}`\n{USAGE}"),
        }
    }
    let targets: Vec<&Target> = TARGETS
        .iter()
        .filter(|t| names.is_empty() || names.iter().any(|n| n == t.name))
        .collect();
    let bin_dir = build(root, &targets)?;
    std::fs::create_dir_all(&artifacts)
        .with_context(|| format!("creating {}", artifacts.display()))?;
    let mut outcomes = Vec::new();
    for t in &targets {
        let corpus = root.join("target/fuzz/corpus").join(t.name);
        seed(root, t, &corpus)?;
        let o = run_target(&bin_dir.join(t.name), t, &corpus, &artifacts, seconds, runs)?;
        eprintln!(
            "xtask fuzz: {}: {} executions, cov {}, corpus {}, peak RSS {} MB{}",
            o.target,
            o.executions,
            o.coverage,
            o.corpus,
            o.peak_rss_mb,
            if o.crashed { ", CRASHED" } else { "" }
        );
        outcomes.push(o);
    }
    let table = markdown(&outcomes, seconds);
    println!("{table}");
    if let Some(path) = report {
        let tmp = path.with_extension("tmp");
        std::fs::write(&tmp, &table).with_context(|| format!("writing {}", tmp.display()))?;
        std::fs::rename(&tmp, &path).with_context(|| format!("writing {}", path.display()))?;
    }
    let crashed: Vec<_> = outcomes.iter().filter(|o| o.crashed).collect();
    if !crashed.is_empty() {
        eprintln!(
            "xtask fuzz: {} target(s) crashed; inputs under {}",
            crashed.len(),
            artifacts.display()
        );
    }
    Ok(crashed.is_empty())
}

/// Builds the targets; returns the folder of their binaries.
fn build(root: &Path, targets: &[&Target]) -> Result<PathBuf> {
    let host = host_triple()?;
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let target_dir = root.join("target/fuzz/build");
    let flags = [
        "--cfg fuzzing",
        "-Cpasses=sancov-module",
        "-Cllvm-args=-sanitizer-coverage-level=4",
        "-Cllvm-args=-sanitizer-coverage-inline-8bit-counters",
        "-Cllvm-args=-sanitizer-coverage-pc-table",
        "-Cllvm-args=-sanitizer-coverage-trace-compares",
        "-Cdebug-assertions",
        "-Coverflow-checks",
    ]
    .join(" ");
    let mut cmd = Command::new(&cargo);
    cmd.current_dir(root.join("crates/voxel/fuzz"))
        .args(["build", "--release", "--quiet", "--target", &host])
        .env("RUSTFLAGS", flags)
        .env("CARGO_TARGET_DIR", &target_dir);
    for t in targets {
        cmd.args(["--bin", t.name]);
    }
    eprintln!(
        "xtask fuzz: building {} target(s) for {host}",
        targets.len()
    );
    if !cmd.status().context("running cargo build")?.success() {
        bail!(
            "building the fuzz targets failed (libFuzzer needs a C++ compiler: on Debian/Ubuntu \
             `apt-get install -y g++`)"
        );
    }
    Ok(target_dir.join(host).join("release"))
}

fn host_triple() -> Result<String> {
    let rustc = std::env::var("RUSTC").unwrap_or_else(|_| "rustc".into());
    let out = Command::new(rustc)
        .arg("-vV")
        .output()
        .context("running rustc -vV")?;
    String::from_utf8_lossy(&out.stdout)
        .lines()
        .find_map(|l| l.strip_prefix("host: ").map(str::to_string))
        .context("rustc -vV printed no host")
}

/// Fills the working corpus with the seeds that fit the target's `max_len` (existing
/// entries, found by earlier runs, stay).
fn seed(root: &Path, t: &Target, corpus: &Path) -> Result<()> {
    std::fs::create_dir_all(corpus).with_context(|| format!("creating {}", corpus.display()))?;
    let mut sources = files_in(&root.join("crates/voxel/fuzz/seeds").join(t.name));
    match t.name {
        "vox" | "obj" | "ply" => sources.extend(
            files_in(&root.join("assets/models"))
                .into_iter()
                .filter(|p| p.extension().is_some_and(|e| e == t.name)),
        ),
        "pipeline" => sources.extend(files_in(&root.join("assets/pipelines"))),
        "scene" => sources.extend(files_in(&root.join("assets/scenes"))),
        "cache" => {
            let path = corpus.join("seed-knight-level-3.bin");
            if !path.exists() {
                write_cache_seed(root, &path)?;
            }
        }
        _ => {}
    }
    for src in sources {
        let Ok(meta) = std::fs::metadata(&src) else {
            continue;
        };
        if meta.len() as usize > t.max_len {
            continue;
        }
        let name = format!(
            "seed-{}",
            src.file_name().unwrap_or_default().to_string_lossy()
        );
        std::fs::copy(&src, corpus.join(name))
            .with_context(|| format!("copying {}", src.display()))?;
    }
    Ok(())
}

fn files_in(dir: &Path) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
        .map(|rd| {
            rd.flatten()
                .map(|e| e.path())
                .filter(|p| p.is_file())
                .collect()
        })
        .unwrap_or_default();
    v.sort();
    v
}

/// A real cache file (the knight at level 3, a few KB) for the cache reader's corpus.
fn write_cache_seed(root: &Path, path: &Path) -> Result<()> {
    use ssbvb_voxel::{cache, load, prepare, progress::NoProgress};
    let level = 3;
    let model = load::load_model(&root.join("assets/models/chr_knight.vox"))?;
    let (asset, _) = prepare::prepare_asset(&model, level, &NoProgress)?;
    cache::write_cache(path, &asset, 0x5eed, level)?;
    Ok(())
}

fn run_target(
    bin: &Path,
    t: &Target,
    corpus: &Path,
    artifacts: &Path,
    seconds: u64,
    runs: Option<u64>,
) -> Result<Outcome> {
    let mut cmd = Command::new(bin);
    cmd.arg(corpus)
        .arg(format!("-max_total_time={seconds}"))
        .arg(format!("-max_len={}", t.max_len))
        .arg(format!(
            "-artifact_prefix={}/{}-",
            artifacts.display(),
            t.name
        ))
        .args(["-print_final_stats=1", "-timeout=10", "-rss_limit_mb=2048"]);
    if let Some(n) = runs {
        cmd.arg(format!("-runs={n}"));
    }
    eprintln!("xtask fuzz: {} for {seconds} s", t.name);
    let out = cmd
        .output()
        .with_context(|| format!("running {}", bin.display()))?;
    let log = String::from_utf8_lossy(&out.stderr);
    let mut o = parse_log(&log);
    o.target = t.name.to_string();
    o.crashed |= !out.status.success();
    if o.crashed {
        let tail: Vec<&str> = log.lines().rev().take(40).collect();
        for l in tail.into_iter().rev() {
            eprintln!("  {l}");
        }
    }
    Ok(o)
}

/// Reads libFuzzer's output: the final statistics and the last status line.
pub fn parse_log(log: &str) -> Outcome {
    let mut o = Outcome::default();
    let number = |s: &str| s.trim().parse::<u64>().unwrap_or(0);
    for line in log.lines() {
        if let Some(v) = line.strip_prefix("stat::number_of_executed_units:") {
            o.executions = number(v);
        } else if let Some(v) = line.strip_prefix("stat::peak_rss_mb:") {
            o.peak_rss_mb = number(v);
        }
        let mut words = line.split_whitespace();
        while let Some(w) = words.next() {
            match w {
                "cov:" => o.coverage = words.next().map_or(o.coverage, number),
                "corp:" => {
                    let v = words.next().unwrap_or("");
                    o.corpus = number(v.split('/').next().unwrap_or(""));
                }
                _ => {}
            }
        }
        if line.contains("ERROR: libFuzzer")
            || line.contains("==ERROR:")
            || line.starts_with("SUMMARY: libFuzzer")
            || line.contains("panicked at")
        {
            o.crashed = true;
        }
    }
    o
}

fn markdown(outcomes: &[Outcome], seconds: u64) -> String {
    let mut s = String::from(
        "| target | seconds | executions | coverage (edges) | corpus | peak RSS MB | crashed |\n\
         |---|---:|---:|---:|---:|---:|---|\n",
    );
    for o in outcomes {
        s.push_str(&format!(
            "| {} | {seconds} | {} | {} | {} | {} | {} |\n",
            o.target,
            o.executions,
            o.coverage,
            o.corpus,
            o.peak_rss_mb,
            if o.crashed { "yes" } else { "no" }
        ));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn libfuzzer_output_is_read() {
        let log = "INFO: Seed: 1\n\
                   #2\tINITED cov: 120 ft: 130 corp: 3/1024b exec/s: 0 rss: 30Mb\n\
                   #4096\tpulse  cov: 150 ft: 170 corp: 9/2Kb lim: 40 exec/s: 2048 rss: 33Mb\n\
                   #8000\tDONE   cov: 151 ft: 172 corp: 10/2Kb lim: 40 exec/s: 2000 rss: 34Mb\n\
                   stat::number_of_executed_units: 8000\n\
                   stat::peak_rss_mb: 34\n";
        let o = parse_log(log);
        assert_eq!(
            (o.executions, o.coverage, o.corpus, o.peak_rss_mb, o.crashed),
            (8000, 151, 10, 34, false)
        );
        let crash = format!("{log}==123== ERROR: libFuzzer: deadly signal\n");
        assert!(parse_log(&crash).crashed);
        let panic = "thread '<unnamed>' panicked at src/x.rs:1:1:\n";
        assert!(parse_log(panic).crashed);
    }
}
