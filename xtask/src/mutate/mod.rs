//! `cargo xtask mutate-shaders`: mutation testing of the WGSL shaders. Each mutant (one
//! change of one file, `sites.rs`) is validated with naga like `validate-shaders`; the
//! valid ones are run with the GPU tests that exercise that file (`TEST_MAP`, or
//! `--tests`), through `SSBVB_SHADER_DIR` so that no mutant needs a rebuild. A mutant is
//! caught when a test fails, missed when all pass, timed out when the run exceeds the
//! limit (a hang or a far slower shader), invalid when naga rejects it.

mod report;
mod sites;

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use anyhow::{Context, Result, bail};

use report::{FileResult, Outcome};
use sites::Mutant;

/// Usage of the task.
pub const USAGE: &str =
    "usage: cargo xtask mutate-shaders [FILE ...] [--tests FILTER]... [--report FILE]
       [--timeout SECONDS] [--lines A-B] [--at L:C,...] [--every N] [--list]
       [--test-binary PATH]

  FILE            shader files under shaders/ (default: the core shaders: the march, the filter,
                  the instance hierarchy, billboards and splats, smoothing, composite, the shading
                  in common.inc.wgsl, the dense DDA and the octree caster)
  --tests FILTER  run the GPU tests whose names contain FILTER (repeatable, or comma-separated)
                  instead of each file's entry in the test map
  --report FILE   Markdown report (default target/mutate-shaders.md), rewritten after each file
  --timeout S     seconds per mutant run (default: 3 x the unmutated run + 30)
  --lines A-B     only mutants on lines A to B of each file
  --at L:C,...    only mutants at these line:column positions (a report's missed ones, to
                  run them again against other tests)
  --every N       only every N-th mutant of each file (a sample; 1 = all)
  --list          print the mutants and exit (builds nothing, runs nothing)
  --test-binary P the GPU test binary (default: built with cargo test -p ssbvb-tests --test gpu)";

/// The core shaders, the default set.
pub const CORE: &[&str] = &[
    "sparse_march.inc.wgsl",
    "filter_march.inc.wgsl",
    "ray_march_filter.wgsl",
    "ray_march_gbuffer.wgsl",
    "instance_bvh.inc.wgsl",
    "billboard_quad.inc.wgsl",
    "billboards.wgsl",
    "splat_billboards.wgsl",
    "splat_billboards.inc.wgsl",
    "splat_billboards_wide.wgsl",
    "smooth.wgsl",
    "composite.wgsl",
    "composite.inc.wgsl",
    "common.inc.wgsl",
    "dense_dda.wgsl",
    "octree_ray_cast.wgsl",
];

