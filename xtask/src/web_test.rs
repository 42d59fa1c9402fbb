//! `cargo xtask web-test` (run by `cargo xtask test`): the page built and opened in
//! headless Chromium (puppeteer-core, driven by `xtask/web_test.mjs`), each case's frame
//! read back with `window.ssbvb.readPixels()` / `readVoxelMask()` and compared with
//! `ssbvb render` of the same scene, pipeline, camera and size on the native Vulkan
//! adapter: PSNR ≥ [`MIN_PSNR_DB`] and voxel coverage IoU ≥ [`MIN_IOU`]. A model handed
//! to the page's loading path must draw voxels, a broken file must get the page's message,
//! and the browser's console must hold no error.

use std::path::{Path, PathBuf};
use std::process::Command;

use anyhow::{Context, Result, bail};

use crate::web;

/// Least PSNR of the page's frame against the native one (the bound).
const MIN_PSNR_DB: f64 = 40.0;
/// Least IoU of the page's voxel coverage against the native one.
const MIN_IOU: f64 = 0.999;
/// The frame size of every case: small, so the software adapters stay quick.
const SIZE: (u32, u32) = (200, 150);
/// puppeteer-core's version (its 24 line runs on Node 18+).
const PUPPETEER: &str = "puppeteer-core@24.43.1";

/// One page to open: (case name, scene, pipeline or `None` for the page's default).
const CASES: &[(&str, &str, Option<&str>)] = &[
    ("default", "default", None),
    ("esvo", "default", Some("esvo")),
    ("octree", "default", Some("octree")),
];

/// Runs the browser test; `Ok(false)` when a check fails.
pub fn run(root: &Path) -> Result<bool> {
    let chromium = ensure_chromium()?;
    let site = web::build(root)?;
    let work = web::target_dir(root).join("web-test");
    let out = work.join("out");
    let _ = std::fs::remove_dir_all(&out);
    std::fs::create_dir_all(&out)?;
    ensure_puppeteer(&work)?;
    std::fs::copy(root.join("xtask/web_test.mjs"), work.join("web_test.mjs"))?;
    std::fs::write(
        out.join("broken.ply"),
        b"ply\nformat nonsense\nend_header\n",
    )?;
    let server = web::Server::start(&site, 0)?;
    let cases: Vec<serde_json::Value> = CASES
        .iter()
        .map(|(name, scene, pipeline)| {
            let mut q = format!("scene={scene}&size={}x{}", SIZE.0, SIZE.1);
            if let Some(p) = pipeline {
                q.push_str(&format!("&pipeline={p}"));
            }
            serde_json::json!({ "name": name, "query": q })
        })
        .collect();
    let plan = serde_json::json!({
        "chromium": chromium,
        "base_url": server.url(),
        "out_dir": out,
        "timeout_ms": 300_000,
        "cases": cases,
        "model": { "name": "cow.obj", "path": root.join("assets/models/cow.obj"), "level": 6 },
        "bad": { "name": "broken.ply", "path": out.join("broken.ply") },
    });
    let plan_path = out.join("plan.json");
    std::fs::write(&plan_path, serde_json::to_vec_pretty(&plan)?)?;
    eprintln!("xtask: headless Chromium on {}", server.url());
    let ok = Command::new("node")
        .current_dir(&work)
        .arg("web_test.mjs")
        .arg(&plan_path)
        .status()
        .context("running node (Node.js 18 or newer is needed for the browser test)")?
        .success();
    server.stop();
    if !ok {
        bail!(
            "the browser run failed (see above; {} has what it wrote)",
            out.display()
        );
    }
    let result: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("result.json"))?)?;
    check(root, &out, &result)
}

