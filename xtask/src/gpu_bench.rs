//! `cargo xtask gpu-bench`: the measurements a lent GPU machine is for, as one command.
//!
//! It builds nothing it does not need (a release `ssbvb` already there is used as it is:
//! `--bin`, else `target/release/ssbvb`; only without one is it built), checks that the
//! adapter `ssbvb` would use is a real GPU, then writes `docs/bench/<gpu>/`:
//!
//! - `env.txt`: the adapter listing, `nvidia-smi`'s line where there is one, the commit;
//! - `calibrate.log`: `ssbvb calibrate`, each SSBVB form's frame on this GPU (the default
//!   scene at 1280×720; it also makes the measured fastest this machine's default);
//! - `forms/`: every SSBVB form beside the ray casters' fragment and compute forms at the
//!   paper's view (bunny, level 9; 1280×720 and 1920×1080), whose `bench.json` rows carry
//!   each pass's GPU time (the per-pass breakdown);
//! - `crowd/`: `bench --preset scale` at 4096 instances, the SSBVB forms (the filter's
//!   second proxy layer too) beside ESVO's and the octree caster's compute forms;
//! - `render/`: `render --json` of the default scene and of the 4096-bunny grid with the
//!   default form and each SSBVB form (each pass's GPU time and the work counters);
//! - `paper/`: `bench --preset paper` (every model, the 4096-bunny grid, Figure 8);
//! - `summary.md`: each step's command, exit status and seconds.
//!
//! The steps run in that order, cheapest first, so that a lease cut short still leaves the
//! breakdown; a step that fails is recorded and the next one runs. `--dry-run` prints the
//! steps without running them (how the tests check the plan).

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

use anyhow::{Context, Result, bail};