/// Which GPU tests (name filters of the `gpu` test binary) exercise each shader: the
/// tests of the passes that include it, the cheapest and sharpest first (a mutant's run
/// stops at the first filter whose tests fail). A file not listed runs every GPU test.
pub const TEST_MAP: &[(&str, &[&str])] = &[
    (
        "sparse_march.inc.wgsl",
        &[
            "ties::exact",
            "ties::fast",
            "streaming::",
            "ray_march_filter::",
            "empty_space::",
            "scale::counters",
            "scale::a_grid",
        ],
    ),
    (
        "ray_march_filter.wgsl",
        &[
            "ties::exact",
            "ties::fast",
            "streaming::",
            "ray_march_filter::",
            "empty_space::",
            "scale::counters",
            "scale::a_grid",
            "scale::models_of",
        ],
    ),
    (
        "filter_march.inc.wgsl",
        &[
            "ties::exact",
            "ties::fast",
            "streaming::",
            "ray_march_filter::",
            "ray_march_gbuffer::",
            "scale::counters",
            "scale::a_grid",
        ],
    ),
    (
        "ray_march_gbuffer.wgsl",
        &["ray_march_gbuffer::", "streaming::a_quarter"],
    ),
    (
        "instance_bvh.inc.wgsl",
        &[
            "instance_lists::",
            "ties::",
            "ray_march_filter::many",
            "scale::",
            "ray_casters::",
            "ray_cast_compute::",
        ],
    ),
    (
        "billboard_quad.inc.wgsl",
        &[
            "billboard_footprint::isolated",
            "splat::",
            "billboards::",
            "billboard_harness::",
            "billboard_footprint::",
        ],
    ),
    (
        "billboards.wgsl",
        &[
            "billboard_footprint::isolated",
            "splat::",
            "billboards::",
            "billboard_harness::",
            "billboard_footprint::",
        ],
    ),
    ("splat_billboards.inc.wgsl", &["splat::"]),
    // The two-step form runs only on a device without 64-bit atomics: the test that
    // holds it to the one-step form makes one.
    ("splat_billboards.wgsl", &["splat::the_two_step"]),
    ("splat_billboards_wide.wgsl", &["splat::"]),
    ("smooth.wgsl", &["smooth_composite::"]),
    ("composite.wgsl", &["smooth_composite::"]),
    ("composite.inc.wgsl", &["smooth_composite::"]),
    (
        "common.inc.wgsl",
        &[
            "ties::exact",
            // The G-buffer's geometric normals (`oct_encode`) on lattice rays.
            "ties::ray_casters",
            "smooth_composite::",
            "billboards::",
            "triangles::",
        ],
    ),
    (
        "dense_dda.wgsl",
        &["ties::ray_casters", "dense_dda::", "ray_casters::"],
    ),
    (
        "octree_ray_cast.wgsl",
        &[
            "ties::ray_casters",
            "octree_ray_cast::",
            "ray_casters::",
            "ray_cast_compute::",
        ],
    ),
    (
        "esvo_ray_cast.wgsl",
        &["ties::ray_casters", "esvo_ray_cast::", "ray_cast_compute::"],
    ),
    (
        "ray_cast.inc.wgsl",
        &[
            "ties::ray_casters",
            "dense_dda::",
            "octree_ray_cast::",
            "esvo_ray_cast::",
            "ray_casters::",
            "ray_cast_compute::",
        ],
    ),
    ("ray_cast_compute.inc.wgsl", &["ray_cast_compute::"]),
    (
        "tile_list.inc.wgsl",
        &[
            "ray_march_filter::tiles",
            "ray_cast_compute::",
            "ray_march_filter::",
        ],
    ),
    ("edge_aa.wgsl", &["edge_aa::"]),
];

#[derive(Debug, Default)]
struct Options {
    files: Vec<String>,
    tests: Vec<String>,
    report: Option<PathBuf>,
    timeout: Option<u64>,
    lines: Option<(usize, usize)>,
    /// `--at`: (line, column) positions; empty: every position.
    at: Vec<(usize, usize)>,
    every: usize,
    list: bool,
    test_binary: Option<PathBuf>,
}

fn parse(args: &[String]) -> Result<Options> {
    let mut o = Options {
        every: 1,
        ..Default::default()
    };
    let mut it = args.iter();
    while let Some(a) = it.next() {
        let mut value = |name: &str| {
            it.next()
                .cloned()
                .with_context(|| format!("{name} needs a value\n{USAGE}"))
        };
        match a.as_str() {
            "--tests" => o.tests.extend(
                value("--tests")?
                    .split(',')
                    .filter(|s| !s.is_empty())
                    .map(str::to_string),
            ),
            "--report" => o.report = Some(value("--report")?.into()),
            "--timeout" => {
                let v = value("--timeout")?;
                o.timeout =
                    Some(v.parse().ok().filter(|&s| s > 0).with_context(|| {
                        format!("--timeout {v}: not a positive number of seconds")
                    })?);
            }
            "--lines" => {
                let v = value("--lines")?;
                let range = v
                    .split_once('-')
                    .and_then(|(a, b)| Some((a.parse().ok()?, b.parse().ok()?)))
                    .filter(|(a, b): &(usize, usize)| a <= b);
                o.lines =
                    Some(range.with_context(|| format!("--lines {v}: expected A-B with A <= B"))?);
            }
            "--at" => {
                let v = value("--at")?;
                for p in v.split(',').filter(|p| !p.is_empty()) {
                    let pos = p
                        .split_once(':')
                        .and_then(|(l, c)| Some((l.parse().ok()?, c.parse().ok()?)))
                        .with_context(|| format!("--at {p}: expected LINE:COLUMN"))?;
                    o.at.push(pos);
                }
            }
            "--every" => {
                let v = value("--every")?;
                o.every = v
                    .parse()
                    .ok()
                    .filter(|&n| n > 0)
                    .with_context(|| format!("--every {v}: not a positive whole number"))?;
            }
            "--list" => o.list = true,
            "--test-binary" => o.test_binary = Some(value("--test-binary")?.into()),
            f if f.starts_with("--") => bail!("unknown option {f}\n{USAGE}"),
            f => o.files.push(
                Path::new(f)
                    .file_name()
                    .map(|n| n.to_string_lossy().into_owned())
                    .unwrap_or_else(|| f.to_string()),
            ),
        }
    }
    if o.files.is_empty() {
        o.files = CORE.iter().map(|s| s.to_string()).collect();
    }
    Ok(o)
}

