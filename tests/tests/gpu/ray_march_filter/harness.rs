//! What the filter tests share: a filter frame rendered and decoded into reference-comparable
//! hits, and the per-pixel comparison against the CPU reference with its tolerances (see
//! the parent module's docs).

use glam::{DAffine3, DVec3};
use ssbvb_gpu::scene::Scene;
use ssbvb_passes::kinds::ray_march_filter::VoxelSlot;
use ssbvb_passes::measure::ssbvb::{draw_args, read_slots};
use ssbvb_tests::{Frame, ctx, reference_of, render};
use ssbvb_voxel::accuracy::{self, AccuracyReport, GpuHit};
use ssbvb_voxel::camera::Camera;
use ssbvb_voxel::model::cell_size;
use ssbvb_voxel::reference::{self, ReferenceImage};

use crate::empty_space::{debug_png, entries, prefilter_pipeline};

/// Placed instances of a scene in the reference's order, with the level each takes for
/// `camera` on a `screen`-sized frame.
pub(super) fn placed(
    scene: &Scene,
    camera: &Camera,
    screen: (u32, u32),
) -> Vec<(DAffine3, u32, usize)> {
    let mut out = Vec::new();
    for (oi, o) in scene.objects.iter().enumerate() {
        let max = o.asset.lods.len() as u32 - 1;
        for xf in &o.instances {
            let l = ssbvb_gpu::scene::choose_level(o.lod, xf, camera, screen, max);
            out.push((*xf, l, oi));
        }
    }
    out
}

/// A rendered filter frame, decoded.
pub(crate) struct FilterRun {
    pub(crate) frame: Frame,
    pub(crate) slots: Vec<VoxelSlot>,
    pub(crate) fill: u32,
    /// Per pixel, the GPU's hit in the reference's numbering.
    pub(crate) hits: Vec<Option<GpuHit>>,
}

pub(crate) fn run_filter(
    scene: &Scene,
    camera: &Camera,
    size: (u32, u32),
    max_steps: u32,
) -> FilterRun {
    run_filter_with(&prefilter_pipeline(max_steps), scene, camera, size, size)
}

/// Renders `pipeline` at `size`; its filter runs on a `grid` of texels (the screen, or a
/// fraction of it), in whose numbering the hits are returned.
pub(crate) fn run_filter_with(
    pipeline: &str,
    scene: &Scene,
    camera: &Camera,
    size: (u32, u32),
    grid: (u32, u32),
) -> FilterRun {
    filter_run_of(
        render(pipeline, scene.clone(), camera, size),
        scene,
        camera,
        size,
        grid,
    )
}

/// The hits and billboards of `frame`, a filter's frame of `scene` at `size` (its filter
/// run on a `grid` of texels).
pub(crate) fn filter_run_of(
    frame: Frame,
    scene: &Scene,
    camera: &Camera,
    size: (u32, u32),
    grid: (u32, u32),
) -> FilterRun {
    let c = ctx();
    let fill = frame.renderer.fill_count(c).unwrap().unwrap();
    let args = draw_args(c, &frame.renderer).unwrap();
    assert_eq!(
        (args.vertex_count, args.first_vertex, args.first_instance),
        (4, 0, 0)
    );
    let slots = read_slots(c, &frame.renderer).unwrap();
    let pixels = (grid.0 * grid.1) as usize;
    assert!(fill as usize <= pixels, "fill {fill} > {pixels} pixels");
    assert_eq!(slots.len(), fill as usize);
    for e in entries(&frame) {
        assert!(e.iter().all(|v| v.is_finite()), "entry {e:?}");
    }
    let hits = hits_of_slots(scene, camera, size, &frame.scene.visible, &slots, pixels);
    FilterRun {
        frame,
        slots,
        fill,
        hits,
    }
}

/// Per pixel of a `pixels`-texel grid, the hit of the SSBVB `slots` in the reference's
/// numbering (`visible`: the scene's visible instances of that frame).
pub(super) fn hits_of_slots(
    scene: &Scene,
    camera: &Camera,
    size: (u32, u32),
    visible: &[ssbvb_gpu::scene::VisibleInstance],
    slots: &[VoxelSlot],
    pixels: usize,
) -> Vec<Option<GpuHit>> {
    let inst = placed(scene, camera, size);
    let mut hits = vec![None; pixels];
    for s in slots {
        assert!((s.pixel as usize) < pixels, "{s:?}");
        assert!(s.t.is_finite() && s.t >= 0.0, "{s:?}");
        assert!(s.face < 6, "{s:?}");
        let vis = visible[s.instance as usize];
        let (xf, level, _) = inst[vis.scene_index as usize];
        assert_eq!(vis.level, level);
        let n = s.face_normal().map(f64::from);
        let nw = (xf.matrix3.inverse().transpose() * DVec3::from(n)).normalize();
        // The voxel's grid level rides in the slot: the instance's, every page resident.
        assert_eq!(s.voxel.uv, level, "{s:?}");
        let cell = s.voxel.cell();
        let max = 1u32 << level;
        assert!(cell.iter().all(|&c| c < max), "{s:?}");
        let h = &mut hits[s.pixel as usize];
        assert!(h.is_none(), "pixel {} filled twice", s.pixel);
        *h = Some(GpuHit {
            instance: vis.scene_index,
            cell,
            t: s.t as f64,
            normal: nw.as_vec3().to_array(),
        });
    }
    hits
}