const HELP: &str =
    "usage: cargo xtask gpu-bench [--bin PATH] [--out DIR] [--frames N] [--skip-paper]
                               [--allow-software] [--dry-run]
  --bin PATH          the ssbvb binary to run (default: target/release/ssbvb, built only if missing)
  --out DIR           where to write (default: docs/bench/<gpu>, the adapter's name in lower case)
  --frames N          timed frames per measurement (default 10)
  --skip-paper        leave out `bench --preset paper` (the longest step)
  --allow-software    run on a software adapter too (to try the command without a GPU)
  --dry-run           print the steps and write nothing";

/// The options of one run.
#[derive(Debug, Clone, PartialEq)]
struct Options {
    bin: Option<PathBuf>,
    out: Option<PathBuf>,
    frames: u32,
    skip_paper: bool,
    allow_software: bool,
    dry_run: bool,
}

fn parse(args: &[String]) -> Result<Option<Options>> {
    let mut o = Options {
        bin: None,
        out: None,
        frames: 10,
        skip_paper: false,
        allow_software: false,
        dry_run: false,
    };
    let mut it = args.iter();
    while let Some(a) = it.next() {
        let mut value = |name: &str| {
            it.next()
                .cloned()
                .with_context(|| format!("{name} needs a value\n{HELP}"))
        };
        match a.as_str() {
            "--bin" => o.bin = Some(PathBuf::from(value("--bin")?)),
            "--out" => o.out = Some(PathBuf::from(value("--out")?)),
            "--frames" => {
                let v = value("--frames")?;
                o.frames = v
                    .parse()
                    .ok()
                    .filter(|n| (1..=1000).contains(n))
                    .with_context(|| format!("--frames must be 1..=1000, got `{v}`"))?;
            }
            "--skip-paper" => o.skip_paper = true,
            "--allow-software" => o.allow_software = true,
            "--dry-run" => o.dry_run = true,
            "-h" | "--help" => {
                println!("{HELP}");
                return Ok(None);
            }
            other => bail!("unknown gpu-bench option `{other}`\n{HELP}"),
        }
    }
    Ok(Some(o))
}

/// A folder name for an adapter: its name in lower case, runs of anything but letters and
/// digits as one `-` (`NVIDIA H100 80GB HBM3` → `nvidia-h100-80gb-hbm3`).
fn slug(adapter: &str) -> String {
    let mut s = String::new();
    for c in adapter.chars() {
        if c.is_ascii_alphanumeric() {
            s.push(c.to_ascii_lowercase());
        } else if !s.ends_with('-') && !s.is_empty() {
            s.push('-');
        }
    }
    s.trim_end_matches('-').to_string()
}

/// The adapter `ssbvb adapter` chose: its report line after `chosen: `.
fn chosen_adapter(listing: &str) -> Option<&str> {
    listing
        .lines()
        .find_map(|l| l.strip_prefix("chosen: "))
        .map(str::trim)
}

/// One measurement: a name, the arguments to `ssbvb`, and where its stdout goes (under the
/// output folder).
#[derive(Debug, Clone, PartialEq)]
struct Step {
    name: String,
    args: Vec<String>,
    stdout: String,
}

/// One SSBVB form of the engine's table, as `ssbvb pipeline forms --json` lists it.
#[derive(Debug, Clone, PartialEq)]
struct Form {
    /// Its technique name (`ssbvb-direct`).
    name: String,
    /// Its pipeline file, relative to `assets/`.
    file: String,
}

impl Form {
    /// Its label in the render step's file names (`direct`; the paper's raster form keeps
    /// its old label, `raster`).
    fn label(&self) -> String {
        match self.name.as_str() {
            "ssbvb-unique" => "raster".into(),
            n => n.trim_start_matches("ssbvb-").into(),
        }
    }
}

/// The forms of the engine's table, from the binary that will be measured.
fn forms_of(bin: &Path, root: &Path) -> Result<Vec<Form>> {
    let out = ssbvb(bin, root)
        .args(["pipeline", "forms", "--json"])
        .output()
        .context("running ssbvb pipeline forms")?;
    if !out.status.success() {
        bail!(
            "ssbvb pipeline forms --json failed: {}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    let table: serde_json::Value =
        serde_json::from_slice(&out.stdout).context("reading ssbvb pipeline forms --json")?;
    let text = |f: &serde_json::Value, key: &str| f[key].as_str().map(str::to_string);
    table
        .as_array()
        .and_then(|forms| {
            forms
                .iter()
                .map(|f| {
                    Some(Form {
                        name: text(f, "name")?,
                        file: text(f, "file")?,
                    })
                })
                .collect::<Option<Vec<Form>>>()
        })
        .filter(|f| !f.is_empty())
        .context("ssbvb pipeline forms --json: not a list of forms with a name and a file")
}

/// The ESVO and octree baselines measured beside the forms.
const BASELINES: &str = "esvo,esvo-compute,esvo-all-compute";

/// The steps, cheapest first (see the module docs), over the engine's `forms`.
fn steps(out: &Path, frames: u32, skip_paper: bool, forms: &[Form]) -> Vec<Step> {
    let names = |keep: &dyn Fn(&Form) -> bool| -> Vec<String> {
        forms
            .iter()
            .filter(|f| keep(f))
            .map(|f| f.name.clone())
            .collect()
    };
    // Every form; the crowd leaves out the paper's raster form (one billboard per visible
    // voxel of 4096 bunnies).
    let all = names(&|_| true).join(",");
    let crowd = names(&|f| f.name != "ssbvb-unique").join(",");
    let forms_techniques = format!("ssbvb,{all},{BASELINES},octree,octree-compute");
    let crowd_techniques = format!("ssbvb,{crowd},{BASELINES},octree-compute");
    let o = |sub: &str| out.join(sub).display().to_string();
    let f = frames.to_string();
    let mut v = vec![Step {
        name: "calibrate".into(),
        args: ["calibrate", "--size", "1280x720", "--frames", &f]
            .map(String::from)
            .to_vec(),
        stdout: "calibrate.log".into(),
    }];
    v.push(Step {
        name: "forms".into(),
        args: [
            "bench",
            "--levels",
            "9",
            "--sizes",
            "1280x720,1920x1080",
            "--techniques",
            &forms_techniques,
            "--frames",
            &f,
            "--out",
            &o("forms"),
        ]
        .map(String::from)
        .to_vec(),
        stdout: "forms/bench.log".into(),
    });
    let scenes = [
        ("bunny", "assets/scenes/default.ron"),
        ("grid4096", "assets/scenes/bunnies_4096.ron"),
    ];
    let rendered: Vec<(String, Option<String>)> = std::iter::once(("default".into(), None))
        .chain(
            forms
                .iter()
                .map(|f| (f.label(), Some(format!("assets/{}", f.file)))),
        )
        .collect();
    v.push(Step {
        name: "crowd".into(),
        args: [
            "bench",
            "--preset",
            "scale",
            "--instances",
            "4096",
            "--sizes",
            "1280x720",
            "--techniques",
            &crowd_techniques,
            "--frames",
            &f,
            "--out",
            &o("crowd"),
        ]
        .map(String::from)
        .to_vec(),
        stdout: "crowd/scale.log".into(),
    });
    for (scene_name, scene) in scenes {
        for (form_name, pipeline) in &rendered {
            let name = format!("{scene_name}_{form_name}");
            let mut args: Vec<String> = [
                "render",
                scene,
                "--size",
                "1280x720",
                "--json",
                "-o",
                &o(&format!("render/{name}.png")),
            ]
            .map(String::from)
            .to_vec();
            if let Some(p) = pipeline {
                args.extend(["--pipeline".to_string(), p.to_string()]);
            }
            v.push(Step {
                name: format!("render {name}"),
                args,
                stdout: format!("render/{name}.json"),
            });
        }
    }
    if !skip_paper {
        v.push(Step {
            name: "paper".into(),
            args: [
                "bench",
                "--preset",
                "paper",
                "--frames",
                &f,
                "--out",
                &o("paper"),
            ]
            .map(String::from)
            .to_vec(),
            stdout: "paper/paper.log".into(),
        });
    }
    v
}

/// The ssbvb binary: `--bin`, else the release build, built only if it is missing.
fn binary(root: &Path, o: &Options) -> Result<PathBuf> {
    if let Some(b) = &o.bin {
        if !b.is_file() {
            bail!("--bin {}: no such file", b.display());
        }
        return Ok(b.clone());
    }
    let b = root.join("target/release/ssbvb");
    if b.is_file() || o.dry_run {
        return Ok(b);
    }
    eprintln!("xtask: no target/release/ssbvb; building it (cargo build --release -p ssbvb)");
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let ok = Command::new(cargo)
        .current_dir(root)
        .args(["build", "--release", "-p", "ssbvb"])
        .status()
        .context("running cargo build")?
        .success();
    if !ok {
        bail!("building the release ssbvb failed");
    }
    Ok(b)
}

/// `ssbvb` run from the repository root on Vulkan (unless `WGPU_BACKEND` says otherwise).
fn ssbvb(bin: &Path, root: &Path) -> Command {
    let mut c = Command::new(bin);
    c.current_dir(root);
    if std::env::var_os("WGPU_BACKEND").is_none() {
        c.env("WGPU_BACKEND", "vulkan");
    }
    c
}

/// Runs `cargo xtask gpu-bench`.
pub fn run(root: &Path, args: &[String]) -> Result<bool> {
    let Some(o) = parse(args)? else {
        return Ok(true);
    };
    let bin = binary(root, &o)?;
    if o.dry_run {
        let out = o
            .out
            .clone()
            .unwrap_or_else(|| root.join("docs/bench/<gpu>"));
        let forms = if bin.is_file() {
            forms_of(&bin, root)?
        } else {
            eprintln!(
                "xtask: no {}: the forms come from the binary (`ssbvb pipeline forms`); \
                 build it (cargo build --release -p ssbvb) to list every step",
                bin.display()
            );
            Vec::new()
        };
        for s in steps(&out, o.frames, o.skip_paper, &forms) {
            println!("{}: ssbvb {} > {}", s.name, s.args.join(" "), s.stdout);
        }
        return Ok(true);
    }
    let listing = ssbvb(&bin, root)
        .arg("adapter")
        .output()
        .context("running ssbvb adapter")?;
    let listing_text = String::from_utf8_lossy(&listing.stdout).to_string();
    let Some(adapter) = chosen_adapter(&listing_text).map(str::to_string) else {
        bail!(
            "no adapter runs the default pipeline:\n{listing_text}{}",
            String::from_utf8_lossy(&listing.stderr)
        );
    };
    if adapter.contains("software") && !o.allow_software {
        bail!(
            "the adapter is a software one ({adapter}); gpu-bench measures a GPU \
             (--allow-software to run it anyway)"
        );
    }
    let name = adapter.split(" (").next().unwrap_or(&adapter);
    let out = o
        .out
        .clone()
        .unwrap_or_else(|| root.join("docs/bench").join(slug(name)));
    for sub in ["forms", "crowd", "render", "paper"] {
        std::fs::create_dir_all(out.join(sub))
            .with_context(|| format!("creating {}", out.join(sub).display()))?;
    }
    write_env(root, &out, &listing_text)?;
    let mut summary =
        format!("# gpu-bench on {adapter}\n\n| step | status | s |\n|---|---|---:|\n");
    let mut all_ok = true;
    let forms = forms_of(&bin, root)?;
    for s in steps(&out, o.frames, o.skip_paper, &forms) {
        eprintln!("xtask: gpu-bench: {} (ssbvb {})", s.name, s.args.join(" "));
        let start = Instant::now();
        let result = ssbvb(&bin, root).args(&s.args).output();
        let secs = start.elapsed().as_secs_f64();
        let status = match result {
            Ok(r) => {
                let path = out.join(&s.stdout);
                std::fs::write(&path, &r.stdout)
                    .with_context(|| format!("writing {}", path.display()))?;
                if !r.stderr.is_empty() {
                    std::fs::write(path.with_extension("stderr"), &r.stderr)
                        .with_context(|| format!("writing {}.stderr", path.display()))?;
                }
                if r.status.success() {
                    "ok".to_string()
                } else {
                    all_ok = false;
                    format!("failed ({}; see {}.stderr)", r.status, s.stdout)
                }
            }
            Err(e) => {
                all_ok = false;
                format!("did not start: {e}")
            }
        };
        summary.push_str(&format!("| {} | {status} | {secs:.1} |\n", s.name));
        std::fs::write(out.join("summary.md"), &summary)
            .with_context(|| format!("writing {}", out.join("summary.md").display()))?;
    }
    println!("{summary}\nwrote {}", out.display());
    Ok(all_ok)
}

/// `env.txt`: the commit, `nvidia-smi`'s view of the GPU where it has one, and the adapter
/// listing.
fn write_env(root: &Path, out: &Path, listing: &str) -> Result<()> {
    let run = |c: &mut Command| {
        c.output()
            .ok()
            .filter(|o| o.status.success())
            .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
    };
    let commit = run(Command::new("git")
        .current_dir(root)
        .args(["rev-parse", "HEAD"]))
    .unwrap_or_else(|| "unknown (no git)".into());
    let smi = run(Command::new("nvidia-smi").args([
        "--query-gpu=name,driver_version,memory.total,clocks.max.sm",
        "--format=csv",
    ]))
    .unwrap_or_else(|| "nvidia-smi: not available".into());
    let text = format!("commit: {commit}\n{smi}\n{listing}");
    std::fs::write(out.join("env.txt"), text)
        .with_context(|| format!("writing {}", out.join("env.txt").display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn args(s: &str) -> Vec<String> {
        s.split_whitespace().map(String::from).collect()
    }

    #[test]
    fn options_parse_and_bad_ones_are_named() {
        let o = parse(&args("--frames 3 --skip-paper --out x"))
            .unwrap()
            .unwrap();
        assert_eq!(o.frames, 3);
        assert!(o.skip_paper && !o.dry_run);
        assert_eq!(o.out, Some(PathBuf::from("x")));
        for (bad, want) in [
            ("--frames 0", "--frames must be 1..=1000"),
            ("--frames", "--frames needs a value"),
            ("--nope", "unknown gpu-bench option `--nope`"),
        ] {
            let e = parse(&args(bad)).unwrap_err().to_string();
            assert!(e.contains(want), "{bad}: {e}");
        }
    }

    #[test]
    fn folders_are_named_after_the_adapter() {
        assert_eq!(slug("NVIDIA H100 80GB HBM3"), "nvidia-h100-80gb-hbm3");
        assert_eq!(
            slug("llvmpipe (LLVM 15.0.6, 256 bits)"),
            "llvmpipe-llvm-15-0-6-256-bits"
        );
        let listing = "adapters, best first:\n  NVIDIA H200 [Vulkan, DiscreteGpu]: fits\nchosen: NVIDIA H200 (Vulkan, DiscreteGpu, NVIDIA 580)\n";
        assert_eq!(
            chosen_adapter(listing),
            Some("NVIDIA H200 (Vulkan, DiscreteGpu, NVIDIA 580)")
        );
        assert_eq!(chosen_adapter("adapters:\n  (none)\n"), None);
    }

    /// The engine's table as `ssbvb pipeline forms --json` printed it at the time of
    /// writing (the binary is not built by this test).
    fn table() -> Vec<Form> {
        [
            ("ssbvb-direct", "pipelines/ssbvb_direct.ron"),
            ("ssbvb-pixel", "pipelines/ssbvb_pixel.ron"),
            ("ssbvb-compute", "pipelines/ssbvb_compute.ron"),
            ("ssbvb-all-compute", "pipelines/ssbvb_all_compute.ron"),
            ("ssbvb-splat", "pipelines/ssbvb_splat.ron"),
            ("ssbvb-unique", "pipelines/ssbvb_unique.ron"),
        ]
        .map(|(name, file)| Form {
            name: name.into(),
            file: file.into(),
        })
        .to_vec()
    }

    #[test]
    fn the_breakdown_runs_before_the_paper_preset_and_every_form_is_rendered() {
        let s = steps(Path::new("/o"), 5, false, &table());
        assert_eq!(s.first().unwrap().name, "calibrate");
        assert_eq!(s[1].name, "forms");
        assert_eq!(s[2].name, "crowd");
        assert_eq!(s.last().unwrap().name, "paper");
        assert!(s[1].args.join(" ").contains(
            "ssbvb,ssbvb-direct,ssbvb-pixel,ssbvb-compute,ssbvb-all-compute,ssbvb-splat,\
             ssbvb-unique,esvo,esvo-compute,esvo-all-compute"
        ));
        assert!(!s[2].args.join(" ").contains("ssbvb-unique"));
        assert!(s[2].args.join(" ").contains("octree-compute"));
        let renders: Vec<&Step> = s.iter().filter(|s| s.args[0] == "render").collect();
        // Two scenes, the default and each of the six forms.
        assert_eq!(renders.len(), 14);
        assert!(
            renders
                .iter()
                .any(|r| r.args.join(" ").contains("render/bunny_raster.png"))
        );
        assert!(
            renders
                .iter()
                .all(|r| r.args.contains(&"--json".to_string()))
        );
        assert!(
            renders
                .iter()
                .any(|r| r.args.join(" ").contains("bunnies_4096.ron")
                    && r.args.join(" ").contains("ssbvb_unique.ron"))
        );
        assert!(
            s.iter()
                .all(|s| s.args.contains(&"5".to_string()) || s.args[0] == "render")
        );
        let skipped = steps(Path::new("/o"), 5, true, &table());
        assert!(skipped.iter().all(|s| s.name != "paper"));
    }
}
