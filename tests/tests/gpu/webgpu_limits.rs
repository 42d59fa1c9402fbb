//! Every bundled pipeline on a device created with WebGPU's default limits and no optional
//! feature (what a browser or a minimal driver guarantees), on the same adapter as the other
//! tests. A pipeline either fits, and then every pass builds and renders a frame with no
//! validation error, or the requirements check refuses it up front naming the limit or
//! capability (never a validation error in the middle of a frame). The outcome per pipeline
//! is the table in `docs/architecture.md` ("What each pass needs").

use std::sync::{Arc, Mutex};

use glam::DVec3;
use ssbvb_gpu::scene::GpuScene;
use ssbvb_gpu::{GpuContext, wgpu};
use ssbvb_passes::{Profiling, Renderer};
use ssbvb_voxel::camera::Camera;

const PIPELINES: [&str; 9] = [
    "ssbvb",
    "ssbvb_flat",
    "ssbvb_splat",
    "ssbvb_embedded",
    "dense_dda",
    "octree_ray_cast",
    "esvo",
    "cube_raster",
    "rastavox",
];

/// A device on the shared adapter with WebGPU's default limits and no optional feature, and
/// the errors wgpu reports outside error scopes.
fn minimal_device() -> (GpuContext, Arc<Mutex<Vec<String>>>) {
    let shared = ssbvb_tests::ctx();
    let (device, queue) =
        pollster::block_on(shared.adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("webgpu defaults"),
            required_features: wgpu::Features::empty(),
            required_limits: wgpu::Limits::default(),
            ..Default::default()
        }))
        .expect("a device with WebGPU's default limits");
    let errors = Arc::new(Mutex::new(Vec::new()));
    let sink = errors.clone();
    device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
        sink.lock().unwrap().push(e.to_string());
    }));
    let ctx = GpuContext::from_parts(
        shared.instance.clone(),
        shared.adapter.clone(),
        device,
        queue,
    );
    (ctx, errors)
}

#[test]
fn each_pipeline_fits_webgpu_default_limits_or_is_refused_up_front() {
    let (ctx, errors) = minimal_device();
    let limits = ctx.device.limits();
    let downlevel = ctx.adapter.get_downlevel_capabilities().flags;
    let asset = ssbvb_tests::model_asset("bunny.obj", 5);
    let camera = Camera::new(DVec3::new(0.9, 0.5, 1.8), DVec3::ZERO);
    let mut fitting = 0;
    for name in PIPELINES {
        let path = format!(
            "{}/../assets/pipelines/{name}.ron",
            env!("CARGO_MANIFEST_DIR")
        );
        let src = std::fs::read_to_string(&path).unwrap();
        let resolved = ssbvb_graph::resolve_str(&src, &path).unwrap_or_else(|e| panic!("{e}"));
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
            continue;
        }
        let scene = ssbvb_tests::single_object_scene(asset.clone(), 5);
        let mut gpu_scene = GpuScene::new(&ctx, scene).unwrap_or_else(|e| panic!("{name}: {e}"));
        let mut renderer = Renderer::new(&ctx, &gpu_scene, resolved, (64, 48))
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        renderer
            .render(&ctx, &mut gpu_scene, &camera, Profiling::Off)
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        ctx.wait_idle().unwrap();
        let errs = std::mem::take(&mut *errors.lock().unwrap());
        assert!(errs.is_empty(), "{name} under WebGPU defaults: {errs:#?}");
        let fill = renderer.fill_count(&ctx).unwrap();
        println!("{name}: fits; fill {fill:?}");
        fitting += 1;
    }
    println!(
        "{fitting} of {} pipelines fit WebGPU's default limits",
        PIPELINES.len()
    );
    // What each kind needs beyond WebGPU's defaults (the table in docs/architecture.md).
    let scene = ssbvb_gpu::scene::SCENE_STORAGE_BUFFERS as u64;
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
