//! `--limits webgpu` (WebGPU's default limits and no optional feature, what a browser
//! guarantees): `adapter` lists each adapter's verdict under those limits, every bundled
//! scene renders under them as under the adapter's own, and `render` refuses up front a
//! pipeline that needs more, naming the limit and who needs it, rather than failing with a
//! validation error mid-frame. `render --json` says which limits the device was created
//! with.

use super::{ssbvb, stdout_json, succeeded};

#[test]
fn webgpu_limits_are_checked_up_front_and_named() {
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("x.png");
    // The adapter's own limits: the default, and what `--json` says. A cache of its own:
    // a calibration in the user's cache (`ssbvb calibrate`) would choose instead of the
    // rule.
    let out = succeeded(
        ssbvb()
            .env("SSBVB_CACHE_DIR", dir.path().join("cache"))
            .args([
                "render", "--size", "32x24", "--json", "--limits", "adapter", "-o",
            ])
            .arg(&png),
    );
    let json = stdout_json(&out);
    assert_eq!(json["limits"], "adapter");
    // No `--pipeline` and none in the default scene: the rule's form for this adapter
    // (lavapipe runs the frame without billboards), with the adapter and why in
    // `pipeline_choice`.
    let choice = &json["pipeline_choice"];
    assert_eq!(choice["by"], "adapter", "{json}");
    assert_eq!(choice["pipeline"], json["pipeline"], "{json}");
    assert!(
        choice["pipeline"]
            .as_str()
            .unwrap()
            .ends_with("pipelines/ssbvb_direct.ron")
            && choice["reason"]
                .as_str()
                .unwrap()
                .contains("straight into the G-buffer by the march (no SSBVB) on llvmpipe")
            && !choice["reason"].as_str().unwrap().contains("WebGPU"),
        "{json}"
    );
    // The paper's raster form is one flag away.
    let out = succeeded(
        ssbvb()
            .args(["render", "--size", "32x24", "--json", "--pipeline"])
            .arg(
                std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
                    .join("../../assets/pipelines/ssbvb_unique.ron"),
            )
            .arg("-o")
            .arg(&png),
    );
    let json = stdout_json(&out);
    assert_eq!(json["pipeline_choice"]["by"], "flag", "{json}");
    assert!(
        json["pipeline"]
            .as_str()
            .unwrap()
            .ends_with("pipelines/ssbvb_unique.ron"),
        "{json}"
    );

    // `adapter --limits webgpu`: every adapter's verdict under WebGPU's defaults; the
    // default pipeline fits them.
    let out = succeeded(ssbvb().args(["adapter", "--limits", "webgpu"]));
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        stdout.contains("under WebGPU's default limits") && stdout.contains(": fits"),
        "{stdout}"
    );

    // Every bundled scene draws under them what it draws under the adapter's limits
    // (the GPU test `webgpu_limits` holds every bundled pipeline to the same).
    let mut scenes: Vec<_> = std::fs::read_dir(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/scenes"),
    )
    .unwrap()
    .map(|e| e.unwrap().path())
    .filter(|p| p.extension().is_some_and(|x| x == "ron"))
    .collect();
    scenes.sort();
    assert!(scenes.len() >= 5, "{scenes:?}");
    for scene in &scenes {
        let frame = |limits: &str| {
            let png = dir.path().join(format!("{limits}.png"));
            let out = succeeded(
                ssbvb()
                    .args(["render", "--size", "48x36", "--json", "--limits", limits])
                    .arg(scene)
                    .arg("-o")
                    .arg(&png),
            );
            let json = stdout_json(&out);
            assert_eq!(json["limits"], limits);
            // A scene without `pipeline:` gets the rule's form, which must fit the limits
            // the device is created with (it drew), and the reason names them.
            let choice = &json["pipeline_choice"];
            if choice["by"] == "adapter" {
                let reason = choice["reason"].as_str().unwrap();
                assert_eq!(
                    reason.contains("under WebGPU's default limits"),
                    limits == "webgpu",
                    "{json}"
                );
            }
            (image::open(&png).unwrap().to_rgba8().into_raw(), json)
        };
        let ((webgpu, json), (adapter, _)) = (frame("webgpu"), frame("adapter"));
        let fallbacks = json["fallbacks"].to_string();
        if fallbacks.contains("conservative rasterization") {
            // An animated object: its exact GPU voxelization needs f64 shaders, which
            // WebGPU's defaults lack; the raster one differs at the surface (measured
            // 31.2 dB at 48x36 for the twisting bunny).
            let db = ssbvb_voxel::accuracy::psnr_rgba8(&webgpu, &adapter).unwrap();
            assert!(db >= 25.0, "{}: {db:.1} dB", scene.display());
        } else {
            assert!(
                webgpu == adapter,
                "{}: the frame under WebGPU's limits differs ({fallbacks})",
                scene.display()
            );
        }
    }

    // A pipeline that needs more (the ESVO caster in compute form also binds its hits) is
    // refused before it draws, naming the limit and the pass.
    let esvo = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/pipelines/esvo.ron"),
    )
    .unwrap();
    let compute = dir.path().join("esvo_compute.ron");
    std::fs::write(
        &compute,
        esvo.replace(
            "kind: EsvoRayCast(max_steps: 4096)",
            "kind: EsvoRayCast(max_steps: 4096, compute: true)",
        ),
    )
    .unwrap();
    std::fs::remove_file(&png).ok();
    let out = ssbvb()
        .args([
            "render",
            "--size",
            "32x24",
            "--limits",
            "webgpu",
            "--pipeline",
        ])
        .arg(&compute)
        .arg("-o")
        .arg(&png)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{stderr}");
    assert!(
        stderr.contains("max_storage_buffers_per_shader_stage >= 9")
            && stderr.contains("EsvoRayCast, compute")
            && !stderr.contains("panicked"),
        "{stderr}"
    );
    assert!(!png.exists());
}
