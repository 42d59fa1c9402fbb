//! Pages by demand under a GPU budget (`GpuScene::streamed`, `streaming.rs`): the first
//! frame shows coarser voxels where pages are missing, never a hole; frames converge to
//! exactly the unbudgeted image; least recently used pages leave when the budget is full;
//! a damaged page is refused and its rays keep a coarser level; a budget below the fixed
//! part is an error naming the minimum.

use std::sync::Arc;

use glam::DVec3;
use ssbvb_gpu::scene::{GpuScene, StreamingOptions};
use ssbvb_gpu::{GpuContext, ResourceError};
use ssbvb_passes::{PassError, Profiling, Renderer};
use ssbvb_voxel::asset::VoxelAsset;
use ssbvb_voxel::camera::Camera;

const SIZE: (u32, u32) = (128, 96);
const LEVEL: u32 = 8;
const PIPELINE: &str = include_str!("../../../assets/pipelines/ssbvb_unique.ron");
const DIRECT: &str = include_str!("../../../assets/pipelines/ssbvb_direct.ron");

fn asset() -> Arc<VoxelAsset> {
    ssbvb_tests::model_asset("bunny.obj", LEVEL)
}

fn front() -> Camera {
    Camera::new(DVec3::new(0.9, 0.5, 1.8), DVec3::new(0.0, 0.0, 0.0))
}

fn back() -> Camera {
    Camera::new(DVec3::new(-0.9, 0.3, -1.8), DVec3::new(0.0, 0.0, 0.0))
}

/// Output colour and voxel coverage of one frame.
struct Image {
    color: Vec<u8>,
    covered: Vec<bool>,
}

fn grab(r: &Renderer) -> Image {
    let c = ssbvb_tests::ctx();
    let read = |name: &str| {
        let i = r.resource(name).unwrap();
        c.read_texture(
            &r.resources.texture(i).texture,
            ssbvb_gpu::wgpu::TextureAspect::All,
        )
        .unwrap()
        .bytes
    };
    let albedo = read("gbuffer_albedo");
    Image {
        color: read("color"),
        covered: albedo.chunks(4).map(|p| p[3] > 0).collect(),
    }
}

fn frame(c: &GpuContext, r: &mut Renderer, scene: &mut GpuScene, cam: &Camera) -> Image {
    r.render(c, scene, cam, Profiling::Off)
        .unwrap_or_else(|e| panic!("{e}"));
    c.wait_idle().unwrap();
    let errs = c.take_uncaptured_errors();
    assert!(errs.is_empty(), "wgpu errors: {errs:#?}");
    grab(r)
}

fn unbudgeted(cam: &Camera) -> (Image, u64) {
    unbudgeted_with(PIPELINE, cam)
}

fn unbudgeted_with(pipeline: &str, cam: &Camera) -> (Image, u64) {
    let c = ssbvb_tests::ctx();
    let scene = ssbvb_tests::single_object_scene(asset(), LEVEL);
    let mut s = GpuScene::new(c, scene).unwrap();
    let resolved = ssbvb_graph::resolve_str(pipeline, "ssbvb").unwrap();
    let mut r = Renderer::new(c, &s, resolved, SIZE).unwrap();
    let total = s.total_memory();
    (frame(c, &mut r, &mut s, cam), total)
}

fn streamed(options: &StreamingOptions) -> (Renderer, GpuScene) {
    streamed_with(PIPELINE, options)
}

fn streamed_with(pipeline: &str, options: &StreamingOptions) -> (Renderer, GpuScene) {
    let c = ssbvb_tests::ctx();
    let scene = ssbvb_tests::single_object_scene(asset(), LEVEL);
    let s = GpuScene::streamed(c, scene, options).unwrap_or_else(|e| panic!("{e}"));
    let resolved = ssbvb_graph::resolve_str(pipeline, "ssbvb").unwrap();
    let r = Renderer::new(c, &s, resolved, SIZE).unwrap();
    (r, s)
}

