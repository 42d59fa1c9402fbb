//! Harness of the cross-crate GPU tests: one shared device per test binary, assets from
//! the repository's test models (prepared once per process), renders of a pipeline with readback of
//! any live resource, and the CPU reference of the same view.

use std::collections::HashMap;
use std::path::PathBuf;
use std::sync::{Arc, Mutex, OnceLock};

use glam::{DAffine3, DMat3, DQuat, DVec3};
use ssbvb_gpu::scene::{GpuScene, LodPolicy, Scene, StreamChunks};
use ssbvb_gpu::{ContextOptions, GpuContext, wgpu};
use ssbvb_passes::runtime::resources::FrameResource;
use ssbvb_passes::{Profiling, Renderer};
use ssbvb_voxel::asset::VoxelAsset;
use ssbvb_voxel::camera::Camera;
use ssbvb_voxel::reference::{self, ReferenceImage};

/// The device shared by every test of this binary. No adapter is a failure with
/// instructions, never a skip.
pub fn ctx() -> &'static GpuContext {
    static CTX: OnceLock<GpuContext> = OnceLock::new();
    CTX.get_or_init(|| {
        // Only for a GL run (`cargo xtask test` runs `core_frames` so): the Vulkan run's
        // environment stays as the user set it.
        if std::env::var("WGPU_BACKEND").is_ok_and(|b| b.to_ascii_lowercase().contains("gl")) {
            // SAFETY: before the binary's first device: no test thread has reached the
            // driver (they all wait here), and none sets the environment.
            unsafe { ssbvb_gpu::context::prefer_gles_on_mesa() };
        }
        let c =
            GpuContext::new_headless(&ContextOptions::default()).unwrap_or_else(|e| panic!("{e}"));
        eprintln!("adapter: {}", c.report());
        c
    })
}

/// Errors wgpu reported outside error scopes on a device of [`device_on_shared_adapter`].
pub type UncapturedErrors = Arc<Mutex<Vec<String>>>;

/// A second device on the shared adapter (a test of what another device does: fewer
/// features, WebGPU's limits) with `features` and `limits`, and the errors it reports
/// outside error scopes.
pub fn device_on_shared_adapter(
    label: &str,
    features: wgpu::Features,
    limits: wgpu::Limits,
) -> (GpuContext, UncapturedErrors) {
    let shared = ctx();
    let (device, queue) =
        pollster::block_on(shared.adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some(label),
            required_features: features,
            required_limits: limits,
            ..Default::default()
        }))
        .unwrap_or_else(|e| panic!("a device `{label}` on the shared adapter: {e}"));
    let errors: UncapturedErrors = Arc::new(Mutex::new(Vec::new()));
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

/// The repository's test models, `assets/models` (fails the test when it is missing).
pub fn models_dir() -> PathBuf {
    let p = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../assets/models"));
    assert!(p.is_dir(), "test models folder {} is missing", p.display());
    p
}

/// The asset of a test model file (`assets/models`) at `level`, prepared once per process.
pub fn model_asset(file: &str, level: u32) -> Arc<VoxelAsset> {
    type AssetCache = Mutex<HashMap<(String, u32), Arc<VoxelAsset>>>;
    static CACHE: OnceLock<AssetCache> = OnceLock::new();
    let cache = CACHE.get_or_init(Default::default);
    if let Some(a) = cache.lock().unwrap().get(&(file.to_string(), level)) {
        return a.clone();
    }
    let path = models_dir().join(file);
    let model = ssbvb_voxel::load::load_model(&path).unwrap_or_else(|e| panic!("{e}"));
    let (asset, _) =
        ssbvb_voxel::prepare::prepare_asset(&model, level, &ssbvb_voxel::progress::NoProgress)
            .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let asset = Arc::new(asset);
    cache
        .lock()
        .unwrap()
        .insert((file.to_string(), level), asset.clone());
    asset
}

/// Three instances of one object that overlap on screen from
/// `(0.5, 1.4, 4.2)` looking at `(0.1, 0, 0)`: the identity, one turned and scaled, and one
/// mirrored (a negative scale on x).
pub fn three_overlapping_instances() -> Vec<DAffine3> {
    vec![
        DAffine3::IDENTITY,
        DAffine3::from_mat3_translation(
            DMat3::from_quat(DQuat::from_rotation_y(1.1)) * 0.7,
            DVec3::new(1.2, 0.2, -0.8),
        ),
        DAffine3::from_mat3_translation(
            DMat3::from_diagonal(DVec3::new(-0.6, 0.6, 0.6)),
            DVec3::new(-0.9, -0.3, 0.7),
        ),
    ]
}

