//! The filter runs one workgroup per 16 × 16 tile of the prepass that holds some proxy
//! (`mark_tiles`, `list_tiles`, an indirect dispatch of `main`). A tile left out of the list
//! would leave its pixels without a ray, so these frames need voxels where a list goes
//! wrong first: beyond the first group of 256 tiles of the list's prefix sum, in tiles the
//! screen's edges cut, and in the rows that a device allowing few workgroups per dimension
//! dispatches the list in.

use glam::DVec3;
use ssbvb_gpu::{GpuContext, wgpu};
use ssbvb_passes::kinds::ray_march_filter::{VoxelSlot, tile_count};
use ssbvb_passes::measure::ssbvb::read_slots;
use ssbvb_tests::reference_of;
use ssbvb_voxel::camera::Camera;

use super::{bunny, check_against_reference, run_filter};
use crate::empty_space::prefilter_pipeline;

/// Reference hits in the pixel rectangle `x0..x1` × `y0..y1`.
fn reference_hits_in(
    reference: &ssbvb_voxel::reference::ReferenceImage,
    (x0, x1): (u32, u32),
    (y0, y1): (u32, u32),
) -> usize {
    (y0..y1)
        .flat_map(|y| (x0..x1).map(move |x| (x, y)))
        .filter(|&(x, y)| reference.hit(x, y).is_some())
        .count()
}

/// 337 × 203 pixels: 22 × 13 = 286 tiles, so the list's prefix sum takes two groups, and
/// the last column and row of tiles are cut by the screen (1 and 11 pixels). The bunny
/// fills the screen's lower right, so voxels lie in the second group and the cut tiles.
#[test]
fn a_screen_of_many_tiles_cut_by_its_edges_matches_the_reference() {
    let size = (337, 203);
    assert!(tile_count(size.0, size.1) > 256);
    let scene = bunny(6);
    let camera = Camera::new(DVec3::new(0.2, 0.6, 1.3), DVec3::new(-0.25, 0.1, 0.0));
    let reference = reference_of(&scene, &camera, size);
    // Tiles 256 and on: rows 11 and 12 (y ≥ 176) from column 14 of row 11.
    let second_group = reference_hits_in(&reference, (0, size.0), (192, size.1))
        + reference_hits_in(&reference, (14 * 16, size.0), (176, 192));
    let cut_column = reference_hits_in(&reference, (336, 337), (0, size.1));
    let cut_row = reference_hits_in(&reference, (0, size.0), (192, size.1));
    assert!(
        second_group > 1000 && cut_column > 10 && cut_row > 500,
        "the view must put voxels where a wrong list loses them: {second_group} in the \
         second group, {cut_column} in the cut column, {cut_row} in the cut row"
    );
    let r = check_against_reference("bunny6_many_tiles", &scene, &camera, size);
    assert!(r.covered_reference > 20_000, "{r:?}");
}

/// The slots of a filter frame on `ctx`, in pixel order.
fn slots_on(
    ctx: &GpuContext,
    scene: ssbvb_gpu::scene::Scene,
    camera: &Camera,
    size: (u32, u32),
) -> Vec<VoxelSlot> {
    let frame = ssbvb_tests::render_on(ctx, &prefilter_pipeline(1024), scene, camera, size);
    let mut slots = read_slots(ctx, &frame.renderer).unwrap();
    slots.sort_by_key(|s| s.pixel);
    slots
}

/// Tiles of a `size` prepass (`entries`, row-major) that hold some proxy, and whether the
/// first does.
fn tiles_with_a_proxy(entries: &[[f32; 4]], size: (u32, u32)) -> (usize, bool) {
    let per_row = size.0.div_ceil(16) as usize;
    let mut tiles = std::collections::BTreeSet::new();
    for (i, e) in entries.iter().enumerate() {
        if e[3] >= 1.0 {
            let (x, y) = (i % size.0 as usize, i / size.0 as usize);
            tiles.insert((y / 16) * per_row + x / 16);
        }
    }
    (tiles.len(), tiles.contains(&0))
}

/// A device that allows 7 workgroups per dimension gets the tile list as rows of 7: the
/// same slots as the shared device, which dispatches it as one row. The last row is not
/// full, and the first tile holds voxels, so the tail of that row (workgroups past the
/// list's end) must not filter the first tile again: it would append its pixels twice.
#[test]
fn a_tile_list_longer_than_a_dispatch_row_fills_the_same_slots() {
    // 7 × 7 tiles: every dispatch of the frame fits 7 workgroups per dimension.
    let size = (112, 112);
    let scene = bunny(6);
    let camera = Camera::new(DVec3::new(1.0, 0.6, 1.5), DVec3::new(0.5, -0.4, 0.1));
    let shared = ssbvb_tests::ctx();
    let (narrow, errors) = ssbvb_tests::device_on_shared_adapter(
        "7 workgroups per dimension",
        shared.device.features(),
        wgpu::Limits {
            max_compute_workgroups_per_dimension: 7,
            ..shared.device.limits()
        },
    );
    let wide = run_filter(&scene, &camera, size, 1024);
    let (listed, first) = tiles_with_a_proxy(&crate::empty_space::entries(&wide.frame), size);
    assert!(
        listed > 7 && listed % 7 != 0 && first,
        "{listed} tiles with a proxy (the first: {first}): the view must leave the last \
         row short and cover the first tile"
    );
    // The filter launched those tiles and no others.
    let counters = wide.frame.renderer.counters(shared).unwrap();
    assert_eq!(counters.filter_tiles, Some(listed as u64));
    let wide_slots = wide.slots;
    let mut expected = wide_slots.clone();
    expected.sort_by_key(|s| s.pixel);
    let narrow_slots = slots_on(&narrow, scene, &camera, size);
    let errs = errors.lock().unwrap().clone();
    assert!(errs.is_empty(), "wgpu errors: {errs:#?}");
    // More than one row of 7 tiles, and more slots than one row could hold.
    assert!(expected.len() > 8 * 16 * 16, "{} slots", expected.len());
    assert_eq!(narrow_slots.len(), expected.len());
    assert!(
        narrow_slots == expected,
        "the row-limited device filled other slots"
    );
}
