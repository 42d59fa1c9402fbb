//! Every test model (`assets/models`) through the whole SSBVB pipeline, against the CPU reference, from
//! several cameras: coverage IoU, same voxel, depth error in voxels, normal error.
//!
//! Tolerances: RayBox billboards intersect the voxel box exactly, so coverage IoU must be
//! ≥ 0.99 (rays through voxel edges may break ties differently in f32 than the reference's
//! f64) and the median depth error ≤ 0.01 voxel. Flat billboards (the paper) cover each
//! voxel's whole projection at the voxel centre's depth: IoU ≥ 0.985 and median depth
//! error ≤ 0.6 voxel along the ray (half a voxel in view depth, / cos of the ray angle).
//! Both modes: at most 8 interior holes per view. The values reached: docs/benchmarks.md.

use glam::DVec3;
use ssbvb_passes::measure::ssbvb::read_slots;
use ssbvb_voxel::accuracy::{self, GpuHit};
use ssbvb_voxel::camera::Camera;

const SSBVB: &str = include_str!("../../../assets/pipelines/ssbvb_flat.ron");
const SIZE: (u32, u32) = (120, 90);

const MODELS: &[(&str, u32)] = &[
    ("bunny.obj", 6),
    ("teapot.obj", 6),
    ("cow.obj", 6),
    ("igea.ply", 6),
    ("chr_knight.vox", 5),
    ("T-Rex.vox", 6),
    ("monu1.vox", 6),
];

fn cameras() -> Vec<Camera> {
    vec![
        Camera::new(DVec3::new(1.8, 1.1, 2.4), DVec3::ZERO),
        Camera::new(DVec3::new(-2.6, -0.8, -1.5), DVec3::new(0.0, 0.1, 0.0)),
        // Straight down the Z axis: rays parallel to grid planes.
        Camera::new(DVec3::new(0.0, 0.0, 3.2), DVec3::ZERO),
    ]
}

fn check(mode: &str) {
    let src = SSBVB.replace("Billboards(mode: Flat", &format!("Billboards(mode: {mode}"));
    for &(file, level) in MODELS {
        let asset = ssbvb_tests::model_asset(file, level);
        let cell = 2.0 / (1u64 << level) as f64;
        for (ci, cam) in cameras().iter().enumerate() {
            let scene = ssbvb_tests::single_object_scene(asset.clone(), level);
            let reference = ssbvb_tests::reference_of(&scene, cam, SIZE);
            let f = ssbvb_tests::render(&src, scene, cam, SIZE);
            let albedo = f.read("gbuffer_albedo");
            let pos = f.read_f32("gbuffer_position");
            let normal = ssbvb_tests::read_geometric_normals(&f);
            let slots = read_slots(ssbvb_tests::ctx(), &f.renderer).unwrap();
            let mut slot_cell = vec![None; (SIZE.0 * SIZE.1) as usize];
            for s in &slots {
                slot_cell[s.pixel as usize] = Some(s.voxel.cell());
            }
            let hits: Vec<Option<GpuHit>> = (0..slot_cell.len())
                .map(|i| {
                    (albedo[i * 4 + 3] > 0).then(|| {
                        let p = &pos[i * 4..i * 4 + 3];
                        assert!(
                            p.iter().chain(&normal[i]).all(|v| v.is_finite()),
                            "{file}: NaN at {i}"
                        );
                        GpuHit {
                            instance: 0,
                            cell: slot_cell[i].unwrap_or([u32::MAX; 3]),
                            t: (p[0] as f64).hypot(p[1] as f64).hypot(p[2] as f64),
                            normal: normal[i],
                        }
                    })
                })
                .collect();
            let r = accuracy::compare(&reference, &hits, &[cell]).unwrap();
            // Holes: pixels the reference covers, the GPU does not, away from silhouettes
            // (all eight neighbours covered by the reference too).
            let (w, h) = (SIZE.0 as i64, SIZE.1 as i64);
            let covered = |x: i64, y: i64| {
                x >= 0 && y >= 0 && x < w && y < h && reference.hits[(y * w + x) as usize].is_some()
            };
            let mut holes = 0;
            for y in 0..h {
                for x in 0..w {
                    let i = (y * w + x) as usize;
                    let interior = (-1..=1).all(|dy| (-1..=1).all(|dx| covered(x + dx, y + dy)));
                    holes += (interior && hits[i].is_none()) as usize;
                }
            }
            eprintln!("{mode} {file} camera {ci}: {holes} interior holes");
            // Measured: none, except 4 on the cow seen straight down the Z axis in both modes
            // (rays exactly on cell planes between two of its parts, where f32 and the f64
            // reference break the tie differently).
            assert!(
                holes <= 8,
                "{mode} {file} camera {ci}: {holes} holes inside the object"
            );
            eprintln!(
                "{mode} {file} L{level} camera {ci}: IoU {:.4}, same voxel {:.4}, depth median {:.4} p95 {:.3} voxels, normal median {:.2}°",
                r.coverage_iou,
                r.same_voxel_rate,
                r.depth_error_voxels.median,
                r.depth_error_voxels.p95,
                r.normal_error_deg.median
            );
            assert!(
                r.covered_reference > 200,
                "{file} camera {ci}: only {} px",
                r.covered_reference
            );
            assert!(r.same_voxel_rate >= 0.99, "{file} camera {ci}: {r:?}");
            match mode {
                "RayBox" => {
                    assert!(r.coverage_iou >= 0.99, "{file} camera {ci}: {r:?}");
                    assert!(
                        r.depth_error_voxels.median <= 0.01,
                        "{file} camera {ci}: {r:?}"
                    );
                    assert!(
                        r.normal_error_deg.median <= 1.0,
                        "{file} camera {ci}: {r:?}"
                    );
                }
                _ => {
                    // Measured: IoU 0.9889 at worst (the knight, silhouettes of voxels
                    // several pixels wide); bound with a margin.
                    assert!(r.coverage_iou >= 0.985, "{file} camera {ci}: {r:?}");
                    assert!(
                        r.depth_error_voxels.median <= 0.6,
                        "{file} camera {ci}: {r:?}"
                    );
                    // Flat billboards report the face their pixel's ray enters.
                    assert!(
                        r.normal_error_deg.median <= 1.0,
                        "{file} camera {ci}: {r:?}"
                    );
                }
            }
        }
    }
}

#[test]
fn every_shared_model_matches_the_reference_with_ray_box_billboards() {
    check("RayBox");
}

#[test]
fn every_shared_model_matches_the_reference_with_flat_billboards() {
    check("Flat");
}
