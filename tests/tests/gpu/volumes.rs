//! Volumetric billboards against the emission–absorption reference: the cloud
//! and the bunny's coverage volume alone, and both mixed with an opaque bunny and the
//! ground plane.

use std::sync::Arc;

use glam::{DAffine3, DVec3};
use ssbvb_gpu::scene::{Scene, VolumeObject};
use ssbvb_tests::render;
use ssbvb_voxel::camera::Camera;
use ssbvb_voxel::rgba_volume::RgbaVolume;
use ssbvb_voxel::rgba_volume::integrate::{self, PlacedVolume};
use ssbvb_voxel::rgba_volume::slicing::choose_level;
use ssbvb_voxel::rgba_volume::sources::{Cloud, from_mesh_coverage};

const VOLUMETRIC: &str = include_str!("../../../assets/pipelines/volumetric.ron");
const SIZE: (u32, u32) = (320, 240);

fn cloud() -> Arc<RgbaVolume> {
    Arc::new(Cloud::default().volume(64).unwrap())
}

fn bunny_volume() -> Arc<RgbaVolume> {
    let mesh = ssbvb_voxel::load::load_mesh(&ssbvb_tests::models_dir().join("bunny.obj")).unwrap();
    Arc::new(from_mesh_coverage(&mesh, 6).unwrap())
}

fn camera() -> Camera {
    let mut c = Camera::new(DVec3::new(1.4, 0.9, 2.9), DVec3::new(0.0, 0.0, 0.0));
    c.near = 0.01;
    c.far = 100.0;
    c
}

/// PSNR (dB) of two sRGB8 RGBA images over the pixels either shows (alpha > 0).
fn psnr_where_drawn(a: &[u8], b: &[u8]) -> (f64, usize) {
    let (mut sq, mut n) = (0.0f64, 0usize);
    for (p, q) in a.chunks(4).zip(b.chunks(4)) {
        if p[3] > 0 || q[3] > 0 {
            for c in 0..3 {
                sq += (f64::from(p[c]) - f64::from(q[c])).powi(2);
            }
            n += 1;
        }
    }
    let mse = sq / (3 * n.max(1)) as f64;
    (10.0 * (255.0 * 255.0 / mse.max(1e-12)).log10(), n)
}

fn write_pair(name: &str, gpu: &[u8], reference: &[u8]) {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("volumes");
    std::fs::create_dir_all(&dir).unwrap();
    let (w, h) = SIZE;
    let mut both = vec![0u8; (w * h * 8) as usize];
    for y in 0..h as usize {
        let row = w as usize * 4;
        both[y * 2 * row..][..row].copy_from_slice(&gpu[y * row..][..row]);
        both[y * 2 * row + row..][..row].copy_from_slice(&reference[y * row..][..row]);
    }
    ssbvb_voxel::reference::write_png_atomic(&dir.join(format!("{name}.png")), w * 2, h, &both)
        .unwrap();
}

/// One volume alone at the default knobs (`volumetric.ron`: half-texel slices, the level
/// by distance) against the integral at the level the slicer chose. The issue's target is
/// 35 dB at 320×240; the bounds sit about 2.5 dB under the measurements (llvmpipe).
fn volume_alone(name: &str, volume: Arc<RgbaVolume>, xf: DAffine3) -> f64 {
    volume_alone_biased(name, volume, xf, 0.0)
}

/// [`volume_alone`] with `mip_bias` levels added (the reference samples the same level).
fn volume_alone_biased(name: &str, volume: Arc<RgbaVolume>, xf: DAffine3, mip_bias: f32) -> f64 {
    let cam = camera();
    let scene = Scene {
        volumes: vec![VolumeObject {
            name: name.into(),
            volume: volume.clone(),
            instances: vec![xf],
        }],
        ..Default::default()
    };
    let pipeline = VOLUMETRIC.replace("mip_bias: 0.0)", &format!("mip_bias: {mip_bias:?})"));
    let f = render(&pipeline, scene, &cam, SIZE);
    let gpu = f.read("color");
    let level = choose_level(&volume, &xf, &cam, SIZE.1, f64::from(mip_bias));
    let placed = [PlacedVolume {
        volume: &volume,
        object_to_world: xf,
        level,
    }];
    let reference = integrate::to_srgb8(&integrate::render(&placed, &cam, SIZE, None, 4));
    write_pair(name, &gpu, &reference);
    let (psnr, n) = psnr_where_drawn(&gpu, &reference);
    eprintln!("{name}: level {level}, PSNR {psnr:.2} dB over {n} pixels");
    // The close view is level 0 by distance: the bias alone sets the level.
    assert_eq!(level, mip_bias as usize, "{name}");
    assert!(n > 5000, "{name}: {n} pixels");
    psnr
}

