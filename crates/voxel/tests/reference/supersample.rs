//! The supersampled reference (`render_supersampled`) against coverage computed from the
//! geometry: a block's silhouette edge placed at a known fraction of a pixel, seen head on
//! with a light that makes its face one flat colour.

use glam::{DAffine3, DVec3};
use ssbvb_voxel::asset::{LodLevel, PackedVoxel, PointCloud, ProxyMesh, SparseLookup};
use ssbvb_voxel::camera::Camera;
use ssbvb_voxel::reference::{
    Instance, MAX_SAMPLES, ReferenceImage, SampleGrid, render, render_supersampled,
};
use ssbvb_voxel::shading::{Light, linear_to_srgb8};
use ssbvb_voxel::svo::morton_encode;

const LEVEL: u32 = 3;
const W: u32 = 9;
const H: u32 = 7;

/// The left half of the grid (x in [-1, 0]), every voxel facing +z with one colour.
fn half_block() -> LodLevel {
    let n = 1u32 << LEVEL;
    let mut cells: Vec<[u32; 3]> = (0..n)
        .flat_map(|z| (0..n).flat_map(move |y| (0..n / 2).map(move |x| [x, y, z])))
        .collect();
    cells.sort_by_key(|&c| morton_encode(c));
    let voxels = cells
        .iter()
        .map(|&c| PackedVoxel::new(c, [0.0, 0.0, 1.0], [0.8, 0.5, 0.2, 1.0], [0.0; 2]))
        .collect();
    LodLevel {
        level: LEVEL,
        point_cloud: PointCloud { voxels },
        lookup: SparseLookup::from_cells(LEVEL, cells.iter().copied()),
        proxy: ProxyMesh::default(),
    }
}

/// No highlight: the face's shading does not depend on where in it a ray lands.
fn flat_light() -> Light {
    Light {
        specular: 0.0,
        ..Light::default()
    }
}

/// A camera 1 in front of the block's face (z = 1), looking along -z, moved along x so that
/// the edge x = 0 projects to image column position `edge_px` (pixels from the left; right
/// of the image's centre, where rays move away from the block's side face x = 0).
fn camera_with_edge_at(edge_px: f64) -> Camera {
    assert!(edge_px >= W as f64 / 2.0);
    let probe = Camera::new(DVec3::new(0.0, 0.0, 2.0), DVec3::ZERO);
    let rays = probe.pixel_rays(W, H);
    // The world x that the probe's ray through `edge_px` meets on the plane z = 1.
    let (o, d) = rays.ray_at(edge_px, H as f64 / 2.0);
    let x = o.x + d.x * (o.z - 1.0) / -d.z;
    Camera::new(DVec3::new(-x, 0.0, 2.0), DVec3::new(-x, 0.0, 0.0))
}

fn render_with(lod: &LodLevel, camera: &Camera, samples: u32) -> ReferenceImage {
    let inst = [Instance {
        lod,
        object_to_world: DAffine3::IDENTITY,
        faces: None,
    }];
    let grid = SampleGrid::from_count(samples).unwrap();
    render_supersampled(&inst, camera, W, H, &flat_light(), grid)
}

/// The face's colour: the one-sample render's colour at a pixel well inside it.
fn face_colour(lod: &LodLevel, camera: &Camera) -> [f32; 4] {
    let inst = [Instance {
        lod,
        object_to_world: DAffine3::IDENTITY,
        faces: None,
    }];
    let one = render(&inst, camera, W, H, &flat_light());
    let c = one.color(0, H / 2);
    assert_eq!(c[3], 1.0, "column 0 shows the face");
    c
}

#[test]
fn a_pixel_split_by_an_edge_at_its_centre_is_half_covered() {
    let lod = half_block();
    // The edge through the centre of column 5: columns 0-4 inside, 6-8 outside.
    let camera = camera_with_edge_at(5.5);
    let face = face_colour(&lod, &camera);
    for samples in [4, 16, 64] {
        let img = render_with(&lod, &camera, samples);
        for y in 0..H {
            for x in 0..W {
                let c = img.color(x, y);
                let coverage = match x {
                    0..=4 => 1.0,
                    5 => 0.5,
                    _ => 0.0,
                };
                // Half the strata of a k × k grid (k even) lie left of the pixel's centre.
                for ch in 0..3 {
                    assert!(
                        (c[ch] - face[ch] * coverage).abs() < 1e-6,
                        "{samples} samples, ({x}, {y}): {c:?}, face {face:?} × {coverage}"
                    );
                }
                assert!(
                    (c[3] - coverage).abs() < 1e-6,
                    "{samples}: ({x}, {y}) {c:?}"
                );
            }
        }
        // The hits stay the centre ray's.
        assert!(img.hit(4, H / 2).is_some() && img.hit(6, H / 2).is_none());
    }
}

