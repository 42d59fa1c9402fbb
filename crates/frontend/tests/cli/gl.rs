//! The GL backend: on Mesa's GL driver (llvmpipe, which wgpu drives as OpenGL
//! ES 3.2: `ssbvb_gpu::context::prefer_gles_on_mesa`), `WGPU_BACKEND=gl ssbvb render` draws
//! what Vulkan (lavapipe) draws: the default SSBVB frame (the compute splat on both) with
//! triangles mixed in (the default scene), 64 instances, the prepass in compute
//! (`ssbvb_compute.ron`), rasterized billboards and a ray caster, byte for byte (as measured;
//! the Vulkan frames are held to the CPU reference by the GPU tests). What GL lacks and
//! what the renderer does instead is listed in `render --json` `fallbacks`. The test fails,
//! never skips, where Mesa's GL is missing (`.ci/run` and `cargo xtask test` install it).

use super::{ssbvb, stdout_json, succeeded};

#[test]
fn gl_draws_what_vulkan_draws() {
    let dir = tempfile::tempdir().unwrap();
    let cases: [(&str, Option<&str>); 5] = [
        ("assets/scenes/default.ron", None),
        (
            "assets/scenes/default.ron",
            Some("assets/pipelines/ssbvb_compute.ron"),
        ),
        ("assets/scenes/bunnies_64.ron", None),
        (
            "assets/scenes/default.ron",
            Some("assets/pipelines/ssbvb_unique.ron"),
        ),
        (
            "assets/scenes/default.ron",
            Some("assets/pipelines/esvo.ron"),
        ),
    ];
    for (i, (scene, pipeline)) in cases.iter().enumerate() {
        let frame = |backend: &str| {
            let png = dir.path().join(format!("{i}_{backend}.png"));
            let mut c = ssbvb();
            c.env("WGPU_BACKEND", backend)
                .args(["render", "--size", "64x48", "--json", scene]);
            if let Some(p) = pipeline {
                c.args(["--pipeline", p]);
            }
            let out = succeeded(c.arg("-o").arg(&png));
            let json = stdout_json(&out);
            (image::open(&png).unwrap().to_rgba8().into_raw(), json)
        };
        let (vulkan, vk_json) = frame("vulkan");
        let (gl, gl_json) = frame("gl");
        let adapter = gl_json["adapter"].as_str().unwrap_or_default();
        assert!(adapter.contains("(Gl,"), "{adapter}");
        assert!(
            vk_json["adapter"]
                .as_str()
                .unwrap_or_default()
                .contains("(Vulkan,"),
            "{vk_json}"
        );
        let fallbacks = gl_json["fallbacks"].to_string();
        assert!(
            fallbacks.contains("copies the depth") && fallbacks.contains("stencil-tested draw"),
            "{fallbacks}"
        );
        // Counted by drawing on GL, read back on Vulkan: the same pixels.
        assert!(gl_json["voxel_pixels"].as_u64().is_some(), "{gl_json}");
        assert_eq!(gl_json["voxel_pixels"], vk_json["voxel_pixels"]);
        let covered = gl.chunks(4).filter(|p| p[3] > 0).count();
        assert!(
            covered > 500,
            "{scene} {pipeline:?}: {covered} pixels drawn"
        );
        assert!(
            gl == vulkan,
            "{scene} {pipeline:?}: the GL frame differs from Vulkan's"
        );
    }
}

/// `SmoothCompute` binds the depth and the stencil aspect of one texture in one dispatch,
/// which GL cannot (its sampled aspect belongs to the texture): on GL the all-compute frame
/// is refused with a message saying so and what to use, never drawn from the wrong aspect.
#[test]
fn gl_refuses_the_compute_smoothing_and_says_why() {
    let dir = tempfile::tempdir().unwrap();
    let out = ssbvb()
        .env("WGPU_BACKEND", "gl")
        .args([
            "render",
            "--size",
            "64x48",
            "--pipeline",
            "assets/pipelines/ssbvb_all_compute.ron",
            "-o",
        ])
        .arg(dir.path().join("x.png"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{stderr}");
    assert!(
        stderr.contains("SmoothCompute") && stderr.contains("use Smooth on GL"),
        "{stderr}"
    );
    assert!(!dir.path().join("x.png").exists());
}