/// A scene with one asset placed once with its object space as world space.
pub fn single_object_scene(asset: Arc<VoxelAsset>, level: u32) -> Scene {
    Scene {
        objects: vec![ssbvb_gpu::scene::VoxelObject {
            asset,
            instances: vec![DAffine3::IDENTITY],
            lod: LodPolicy::Fixed(level),
        }],
        ..Default::default()
    }
}

/// A rendered frame and what produced it.
pub struct Frame {
    /// The renderer (its resources hold every live resource of the pipeline).
    pub renderer: Renderer,
    /// The scene on the GPU.
    pub scene: GpuScene,
}

/// Renders one frame of `scene` with the pipeline text `pipeline` at `size`.
pub fn render(pipeline: &str, scene: Scene, camera: &Camera, size: (u32, u32)) -> Frame {
    render_with_chunks(pipeline, scene, camera, size, StreamChunks::default())
}

/// [`render`] with the scene's streams split into bindings of the given sizes.
pub fn render_with_chunks(
    pipeline: &str,
    scene: Scene,
    camera: &Camera,
    size: (u32, u32),
    chunks: StreamChunks,
) -> Frame {
    render_set_up(pipeline, scene, camera, size, chunks, |_| {})
}

/// [`render`] with rays finding the instances they may meet by their screen tile's list
/// (`instance_lists`, the default) or by the walk over the instance hierarchy.
pub fn render_walking(
    pipeline: &str,
    scene: Scene,
    camera: &Camera,
    size: (u32, u32),
    instance_lists: bool,
) -> Frame {
    render_set_up(
        pipeline,
        scene,
        camera,
        size,
        StreamChunks::default(),
        |s| s.instance_lists = instance_lists,
    )
}

/// The name test pipelines are resolved under: a file of the bundled pipelines' folder, so
/// a text that includes a bundled file (`include: ["ssbvb_compute.ron"]`) reads it.
pub const TEST_PIPELINE: &str =
    concat!(env!("CARGO_MANIFEST_DIR"), "/../assets/pipelines/test.ron");

fn render_set_up(
    pipeline: &str,
    scene: Scene,
    camera: &Camera,
    size: (u32, u32),
    chunks: StreamChunks,
    set_up: impl FnOnce(&mut GpuScene),
) -> Frame {
    let c = ctx();
    let resolved =
        ssbvb_graph::resolve_str(pipeline, TEST_PIPELINE).unwrap_or_else(|e| panic!("{e}"));
    let mut gpu_scene = GpuScene::with_chunks(c, scene, chunks).unwrap_or_else(|e| panic!("{e}"));
    set_up(&mut gpu_scene);
    let mut renderer =
        Renderer::new(c, &gpu_scene, resolved, size).unwrap_or_else(|e| panic!("{e}"));
    // Tests read the counters; `ray_march_filter::uncounted_frames_draw_the_same` holds the
    // uncounted variant to the same output.
    renderer.set_counting(true);
    renderer
        .render(c, &mut gpu_scene, camera, Profiling::Off)
        .unwrap_or_else(|e| panic!("{e}"));
    c.wait_idle().unwrap();
    let errs = c.take_uncaptured_errors();
    assert!(errs.is_empty(), "wgpu errors: {errs:#?}");
    Frame {
        renderer,
        scene: gpu_scene,
    }
}

/// One uncounted frame of `scene` with the pipeline text `pipeline` at `size` on `ctx` (a
/// second device on the shared adapter, whose errors its maker collects; read the frame's
/// resources with `ctx`, not with [`Frame::read`], which reads the shared device's).
pub fn render_on(
    ctx: &GpuContext,
    pipeline: &str,
    scene: Scene,
    camera: &Camera,
    size: (u32, u32),
) -> Frame {
    let resolved =
        ssbvb_graph::resolve_str(pipeline, TEST_PIPELINE).unwrap_or_else(|e| panic!("{e}"));
    let mut gpu_scene = GpuScene::new(ctx, scene).unwrap_or_else(|e| panic!("{e}"));
    let mut renderer =
        Renderer::new(ctx, &gpu_scene, resolved, size).unwrap_or_else(|e| panic!("{e}"));
    renderer
        .render(ctx, &mut gpu_scene, camera, Profiling::Off)
        .unwrap_or_else(|e| panic!("{e}"));
    ctx.wait_idle().unwrap();
    Frame {
        renderer,
        scene: gpu_scene,
    }
}

