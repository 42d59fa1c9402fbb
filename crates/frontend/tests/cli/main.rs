//! The `ssbvb` binary as users run it: exit codes, the CLI contracts, error messages.
//! RastaVox's commands are in `rastavox.rs`.

mod animation;
mod calibrate;
mod cone_trace;
mod device_loss;
mod docs_commands;
mod engine;
mod export;
mod gl;
mod limits;
mod out_of_memory;
mod presets;
mod rastavox;
mod submissions;
mod supersample;
mod volumes;
mod voxel_mask;
mod voxelize_gpu;

use std::path::Path;
use std::process::{Command, Output};

pub(crate) fn ssbvb() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_ssbvb"));
    c.current_dir(Path::new(env!("CARGO_MANIFEST_DIR")).join("../.."));
    c.env(
        "WGPU_BACKEND",
        std::env::var("WGPU_BACKEND").unwrap_or_else(|_| "vulkan".into()),
    );
    c
}

/// Runs `cmd` and asserts that it succeeded (its stderr is the failure message).
pub(crate) fn succeeded(cmd: &mut Command) -> Output {
    let out = cmd.output().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// Checks that `pipeline` passes `pipeline check`, and that each edit of its text (`from` →
/// `to`) is refused on the line of `kind: {kind}(`, naming pass `pass` and the knob.
pub(crate) fn assert_knobs_refused(
    pipeline: &str,
    pass: &str,
    kind: &str,
    edits: &[(&str, &str, &str)],
) {
    let (ok, text) = check(pipeline);
    assert!(ok && text.contains(pass), "{text}");
    let line = line_of(pipeline, &format!("kind: {kind}("));
    for (from, to, knob) in edits {
        let src = pipeline.replacen(from, to, 1);
        assert_ne!(src, pipeline, "{from}");
        let (ok, text) = check(&src);
        assert!(!ok, "{to}: {text}");
        assert!(
            text.contains(&format!("p.ron:{line}:"))
                && text.contains(&format!("pass `{pass}` ({kind}): {knob} must be")),
            "{to}: {text}"
        );
    }
}

/// The names of the passes a `render --json` report timed, in order.
pub(crate) fn pass_names(report: &serde_json::Value) -> Vec<String> {
    report["passes"]
        .as_array()
        .expect("`passes` is an array")
        .iter()
        .map(|p| p["name"].as_str().expect("a pass has a name").to_string())
        .collect()
}

/// The one JSON object a command printed on stdout.
pub(crate) fn stdout_json(out: &Output) -> serde_json::Value {
    serde_json::from_slice(&out.stdout).expect("stdout is one JSON object")
}

const SSBVB: &str = include_str!("../../../../assets/pipelines/ssbvb_unique.ron");

fn check(src: &str) -> (bool, String) {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("p.ron");
    std::fs::write(&p, src).unwrap();
    let out = ssbvb()
        .args(["pipeline", "check"])
        .arg(&p)
        .output()
        .unwrap();
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).to_string() + &String::from_utf8_lossy(&out.stderr),
    )
}

fn line_of(src: &str, needle: &str) -> usize {
    src.lines().position(|l| l.contains(needle)).unwrap() + 1
}

