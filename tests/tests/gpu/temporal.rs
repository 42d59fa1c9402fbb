//! Temporal anti-aliasing (`assets/pipelines/ssbvb_aa.ron`, the default frame's, and
//! `pipelines/raster_aa.ron` here, the raster form's): a still camera converges toward the
//! supersampled reference, a moving one stays nearer it than one sample and flickers less,
//! a camera cut drops the history and a small move keeps it.

use glam::{DAffine3, DVec3};
use ssbvb_gpu::scene::{GpuScene, Scene};
use ssbvb_graph::MAX_VARIANCE_CLIP;
use ssbvb_passes::{Profiling, Renderer};
use ssbvb_tests::ctx;
use ssbvb_voxel::camera::Camera;
use ssbvb_voxel::reference::{Instance, SampleGrid, render_supersampled};
use ssbvb_voxel::shading::srgb_to_linear;

const AA: &str = include_str!("../../../assets/pipelines/ssbvb_aa.ron");
const PLAIN: &str = include_str!("../../../assets/pipelines/ssbvb_pixel.ron");
const RASTER_AA: &str = include_str!("pipelines/raster_aa.ron");
const RASTER: &str = include_str!("../../../assets/pipelines/ssbvb_unique.ron");
const SIZE: (u32, u32) = (96, 72);
const LEVEL: u32 = 6;

fn scene() -> Scene {
    ssbvb_tests::single_object_scene(ssbvb_tests::model_asset("bunny.obj", LEVEL), LEVEL)
}

fn camera() -> Camera {
    Camera::new(DVec3::new(1.6, 1.1, 2.4), DVec3::ZERO)
}

/// A renderer of `pipeline` and its scene.
fn renderer(pipeline: &str, scene: Scene) -> (Renderer, GpuScene) {
    let resolved = ssbvb_graph::resolve_str(pipeline, "test pipeline").unwrap();
    let gpu = GpuScene::new(ctx(), scene).unwrap();
    let r = Renderer::new(ctx(), &gpu, resolved, SIZE).unwrap();
    (r, gpu)
}

/// Draws `frames` frames from `camera`; returns the output's RGBA8 (sRGB, straight alpha).
fn draw(r: &mut Renderer, gpu: &mut GpuScene, camera: &Camera, frames: usize) -> Vec<u8> {
    for _ in 0..frames {
        r.render(ctx(), gpu, camera, Profiling::Off).unwrap();
    }
    ctx().wait_idle().unwrap();
    assert!(ctx().take_uncaptured_errors().is_empty());
    ctx()
        .read_texture(&r.output().texture, ssbvb_gpu::wgpu::TextureAspect::All)
        .unwrap()
        .bytes
}

/// Linear RGB over black (premultiplied by coverage) of straight-alpha sRGB RGBA8.
fn over_black(rgba: &[u8]) -> Vec<[f64; 3]> {
    rgba.chunks_exact(4)
        .map(|p| {
            let a = p[3] as f64 / 255.0;
            std::array::from_fn(|c| srgb_to_linear(p[c] as f32 / 255.0) as f64 * a)
        })
        .collect()
}

fn mean_abs_error(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    let sum: f64 = a
        .iter()
        .zip(b)
        .map(|(x, y)| (0..3).map(|c| (x[c] - y[c]).abs()).sum::<f64>())
        .sum();
    sum / (3 * a.len()) as f64
}

/// Pixels whose alpha is neither 0 nor 1: covered in part (blended across frames).
fn partial(rgba: &[u8]) -> usize {
    rgba.chunks_exact(4)
        .filter(|p| p[3] != 0 && p[3] != 255)
        .count()
}

/// The supersampled reference (16 samples a pixel) of `s`'s bunny from `camera`, linear.
fn truth(s: &Scene, camera: &Camera) -> Vec<[f64; 3]> {
    let inst = [Instance {
        lod: &s.objects[0].asset.lods[LEVEL as usize],
        object_to_world: DAffine3::IDENTITY,
        faces: None,
    }];
    let grid = SampleGrid::from_count(16).unwrap();
    render_supersampled(&inst, camera, SIZE.0, SIZE.1, &s.light, grid)
        .colors
        .iter()
        .map(|c| std::array::from_fn(|k| c[k] as f64))
        .collect()
}