fn check(root: &Path, out: &Path, result: &serde_json::Value) -> Result<bool> {
    let bin = native_binary(root)?;
    let mut ok = true;
    let mut fail = |what: String| {
        eprintln!("web-test: FAIL {what}");
        ok = false;
    };
    for (case, c) in CASES
        .iter()
        .zip(result["cases"].as_array().into_iter().flatten())
    {
        let (name, scene, _) = case;
        let title = c["title"].as_str().unwrap_or_default();
        if !title.starts_with("ssbvb ready") {
            fail(format!("{name}: the page says `{title}`"));
            continue;
        }
        let pipeline = c["stats"]["pipeline"]
            .as_str()
            .unwrap_or_default()
            .to_string();
        if case.2.is_none() {
            // The page's default follows the rule of `ssbvb render`: the direct form on a
            // CPU adapter (a fallback adapter, as headless Chromium's SwiftShader), else not.
            let cpu = c["stats"]["adapter_is_software"].as_bool();
            let direct = pipeline == "ssbvb_direct";
            println!("web-test: {name}: default {pipeline} on a CPU adapter: {cpu:?}");
            if cpu.is_none() || cpu != Some(direct) {
                fail(format!(
                    "{name}: default pipeline {pipeline} with adapter_is_software {cpu:?} ({})",
                    c["stats"]["pipeline_reason"]
                ));
            }
        }
        let native = render_native(&bin, root, out, name, scene, &pipeline)?;
        let page_rgba = std::fs::read(out.join(format!("{name}.rgba")))?;
        let page_mask = std::fs::read(out.join(format!("{name}.mask"))).unwrap_or_default();
        let psnr = psnr_rgb(&native.rgba, &page_rgba);
        let iou = iou(&native.mask, &page_mask);
        println!(
            "web-test: {name} ({scene}, {pipeline}, {}x{}): PSNR {psnr:.2} dB, voxel IoU {iou:.5} \
             ({} native voxel pixels); page: prepare {:.0} ms, first frame at {:.0} ms, 3 frames \
             {:.1} ms",
            SIZE.0,
            SIZE.1,
            native.mask.iter().filter(|&&m| m != 0).count(),
            c["stats"]["prepare_ms"].as_f64().unwrap_or(f64::NAN),
            c["stats"]["first_frame_ms"].as_f64().unwrap_or(f64::NAN),
            c["frames_ms"].as_f64().unwrap_or(f64::NAN),
        );
        let worker = &c["stats"]["models_prepared_in_worker"];
        let updates = &c["stats"]["progress_updates"];
        if worker.as_u64() != Some(1) || updates.as_u64().unwrap_or(0) < 2 {
            fail(format!(
                "{name}: the model was not prepared in the worker with its progress shown \
                 (models_prepared_in_worker {worker}, progress_updates {updates})"
            ));
        }
        if psnr < MIN_PSNR_DB {
            fail(format!("{name}: PSNR {psnr:.2} dB < {MIN_PSNR_DB}"));
        }
        if iou < MIN_IOU {
            fail(format!("{name}: voxel IoU {iou:.5} < {MIN_IOU}"));
        }
    }
    let model = &result["model"];
    let voxels = model["voxel_pixels"].as_u64().unwrap_or(0);
    println!(
        "web-test: loadModel(cow.obj, level 6): {}, {voxels} voxel pixels, {} ms",
        model["outcome"], model["ms"]
    );
    // The scene's bunny and then the cow, both in the worker.
    let in_worker = model["stats"]["models_prepared_in_worker"].as_u64();
    if model["outcome"] != "ok" || voxels < 100 || in_worker != Some(2) {
        fail(format!("a model handed to the page did not draw: {model}"));
    }
    let bad = &result["bad"];
    let message = bad["message"].as_str().unwrap_or_default();
    if !bad["outcome"]
        .as_str()
        .unwrap_or_default()
        .starts_with("rejected")
        || !message.contains("broken.ply")
        || !bad["title"]
            .as_str()
            .unwrap_or_default()
            .starts_with("ssbvb error:")
    {
        fail(format!(
            "a broken file did not get the page's message: {bad}"
        ));
    }
    for (case, want) in [
        ("bad size", "ssbvb error: URL parameter size:"),
        (
            "no WebGPU",
            "ssbvb error: the browser gave no WebGPU adapter",
        ),
    ] {
        let title = result["failures"]
            .as_array()
            .into_iter()
            .flatten()
            .find(|f| f["case"] == case)
            .and_then(|f| f["title"].as_str())
            .unwrap_or_default();
        if !title.starts_with(want) {
            fail(format!("{case}: the page says `{title}`, not `{want}…`"));
        }
    }
    let errors = result["console_errors"]
        .as_array()
        .cloned()
        .unwrap_or_default();
    if !errors.is_empty() {
        fail(format!("the browser's console has errors: {errors:?}"));
    }
    Ok(ok)
}

struct Native {
    rgba: Vec<u8>,
    mask: Vec<u8>,
}