#[test]
fn pipeline_check_prints_the_schedule_and_names_culprits() {
    let (ok, text) = check(SSBVB);
    assert!(ok, "{text}");
    assert!(
        text.contains("0. empty_space")
            && text.contains("5. composite")
            && text.contains("pruned passes: none"),
        "{text}"
    );

    let src = SSBVB.replace("kind: Composite,", "kind: Compsite,");
    let (ok, text) = check(&src);
    assert!(!ok);
    assert!(
        text.contains(&format!("p.ron:{}:", line_of(&src, "Compsite")))
            && text.contains("did you mean `Composite`"),
        "{text}"
    );

    let src = SSBVB.replace(
        r#"(name: "empty_space", kind: EmptySpacePrepass, writes: ["entry", "prepass_depth"]),"#,
        "",
    );
    let (ok, text) = check(&src);
    assert!(!ok);
    assert!(
        text.contains("pass `filter` reads resource `entry`, but no pass writes it"),
        "{text}"
    );
    assert!(
        text.contains(&format!("p.ron:{}:", line_of(&src, r#"reads: ["entry"]"#))),
        "{text}"
    );

    let src = SSBVB.replace(
        r#"writes: ["ssbvb", "billboard_draw"],"#,
        r#"writes: ["ssbvb", "billboard_draw"], after: ["composite"],"#,
    );
    let (ok, text) = check(&src);
    assert!(!ok);
    assert!(
        text.contains("cycle between passes")
            && text.contains("filter")
            && text.contains("composite"),
        "{text}"
    );
}

#[test]
fn bad_inputs_give_clear_errors() {
    let out = ssbvb()
        .args([
            "render",
            "/nonexistent/model.obj",
            "--reference",
            "-o",
            "/tmp/never.png",
        ])
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("/nonexistent/model.obj"));
    // Each bad size gets its own reason, not just clap's usage text.
    for (size, reason) in [
        ("0x10", "size must be 1..=16384 per side, got 0x10"),
        ("20000x10", "size must be 1..=16384 per side, got 20000x10"),
        ("64", "expected WxH, got `64`"),
        ("ax10", "bad size `ax10`"),
    ] {
        let out = ssbvb().args(["render", "--size", size]).output().unwrap();
        assert!(!out.status.success(), "{size}");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(stderr.contains(reason), "{size}: {stderr}");
    }
}

#[test]
fn render_json_and_bench_quick() {
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("r.png");
    let model = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/models/bunny.obj");
    let out = succeeded(
        ssbvb()
            .env("SSBVB_CACHE_DIR", dir.path().join("cache"))
            .arg("render")
            .arg(&model)
            .args([
                "--level",
                "5",
                "--size",
                "64x48",
                "--camera-pos",
                "0,0.3,2.6",
                "--json",
                "-o",
            ])
            .arg(&png),
    );
    let json = stdout_json(&out);
    assert_eq!(json["mode"], "gpu");
    assert!(json["adapter"].as_str().unwrap().len() > 3);
    let fill = json["ssbvb_fill_count"].as_u64().unwrap();
    assert!(fill > 100 && fill <= 64 * 48, "{fill}");
    assert!(png.is_file());

    let out = succeeded(
        ssbvb()
            .env("SSBVB_CACHE_DIR", dir.path().join("cache"))
            .args(["bench", "--preset", "quick", "--out"])
            .arg(dir.path().join("bench")),
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        stdout.contains("adapter:") && stdout.contains("| ssbvb-flat |"),
        "{stdout}"
    );
    let csv = std::fs::read_to_string(dir.path().join("bench/bench.csv")).unwrap();
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let rows: Vec<&str> = csv.lines().skip(1).collect();
    // Lavapipe's `ssbvb` is the direct form: its hits go straight into the G-buffer, so no
    // slot names a pixel's voxel (the GPU test `ray_march_gbuffer` holds its G-buffer to
    // the pixel form's, bit for bit).
    let bench_json: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.path().join("bench/bench.json")).unwrap(),
    )
    .unwrap();
    let default_is_direct = bench_json["pipeline_choice"]["pipeline"]
        .as_str()
        .unwrap()
        .ends_with("ssbvb_direct.ron");
    // 12 techniques (those not left out unless named) x 2 levels.
    assert_eq!(rows.len(), 24, "{csv}");
    let flip_of = |technique: &str, level: &str| -> f64 {
        let r: Vec<&str> = csv
            .lines()
            .find(|l| {
                let c: Vec<&str> = l.split(',').collect();
                c[col("technique")] == technique && c[col("level")] == level
            })
            .unwrap()
            .split(',')
            .collect();
        r[col("flip_mean")].parse().unwrap()
    };
    for r in rows {
        let r: Vec<&str> = r.split(',').collect();
        let num = |name: &str| -> Option<f64> { r[col(name)].parse().ok() };
        let iou = num("coverage_iou").unwrap();
        let depth = num("depth_error_voxels_median").unwrap();
        let normal = num("normal_error_deg_median").unwrap();
        let (psnr, ssim) = (num("psnr_db").unwrap(), num("ssim").unwrap());
        let flip = num("flip_mean").unwrap();
        // Bounds from this preset's measurements on lavapipe (docs/benchmarks.md) with a
        // margin. Every technique shades with the stored normal and reports the entered face
        // as its geometric normal (normal error 0.00°). Exact techniques (ray-box
        // billboards, ray casters, cubes, RastaVox at pixel error 0): IoU 1.0, depth ~1e-6
        // voxel, PSNR 39.7-40.3 / SSIM 0.991+ (the bench pipelines smooth normals, the
        // reference does not; 15.5 dB when they shaded with face normals). Flat billboards:
        // IoU 0.9976+, depth half a voxel (quads at the voxel centre), PSNR 26.9+, SSIM
        // 0.957+.
        if r[col("technique")] == "ssbvb-aa" {
            // Temporal anti-aliasing: its G-buffer is a jittered frame's, up to half a
            // pixel off the reference's rays (measured IoU 0.9914+, PSNR 23.4+ against the
            // one-sample reference; depth on the voxel's face, not its centre: median 0.016
            // and 0.036 voxel at levels 5, 6); against the 16-sample reference it is nearer
            // than the one-sample frame (measured FLIP 0.36x and 0.40x of it at levels 5,
            // 6; the issue's target 0.6x).
            assert!(iou >= 0.98 && depth <= 0.1, "{r:?}");
            assert!(psnr >= 21.0 && ssim >= 0.92, "{r:?}");
            let unique = flip_of("ssbvb-unique", r[col("level")]);
            assert!(
                flip < 0.6 * unique,
                "{r:?}: FLIP {flip} against ssbvb-unique's {unique}"
            );
        } else if matches!(
            r[col("technique")],
            "ssbvb-flat" | "ssbvb-unique" | "ssbvb-splat"
        ) {
            assert!(iou >= 0.995, "{r:?}");
            assert!((0.45..=0.55).contains(&depth), "{r:?}");
            assert!(normal <= 1.0, "{r:?}");
            assert!(psnr >= 25.0 && ssim >= 0.94, "{r:?}");
            assert!((0.025..=0.065).contains(&flip), "{r:?}");
        } else {
            assert!(iou >= 0.999, "{r:?}");
            assert!(depth <= 1e-3 && normal <= 0.5, "{r:?}");
            assert!(psnr >= 36.0 && ssim >= 0.98, "{r:?}");
            // One sample per pixel against the 16-sample reference: the aliasing alone
            // (measured 0.0357-0.0388); the flat billboards add their own (0.040-0.050).
            assert!((0.025..=0.05).contains(&flip), "{r:?}");
        }
        // Voxel ids per pixel come from the filter's slots: every SSBVB row has them
        // (measured 1.0; the unique-voxel rows over the pixels that claimed a voxel), the
        // ray casters and rasterizers leave the column empty.
        match (r[col("technique")], num("same_voxel_rate")) {
            // A jittered frame's slots are its own rays' voxels (measured 0.55 and 0.58).
            ("ssbvb-aa", Some(same)) => assert!(same >= 0.4, "{r:?}"),
            (t, Some(same)) if t.starts_with("ssbvb") => assert!(same >= 0.999, "{r:?}"),
            ("ssbvb", None) if default_is_direct => {}
            (t, None) if t.starts_with("ssbvb") => panic!("no same-voxel rate: {r:?}"),
            (_, same) => assert_eq!(same, None, "{r:?}"),
        }
        // The SSBVB draws one billboard per covered pixel (up to silhouette rays), or with
        // unique_voxels one per visible voxel (fewer: cells span more than a pixel here).
        let technique = r[col("technique")];
        if technique.starts_with("ssbvb") {
            let fill: f64 = r[col("fill_count")].parse().unwrap();
            let covered: f64 = r[col("covered_pixels")].parse().unwrap();
            if matches!(technique, "ssbvb-unique" | "ssbvb-splat") {
                assert!(fill < covered * 0.9 && fill > 0.0, "{r:?}");
            } else {
                assert!((fill / covered - 1.0).abs() < 0.01, "{r:?}");
            }
        }
    }
    assert!(
        stdout.contains("## Fastest technique per cell: bunny.obj"),
        "{stdout}"
    );
}