#[test]
fn the_cloud_matches_its_emission_absorption_integral() {
    // Measured 41.6 dB (37.7 when the slices blended straight into the 8-bit colour).
    let psnr = volume_alone("cloud", cloud(), DAffine3::IDENTITY);
    assert!(psnr >= 39.0, "{psnr}");
}

/// A mip bias samples the coarser level through the same atlas (its bricks, tables and
/// aprons), as the integral through that level does.
#[test]
fn a_mip_bias_slices_the_coarser_level_like_its_integral() {
    // Measured 41.4 dB at level 2.
    let psnr = volume_alone_biased("cloud_bias_2", cloud(), DAffine3::IDENTITY, 2.0);
    assert!(psnr >= 38.0, "{psnr}");
}

#[test]
fn the_bunny_volume_matches_its_emission_absorption_integral() {
    let xf = DAffine3::from_rotation_y(0.4);
    // Measured 50.6 dB.
    let psnr = volume_alone("bunny_volume", bunny_volume(), xf);
    assert!(psnr >= 47.0, "{psnr}");
}

/// Opaque voxels hide the volume behind them and show through the part in front: a cloud
/// half behind, half in front of an opaque bunny (RayBox billboards without smoothing, so
/// the opaque pixels are exact), against the integral ended at the reference's opaque
/// hit and composited over its colour. A slice pass that ignored the depth would paint
/// the cloud's far half over the bunny.
#[test]
fn opaque_voxels_occlude_the_volume_behind_them() {
    let level = 7;
    let cam = camera();
    let cloud_at = DAffine3::from_scale_rotation_translation(
        DVec3::splat(0.9),
        glam::DQuat::IDENTITY,
        DVec3::new(0.35, 0.1, 0.0),
    );
    let mut scene =
        ssbvb_tests::single_object_scene(ssbvb_tests::model_asset("bunny.obj", level), level);
    scene.volumes = vec![VolumeObject {
        name: "cloud".into(),
        volume: cloud(),
        instances: vec![cloud_at],
    }];
    let exact = VOLUMETRIC
        .replace("Billboards(mode: Flat", "Billboards(mode: RayBox")
        .replace(
            r#""normal": "smoothed_normal""#,
            r#""normal": "gbuffer_normal""#,
        );
    let f = render(&exact, scene.clone(), &cam, SIZE);
    let gpu = f.read("color");
    let opaque = ssbvb_tests::reference_of(&scene, &cam, SIZE);
    let volume = &scene.volumes[0].volume;
    let placed = [PlacedVolume {
        volume,
        object_to_world: cloud_at,
        level: choose_level(volume, &cloud_at, &cam, SIZE.1, 0.0),
    }];
    let reference = integrate::to_srgb8(&integrate::render(&placed, &cam, SIZE, Some(&opaque), 4));
    write_pair("cloud_and_bunny", &gpu, &reference);
    let (psnr, n) = psnr_where_drawn(&gpu, &reference);
    // Where the bunny is in front of the cloud's far half: the same pixels without the
    // depth end would be whiter.
    let rays = cam.pixel_rays(SIZE.0, SIZE.1);
    let hidden: Vec<usize> = (0..opaque.hits.len())
        .filter(|&i| {
            let (o, d) = rays.ray(i as u32 % SIZE.0, i as u32 / SIZE.0);
            opaque.hits[i].is_some_and(|h| {
                let all = integrate::integrate(&placed, o, d, f64::INFINITY, 4)[3];
                let seen = integrate::integrate(&placed, o, d, h.t, 4)[3];
                all - seen > 0.2
            })
        })
        .collect();
    // Mean sRGB8 difference over those pixels (measured 0.94; 8.48 with the depth test off).
    let hidden_error = hidden
        .iter()
        .map(|&i| {
            (0..3)
                .map(|c| f64::from(gpu[i * 4 + c].abs_diff(reference[i * 4 + c])))
                .sum::<f64>()
                / 3.0
        })
        .sum::<f64>()
        / hidden.len().max(1) as f64;
    eprintln!(
        "cloud and bunny: PSNR {psnr:.2} dB over {n} pixels; {} pixels hide > 0.2 alpha, \
         mean error there {hidden_error:.2}",
        hidden.len()
    );
    assert!(
        hidden.len() > 500,
        "the view hides too little of the cloud: {}",
        hidden.len()
    );
    assert!(hidden_error <= 2.0, "{hidden_error}");
    // Measured 44.9 dB.
    assert!(psnr >= 42.0, "{psnr}");
}