/// Renders frames until one's feedback misses no page (at most `limit`): that frame's
/// image and how many frames it took.
fn converge(r: &mut Renderer, s: &mut GpuScene, cam: &Camera, limit: usize) -> (Image, usize) {
    let c = ssbvb_tests::ctx();
    for n in 1..=limit {
        let img = frame(c, r, s, cam);
        s.sync_streaming(c).unwrap();
        let st = s.streaming_stats().unwrap();
        if st.pages_missing == 0 {
            return (img, n);
        }
    }
    panic!(
        "no convergence in {limit} frames: {:?}",
        s.streaming_stats()
    );
}

fn count(v: &[bool]) -> usize {
    v.iter().filter(|&&b| b).count()
}

/// A camera near the bunny's face: part of the bunny fills the screen, the case streaming
/// is for (a view of the whole object at its finest level touches ~45 % of that level's
/// pages, more than a quarter budget holds: see the next test).
fn near() -> Camera {
    Camera::new(DVec3::new(0.25, 0.25, 0.75), DVec3::new(-0.1, 0.1, 0.0))
}

#[test]
fn a_quarter_budget_converges_to_the_unbudgeted_image_without_a_hole_on_the_way() {
    // The filter's form, and the direct form's march in a fragment shader, which writes
    // the page feedback through its own binding (without it no page would stream, and
    // the converged image would stay coarser).
    for pipeline in [PIPELINE, DIRECT] {
        quarter_budget_converges(pipeline);
    }
}

fn quarter_budget_converges(pipeline: &str) {
    let c = ssbvb_tests::ctx();
    let (want, total) = unbudgeted_with(pipeline, &near());
    let n = count(&want.covered);
    assert!(n > SIZE.0 as usize * SIZE.1 as usize / 3, "{n} pixels");
    let mut options = StreamingOptions::mib(0);
    options.budget_bytes = total / 4;
    let (mut r, mut s) = streamed_with(pipeline, &options);

    // Frame 1: no page of levels 6..=8 is resident; every pixel the bunny covers is
    // covered by a coarser level (no hole), and the image differs (coarser voxels).
    let first = frame(c, &mut r, &mut s, &near());
    let holes = (0..want.covered.len())
        .filter(|&i| want.covered[i] && !first.covered[i])
        .count();
    assert_eq!(holes, 0, "pixels of the bunny left empty while streaming");
    assert_ne!(first.color, want.color, "frame 1 cannot have level 8 yet");
    s.sync_streaming(c).unwrap();
    let st = s.streaming_stats().unwrap().clone();
    println!("after frame 1: {st:?}");
    // The first missing page of each ray, then those found looking past it.
    assert!(
        st.pages_missing > 5 && st.pages_streamed > st.pages_missing,
        "{st:?}"
    );

    let (got, frames) = converge(&mut r, &mut s, &near(), 24);
    let st = s.streaming_stats().unwrap().clone();
    println!("converged in {} frames: {st:?}", frames + 1);
    assert_eq!(got.covered, want.covered);
    assert_eq!(
        got.color, want.color,
        "the converged image is the unbudgeted one"
    );
    assert!(st.bytes_resident <= options.budget_bytes, "{st:?}");
    assert!(!st.over_budget && st.pages_failed == 0);
}