/// The mean error against 16 samples of the still frame of `plain` and of the first and
/// the sixteenth frame of `aa`, and the partly covered pixels of the last two.
fn still_errors(aa: &str, plain: &str) -> ([f64; 3], [usize; 2]) {
    let s = scene();
    let truth = truth(&s, &camera());
    let (mut plain, mut plain_scene) = renderer(plain, s.clone());
    let plain_out = draw(&mut plain, &mut plain_scene, &camera(), 1);
    let (mut aa, mut aa_scene) = renderer(aa, s);
    let first = draw(&mut aa, &mut aa_scene, &camera(), 1);
    let converged = draw(&mut aa, &mut aa_scene, &camera(), 15);
    let errors = [&plain_out, &first, &converged].map(|o| mean_abs_error(&over_black(o), &truth));
    (errors, [partial(&first), partial(&converged)])
}

#[test]
fn a_still_camera_converges_toward_the_supersampled_reference() {
    // Bounds: the default frame measured 0.42 of its one-sample frame's error; the raster
    // form 0.41 with the pipeline's ray-box billboards (0.45 with flat ones). Each plus
    // about 0.1.
    for (name, aa, plain, bound) in [
        ("ssbvb_aa", AA, PLAIN, 0.5),
        ("ssbvb_raster_aa", RASTER_AA, RASTER, 0.5),
    ] {
        let ([e_plain, e_first, e_aa], [first, converged]) = still_errors(aa, plain);
        eprintln!(
            "{name}: error against 16 samples: plain {e_plain:.5}, first AA frame {e_first:.5}, \
             16 AA frames {e_aa:.5}"
        );
        // One jittered frame has no history: every pixel in or out. Sixteen cover the
        // silhouette in part, and their error is well below the one-sample frame's.
        assert_eq!(first, 0, "{name}");
        assert!(converged > 50, "{name}: {converged}");
        assert!(e_aa < bound * e_plain, "{name}: {e_aa} against {e_plain}");
    }
}

#[test]
fn a_camera_cut_drops_the_history_and_a_small_move_keeps_it() {
    let (mut aa, mut gpu) = renderer(AA, scene());
    let a = camera();
    assert!(partial(&draw(&mut aa, &mut gpu, &a, 16)) > 50);
    // Far beyond the pass's cut (a quarter of the distance to the look-at point).
    let b = Camera::new(DVec3::new(-2.4, 0.6, -1.8), DVec3::ZERO);
    let cut = draw(&mut aa, &mut gpu, &b, 1);
    assert_eq!(partial(&cut), 0, "history survived a cut");
    // A small step after it: blended with the history again.
    let nudged = Camera::new(b.position * 1.01, DVec3::ZERO);
    assert!(partial(&draw(&mut aa, &mut gpu, &nudged, 1)) > 20);
}

/// The camera orbiting by `deg` degrees about the vertical through the look-at point.
fn orbited(c: &Camera, deg: f64) -> Camera {
    let offset = glam::DQuat::from_rotation_y(deg.to_radians()) * (c.position - c.look_at);
    Camera::new(c.look_at + offset, c.look_at)
}

/// The mean error against 16 samples of the frame after eight orbit steps of half a
/// degree (about a pixel of motion a frame at the silhouette), drawn by `pipeline` from a
/// converged still start, and of the one-sample frame there.
fn moving_error(pipeline: &str, plain: &str) -> (f64, f64) {
    let s = scene();
    let (mut aa, mut aa_scene) = renderer(pipeline, s.clone());
    let start = camera();
    draw(&mut aa, &mut aa_scene, &start, 16);
    let mut moved = start;
    let mut out = Vec::new();
    for _ in 0..8 {
        moved = orbited(&moved, 0.5);
        out = draw(&mut aa, &mut aa_scene, &moved, 1);
    }
    let truth = truth(&s, &moved);
    let (mut plain, mut plain_scene) = renderer(plain, s);
    let plain_out = draw(&mut plain, &mut plain_scene, &moved, 1);
    (
        mean_abs_error(&over_black(&out), &truth),
        mean_abs_error(&over_black(&plain_out), &truth),
    )
}

