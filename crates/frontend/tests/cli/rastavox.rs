//! RastaVox from the command line: `render MODEL --pipeline assets/pipelines/rastavox.ron`,
//! the bench technique `rastavox` and `bench --preset rastavox`.

use std::path::Path;

use super::{pass_names, ssbvb, stdout_json, succeeded};

#[test]
fn rastavox_renders_a_model_and_the_default_scene() {
    let dir = tempfile::tempdir().unwrap();
    let model = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/models/bunny.obj");
    let png = dir.path().join("bunny.png");
    let out = succeeded(
        ssbvb()
            .env("SSBVB_CACHE_DIR", dir.path().join("cache"))
            .arg("render")
            .arg(&model)
            .args([
                "--level",
                "6",
                "--size",
                "96x72",
                "--camera-pos",
                "0,0.3,2.6",
            ])
            .args([
                "--pipeline",
                "assets/pipelines/rastavox.ron",
                "--json",
                "-o",
            ])
            .arg(&png),
    );
    let json = stdout_json(&out);
    let passes = pass_names(&json);
    assert!(passes.iter().any(|p| p == "rastavox"), "{passes:?}");
    // The bunny fills a good part of the frame (measured 1 941 of 6 912 pixels).
    let img = image::open(&png).unwrap().to_rgba8();
    let lit = img.pixels().filter(|p| p[3] > 0 && p[0] > 40).count();
    assert!(lit > 1000, "{lit} lit pixels");
    // The bundled default scene (bunny on a ground plane) with this pipeline.
    succeeded(
        ssbvb()
            .env("SSBVB_CACHE_DIR", dir.path().join("cache"))
            .args([
                "render",
                "--size",
                "96x72",
                "--pipeline",
                "assets/pipelines/rastavox.ron",
            ])
            .arg("-o")
            .arg(dir.path().join("scene.png")),
    );
}

#[test]
fn bench_rastavox_preset_and_technique() {
    let dir = tempfile::tempdir().unwrap();
    succeeded(
        ssbvb()
            .env("SSBVB_CACHE_DIR", dir.path().join("cache"))
            .args([
                "bench", "--preset", "rastavox", "--levels", "4,6", "--sizes", "96x72",
            ])
            .args(["--frames", "1", "--instances", "4", "--out"])
            .arg(dir.path().join("rv")),
    );
    let json: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.path().join("rv/rastavox.json")).unwrap(),
    )
    .unwrap();
    // Memory and build: 2 models x 2 levels; the surface is 4 + 8 bytes per voxel.
    let models = json["models"].as_array().unwrap();
    assert_eq!(models.len(), 4, "{models:?}");
    for m in models {
        let surface = m["surface_voxels"].as_f64().unwrap();
        let voxels = m["voxels"].as_f64().unwrap();
        assert!(surface > 100.0 && surface <= voxels, "{m}");
        let base = m["base_mib"].as_f64().unwrap() * (1 << 20) as f64;
        assert!((base - 12.0 * surface).abs() < 1.0, "{m}");
        assert!(m["lod_mib"].as_f64().unwrap() > 0.0, "{m}");
        assert!(m["build_base_ms"].as_f64().unwrap() > 0.0, "{m}");
    }
    // The sweep: 4 pixel errors on the bunny and on 4 bunnies.
    let sweep = json["sweep"].as_array().unwrap();
    assert_eq!(sweep.len(), 8, "{sweep:?}");
    for r in sweep {
        // Against the drawn model the raster is exact up to edge snapping (measured ≥ 0.999
        // here; 0.99 leaves room for the small image).
        assert!(r["coverage_iou"].as_f64().unwrap() >= 0.99, "{r}");
        assert!(r["same_voxel_rate"].as_f64().unwrap() >= 0.98, "{r}");
        if r["pixel_error"].as_f64().unwrap() == 0.0 {
            assert_eq!(r["frame_ms_ratio"].as_f64().unwrap(), 1.0, "{r}");
            assert!(r["coverage_iou_vs_finest"].as_f64().unwrap() >= 0.99, "{r}");
        }
    }
    // More pixel error never draws more voxels.
    for scene in ["bunny", "4 bunnies"] {
        let drawn: Vec<u64> = sweep
            .iter()
            .filter(|r| r["scene"] == scene)
            .map(|r| r["voxels_drawn"].as_u64().unwrap())
            .collect();
        assert_eq!(drawn.len(), 4);
        assert!(drawn.windows(2).all(|w| w[1] <= w[0]), "{scene}: {drawn:?}");
        // The near bunny's voxels project to ~2 px here: only the grid's far bunnies (the
        // grid camera looks over them) get coarser LODs.
        if scene == "4 bunnies" {
            assert!(drawn[3] < drawn[0], "{scene}: {drawn:?}");
        }
    }
    let md = std::fs::read_to_string(dir.path().join("rv/rastavox.md")).unwrap();
    assert!(md.contains("| knight | 6 |"), "{md}");
    // The technique in the main matrix.
    succeeded(
        ssbvb()
            .env("SSBVB_CACHE_DIR", dir.path().join("cache"))
            .args([
                "bench",
                "--techniques",
                "rastavox",
                "--levels",
                "5",
                "--frames",
                "1",
            ])
            .arg("--out")
            .arg(dir.path().join("main")),
    );
    let csv = std::fs::read_to_string(dir.path().join("main/bench.csv")).unwrap();
    assert_eq!(
        csv.lines().filter(|l| l.starts_with("rastavox,")).count(),
        1,
        "{csv}"
    );
}