/// The mutants of `src` the options select.
fn selected(src: &str, o: &Options) -> Vec<Mutant> {
    sites::mutants(src)
        .into_iter()
        .filter(|m| o.lines.is_none_or(|(a, b)| (a..=b).contains(&m.line)))
        .filter(|m| o.at.is_empty() || o.at.contains(&(m.line, m.col)))
        .enumerate()
        .filter(|(i, _)| i % o.every == 0)
        .map(|(_, m)| m)
        .collect()
}

/// The test filters for `file`.
pub fn tests_for(file: &str) -> Vec<String> {
    TEST_MAP
        .iter()
        .find(|(f, _)| *f == file)
        .map(|(_, t)| t.iter().map(|s| s.to_string()).collect())
        .unwrap_or_default()
}

/// Runs the task; `Ok(false)` when a file's unmutated run fails.
pub fn run(root: &Path, args: &[String]) -> Result<bool> {
    if args.iter().any(|a| a == "-h" || a == "--help") {
        println!("{USAGE}");
        return Ok(true);
    }
    let o = parse(args)?;
    let shader_dir = root.join("shaders");
    let mut sources = Vec::new();
    for f in &o.files {
        let p = shader_dir.join(f);
        let src = std::fs::read_to_string(&p)
            .with_context(|| format!("{}: no such shader under {}", f, shader_dir.display()))?;
        sources.push((f.clone(), src));
    }
    if o.list {
        for (f, src) in &sources {
            for m in selected(src, &o) {
                println!("{f}:{}", m.describe());
            }
        }
        return Ok(true);
    }
    let binary = match &o.test_binary {
        Some(b) => b.clone(),
        None => build_gpu_tests(root)?,
    };
    let work = std::env::temp_dir().join(format!("ssbvb-mutate-shaders-{}", std::process::id()));
    copy_shaders(&shader_dir, &work)?;
    let report_path = o
        .report
        .clone()
        .unwrap_or_else(|| root.join("target/mutate-shaders.md"));
    let kinds = crate::shaders::registered();
    let mut results = Vec::new();
    let started = Instant::now();
    for (file, src) in &sources {
        let filters = if o.tests.is_empty() {
            tests_for(file)
        } else {
            o.tests.clone()
        };
        let mutants = selected(src, &o);
        eprintln!(
            "mutate-shaders: {file}: {} mutant(s), tests {}",
            mutants.len(),
            if filters.is_empty() {
                "(all)".to_string()
            } else {
                filters.join(" ")
            }
        );
        // Each filter is a group run on its own, in the map's order, and a mutant's run
        // stops at the first group that fails: the cheap, sharp tests go first.
        let groups: Vec<Vec<String>> = if filters.is_empty() {
            vec![Vec::new()]
        } else {
            filters.iter().map(|f| vec![f.clone()]).collect()
        };
        let mut limits = Vec::new();
        let t0 = Instant::now();
        for g in &groups {
            let g0 = Instant::now();
            let base = run_tests(&binary, &work, g, Duration::from_secs(3600))?;
            if base != TestRun::Passed {
                eprintln!(
                    "mutate-shaders: {file}: the unmutated shaders do not pass the tests {g:?} ({base:?}); fix that first"
                );
                return Ok(false);
            }
            let secs = g0.elapsed().as_secs();
            limits.push(Duration::from_secs(o.timeout.unwrap_or(3 * secs + 30)));
        }
        let baseline = t0.elapsed();
        results.push(FileResult {
            file: file.clone(),
            filters: filters.clone(),
            baseline,
            outcomes: Vec::new(),
        });
        for (i, m) in mutants.iter().enumerate() {
            let target = work.join(file);
            std::fs::write(&target, m.apply(src))
                .with_context(|| format!("writing {}", target.display()))?;
            let verdict = crate::shaders::validate_dir(&work, &kinds)?;
            let outcome = if !verdict.errors.is_empty() {
                Outcome::Invalid
            } else {
                let mut outcome = Outcome::Missed;
                for (g, limit) in groups.iter().zip(&limits) {
                    match run_tests(&binary, &work, g, *limit)? {
                        TestRun::Passed => continue,
                        TestRun::Failed(by) => outcome = Outcome::Caught(by),
                        TestRun::TimedOut => outcome = Outcome::Timeout,
                    }
                    break;
                }
                outcome
            };
            std::fs::write(&target, src)
                .with_context(|| format!("restoring {}", target.display()))?;
            eprintln!(
                "  [{}/{}] {file}:{} {outcome:?}",
                i + 1,
                mutants.len(),
                m.describe()
            );
            let r = results.last_mut().expect("pushed above");
            r.outcomes.push((m.clone(), outcome));
            // Every few mutants, so that an interrupted campaign keeps its results.
            if i % 10 == 9 {
                report::write(&report_path, &results, args, started.elapsed())?;
            }
        }
        report::write(&report_path, &results, args, started.elapsed())?;
    }
    let _ = std::fs::remove_dir_all(&work);
    report::print_summary(&results);
    eprintln!("mutate-shaders: report in {}", report_path.display());
    Ok(true)
}

