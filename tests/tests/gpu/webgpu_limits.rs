//! Every bundled pipeline on a device created with WebGPU's default limits and no optional
//! feature (what a browser or a minimal driver guarantees), on the same adapter as the other
//! tests. A pipeline either fits, and then it draws exactly what it draws on the adapter's
//! own limits, with no validation error, or the requirements check refuses it up front
//! naming the limit (never a validation error in the middle of a frame). Every bundled
//! pipeline fits, so a pass that raises its needs fails here; a form that does not fit
//! (the octree casters' compute form) is refused when its pass is built. The outcome per
//! pipeline is the table in `docs/architecture.md` ("What each pass needs").

use glam::DVec3;
use ssbvb_gpu::scene::{GpuScene, SceneBindings};
use ssbvb_gpu::{GpuContext, wgpu};
use ssbvb_passes::{Profiling, Renderer};
use ssbvb_voxel::camera::Camera;

/// A device on the shared adapter with WebGPU's default limits and no optional feature, and
/// the errors wgpu reports outside error scopes.
fn minimal_device() -> (GpuContext, ssbvb_tests::UncapturedErrors) {
    ssbvb_tests::device_on_shared_adapter(
        "webgpu defaults",
        wgpu::Features::empty(),
        wgpu::Limits::default(),
    )
}

/// The output of `pipeline` (RON text) over `scene` on `ctx`, 64 × 48.
fn draw(ctx: &GpuContext, pipeline: &str, scene: ssbvb_gpu::scene::Scene) -> Vec<u8> {
    let resolved = ssbvb_graph::resolve_str(pipeline, ssbvb_tests::TEST_PIPELINE)
        .unwrap_or_else(|e| panic!("{e}"));
    let camera = Camera::new(DVec3::new(0.9, 0.5, 1.8), DVec3::ZERO);
    let mut gpu_scene = GpuScene::new(ctx, scene).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(gpu_scene.bindings, SceneBindings::SMALLEST);
    let mut renderer =
        Renderer::new(ctx, &gpu_scene, resolved, (64, 48)).unwrap_or_else(|e| panic!("{e}"));
    renderer
        .render(ctx, &mut gpu_scene, &camera, Profiling::Off)
        .unwrap_or_else(|e| panic!("{e}"));
    ctx.wait_idle().unwrap();
    let out = &renderer.output().texture;
    ctx.read_texture(out, wgpu::TextureAspect::All)
        .unwrap()
        .bytes
}