impl Frame {
    /// Bytes of a live resource (texture: tightly packed rows; depth-stencil: depth aspect).
    pub fn read(&self, name: &str) -> Vec<u8> {
        let i = self
            .renderer
            .resource(name)
            .unwrap_or_else(|| panic!("resource `{name}` is not live"));
        match self.renderer.resources.get(i) {
            FrameResource::Buffer(b) => ctx().read_buffer(b).unwrap(),
            FrameResource::Texture(t) => {
                let aspect = if t.texture.format().is_depth_stencil_format() {
                    wgpu::TextureAspect::DepthOnly
                } else {
                    wgpu::TextureAspect::All
                };
                ctx().read_texture(&t.texture, aspect).unwrap().bytes
            }
        }
    }

    /// The stencil aspect of a live depth-stencil texture, one byte per pixel.
    pub fn read_stencil(&self, name: &str) -> Vec<u8> {
        let i = self
            .renderer
            .resource(name)
            .unwrap_or_else(|| panic!("resource `{name}` is not live"));
        let t = self.renderer.resources.texture(i);
        ctx()
            .read_texture(&t.texture, wgpu::TextureAspect::StencilOnly)
            .unwrap()
            .bytes
    }

    /// A live texture as f32s.
    pub fn read_f32(&self, name: &str) -> Vec<f32> {
        bytemuck::pod_collect_to_vec(&self.read(name))
    }

    /// A live resource as u32s.
    pub fn read_u32(&self, name: &str) -> Vec<u32> {
        bytemuck::pod_collect_to_vec(&self.read(name))
    }
}

/// The CPU reference of `scene` seen by `camera` at `size`, each instance at the level the
/// renderer chooses for it (`choose_level`, per instance under `Auto`).
pub fn reference_of(scene: &Scene, camera: &Camera, size: (u32, u32)) -> ReferenceImage {
    let mut instances = Vec::new();
    for o in &scene.objects {
        let max = o.asset.lods.len() as u32 - 1;
        for xf in &o.instances {
            let level = ssbvb_gpu::scene::choose_level(o.lod, xf, camera, size, max);
            instances.push(reference::Instance {
                lod: &o.asset.lods[level as usize],
                object_to_world: *xf,
                faces: None,
            });
        }
    }
    reference::render(&instances, camera, size.0, size.1, &scene.light)
}

pub use ssbvb_passes::measure::f16_to_f32;

/// Texels of a live `Rgba16Float` texture as `[f32; 4]`.
pub fn read_half4(frame: &Frame, name: &str) -> Vec<[f32; 4]> {
    frame
        .read(name)
        .chunks(8)
        .map(|t| std::array::from_fn(|c| f16_to_f32(u16::from_le_bytes([t[2 * c], t[2 * c + 1]]))))
        .collect()
}

/// The geometric normals of a frame's `gbuffer_geometric_normal` (octahedral `Rg16Float`
/// codes, decoded by `ssbvb_passes::kinds::gbuffer::oct_decode`; a non-finite code decodes to
/// NaN, so checks for finite normals still see it).
pub fn read_geometric_normals(frame: &Frame) -> Vec<[f32; 3]> {
    frame
        .read("gbuffer_geometric_normal")
        .chunks_exact(4)
        .map(|c| {
            let h = |i: usize| f16_to_f32(u16::from_le_bytes([c[i], c[i + 1]]));
            let code = [h(0), h(2)];
            if code.iter().all(|v| v.is_finite()) {
                ssbvb_passes::kinds::gbuffer::oct_decode(code)
            } else {
                [f32::NAN; 3]
            }
        })
        .collect()
}