fn copy_shaders(from: &Path, to: &Path) -> Result<()> {
    std::fs::create_dir_all(to).with_context(|| format!("creating {}", to.display()))?;
    for e in std::fs::read_dir(from).with_context(|| format!("reading {}", from.display()))? {
        let p = e?.path();
        if p.extension().is_some_and(|x| x == "wgsl") {
            let dest = to.join(p.file_name().expect("a file"));
            std::fs::copy(&p, &dest).with_context(|| format!("copying {}", p.display()))?;
        }
    }
    Ok(())
}

/// Builds the GPU test binary and returns its path.
fn build_gpu_tests(root: &Path) -> Result<PathBuf> {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    eprintln!("mutate-shaders: cargo test -p ssbvb-tests --test gpu --no-run");
    let out = Command::new(cargo)
        .current_dir(root)
        .args([
            "test",
            "-p",
            "ssbvb-tests",
            "--test",
            "gpu",
            "--no-run",
            "--message-format=json",
        ])
        .stderr(Stdio::inherit())
        .output()
        .context("running cargo")?;
    if !out.status.success() {
        bail!("building the GPU tests failed");
    }
    for line in String::from_utf8_lossy(&out.stdout).lines() {
        let Ok(v) = serde_json::from_str::<serde_json::Value>(line) else {
            continue;
        };
        if v["reason"] == "compiler-artifact"
            && v["target"]["name"] == "gpu"
            && let Some(exe) = v["executable"].as_str()
        {
            return Ok(PathBuf::from(exe));
        }
    }
    bail!("cargo built no `gpu` test executable")
}

/// How a run of the GPU tests ended.
#[derive(Debug, PartialEq, Eq)]
enum TestRun {
    Passed,
    /// The first failing test's name, from the log (empty when it names none).
    Failed(String),
    TimedOut,
}