/// `ssbvb render` of the case on the native adapter, with its voxel mask.
fn render_native(
    bin: &Path,
    root: &Path,
    out: &Path,
    name: &str,
    scene: &str,
    pipeline: &str,
) -> Result<Native> {
    let png = out.join(format!("{name}_native.png"));
    let mask = out.join(format!("{name}_native_mask.png"));
    let mut cmd = Command::new(bin);
    cmd.current_dir(root)
        .arg("render")
        .arg(format!("assets/scenes/{scene}.ron"))
        .arg("--pipeline")
        .arg(format!("assets/pipelines/{pipeline}.ron"))
        .args(["--size", &format!("{}x{}", SIZE.0, SIZE.1), "-o"])
        .arg(&png)
        .arg("--voxel-mask")
        .arg(&mask);
    if std::env::var_os("WGPU_BACKEND").is_none() {
        cmd.env("WGPU_BACKEND", "vulkan");
    }
    let o = cmd.output().context("running ssbvb render")?;
    if !o.status.success() {
        bail!(
            "ssbvb render for {name} failed: {}",
            String::from_utf8_lossy(&o.stderr)
        );
    }
    let rgba = image::open(&png)?.to_rgba8().into_raw();
    let mask = image::open(&mask)?
        .to_luma8()
        .into_raw()
        .into_iter()
        .map(|v| u8::from(v > 127))
        .collect();
    Ok(Native { rgba, mask })
}

/// PSNR over the RGB channels (8-bit), infinite when equal.
fn psnr_rgb(a: &[u8], b: &[u8]) -> f64 {
    if a.len() != b.len() || a.is_empty() {
        return 0.0;
    }
    let (mut sum, mut n) = (0.0f64, 0usize);
    for (pa, pb) in a.chunks_exact(4).zip(b.chunks_exact(4)) {
        for c in 0..3 {
            let d = f64::from(pa[c]) - f64::from(pb[c]);
            sum += d * d;
            n += 1;
        }
    }
    let mse = sum / n as f64;
    if mse == 0.0 {
        f64::INFINITY
    } else {
        10.0 * (255.0f64 * 255.0 / mse).log10()
    }
}

/// Intersection over union of two 0/1 masks (0 when the sizes differ or both are empty).
fn iou(a: &[u8], b: &[u8]) -> f64 {
    if a.len() != b.len() {
        return 0.0;
    }
    let both = a
        .iter()
        .zip(b)
        .filter(|(x, y)| **x != 0 && **y != 0)
        .count();
    let any = a
        .iter()
        .zip(b)
        .filter(|(x, y)| **x != 0 || **y != 0)
        .count();
    if any == 0 {
        0.0
    } else {
        both as f64 / any as f64
    }
}

/// The native `ssbvb` binary (built in the test profile the test run just used).
pub fn native_binary(root: &Path) -> Result<PathBuf> {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let ok = Command::new(cargo)
        .current_dir(root)
        .args(["build", "-p", "ssbvb", "--quiet"])
        .status()
        .context("building ssbvb")?
        .success();
    if !ok {
        bail!("cannot build the ssbvb binary");
    }
    Ok(web::target_dir(root).join("debug/ssbvb"))
}

/// Debian's Chromium (`SSBVB_CHROMIUM` names another), installed with apt when missing
/// and this is root.
fn ensure_chromium() -> Result<PathBuf> {
    if let Some(p) = std::env::var_os("SSBVB_CHROMIUM") {
        return Ok(PathBuf::from(p));
    }
    let path = PathBuf::from("/usr/bin/chromium");
    if path.is_file() {
        return Ok(path);
    }
    if Path::new("/usr/bin/apt-get").exists() && crate::system::is_root() {
        eprintln!("xtask: installing Debian's chromium for the browser test");
        let ok = Command::new("apt-get")
            .args(["install", "-y", "-qq", "chromium"])
            .env("DEBIAN_FRONTEND", "noninteractive")
            .status()
            .is_ok_and(|s| s.success());
        if ok && path.is_file() {
            return Ok(path);
        }
    }
    bail!(
        "the browser test needs Chromium: `apt-get install chromium` (Debian), or set \
         SSBVB_CHROMIUM to a Chromium or Chrome binary"
    )
}

/// puppeteer-core in `work/node_modules` (npm, once).
fn ensure_puppeteer(work: &Path) -> Result<()> {
    if work
        .join("node_modules/puppeteer-core/package.json")
        .is_file()
    {
        return Ok(());
    }
    eprintln!("xtask: npm install {PUPPETEER}");
    let ok = Command::new("npm")
        .current_dir(work)
        .args(["install", "--no-audit", "--no-fund", "--no-save", PUPPETEER])
        .status()
        .context("running npm (Node.js and npm are needed for the browser test)")?
        .success();
    if !ok {
        bail!("npm install {PUPPETEER} failed");
    }
    Ok(())
}