/// The G-buffer of a ray-cast or rasterized frame as reference-comparable hits: one per
/// pixel where something was drawn, with the depth along the pixel's ray and the written
/// geometric normal (instance and cell unknown: [`u32::MAX`]). Fails the test at a non-finite
/// position or normal, or a drawn pixel whose stencil is not the voxel value (1; where the
/// device can read the stencil back); `what` names the render in those messages.
pub fn gbuffer_hits(frame: &Frame, what: &str) -> Vec<Option<ssbvb_voxel::accuracy::GpuHit>> {
    let albedo = frame.read("gbuffer_albedo");
    let pos = frame.read_f32("gbuffer_position");
    let normal = read_geometric_normals(frame);
    let shading = read_half4(frame, "gbuffer_normal");
    // GL cannot copy a stencil to a buffer: there the stencil is not checked.
    let copies = ctx()
        .adapter
        .get_downlevel_capabilities()
        .flags
        .contains(wgpu::DownlevelFlags::DEPTH_TEXTURE_AND_BUFFER_COPIES);
    let stencil = copies.then(|| frame.read_stencil("depth_stencil"));
    (0..normal.len())
        .map(|i| {
            (albedo[i * 4 + 3] > 0).then(|| {
                let p = &pos[i * 4..i * 4 + 4];
                let n = normal[i];
                assert!(
                    p.iter().chain(&n).all(|v| v.is_finite()),
                    "{what}: NaN at {i}"
                );
                // The shading normal: a unit vector (f16), w = 1.
                let s = shading[i];
                let len = (s[0] * s[0] + s[1] * s[1] + s[2] * s[2]).sqrt();
                assert!(
                    (len - 1.0).abs() < 2e-3 && s[3] == 1.0,
                    "{what}: shading normal {s:?} at {i}"
                );
                if let Some(stencil) = &stencil {
                    assert_eq!(stencil[i], 1, "{what}: stencil at {i}");
                }
                ssbvb_voxel::accuracy::GpuHit {
                    instance: u32::MAX,
                    cell: [u32::MAX; 3],
                    t: (p[0] as f64).hypot(p[1] as f64).hypot(p[2] as f64),
                    normal: n,
                }
            })
        })
        .collect()
}

/// A camera whose rays run almost in the plane of the top faces of the lowest voxel layer
/// of `asset` at `level` (grazing rays: the hardest ties for every traversal).
pub fn grazing_camera(asset: &VoxelAsset, level: u32) -> Camera {
    let cell = 2.0 / (1u64 << level) as f64;
    let min_y = asset.lods[level as usize]
        .point_cloud
        .voxels
        .iter()
        .map(|v| v.cell()[1])
        .min()
        .expect("a non-empty level");
    let y = -1.0 + (min_y as f64 + 1.01) * cell;
    Camera::new(
        glam::DVec3::new(3.0, y, 0.7),
        glam::DVec3::new(0.0, y + 0.002, 0.0),
    )
}

/// The accuracy bounds of the face rasterizers (the cube rasterizer and RastaVox: the same
/// faces and the same fragment stage, `face_raster.inc.wgsl`) against the reference of the
/// model they draw, measured on lavapipe and given a margin:
/// - coverage IoU (measured ≥ 0.9986 for cubes, ≥ 0.9993 for RastaVox) ≥ 0.995, and
///   same-voxel rate (≥ 0.9963, ≥ 0.9954) ≥ 0.99: the rasterizer snaps vertices to its
///   sub-pixel grid (8 bits on lavapipe), so a pixel centre within ~1/512 px of a projected
///   voxel edge may land on the other side of it than the exact f64 ray (more often in
///   axis-aligned views, whose pixel rays run along grid planes);
/// - depth error median (≤ 1.7e-5 voxels) ≤ 1e-4 and p95 (≤ 6.2e-5) ≤ 1e-3: the same
///   ray–plane intersection as the reference, in f32;
/// - normal error median and p95 (0.00°) ≤ 0.1° and 1°: exact face normals in f16.
///
/// At least 200 covered pixels, so an empty image cannot pass.
pub fn assert_face_raster_accurate(r: &ssbvb_voxel::accuracy::AccuracyReport, what: &str) {
    assert!(
        r.covered_reference > 200,
        "{what}: only {} px",
        r.covered_reference
    );
    assert!(r.coverage_iou >= 0.995, "{what}: {r:?}");
    assert!(r.same_voxel_rate >= 0.99, "{what}: {r:?}");
    assert!(r.depth_error_voxels.median <= 1e-4, "{what}: {r:?}");
    assert!(r.depth_error_voxels.p95 <= 1e-3, "{what}: {r:?}");
    assert!(r.normal_error_deg.median <= 0.1, "{what}: {r:?}");
    assert!(r.normal_error_deg.p95 <= 1.0, "{what}: {r:?}");
}