/// For each of `pipelines`, the mean difference between its consecutive frames (linear,
/// over black) along `steps` orbit steps of `deg` degrees from a converged still start,
/// over the same for the supersampled reference's frames: 1 is as steady as the truth.
fn orbit_flicker(pipelines: &[&str], steps: usize, deg: f64) -> Vec<f64> {
    let s = scene();
    let path: Vec<Camera> = std::iter::successors(Some(camera()), |c| Some(orbited(c, deg)))
        .take(steps + 1)
        .collect();
    let steadiness = |frames: &[Vec<[f64; 3]>]| -> f64 {
        frames
            .windows(2)
            .map(|w| mean_abs_error(&w[0], &w[1]))
            .sum::<f64>()
    };
    let truths: Vec<Vec<[f64; 3]>> = path.iter().map(|c| truth(&s, c)).collect();
    let truth = steadiness(&truths);
    pipelines
        .iter()
        .map(|p| {
            let (mut r, mut g) = renderer(p, s.clone());
            let mut frames = vec![over_black(&draw(&mut r, &mut g, &path[0], 16))];
            for c in &path[1..] {
                frames.push(over_black(&draw(&mut r, &mut g, c, 1)));
            }
            steadiness(&frames) / truth
        })
        .collect()
}

/// In motion the history is reprojected and resampled every frame: the anti-aliased frame
/// must stay well nearer the supersampled reference than the one-sample frame, and the
/// dilated motion must count: without `dilate` the history's soft silhouette stays behind
/// the moving object as a ghost on the background. (`unjitter` is logged: at this level's
/// large voxels its gain is within 1 %; the quality preset measures it at level 8.)
#[test]
fn a_moving_camera_stays_nearer_the_supersampled_reference_than_one_sample() {
    let (e_aa, e_plain) = moving_error(AA, PLAIN);
    let variant = |param: &str| {
        let text = AA.replace("kind: Temporal(", &format!("kind: Temporal({param}, "));
        assert_ne!(text, AA, "the pipeline's Temporal pass changed");
        moving_error(&text, PLAIN).0
    };
    let (no_dilate, no_unjitter) = (variant("dilate: false"), variant("unjitter: false"));
    let clipped = |to: f32| {
        let clip = temporal_params(AA).variance_clip;
        let text = AA.replace(
            &format!("variance_clip: {clip}"),
            &format!("variance_clip: {to:?}"),
        );
        assert_ne!(text, AA, "the pipeline sets a variance_clip");
        moving_error(&text, PLAIN).0
    };
    let (min_max, tight) = (clipped(MAX_VARIANCE_CLIP), clipped(0.05));
    eprintln!(
        "error against 16 samples after 8 moving frames: plain {e_plain:.5}, AA {e_aa:.5}, \
         without dilate {no_dilate:.5}, without unjitter {no_unjitter:.5}, `variance_clip` 3 {min_max:.5}, 0.05 {tight:.5}"
    );
    // Measured: 0.67 of the one-sample frame's error (the raster form: 0.64), 0.64 of the
    // error without dilate (1.05 of one sample's). Bounds: each plus about 0.1.
    assert!(e_aa < 0.77 * e_plain, "{e_aa} against {e_plain}");
    assert!(
        e_aa < 0.8 * no_dilate,
        "{e_aa} against {no_dilate} without dilate"
    );
    // `variance_clip` reaches the moving pipeline: held to 0.05 deviations of the mean the
    // history is mostly dropped (measured 0.00804 against 0.00777 with the min-max bounds,
    // 3.5 %; at this level the bundled 0.75 is within 1 % of either). Bound: 1 %.
    assert!(
        tight > 1.01 * min_max,
        "variance_clip 0.05: {tight}, 3: {min_max}"
    );
    let (e_raster_aa, e_raster) = moving_error(RASTER_AA, RASTER);
    eprintln!("the raster form: plain {e_raster:.5}, AA {e_raster_aa:.5}");
    assert!(
        e_raster_aa < 0.75 * e_raster,
        "{e_raster_aa} against {e_raster}"
    );
}