#[test]
fn every_pipeline_draws_under_webgpu_default_limits_what_it_draws_under_the_adapters() {
    let (ctx, errors) = minimal_device();
    let limits = ctx.device.limits();
    let downlevel = ctx.adapter.get_downlevel_capabilities().flags;
    let asset = ssbvb_tests::model_asset("bunny.obj", 5);
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../assets/pipelines");
    let mut names: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "ron"))
        .map(|p| p.file_stem().unwrap().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert!(names.len() >= 13, "{names:?}");
    let mut refused = Vec::new();
    for name in &names {
        let path = dir.join(format!("{name}.ron"));
        let src = std::fs::read_to_string(&path).unwrap();
        let resolved = ssbvb_graph::resolve_str(&src, &path.display().to_string())
            .unwrap_or_else(|e| panic!("{e}"));
        let verdict =
            ssbvb_passes::pipeline_requirements(&resolved).check_with(downlevel, &limits, |f| {
                ctx.adapter.get_texture_format_features(f).allowed_usages
            });
        if !verdict.fits() {
            println!("{name}: refused: {}", verdict.missing.join("; "));
            assert!(
                verdict.missing.iter().all(|m| m.contains("pass `")
                    || m.contains("scene")
                    || m.contains("resource `")),
                "{name}: a refusal that names no pass, resource or the scene: {verdict:?}"
            );
            refused.push((name.clone(), verdict.missing.join("; ")));
            continue;
        }
        let scene = || ssbvb_tests::single_object_scene(asset.clone(), 5);
        let minimal = draw(&ctx, &src, scene());
        let errs = std::mem::take(&mut *errors.lock().unwrap());
        assert!(errs.is_empty(), "{name} under WebGPU defaults: {errs:#?}");
        let full = draw(ssbvb_tests::ctx(), &src, scene());
        let covered = minimal.chunks(4).filter(|p| *p != &minimal[..4]).count();
        assert!(
            covered > 100,
            "{name}: {covered} pixels differ from the corner"
        );
        // Without the optional DEPTH32FLOAT_STENCIL8 the depth-stencil falls back to
        // Depth24PlusStencil8: depth ties between a pipeline's passes may resolve otherwise
        // (the bound: 40 dB). Every other difference is a bug.
        let psnr = ssbvb_voxel::accuracy::psnr_rgba8(&minimal, &full).unwrap();
        println!("{name}: fits, PSNR {psnr:.1} dB against the adapter-limits frame");
        assert!(psnr >= 40.0, "{name}: {psnr:.1} dB");
    }
    assert!(refused.is_empty(), "{refused:#?}");

    // The octree casters' compute form binds its hits too: 9 storage buffers, refused when
    // the pass is built, naming the limit, and no validation error.
    let esvo = std::fs::read_to_string(dir.join("esvo.ron")).unwrap();
    let compute = esvo.replace(
        "kind: EsvoRayCast(max_steps: 4096)",
        "kind: EsvoRayCast(max_steps: 4096, compute: true)",
    );
    assert_ne!(compute, esvo, "esvo.ron changed");
    let resolved = ssbvb_graph::resolve_str(&compute, "esvo compute").unwrap();
    let gpu_scene =
        GpuScene::new(&ctx, ssbvb_tests::single_object_scene(asset.clone(), 5)).unwrap();
    match Renderer::new(&ctx, &gpu_scene, resolved, (64, 48)) {
        Err(e) => {
            let text = e.to_string();
            assert!(
                text.contains("max_storage_buffers_per_shader_stage >= 9")
                    && text.contains("EsvoRayCast, compute"),
                "{text}"
            );
        }
        Ok(_) => panic!("the compute form was built under WebGPU's limits"),
    }
    ctx.wait_idle().unwrap();
    let errs = std::mem::take(&mut *errors.lock().unwrap());
    assert!(errs.is_empty(), "{errs:#?}");
    // What each kind needs beyond WebGPU's defaults (the table in docs/architecture.md).
    let scene = u64::from(ssbvb_gpu::scene::SceneBindings::SMALLEST.max_storage_buffers());
    for kind in ssbvb_passes::registered_kinds() {
        let n = ssbvb_passes::kinds::registration(&kind).unwrap().needs;
        println!(
            "{}: {:?}, {} storage buffers per stage ({scene} of the scene), {} bind groups, \
             flags {:?}, limit {:?}",
            kind.name(),
            kind.stage(),
            scene + n.storage_buffers,
            n.bind_groups,
            n.flags,
            n.limit.map(|l| (l.name, l.at_least)),
        );
        assert!(n.bind_groups <= u64::from(wgpu::Limits::default().max_bind_groups));
    }
}

/// Every registered pass kind's WGSL compiles into a shader module on the WebGPU-defaults
/// device: what the limits refuse is the binding layout, not the shader code.
#[test]
fn every_pass_kind_shader_compiles_under_webgpu_default_limits() {
    let (ctx, errors) = minimal_device();
    let kinds = ssbvb_passes::registered_kinds();
    assert!(kinds.len() >= 10, "{} registered kinds", kinds.len());
    for kind in kinds {
        let file = ssbvb_passes::kinds::registration(&kind).unwrap().shader;
        let src = ssbvb_gpu::shaders::source(file).unwrap_or_else(|e| panic!("{e}"));
        ctx.shader(file, &src)
            .unwrap_or_else(|e| panic!("{} ({file}) under WebGPU defaults: {e}", kind.name()));
    }
    ctx.wait_idle().unwrap();
    let errs = std::mem::take(&mut *errors.lock().unwrap());
    assert!(errs.is_empty(), "{errs:#?}");
}
