//! The engine's API on the shared device (handed in as a host's device): voxels from
//! arrays against the CPU reference of the same content, dense and sparse input drawing
//! the same image, an empty grid drawing an empty frame with a warning, resizing.

use glam::DVec3;
use ssbvb_engine::arrays::{Array, ArrayData, Placement, SparseColors, VoxelArrays};
use ssbvb_engine::{Content, Engine, HostDevice, RenderOptions};
use ssbvb_voxel::accuracy;
use ssbvb_voxel::progress::NoProgress;

const SIZE: (u32, u32) = (96, 72);

fn host() -> HostDevice {
    let c = ssbvb_tests::ctx();
    HostDevice {
        instance: c.instance.clone(),
        adapter: c.adapter.clone(),
        device: c.device.clone(),
        queue: c.queue.clone(),
        target: None,
    }
}

fn options() -> RenderOptions {
    RenderOptions {
        size: SIZE,
        host: Some(host()),
        ..RenderOptions::default()
    }
}

/// A 20 × 12 × 16 grid holding a ball of radius 7 around (10, 6, 8) cut by the grid's
/// top, coloured by height: `(rgba, coords, colours)` of its set cells.
fn ball() -> (Vec<u8>, Vec<i32>, Vec<u8>) {
    let (nx, ny, nz) = (20usize, 12usize, 16usize);
    let mut rgba = vec![0u8; nx * ny * nz * 4];
    let (mut coords, mut colors) = (Vec::new(), Vec::new());
    for x in 0..nx {
        for y in 0..ny {
            for z in 0..nz {
                let d = DVec3::new(x as f64 - 10.0, y as f64 - 6.0, z as f64 - 8.0);
                if d.length() > 7.0 {
                    continue;
                }
                let px = [200, (20 * y) as u8, 60, 255];
                let i = ((x * ny + y) * nz + z) * 4;
                rgba[i..i + 4].copy_from_slice(&px);
                coords.extend([x as i32, y as i32, z as i32]);
                colors.extend(px);
            }
        }
    }
    (rgba, coords, colors)
}

const PLACEMENT: Placement = Placement {
    origin: [-2.0, -1.0, 0.5],
    voxel_size: 0.2,
};

/// Voxels from a dense array, framed by the engine's camera, against the CPU reference of
/// the same content: the coverage agrees (IoU ≥ 0.98, measured 1.0 on lavapipe) and the
/// same voxels are hit; the sparse form of the same cells draws the same bytes.
#[test]
fn arrays_render_what_the_reference_sees_and_dense_equals_sparse() {
    let (rgba, coords, colors) = ball();
    let dense = VoxelArrays::Dense(Array::new(vec![20, 12, 16, 4], ArrayData::U8(&rgba)));
    let content = Content::from_arrays(&dense, PLACEMENT, &NoProgress).unwrap();
    assert!(content.warnings.is_empty(), "{:?}", content.warnings);
    let scene = content.scene.clone();
    let camera = content.camera;
    let mut engine = Engine::open(content, &options()).unwrap();
    assert_eq!(engine.choice().by, "adapter", "{:?}", engine.choice());
    engine.render().unwrap();
    let image = engine.read_rgba8().unwrap();
    let gpu = engine.gpu();
    let hits = ssbvb_passes::measure::gbuffer_hits(&gpu.ctx, &gpu.renderer).unwrap();
    let reference = ssbvb_tests::reference_of(&scene, &camera, SIZE);
    let level = scene.objects[0].asset.lods.len() - 1;
    assert_eq!(level, 4, "the ball's 15 cells across need the 16-cell grid");
    let r = accuracy::compare(&reference, &hits, &[PLACEMENT.voxel_size]).unwrap();
    eprintln!(
        "arrays ({}): IoU {:.4}, same voxel {:.4}, {} px",
        engine.adapter(),
        r.coverage_iou,
        r.same_voxel_rate,
        r.covered_reference
    );
    // The framing keeps the whole ball in view, and it fills a good part of it.
    assert!(r.covered_reference > 600, "{r:?}");
    assert!(r.coverage_iou >= 0.98, "{r:?}");
    assert!(r.depth_error_voxels.median <= 0.75, "{r:?}");

    let sparse = VoxelArrays::Sparse {
        coords: Array::new(vec![coords.len() / 3, 3], ArrayData::I32(&coords)),
        colors: SparseColors::Each(Array::new(
            vec![colors.len() / 4, 4],
            ArrayData::U8(&colors),
        )),
    };
    let content = Content::from_arrays(&sparse, PLACEMENT, &NoProgress).unwrap();
    assert_eq!(content.camera, camera);
    let mut engine = Engine::open(content, &options()).unwrap();
    engine.render().unwrap();
    assert!(
        engine.read_rgba8().unwrap() == image,
        "sparse and dense differ"
    );

    // A resized engine draws the new size.
    engine.resize((40, 30)).unwrap();
    engine.render().unwrap();
    assert_eq!(engine.read_rgba8().unwrap().len(), 40 * 30 * 4);
    assert!(engine.resize((0, 30)).is_err());
}