/// Along an orbit of a degree a frame (a pixel or two of motion at the silhouette) the
/// anti-aliased frames change from one to the next less than the supersampled reference's
/// do (its history smooths what the jitter adds), and the one-sample frames more (their
/// silhouettes step from pixel to pixel): the quality preset's flicker ratio, at the tests'
/// level.
#[test]
fn a_moving_camera_flickers_less_than_one_sample_and_no_more_than_the_truth() {
    let [plain, aa] = orbit_flicker(&[PLAIN, AA], 12, 1.0)[..] else {
        unreachable!("two pipelines")
    };
    eprintln!("frame-to-frame change over the reference's: plain {plain:.3}, AA {aa:.3}");
    // Measured: plain 1.21, AA 0.87 (with the min-max bounds, `variance_clip` 3: 0.87; with
    // the history clipped to 0.05 deviations: 0.88: at this level the clamp's share is
    // small; the quality preset measures it at level 8). Bounds: the 1.0 less a
    // margin for AA, and above 0.6 (a frame that lags or freezes changes less than the
    // truth's); a tenth above the truth for one sample (the measure must see it).
    assert!(aa < 0.95 && aa > 0.6, "{aa}");
    assert!(plain > 1.1, "{plain}");
}

/// For each camera of `path` after the first, `aa`'s output's mean difference (linear, over
/// black) from the one-sample frame of that camera over that from the one-sample frame of
/// the camera before, both pipelines drawing `scene` frame after frame.
fn follows_along(scene: &Scene, path: &[Camera]) -> Vec<f64> {
    // The history is under test, not the level choice: the AA frame at the plain frame's
    // levels (its `lod_bias` is checked on its own below).
    let (mut aa, mut aa_scene) = renderer(&without_lod_bias(AA), scene.clone());
    let (mut plain, mut plain_scene) = renderer(PLAIN, scene.clone());
    let mut previous: Option<Vec<[f64; 3]>> = None;
    let mut ratios = Vec::new();
    for c in path {
        let a = over_black(&draw(&mut aa, &mut aa_scene, c, 1));
        let p = over_black(&draw(&mut plain, &mut plain_scene, c, 1));
        assert_eq!(
            aa_scene.lod_histogram(),
            plain_scene.lod_histogram(),
            "both draw the same levels"
        );
        if let Some(before) = &previous {
            ratios.push(mean_abs_error(&a, &p) / mean_abs_error(&a, before));
        }
        previous = Some(p);
    }
    ratios
}

/// Extremes: 4096 bunnies under Auto LOD while the camera dollies in (instances switch
/// levels every frame), then a camera inside the bunny's proxy, between its voxels,
/// turning. Every frame draws without a validation error (`draw` checks), and each
/// anti-aliased frame is nearer its own camera's one-sample frame than the previous
/// camera's: a history kept across a level switch or a large move would pull it back.
#[test]
fn many_instances_switching_levels_and_a_camera_inside_keep_no_stale_history() {
    let grid = crate::scale::bunny_grid(64, 4, ssbvb_gpu::scene::LodPolicy::AUTO);
    let look = DVec3::new(0.0, -1.0, 0.0);
    let far = DVec3::new(-40.0, 12.0, -40.0);
    let dolly: Vec<Camera> = (0..10)
        .map(|i| Camera::new(look + (far - look) * (1.0 - 0.02 * i as f64), look))
        .collect();
    let (mut r, mut g) = renderer(PLAIN, grid.clone());
    let mut levels = Vec::new();
    for c in &dolly {
        draw(&mut r, &mut g, c, 1);
        let mut l: Vec<(u32, u32)> = g.visible.iter().map(|v| (v.scene_index, v.level)).collect();
        l.sort();
        levels.push(l);
    }
    let switches = levels.windows(2).filter(|w| w[0] != w[1]).count();
    let along_dolly = follows_along(&grid, &dolly);
    let eye = DVec3::new(0.05, 0.0, 0.1);
    let inside: Vec<Camera> = (0..6)
        .map(|i| {
            let turn = glam::DQuat::from_rotation_y((4.0 * i as f64).to_radians());
            Camera::new(eye, eye + turn * DVec3::new(0.3, -0.2, -1.0))
        })
        .collect();
    let along_inside = follows_along(&scene(), &inside);
    eprintln!(
        "{switches} of 9 dolly steps switch levels; the anti-aliased frame's difference from \
         its own one-sample frame over that from the previous one: dolly {along_dolly:.3?}, \
         inside {along_inside:.3?}"
    );
    assert!(switches >= 5, "the dolly must switch levels: {switches}");
    // Measured: 0.62-0.73 on the dolly (its bunnies are a few pixels, and the jitter's
    // half-pixel shift is most of the difference), 0.11-0.15 inside; with the history read
    // where the pixel is rather than where its surface was, 0.80-1.06 and 0.25-0.32 (the
    // clamp on). Bounds: each plus about 0.12.
    let worst = |v: &[f64]| v.iter().fold(0.0f64, |m, &d| m.max(d));
    assert!(worst(&along_dolly) < 0.85, "{along_dolly:?}");
    assert!(worst(&along_inside) < 0.27, "{along_inside:?}");
}