#[test]
fn bench_quick_sweep_writes_sweeps_and_plots() {
    let dir = tempfile::tempdir().unwrap();
    let out = succeeded(
        ssbvb()
            .env("SSBVB_CACHE_DIR", dir.path().join("cache"))
            .args(["bench", "--preset", "quick", "--sweep", "--out"])
            .arg(dir.path().join("bench")),
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("## Knob sweeps"), "{stdout}");
    let csv = std::fs::read_to_string(dir.path().join("bench/sweeps.csv")).unwrap();
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let rows: Vec<Vec<&str>> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    // Six knobs (the quick preset's values), at 160x120.
    assert_eq!(rows.len(), 17, "{csv}");
    for (knob, values) in [
        ("max_steps", 3),
        ("size_scale", 3),
        ("max_i", 3),
        ("min_dist", 3),
        ("resolution_scale", 2),
        ("lod_bias", 3),
    ] {
        let n = rows.iter().filter(|r| r[col("knob")] == knob).count();
        assert_eq!(n, values, "{knob}: {csv}");
    }
    // The filter at half resolution still finds most of the bunny (its cells span about
    // 2 px here), and finds fewer slots than at full resolution.
    let scale = |v: &str| {
        rows.iter()
            .find(|r| r[col("knob")] == "resolution_scale" && r[col("value")] == v)
            .unwrap()
    };
    let (half, full) = (scale("0.5"), scale("1"));
    let iou: f64 = half[col("coverage_iou")].parse().unwrap();
    assert!(iou >= 0.8, "{csv}");
    let fill = |r: &Vec<&str>| r[col("fill_count")].parse::<u64>().unwrap();
    assert!(fill(half) * 3 < fill(full), "{csv}");
    for r in &rows {
        assert_eq!((r[col("width")], r[col("height")]), ("160", "120"), "{csv}");
        let ms: f64 = r[col("frame_ms_median")].parse().unwrap();
        assert!(ms > 0.0, "{csv}");
        let iou: f64 = r[col("coverage_iou")].parse().unwrap();
        assert!((0.0..=1.0).contains(&iou), "{csv}");
    }
    // The default pipeline matches the reference closely, with a finite shaded PSNR.
    let default = rows
        .iter()
        .find(|r| r[col("knob")] == "max_steps" && r[col("is_default")] == "true")
        .unwrap();
    // Measured on lavapipe: IoU 0.9990, PSNR 29.9 dB, SSIM 0.979.
    let iou: f64 = default[col("coverage_iou")].parse().unwrap();
    assert!(iou >= 0.995, "{csv}");
    let psnr: f64 = default[col("psnr_db")].parse().unwrap();
    assert!(psnr >= 27.0, "{csv}");
    // SSIM falls when the march is cut short (holes in the bunny).
    let ssim = |r: &Vec<&str>| r[col("ssim")].parse::<f64>().unwrap();
    let short = rows
        .iter()
        .find(|r| r[col("knob")] == "max_steps" && r[col("value")] == "8")
        .unwrap();
    assert!(ssim(default) > 0.95 && ssim(default) <= 1.0, "{csv}");
    assert!(ssim(short) < ssim(default) - 0.05, "{csv}");
    let json: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.path().join("bench/bench.json")).unwrap(),
    )
    .unwrap();
    assert_eq!(json["sweeps"].as_array().unwrap().len(), 17);
    for png in ["time_vs_level.png", "trade_max_steps.png"] {
        let bytes = std::fs::read(dir.path().join("bench").join(png)).unwrap();
        assert!(bytes.starts_with(b"\x89PNG"), "{png}");
    }
}