/// Whether the reference's hit/miss at pixel `(x, y)` changes within `eps` pixels.
pub(super) fn grazes(
    scene: &Scene,
    camera: &Camera,
    size: (u32, u32),
    x: u32,
    y: u32,
    eps: f64,
) -> bool {
    let inst = placed(scene, camera, size);
    let refs: Vec<reference::Instance> = inst
        .iter()
        .map(|(xf, l, oi)| reference::Instance {
            lod: &scene.objects[*oi].asset.lods[*l as usize],
            object_to_world: *xf,
            faces: None,
        })
        .collect();
    let rays = camera.pixel_rays(size.0, size.1);
    let trace = |dx: f64, dy: f64| {
        let (o, d) = rays.ray_at(x as f64 + 0.5 + dx, y as f64 + 0.5 + dy);
        reference::trace_ray(&refs, o, d, rays.forward()).is_some()
    };
    let centre = trace(0.0, 0.0);
    [
        (-1.0, 0.0),
        (1.0, 0.0),
        (0.0, -1.0),
        (0.0, 1.0),
        (-1.0, -1.0),
        (1.0, 1.0),
        (-1.0, 1.0),
        (1.0, -1.0),
    ]
    .iter()
    .any(|(dx, dy)| trace(dx * eps, dy * eps) != centre)
}

/// World size of one cell of every instance (uniform scale assumed: cube root of |det|).
pub(crate) fn cell_sizes(scene: &Scene, camera: &Camera, screen: (u32, u32)) -> Vec<f64> {
    placed(scene, camera, screen)
        .iter()
        .map(|(xf, l, _)| cell_size(*l) * xf.matrix3.determinant().abs().cbrt())
        .collect()
}

/// GPU vs reference as a picture: green same voxel, yellow another voxel, red reference
/// only, blue GPU only.
pub(super) fn diff_png(
    name: &str,
    size: (u32, u32),
    reference: &ReferenceImage,
    hits: &[Option<GpuHit>],
) {
    let rgba: Vec<u8> = reference
        .hits
        .iter()
        .zip(hits)
        .flat_map(|(r, g)| match (r, g) {
            (Some(r), Some(g)) if r.instance == g.instance && r.cell == g.cell => [0, 160, 0, 255],
            (Some(_), Some(_)) => [255, 255, 0, 255],
            (Some(_), None) => [255, 0, 0, 255],
            (None, Some(_)) => [0, 0, 255, 255],
            (None, None) => [0, 0, 0, 255],
        })
        .collect();
    debug_png(&format!("{name}_diff"), size.0, size.1, &rgba);
    debug_png(
        &format!("{name}_reference"),
        size.0,
        size.1,
        &reference.to_rgba8(),
    );
}

/// Renders `scene` with the filter and checks it against the reference; returns the
/// report (also printed, for the numbers in reviews).
pub(crate) fn check_against_reference(
    name: &str,
    scene: &Scene,
    camera: &Camera,
    size: (u32, u32),
) -> AccuracyReport {
    check_pipeline_against_reference(&prefilter_pipeline(1024), name, scene, camera, size)
}

/// [`check_against_reference`] with the filter of `pipeline` (a [`prefilter_pipeline`]
/// with an edited filter).
pub(super) fn check_pipeline_against_reference(
    pipeline: &str,
    name: &str,
    scene: &Scene,
    camera: &Camera,
    size: (u32, u32),
) -> AccuracyReport {
    let run = run_filter_with(pipeline, scene, camera, size, size);
    let reference = reference_of(scene, camera, size);
    assert!(reference.all_finite());
    diff_png(name, size, &reference, &run.hits);
    let report =
        accuracy::compare(&reference, &run.hits, &cell_sizes(scene, camera, size)).unwrap();
    eprintln!("{name}: {report:?}");
    // Compaction: one slot per covered pixel.
    assert_eq!(run.fill as usize, report.covered_gpu);
    assert_eq!(run.slots.len(), report.covered_gpu);
    // Coverage: differences only where the ray grazes a silhouette (module docs).
    let mut differing = 0;
    for y in 0..size.1 {
        for x in 0..size.0 {
            let i = (y * size.0 + x) as usize;
            if reference.hits[i].is_some() != run.hits[i].is_some() {
                differing += 1;
                assert!(
                    grazes(scene, camera, size, x, y, 1e-3),
                    "{name}: pixel ({x}, {y}) reference {:?} GPU {:?}: coverage differs on a \
                     ray that does not graze a silhouette",
                    reference.hits[i],
                    run.hits[i]
                );
            }
        }
    }
    assert!(
        differing <= 4 + report.covered_reference / 1000,
        "{name}: {differing} pixels differ in coverage"
    );
    assert!(
        report.same_voxel_rate >= 0.99,
        "{name}: same-voxel rate {}",
        report.same_voxel_rate
    );
    // Measured on lavapipe: medians up to 2.6e-4 voxel (a level-11 grid seen whole),
    // 1e-5 typically; the bound keeps a 4x margin and catches a march that is off by a
    // fraction of a cell.
    assert!(
        report.depth_error_voxels.median <= 1e-3,
        "{name}: depth error {:?}",
        report.depth_error_voxels
    );
    report
}