/// The parameters of `pipeline`'s temporal pass.
fn temporal_params(pipeline: &str) -> ssbvb_graph::TemporalParams {
    let resolved = ssbvb_graph::resolve_str(pipeline, "test pipeline").unwrap();
    resolved
        .passes
        .iter()
        .find_map(|p| match &p.kind {
            ssbvb_graph::PassKind::Temporal(t) => Some(*t),
            _ => None,
        })
        .expect("a temporal pass")
}

/// `pipeline` with its temporal pass's `lod_bias` set to 0.
fn without_lod_bias(pipeline: &str) -> String {
    let bias = temporal_params(pipeline).lod_bias;
    let out = pipeline.replace(&format!("lod_bias: {bias}"), "lod_bias: 0");
    assert!(bias > 0 && out != pipeline, "the pipeline sets a lod_bias");
    out
}

/// Sorted (instance, level) pairs of the instances `pipeline` draws of `scene` from
/// `camera`, after two frames (the second holds the first's levels by hysteresis).
fn drawn_levels(pipeline: &str, scene: &Scene, camera: &Camera) -> Vec<(u32, u32)> {
    let (mut r, mut g) = renderer(pipeline, scene.clone());
    draw(&mut r, &mut g, camera, 2);
    let mut l: Vec<(u32, u32)> = g.visible.iter().map(|v| (v.scene_index, v.level)).collect();
    l.sort();
    l
}

/// The anti-aliased pipelines draw each Auto LOD instance `lod_bias` levels finer than the
/// plain frame, at most the asset's finest; instances at a fixed level keep it, and with
/// `lod_bias` 0 the levels are the plain frame's.
#[test]
fn a_temporal_pass_draws_auto_lod_instances_lod_bias_levels_finer() {
    use ssbvb_gpu::scene::LodPolicy;
    let finest = 6;
    let auto = crate::scale::bunny_grid(8, finest, LodPolicy::AUTO);
    let camera = Camera::new(DVec3::new(-4.0, 9.0, 14.0), DVec3::ZERO);
    let plain = drawn_levels(PLAIN, &auto, &camera);
    let levels: std::collections::BTreeSet<u32> = plain.iter().map(|p| p.1).collect();
    eprintln!("plain frame's levels: {levels:?}");
    assert!(plain.len() >= 32, "{} instances drawn", plain.len());
    assert!(
        levels.len() >= 2 && levels.iter().any(|&l| l + 2 < finest),
        "the view must hold several levels well below the finest: {levels:?}"
    );
    for aa in [AA, RASTER_AA] {
        let bias = temporal_params(aa).lod_bias;
        let finer: Vec<(u32, u32)> = plain
            .iter()
            .map(|&(i, l)| (i, (l + bias).min(finest)))
            .collect();
        assert_eq!(drawn_levels(aa, &auto, &camera), finer);
        assert_eq!(drawn_levels(&without_lod_bias(aa), &auto, &camera), plain);
    }
    let fixed = crate::scale::bunny_grid(8, finest, LodPolicy::Fixed(3));
    let fixed_levels = drawn_levels(AA, &fixed, &camera);
    assert!(!fixed_levels.is_empty());
    assert!(
        fixed_levels.iter().all(|&(_, l)| l == 3),
        "{fixed_levels:?}"
    );
}