/// A copy of the binary outside the source tree (its assets forced to the embedded copy)
/// renders the default scene, quietly on a headless machine (no window-system probe lines),
/// and a scene without `pipeline:` in any folder uses the default pipeline.
#[test]
fn relocated_binary_renders_the_bundled_scene_quietly() {
    let dir = tempfile::tempdir().unwrap();
    let bin = dir.path().join("bin/ssbvb");
    std::fs::create_dir_all(bin.parent().unwrap()).unwrap();
    std::fs::copy(env!("CARGO_BIN_EXE_ssbvb"), &bin).unwrap();
    let cache = dir.path().join("cache");
    let run = |args: &[&str]| {
        let out = Command::new(&bin)
            .current_dir(dir.path())
            .env("SSBVB_ASSETS_DIR", "bundled")
            .env("SSBVB_CACHE_DIR", &cache)
            .env(
                "WGPU_BACKEND",
                std::env::var("WGPU_BACKEND").unwrap_or_else(|_| "vulkan".into()),
            )
            .env_remove("XDG_RUNTIME_DIR")
            .args(args)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr).to_string();
        assert!(out.status.success(), "{args:?}: {stderr}");
        assert!(
            !stderr.contains("XDG_RUNTIME_DIR") && !stderr.contains("error"),
            "{args:?} printed to stderr: {stderr}"
        );
        serde_json::from_slice::<serde_json::Value>(&out.stdout).expect("one JSON object")
    };
    let json = run(&["render", "--size", "64x48", "--json", "-o", "default.png"]);
    let pipeline = json["pipeline"].as_str().unwrap();
    assert!(
        pipeline.starts_with(&cache.display().to_string()) && pipeline.contains("bundled-assets"),
        "{pipeline}"
    );
    assert!(json["ssbvb_fill_count"].as_u64().unwrap() > 50, "{json}");
    assert!(dir.path().join("default.png").is_file());

    let elsewhere = dir.path().join("some/other/folder");
    std::fs::create_dir_all(&elsewhere).unwrap();
    let bunny = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/models/bunny.obj");
    std::fs::write(
        elsewhere.join("scene.ron"),
        format!(
            "Scene(objects: [(model: {:?}, level: 4, lod: Fixed(4))])",
            bunny.canonicalize().unwrap()
        ),
    )
    .unwrap();
    let json = run(&[
        "render",
        "some/other/folder/scene.ron",
        "--size",
        "32x24",
        "--json",
        "-o",
        "other.png",
    ]);
    // No `pipeline:` in the scene: the adapter's default form (lavapipe's: the direct
    // form), from the bundled copy too.
    let pipeline = json["pipeline"].as_str().unwrap();
    assert!(
        pipeline.ends_with("pipelines/ssbvb_direct.ron")
            || pipeline.ends_with("pipelines/ssbvb_pixel.ron"),
        "{json}"
    );
    assert_eq!(json["pipeline_choice"]["by"], "adapter", "{json}");
}