/// Runs the GPU tests matching `filters` (all when empty) with the shaders of `dir`.
fn run_tests(binary: &Path, dir: &Path, filters: &[String], limit: Duration) -> Result<TestRun> {
    let log = dir.join("test-run.log");
    let log_file =
        std::fs::File::create(&log).with_context(|| format!("creating {}", log.display()))?;
    let mut cmd = Command::new(binary);
    cmd.args(filters)
        .env("SSBVB_SHADER_DIR", dir)
        .stdout(log_file.try_clone()?)
        .stderr(log_file);
    if std::env::var_os("WGPU_BACKEND").is_none() {
        cmd.env("WGPU_BACKEND", "vulkan");
    }
    #[cfg(unix)]
    std::os::unix::process::CommandExt::process_group(&mut cmd, 0);
    let mut child = cmd
        .spawn()
        .with_context(|| format!("running {}", binary.display()))?;
    let t0 = Instant::now();
    loop {
        if let Some(status) = child.try_wait()? {
            if status.success() {
                return Ok(TestRun::Passed);
            }
            let text = std::fs::read_to_string(&log).unwrap_or_default();
            let first = text
                .lines()
                .find_map(|l| l.strip_prefix("test ")?.strip_suffix(" ... FAILED"))
                .unwrap_or_default();
            return Ok(TestRun::Failed(first.to_string()));
        }
        if t0.elapsed() > limit {
            // The whole group: a hung test run may have spawned helpers.
            #[cfg(unix)]
            let _ = Command::new("kill")
                .args(["-KILL", &format!("-{}", child.id())])
                .status();
            let _ = child.kill();
            let _ = child.wait();
            return Ok(TestRun::TimedOut);
        }
        std::thread::sleep(Duration::from_millis(200));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_core_shader_exists_and_has_tests_in_the_map() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shaders");
        for f in CORE {
            assert!(dir.join(f).is_file(), "{f}");
            assert!(!tests_for(f).is_empty(), "{f} has no tests in TEST_MAP");
        }
        for (f, _) in TEST_MAP {
            assert!(
                dir.join(f).is_file(),
                "TEST_MAP names {f}, which does not exist"
            );
        }
    }

    #[test]
    fn every_core_shader_has_mutants_and_options_are_checked() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shaders");
        for f in CORE {
            let src = std::fs::read_to_string(dir.join(f)).unwrap();
            assert!(!sites::mutants(&src).is_empty(), "{f}");
        }
        let args = |s: &[&str]| s.iter().map(|a| a.to_string()).collect::<Vec<_>>();
        let o = parse(&args(&[
            "shaders/smooth.wgsl",
            "--lines",
            "10-20",
            "--every",
            "2",
        ]))
        .unwrap();
        assert_eq!(
            (o.files, o.lines, o.every),
            (vec!["smooth.wgsl".to_string()], Some((10, 20)), 2)
        );
        assert!(parse(&args(&["--lines", "20-10"])).is_err());
        assert!(parse(&args(&["--every", "0"])).is_err());
        assert!(parse(&args(&["--timeout"])).is_err());
        assert!(parse(&args(&["--bogus"])).is_err());
        let o = parse(&args(&["--tests", "a::,b::", "--tests", "c"])).unwrap();
        assert_eq!(o.tests, vec!["a::", "b::", "c"]);
        let o = parse(&args(&["--at", "36:12,90:41"])).unwrap();
        assert_eq!(o.at, vec![(36, 12), (90, 41)]);
        assert!(parse(&args(&["--at", "36"])).is_err());
        assert!(parse(&args(&["--at", "a:1"])).is_err());
        // Only the mutants at those positions.
        let src = "fn f(x: f32) -> f32 {\n    return x * 2.0 + 1.0;\n}\n";
        let all = sites::mutants(src);
        let (line, col) = (all[0].line, all[0].col);
        let at = selected(
            src,
            &parse(&args(&["--at", &format!("{line}:{col}")])).unwrap(),
        );
        assert!(!at.is_empty() && at.len() < all.len());
        assert!(at.iter().all(|m| (m.line, m.col) == (line, col)));
    }
}