/// An empty grid is an empty frame, said in a warning, not an error.
#[test]
fn an_empty_grid_draws_an_empty_frame_with_a_warning() {
    let none = vec![false; 4 * 4 * 4];
    let arrays = VoxelArrays::Occupancy {
        occupied: Array::new(vec![4, 4, 4], ArrayData::Bool(&none)),
        color: [255; 4],
    };
    let content = Content::from_arrays(&arrays, Placement::default(), &NoProgress).unwrap();
    let mut engine = Engine::open(content, &options()).unwrap();
    assert_eq!(engine.warnings().len(), 1, "{:?}", engine.warnings());
    assert!(engine.warnings()[0].to_string().contains("no voxel is set"));
    let frame = engine.render().unwrap();
    assert_eq!(frame.visible_instances, 0);
    let depth = engine.read_depth().unwrap();
    assert!(depth.iter().all(|d| d.is_infinite()));
}

/// A host's texture as the frame's target: the frame drawn into it is the frame the engine
/// draws into its own (read back through the host's handle, not the engine's).
#[test]
fn the_frame_is_drawn_into_the_hosts_texture() {
    let (rgba, _, _) = ball();
    let dense = || VoxelArrays::Dense(Array::new(vec![20, 12, 16, 4], ArrayData::U8(&rgba)));
    let content = Content::from_arrays(&dense(), PLACEMENT, &NoProgress).unwrap();
    let mut own = Engine::open(content, &options()).unwrap();
    own.render().unwrap();
    let want = own.read_rgba8().unwrap();
    let out = &own.gpu().renderer.output().texture;
    let (format, usage) = (out.format(), out.usage());
    let c = ssbvb_tests::ctx();
    let target = c
        .device
        .create_texture(&ssbvb_gpu::wgpu::TextureDescriptor {
            label: Some("host target"),
            size: ssbvb_gpu::wgpu::Extent3d {
                width: SIZE.0,
                height: SIZE.1,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: ssbvb_gpu::wgpu::TextureDimension::D2,
            format,
            usage,
            view_formats: &[],
        });
    let content = Content::from_arrays(&dense(), PLACEMENT, &NoProgress).unwrap();
    let mut into_host = Engine::open(
        content,
        &RenderOptions {
            host: Some(HostDevice {
                target: Some(target.clone()),
                ..host()
            }),
            ..options()
        },
    )
    .unwrap();
    into_host.render().unwrap();
    let got = c
        .read_texture(&target, ssbvb_gpu::wgpu::TextureAspect::All)
        .unwrap()
        .to_rgba8()
        .unwrap();
    assert!(want.chunks(4).filter(|p| p[3] > 0).count() > 600);
    let differ = want.iter().zip(&got).filter(|(a, b)| a != b).count();
    assert_eq!(differ, 0, "{differ} bytes differ");
    assert!(into_host.resize((10, 10)).is_err());
}

/// A host's device with less than the adapter offers: under WebGPU's default limits the
/// engine picks a form that device runs and says why it passed over others; under the
/// downlevel limits no form fits, and opening is an error naming what the device lacks,
/// not a validation error.
#[test]
fn a_hosts_device_gets_a_form_it_runs_or_the_reason_it_runs_none() {
    let (rgba, _, _) = ball();
    let dense = || VoxelArrays::Dense(Array::new(vec![20, 12, 16, 4], ArrayData::U8(&rgba)));
    let on = |ctx: &ssbvb_gpu::GpuContext| HostDevice {
        instance: ctx.instance.clone(),
        adapter: ctx.adapter.clone(),
        device: ctx.device.clone(),
        queue: ctx.queue.clone(),
        target: None,
    };
    let (webgpu, errors) = ssbvb_tests::device_on_shared_adapter(
        "host with WebGPU's limits",
        ssbvb_gpu::wgpu::Features::empty(),
        ssbvb_gpu::wgpu::Limits::default(),
    );
    let content = Content::from_arrays(&dense(), PLACEMENT, &NoProgress).unwrap();
    let options = |host| RenderOptions {
        host: Some(host),
        ..options()
    };
    let mut engine = Engine::open(content, &options(on(&webgpu))).unwrap();
    eprintln!("host under WebGPU's limits: {:?}", engine.choice());
    assert!(engine.choice().reason.contains("(the host's device)"));
    engine.render().unwrap();
    assert!(engine.read_rgba8().unwrap().chunks(4).any(|p| p[3] > 0));
    assert!(
        errors.lock().unwrap().is_empty(),
        "{:?}",
        errors.lock().unwrap()
    );

    let (small, errors) = ssbvb_tests::device_on_shared_adapter(
        "host with the downlevel limits",
        ssbvb_gpu::wgpu::Features::empty(),
        ssbvb_gpu::wgpu::Limits::downlevel_defaults(),
    );
    let content = Content::from_arrays(&dense(), PLACEMENT, &NoProgress).unwrap();
    let e = match Engine::open(content, &options(on(&small))) {
        Ok(engine) => panic!("opened with {:?}", engine.choice()),
        Err(e) => e.to_string(),
    };
    assert!(
        e.contains("the host's device") && e.contains("cannot run this pipeline: it lacks"),
        "{e}"
    );
    assert!(
        errors.lock().unwrap().is_empty(),
        "{:?}",
        errors.lock().unwrap()
    );
}

/// Content handed to an open engine draws what an engine opened with it draws, byte for
/// byte, in every SSBVB form the device runs and in a ray caster; the SSBVB forms keep
/// their compiled pipelines (every pass scene-free, the same bindings), the ray caster
/// (whose passes are not marked scene-free) makes them again.
#[test]
fn new_content_on_an_open_engine_draws_what_a_fresh_engine_draws() {
    let (rgba, coords, _) = ball();
    let first = Content::from_arrays(
        &VoxelArrays::Dense(Array::new(vec![20, 12, 16, 4], ArrayData::U8(&rgba))),
        PLACEMENT,
        &NoProgress,
    )
    .unwrap();
    // Another object: the ball's cells as a sparse slab in one colour, placed elsewhere.
    let slab: Vec<i32> = coords
        .chunks(3)
        .filter(|c| c[1] < 6)
        .flat_map(|c| [c[0], c[1], c[2] * 2])
        .collect();
    let second = || {
        Content::from_arrays(
            &VoxelArrays::Sparse {
                coords: Array::new(vec![slab.len() / 3, 3], ArrayData::I32(&slab)),
                colors: SparseColors::One([40, 180, 90, 255]),
            },
            Placement {
                origin: [0.5, -1.5, -2.0],
                voxel_size: 0.15,
            },
            &NoProgress,
        )
        .unwrap()
    };
    let assets = ssbvb_engine::assets::assets_dir();
    let mut tried = 0;
    let pipelines = ssbvb_engine::FORMS
        .iter()
        .map(|f| (f.file, true))
        .chain([("pipelines/esvo.ron", false)]);
    for (file, scene_free) in pipelines {
        let opts = RenderOptions {
            pipeline: Some(assets.join(file)),
            ..options()
        };
        let Ok(mut fresh) = Engine::open(second(), &opts) else {
            // A form this device cannot run (the choice test names why).
            continue;
        };
        tried += 1;
        fresh.render().unwrap();
        let want = fresh.read_rgba8().unwrap();
        assert!(want.chunks(4).any(|p| p[3] > 0), "{file}: an empty frame");
        let mut swapped = Engine::open(first.clone(), &opts).unwrap();
        swapped.render().unwrap();
        let before = swapped.read_rgba8().unwrap();
        let kept = swapped.set_content(second()).unwrap();
        assert_eq!(kept, scene_free, "{file}");
        assert_eq!(swapped.camera(), fresh.camera(), "{file}");
        swapped.render().unwrap();
        let got = swapped.read_rgba8().unwrap();
        assert_ne!(before, got, "{file}: the old content is still drawn");
        assert!(got == want, "{file}: differs from a fresh engine's frame");
    }
    assert!(tried >= 3, "only {tried} pipelines ran on this device");
}