#[test]
fn turning_round_evicts_the_least_recently_used_pages_and_converges_each_time() {
    let c = ssbvb_tests::ctx();
    let mut options = StreamingOptions::mib(0);
    let (want_front, total) = unbudgeted(&front());
    let (want_back, _) = unbudgeted(&back());
    // 60 % of the object: one side's pages fit (a side touches ~45 % of level 8's pages,
    // measured), both sides' (~65 %) do not.
    options.budget_bytes = total * 6 / 10;
    let (mut r, mut s) = streamed(&options);
    let mut evicted = 0;
    for (cam, want) in [
        (front(), &want_front),
        (back(), &want_back),
        (front(), &want_front),
    ] {
        let first = frame(c, &mut r, &mut s, &cam);
        assert!((0..want.covered.len()).all(|i| !want.covered[i] || first.covered[i]));
        let (got, frames) = converge(&mut r, &mut s, &cam, 24);
        let st = s.streaming_stats().unwrap().clone();
        println!("converged in {} frames: {st:?}", frames + 1);
        assert_eq!(got.covered, want.covered);
        assert_eq!(got.color, want.color);
        assert!(st.bytes_resident <= options.budget_bytes);
        assert!(st.pages_evicted >= evicted);
        evicted = st.pages_evicted;
    }
    assert!(
        evicted > 0,
        "both sides fitted: the budget does not test eviction"
    );
    // Evicting everything brings frame-1 coarseness back, without holes.
    s.evict_all_pages(c);
    let again = frame(c, &mut r, &mut s, &front());
    assert_ne!(again.color, want_front.color);
    assert!((0..want_front.covered.len()).all(|i| !want_front.covered[i] || again.covered[i]));
}

#[test]
fn a_view_that_does_not_fit_settles_at_a_coarser_level_exactly() {
    let c = ssbvb_tests::ctx();
    // A fifth of the object: the front view's level-8 pages (~45 % of them) do not fit;
    // level 7 needs a quarter of that.
    let (_, total) = unbudgeted(&front());
    let mut options = StreamingOptions::mib(0);
    options.budget_bytes = total / 5;
    let (mut r, mut s) = streamed(&options);
    let (got, frames) = converge(&mut r, &mut s, &front(), 40);
    let st = s.streaming_stats().unwrap().clone();
    println!("converged in {frames} frames: {st:?}");
    let cap = st.level_cap.expect("the level-8 view does not fit");
    assert!((LEVEL - 2..LEVEL).contains(&cap), "{st:?}");
    assert!(st.bytes_resident <= options.budget_bytes);
    // The oracle: the unbudgeted render of the same asset at that level, pixel for pixel.
    let scene = ssbvb_tests::single_object_scene(asset(), cap);
    let mut u = GpuScene::new(c, scene).unwrap();
    let resolved = ssbvb_graph::resolve_str(PIPELINE, "ssbvb").unwrap();
    let mut ur = Renderer::new(c, &u, resolved, SIZE).unwrap();
    let want = frame(c, &mut ur, &mut u, &front());
    assert!(count(&want.covered) > 1500);
    assert_eq!(got.covered, want.covered);
    assert_eq!(got.color, want.color);
}