#[test]
fn coverage_of_a_pixel_converges_to_the_covered_fraction() {
    let lod = half_block();
    for fraction in [0.1, 0.3, 0.62, 0.9] {
        let camera = camera_with_edge_at(5.0 + fraction);
        for samples in [4, 16, 64, 256] {
            let img = render_with(&lod, &camera, samples);
            let k = (samples as f64).sqrt();
            // Each column of strata is all in or all out but the one the edge crosses.
            let alpha = img.color(5, H / 2)[3] as f64;
            assert!(
                (alpha - fraction).abs() <= 1.0 / k + 1e-6,
                "{samples} samples, edge at {fraction}: coverage {alpha}"
            );
            assert_eq!(img.color(4, H / 2)[3], 1.0);
            assert_eq!(img.color(6, H / 2)[3], 0.0);
        }
    }
}

#[test]
fn samples_lie_one_in_each_stratum_jittered_and_reproducibly() {
    let grid = SampleGrid::from_count(16).unwrap();
    assert_eq!(grid.count(), 16);
    let mut offsets = std::collections::BTreeSet::new();
    for (px, py) in [(0, 0), (5, 3), (1000, 2000)] {
        for i in 0..16 {
            let (x, y) = grid.position(px, py, i);
            let (fx, fy) = (x - px as f64, y - py as f64);
            let (sx, sy) = ((i % 4) as f64, (i / 4) as f64);
            assert!(
                fx >= sx / 4.0 && fx < (sx + 1.0) / 4.0 && fy >= sy / 4.0 && fy < (sy + 1.0) / 4.0,
                "pixel ({px}, {py}) sample {i} at ({fx}, {fy})"
            );
            assert_eq!(grid.position(px, py, i), (x, y));
            offsets.insert(((fx * 4.0).fract().to_bits(), (fy * 4.0).fract().to_bits()));
        }
    }
    // Jittered: no two samples at the same place in their strata.
    assert_eq!(offsets.len(), 48);
    assert_eq!(SampleGrid::CENTRE.position(7, 2, 0), (7.5, 2.5));
    let lod = half_block();
    let camera = camera_with_edge_at(5.3);
    assert_eq!(
        render_with(&lod, &camera, 16),
        render_with(&lod, &camera, 16)
    );
}

#[test]
fn sample_counts_run_from_1_to_1024_on_the_most_nearly_square_grid() {
    for (n, strata) in [
        (1, (1, 1)),
        (4, (2, 2)),
        (8, (4, 2)),
        (12, (4, 3)),
        (16, (4, 4)),
        (7, (7, 1)),
        (256, (16, 16)),
        (1024, (32, 32)),
    ] {
        let g = SampleGrid::from_count(n).unwrap();
        assert_eq!((g.count(), g.strata()), (n, strata));
    }
    for n in [0, 1025, u32::MAX] {
        let e = SampleGrid::from_count(n).unwrap_err().to_string();
        assert!(
            e.contains(&n.to_string()) && e.contains("from 1 to 1024"),
            "{e}"
        );
    }
    assert_eq!(MAX_SAMPLES, 1024);
}

#[test]
fn every_stratum_of_a_pixel_holds_exactly_one_sample() {
    for n in [2, 6, 8, 9, 13] {
        let g = SampleGrid::from_count(n).unwrap();
        let (cols, rows) = g.strata();
        let mut seen = vec![0; n as usize];
        for i in 0..n {
            let (x, y) = g.position(3, 5, i);
            assert!(
                (3.0..4.0).contains(&x) && (5.0..6.0).contains(&y),
                "{n}: {x} {y}"
            );
            let (sx, sy) = (
                ((x - 3.0) * cols as f64) as u32,
                ((y - 5.0) * rows as f64) as u32,
            );
            seen[(sy * cols + sx) as usize] += 1;
        }
        assert!(seen.iter().all(|&c| c == 1), "{n}: {seen:?}");
    }
}

#[test]
fn partly_covered_pixels_are_written_with_straight_alpha() {
    let img = ReferenceImage {
        width: 3,
        height: 1,
        hits: vec![None; 3],
        colors: vec![[0.25, 0.1, 0.4, 0.5], [0.5, 0.2, 0.8, 1.0], [0.0; 4]],
    };
    let px = img.to_rgba8();
    let s = linear_to_srgb8;
    assert_eq!(&px[0..4], &[s(0.5), s(0.2), s(0.8), 128]);
    assert_eq!(&px[4..8], &[s(0.5), s(0.2), s(0.8), 255]);
    assert_eq!(&px[8..12], &[0, 0, 0, 0]);
}