/// Scale and the extremes: 27 overlapping cloud instances (two volume objects, so both
/// the per-instance and the per-object atlas mapping are used), a camera inside one of
/// them, and a far view where the level coarsens by distance. Each against the integral
/// through the levels the slicer chose (160×120).
#[test]
fn many_instances_a_camera_inside_and_a_far_view_match_the_integral() {
    let size = (160, 120);
    let (a, b) = (
        cloud(),
        Arc::new(
            Cloud {
                seed: 9,
                ..Cloud::default()
            }
            .volume(32)
            .unwrap(),
        ),
    );
    let mut instances = [Vec::new(), Vec::new()];
    for i in 0..27 {
        let (x, y, z) = ((i % 3) as f64, ((i / 3) % 3) as f64, (i / 9) as f64);
        let xf = DAffine3::from_scale_rotation_translation(
            DVec3::splat(0.7),
            glam::DQuat::from_rotation_y(0.3 * i as f64),
            DVec3::new(x - 1.0, y - 1.0, z - 1.0) * 1.1,
        );
        instances[i % 2].push(xf);
    }
    let scene = Scene {
        volumes: vec![
            VolumeObject {
                name: "a".into(),
                volume: a.clone(),
                instances: instances[0].clone(),
            },
            VolumeObject {
                name: "b".into(),
                volume: b.clone(),
                instances: instances[1].clone(),
            },
        ],
        ..Default::default()
    };
    let inside = {
        let mut c = Camera::new(DVec3::new(0.05, 0.02, 0.03), DVec3::new(1.0, 0.3, -2.0));
        c.near = 0.001;
        c
    };
    let far = {
        // About 92 units away through a 6° lens: a pixel is ~3.6 texels of the 64³ cloud.
        let mut c = Camera::new(DVec3::new(40.0, 24.0, 80.0), DVec3::ZERO);
        c.fov_y_deg = 6.0;
        c
    };
    // Measured: grid 43.4 dB, inside 55.4, far 45.1 (levels 0 and 1); bounds ~3 dB under.
    for (name, cam, bound) in [
        ("grid", camera(), 40.0),
        ("inside", inside, 52.0),
        ("far", far, 42.0),
    ] {
        let f = render(VOLUMETRIC, scene.clone(), &cam, size);
        let gpu = f.read("color");
        let mut placed = Vec::new();
        for (v, xfs) in [(&a, &instances[0]), (&b, &instances[1])] {
            for xf in xfs {
                placed.push(PlacedVolume {
                    volume: v,
                    object_to_world: *xf,
                    level: choose_level(v, xf, &cam, size.1, 0.0),
                });
            }
        }
        let levels: Vec<usize> = placed.iter().map(|p| p.level).collect();
        let reference = integrate::to_srgb8(&integrate::render(&placed, &cam, size, None, 4));
        let (psnr, n) = psnr_where_drawn(&gpu, &reference);
        eprintln!(
            "{name}: levels {:?}..{:?}, PSNR {psnr:.2} dB over {n} pixels",
            levels.iter().min(),
            levels.iter().max()
        );
        assert!(n > 1000, "{name}: {n} pixels");
        if name == "far" {
            assert!(levels.iter().any(|&l| l >= 1), "{name}: {levels:?}");
        }
        assert!(psnr >= bound, "{name}: {psnr}");
    }
}