#[test]
fn objects_and_instances_share_the_pools_and_converge_to_the_unbudgeted_image() {
    let c = ssbvb_tests::ctx();
    // Two assets (the bunny at level 8, the knight at level 7), three instances each at
    // different distances (per-instance Auto LOD: several levels of each in view).
    let knight = ssbvb_tests::model_asset("chr_knight.vox", 7);
    let place = |x: f64, z: f64, s: f64| {
        glam::DAffine3::from_scale_rotation_translation(
            DVec3::splat(s),
            glam::DQuat::from_rotation_y(x * 0.7),
            DVec3::new(x, 0.0, z),
        )
    };
    let scene = ssbvb_gpu::scene::Scene {
        objects: vec![
            ssbvb_gpu::scene::VoxelObject {
                asset: asset(),
                instances: vec![
                    place(-0.6, 0.0, 0.5),
                    place(0.8, -2.0, 0.5),
                    place(-1.5, -6.0, 0.5),
                ],
                lod: ssbvb_gpu::scene::LodPolicy::AUTO,
            },
            ssbvb_gpu::scene::VoxelObject {
                asset: knight,
                instances: vec![
                    place(0.5, 0.3, 0.4),
                    place(-0.9, -3.0, 0.4),
                    place(1.6, -5.0, 0.4),
                ],
                lod: ssbvb_gpu::scene::LodPolicy::AUTO,
            },
        ],
        ..Default::default()
    };
    let cam = Camera::new(DVec3::new(0.0, 0.6, 1.8), DVec3::new(0.0, 0.0, -2.0));
    let resolved = || ssbvb_graph::resolve_str(PIPELINE, "ssbvb").unwrap();
    let mut u = GpuScene::new(c, scene.clone()).unwrap();
    let mut ur = Renderer::new(c, &u, resolved(), SIZE).unwrap();
    let want = frame(c, &mut ur, &mut u, &cam);
    let levels = u.lod_histogram();
    assert!(levels.len() >= 3, "{levels:?}");
    assert!(count(&want.covered) > 2000, "{}", count(&want.covered));
    // A budget that holds the view but not every page the two objects have.
    let mut options = StreamingOptions::mib(0);
    options.budget_bytes = u.total_memory() / 2;
    let mut s = GpuScene::streamed(c, scene, &options).unwrap();
    let mut r = Renderer::new(c, &s, resolved(), SIZE).unwrap();
    let first = frame(c, &mut r, &mut s, &cam);
    assert!((0..want.covered.len()).all(|i| !want.covered[i] || first.covered[i]));
    let (got, frames) = converge(&mut r, &mut s, &cam, 24);
    let st = s.streaming_stats().unwrap().clone();
    println!("converged in {frames} frames: {st:?}");
    assert_eq!(st.level_cap, None);
    assert!(st.pages_resident < st.pages_total);
    assert_eq!(got.covered, want.covered);
    assert_eq!(got.color, want.color);
}

#[test]
fn a_budget_below_the_fixed_part_is_an_error_naming_the_minimum() {
    let c = ssbvb_tests::ctx();
    let scene = ssbvb_tests::single_object_scene(asset(), LEVEL);
    let e = match GpuScene::streamed(c, scene.clone(), &StreamingOptions::mib(0)) {
        Err(e) => e,
        Ok(_) => panic!("a zero budget was accepted"),
    };
    let ResourceError::BudgetTooSmall { minimum, .. } = e else {
        panic!("{e}");
    };
    let msg = e.to_string();
    assert!(
        msg.contains(&format!("--gpu-budget {}", minimum.div_ceil(1 << 20))),
        "{msg}"
    );
    let mut exact = StreamingOptions::mib(0);
    exact.budget_bytes = minimum;
    assert!(GpuScene::streamed(c, scene.clone(), &exact).is_ok());
    exact.budget_bytes = minimum - 1;
    assert!(GpuScene::streamed(c, scene, &exact).is_err());
}

#[test]
fn passes_that_read_whole_levels_are_refused_under_a_budget() {
    let c = ssbvb_tests::ctx();
    let scene = ssbvb_tests::single_object_scene(asset(), LEVEL);
    let s = GpuScene::streamed(c, scene, &StreamingOptions::mib(64)).unwrap();
    for p in [
        include_str!("../../../assets/pipelines/octree.ron"),
        include_str!("../../../assets/pipelines/cube_raster.ron"),
    ] {
        let resolved = ssbvb_graph::resolve_str(p, "p").unwrap();
        match Renderer::new(c, &s, resolved, SIZE) {
            Err(e @ PassError::NeedsWholeLevels { .. }) => {
                assert!(e.to_string().contains("GPU budget"), "{e}")
            }
            Err(e) => panic!("{e}"),
            Ok(_) => panic!("a whole-level pass was built on a paged scene"),
        }
    }
}