/// `ssbvb adapter` gives every adapter a verdict (lavapipe and Mesa's GL both fit: the GL
/// backend runs the default pipeline, CLI test `gl`); a forced backend with no adapter here
/// gets one clear error with the fix, never a validation error.
#[test]
fn adapters_are_checked_before_use() {
    let out = ssbvb().arg("adapter").output().unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(stdout.contains("[Vulkan, Cpu]: fits"), "{stdout}");
    assert!(stdout.contains("chosen: "), "{stdout}");
    let out = succeeded(ssbvb().env("WGPU_BACKEND", "gl").arg("adapter"));
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("[Gl, Cpu]: fits"), "{stdout}");
    let out = ssbvb()
        .env("WGPU_BACKEND", "dx12")
        .args(["render", "--size", "32x24", "-o"])
        .arg(tempfile::tempdir().unwrap().path().join("x.png"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(!stderr.contains("validation"), "{stderr}");
    assert!(
        stderr.contains("mesa-vulkan-drivers libvulkan1"),
        "{stderr}"
    );
}

/// No far plane by default: a bunny 1e4 units away still renders; `--far` below its
/// distance clips it and the report says why; bad planes are refused.
#[test]
fn near_and_far_planes() {
    let dir = tempfile::tempdir().unwrap();
    let model = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/models/bunny.obj");
    let render = |extra: &[&str]| {
        let out = ssbvb()
            .env("SSBVB_CACHE_DIR", dir.path().join("cache"))
            .arg("render")
            .arg(&model)
            .args(["--level", "5", "--size", "48x36", "--json", "-o"])
            .arg(dir.path().join("far.png"))
            // 1e4 units away through a lens that the bunny fills.
            .args(["--camera-pos", "0,0,10000", "--fov-y", "0.015"])
            .args(extra)
            .output()
            .unwrap();
        (
            out.status.success(),
            serde_json::from_slice::<serde_json::Value>(&out.stdout).ok(),
            String::from_utf8_lossy(&out.stderr).to_string(),
        )
    };
    let (ok, json, err) = render(&[]);
    assert!(ok, "{err}");
    let json = json.unwrap();
    assert!(json["covered_pixels"].as_u64().unwrap() > 300, "{json}");
    assert_eq!(json["warnings"].as_array().unwrap().len(), 0, "{json}");
    let (ok, json, err) = render(&["--far", "1000"]);
    assert!(ok, "{err}");
    let json = json.unwrap();
    assert_eq!(json["covered_pixels"].as_u64().unwrap(), 0, "{json}");
    let w = json["warnings"][0].as_str().unwrap();
    assert!(w.contains("beyond the far plane (1000)"), "{w}");
    for (flags, reason) in [
        (&["--near", "0"][..], "--near must be a positive number"),
        (&["--far", "-1"][..], "--far must be a distance"),
        (
            &["--near", "5", "--far", "2"][..],
            "far plane (2) must be beyond the near plane (5)",
        ),
    ] {
        let (ok, _, err) = render(flags);
        assert!(!ok && err.contains(reason), "{flags:?}: {err}");
    }
}

/// The paper's scene in small (`bunnies_64.ron`): `render --json` reports the per-level
/// histogram of the visible instances and the filter's counters, and the filter tests a
/// few boxes per ray rather than every visible instance: fewer by its tile's list (the
/// default) than by the walk over the hierarchy (`--instance-walk hierarchy`), which draws
/// the same image.
#[test]
fn bunny_grid_scene_reports_levels_and_counters() {
    let dir = tempfile::tempdir().unwrap();
    let render = |walk: &str| {
        let png = dir.path().join(format!("grid_{walk}.png"));
        let out = succeeded(
            ssbvb()
                .env("SSBVB_CACHE_DIR", dir.path().join("cache"))
                .args([
                    "render",
                    "assets/scenes/bunnies_64.ron",
                    "--size",
                    "96x72",
                    "--json",
                    "--instance-walk",
                    walk,
                    "-o",
                ])
                .arg(&png),
        );
        (stdout_json(&out), std::fs::read(&png).unwrap())
    };
    let (json, image) = render("lists");
    let (walked, walked_image) = render("hierarchy");
    assert!(image == walked_image, "the walks drew different images");
    let visible = json["visible_instances"].as_u64().unwrap();
    assert!(visible >= 40, "{json}");
    let levels = json["lod_histogram"].as_object().unwrap();
    let total: u64 = levels.values().map(|v| v.as_u64().unwrap()).sum();
    assert_eq!(total, visible, "{json}");
    assert!(
        levels.len() >= 2,
        "near and far bunnies take different levels: {json}"
    );
    assert!(
        levels.keys().all(|l| l.parse::<u32>().unwrap() <= 7),
        "{json}"
    );
    let c = &json["counters"];
    let rays = c["filter_rays"].as_u64().unwrap();
    let fill = json["ssbvb_fill_count"].as_u64().unwrap();
    // The direct form (lavapipe's default) writes its hits straight into the G-buffer: no
    // billboard; the pixel form draws one entry per filled slot.
    if json["pipeline"]
        .as_str()
        .unwrap()
        .ends_with("ssbvb_direct.ron")
    {
        assert!(c["billboards_drawn"].is_null(), "{json}");
    } else {
        assert_eq!(c["billboards_drawn"].as_u64(), Some(fill), "{json}");
    }
    assert!(rays >= fill && fill > 1000, "{json}");
    let boxes = c["instance_boxes_per_ray"].as_f64().unwrap();
    let walked_boxes = walked["counters"]["instance_boxes_per_ray"]
        .as_f64()
        .unwrap();
    // Measured on lavapipe: 7.8 by the lists, 16.7 by the hierarchy.
    assert!(boxes > 1.0 && boxes < 0.7 * walked_boxes, "{json} {walked}");
    assert!(walked_boxes < visible as f64 / 2.0, "{walked}");
    assert!(c["march_steps_mean"].as_f64().unwrap() >= 1.0, "{json}");
    assert!(c["march_steps_p99"].as_u64().unwrap() >= 1, "{json}");
}

/// `bench --preset scale` in small: a row per technique and view with the counters, the
/// instance count and the IoU against the reference, and the three output files.
/// `--preset paper` (CLI contract): every model of `assets/models/` in the matrix, then the
/// 4096-bunny grid, compared in paper.csv with each SSBVB frame over each ray caster's.
#[test]
fn levels_above_13_are_refused_with_the_limit_named() {
    let out = ssbvb()
        .args([
            "voxelize",
            "assets/models/bunny.obj",
            "--level",
            "14",
            "--no-cache",
        ])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(
        text.contains("level 14") && text.contains("maximum level 13"),
        "{text}"
    );
}

/// `render --gpu-budget`: frames until no page is missing, the `streaming` report of the
/// CLI contract, and the same image as without a budget; bad budgets are clear errors.
#[test]
fn render_under_a_gpu_budget_converges_to_the_unbudgeted_image() {
    let dir = tempfile::tempdir().unwrap();
    let model = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/models/bunny.obj");
    let render = |extra: &[&str], png: &str| {
        let out = ssbvb()
            .env("SSBVB_CACHE_DIR", dir.path().join("cache"))
            .arg("render")
            .arg(&model)
            .args([
                "--level",
                "7",
                "--size",
                "96x72",
                "--camera-pos",
                "0.5,0.3,1.2",
                "--json",
                "-o",
            ])
            .arg(dir.path().join(png))
            .args(extra)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr).to_string();
        let json = serde_json::from_slice::<serde_json::Value>(&out.stdout).ok();
        (out.status.success(), json, stderr)
    };
    let (ok, full, err) = render(&[], "full.png");
    assert!(ok, "{err}");
    let full = full.unwrap();
    assert!(full["streaming"].is_null(), "{full}");
    let (ok, budget, err) = render(&["--gpu-budget", "1"], "budget.png");
    assert!(ok, "{err}");
    let budget = budget.unwrap();
    let s = &budget["streaming"];
    let frames = s["frames_to_converge"].as_u64().unwrap();
    assert!((2..=64).contains(&frames), "{s}");
    assert_eq!(s["converged"], true, "{s}");
    let resident = s["pages_resident"].as_u64().unwrap();
    let streamed = s["pages_streamed"].as_u64().unwrap();
    assert!(resident > 10 && streamed >= resident, "{s}");
    assert!(resident < s["pages_total"].as_u64().unwrap(), "{s}");
    let bytes = s["bytes_resident"].as_u64().unwrap();
    assert!(
        bytes > s["fixed_bytes"].as_u64().unwrap() && bytes <= 1 << 20,
        "{s}"
    );
    assert_eq!(budget["voxel_pixels"], full["voxel_pixels"]);
    assert!(full["voxel_pixels"].as_u64().unwrap() > 1000, "{full}");
    let png = |n: &str| std::fs::read(dir.path().join(n)).unwrap();
    assert!(png("full.png") == png("budget.png"), "the images differ");

    let (ok, _, err) = render(&["--gpu-budget", "0"], "zero.png");
    assert!(!ok && err.contains("--gpu-budget must be"), "{err}");
    let (ok, _, err) = render(
        &[
            "--gpu-budget",
            "1",
            "--pipeline",
            "assets/pipelines/octree.ron",
        ],
        "octree.png",
    );
    assert!(
        !ok && err.contains("cannot run under a GPU budget"),
        "{err}"
    );
}