#[test]
fn a_page_that_fails_its_checksum_is_refused_and_its_rays_stay_coarser() {
    let c = ssbvb_tests::ctx();
    let a = asset();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bunny.ssbvbast");
    ssbvb_voxel::cache::write_cache(&path, &a, 7, LEVEL).unwrap();
    // Damage one byte in every fourth page of level 8.
    let mut bytes = std::fs::read(&path).unwrap();
    let cloud = &a.lods[LEVEL as usize].point_cloud.voxels;
    let needle: &[u8] = bytemuck::cast_slice(cloud);
    let at = bytes
        .windows(needle.len())
        .position(|w| w == needle)
        .unwrap();
    let index = ssbvb_voxel::cache::page_index(cloud);
    for e in index.iter().step_by(4) {
        bytes[at + e.first_voxel as usize * 16 + 8] ^= 0x80;
    }
    std::fs::write(&path, &bytes).unwrap();
    let file = Arc::new(ssbvb_voxel::cache::PageFile::open(&path, 7, LEVEL).unwrap());

    let (want, total) = unbudgeted(&front());
    let mut options = StreamingOptions::mib(0);
    options.budget_bytes = total / 2;
    options.page_files = vec![Some(file)];
    let (mut r, mut s) = streamed(&options);
    let (got, _) = converge(&mut r, &mut s, &front(), 24);
    let st = s.streaming_stats().unwrap().clone();
    let errors = s.page_errors();
    println!("{st:?}\n{}", errors.join("\n"));
    assert!(st.pages_failed > 0 && errors.len() as u64 == st.pages_failed);
    assert!(
        errors.iter().all(|e| e.contains("bunny.ssbvbast")
            && e.contains("checksum")
            && e.contains("of level 8")),
        "{errors:?}"
    );
    // Never a hole: the refused pages' pixels show level 7 (or coarser) voxels.
    assert!((0..want.covered.len()).all(|i| !want.covered[i] || got.covered[i]));
    assert_ne!(got.color, want.color);
    let _ = c;
}

#[test]
fn levels_that_borrow_a_coarser_proxy_converge_to_the_unbudgeted_image() {
    let (want_front, total) = unbudgeted(&front());
    // Inside the [-1, 1]³ box, in an octant of bunny (level 5's page there is occupied)
    // but away from it (level 8's page there is empty).
    let corner = Camera::new(DVec3::new(0.9, 0.55, 0.9), DVec3::new(0.0, 0.0, 0.0));
    let (want_near, _) = unbudgeted(&near());
    let (want_corner, _) = unbudgeted(&corner);
    let own = streamed(&StreamingOptions::mib(0).with_budget(total)).1;
    // Levels 6-8 draw level 5's proxy: from outside its boxes (front) the prepass starts
    // rays at them; from inside one (near: level 5's pages are half the object wide) rays
    // start at the camera.
    let mut options = StreamingOptions::mib(0).with_budget(total);
    options.proxy_level = 5;
    let (mut r, mut s) = streamed(&options);
    let borrowed = s.streaming_stats().unwrap().fixed_bytes;
    let own = own.streaming_stats().unwrap().fixed_bytes;
    assert!(
        borrowed < own,
        "fixed part {borrowed} with borrowed proxies, {own} with their own"
    );
    for (cam, want) in [
        (front(), &want_front),
        (near(), &want_near),
        (corner, &want_corner),
    ] {
        let (got, frames) = converge(&mut r, &mut s, &cam, 24);
        assert!(got.covered == want.covered, "coverage differs");
        let diff: Vec<u8> = (got.color.iter().zip(&want.color))
            .map(|(a, b)| a.abs_diff(*b))
            .collect();
        let n = diff.chunks(4).filter(|p| p.iter().any(|&d| d > 0)).count();
        let max = diff.iter().max().unwrap();
        println!("converged in {frames} frames; {n} pixels differ, at most by {max}");
        // Measured on lavapipe: front 3 of 12288 pixels by 1 (rays that start earlier
        // round differently), near none. Bound: 1 step, 1 % of the pixels.
        assert!(
            *max <= 1 && n * 100 <= diff.len() / 4,
            "{n} pixels, max {max}"
        );
    }
}