/// `render --frames N`: a soak along an orbit reports memory after the warm-up and at the
/// end; a frame that leaked a buffer would show in the counts.
#[test]
fn render_frames_soaks_and_reports_memory() {
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("soak.png");
    let out = ssbvb()
        .args([
            "render", "--size", "64x48", "--frames", "60", "--json", "-o",
        ])
        .arg(&png)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    let r = stdout_json(&out);
    let s = &r["soak"];
    assert_eq!(s["frames"], 60, "{s}");
    assert_eq!(s["camera_path"], "orbit");
    assert_eq!(
        (s["start"]["frame"].as_u64(), s["end"]["frame"].as_u64()),
        (Some(10), Some(60))
    );
    assert!(
        s["start"]["buffers"].as_u64().unwrap() > 0,
        "the device counts nothing: {s}"
    );
    for key in ["gpu_bytes", "buffers", "bind_groups"] {
        assert_eq!(s["start"][key], s["end"][key], "{key}: {s}");
    }
    assert_eq!(s["samples"].as_array().unwrap().len(), 10, "{s}");
    let rss = s["rss_growth_percent"].as_f64().unwrap();
    assert!(rss.abs() < 10.0, "{s}");
    assert!(png.exists());
    // Without --frames there is no soak; --frames 0 and a soak of the reference are refused.
    let out = ssbvb()
        .args(["render", "--size", "32x24", "--json", "-o"])
        .arg(&png)
        .output()
        .unwrap();
    let r = stdout_json(&out);
    assert!(r["soak"].is_null());
    for (args, want) in [
        (&["--frames", "0"][..], "--frames"),
        (
            &["--frames", "5", "--reference"][..],
            "does not apply to --reference",
        ),
    ] {
        let out = ssbvb()
            .arg("render")
            .args(args)
            .arg("-o")
            .arg(&png)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            !out.status.success() && err.contains(want),
            "{args:?}: {err}"
        );
    }
}
