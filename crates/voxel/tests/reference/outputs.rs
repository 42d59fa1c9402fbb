//! The reference's outputs against values computed here: each hit's shaded colour, the
//! image accessors, the tie between identical instances and the PNG encodings of normals
//! and depth (mutation testing found these unpinned: `docs/reliability.md`).

use glam::{DAffine3, DVec3};
use ssbvb_voxel::camera::Camera;
use ssbvb_voxel::reference::{Hit, Instance, ReferenceImage, render, shade_hit, trace_ray};
use ssbvb_voxel::shading::{Light, shade};

use super::{ball_cells, lod};

/// A light with a strong highlight, so the view direction matters.
fn light() -> Light {
    Light {
        specular: 0.8,
        shininess: 8.0,
        ..Light::default()
    }
}

#[test]
fn colours_are_the_shading_of_the_hit_voxels() {
    let l = lod(4, &ball_cells(4, 0.8));
    let inst = [Instance {
        lod: &l,
        object_to_world: DAffine3::IDENTITY,
        faces: None,
    }];
    let cam = Camera::new(DVec3::new(1.2, 0.9, 2.2), DVec3::ZERO);
    let (w, h) = (32, 24);
    let light = light();
    let img = render(&inst, &cam, w, h, &light);
    assert!(img.coverage() > 150, "{}", img.coverage());
    let rays = cam.pixel_rays(w, h);
    let mut distinct = std::collections::BTreeSet::new();
    for y in 0..h {
        for x in 0..w {
            let i = (y * w + x) as usize;
            assert_eq!(img.color(x, y), img.colors[i]);
            let Some(hit) = img.hit(x, y) else {
                assert_eq!(img.color(x, y), [0.0; 4]);
                continue;
            };
            let (o, d) = rays.ray(x, y);
            // By hand: the voxel's colour and stored normal (identity transform), the view
            // toward the eye.
            let v = &l.point_cloud.voxels[hit.voxel as usize];
            let c = v.color();
            let view = (-d).as_vec3().to_array();
            let rgb = shade([c[0], c[1], c[2]], v.normal(), view, &light);
            let got = img.colors[i];
            for k in 0..3 {
                assert!(
                    (got[k] - rgb[k]).abs() < 1e-6,
                    "({x}, {y}): {got:?} vs {rgb:?}"
                );
            }
            assert_eq!(got[3], 1.0);
            assert_eq!(shade_hit(&inst, hit, d, &light), got);
            distinct.insert(got.map(f32::to_bits));
            // The single-ray entry point finds the same hit (it normalizes the direction:
            // the same up to rounding).
            let again = trace_ray(&inst, o, d * 3.0, rays.forward()).unwrap();
            assert_eq!(
                (again.voxel, again.cell, again.face_normal),
                (hit.voxel, hit.cell, hit.face_normal)
            );
            assert!(
                (again.t - hit.t).abs() < 1e-12
                    && (again.view_depth - hit.view_depth).abs() < 1e-12
            );
        }
    }
    assert!(distinct.len() > 20, "{} distinct colours", distinct.len());
}

#[test]
fn identical_instances_tie_to_the_lowest_index() {
    let l = lod(3, &ball_cells(3, 0.9));
    let inst: Vec<Instance> = (0..4)
        .map(|_| Instance {
            lod: &l,
            object_to_world: DAffine3::from_translation(DVec3::new(0.1, 0.0, 0.0)),
            faces: None,
        })
        .collect();
    let img = render(&inst, &Camera::default(), 24, 18, &Light::default());
    assert!(img.coverage() > 50);
    assert!(img.hits.iter().flatten().all(|h| h.instance == 0));
    // The same voxel in two instances whose boxes differ (so the hierarchy meets them in
    // either order): where both show it at the same distance, the lower index wins.
    let small = lod(2, &[[2, 2, 2]]);
    let big = lod(2, &[[2, 2, 2], [0, 0, 0], [3, 3, 3], [0, 3, 0]]);
    for (first, second) in [(&small, &big), (&big, &small)] {
        let inst = [first, second].map(|l| Instance {
            lod: l,
            object_to_world: DAffine3::IDENTITY,
            faces: None,
        });
        for eye in [
            DVec3::new(2.0, 1.5, 3.0),
            DVec3::new(-3.0, -1.0, -2.0),
            DVec3::new(0.2, 3.5, 0.1),
        ] {
            let img = render(
                &inst,
                &Camera::new(eye, DVec3::splat(0.25)),
                32,
                24,
                &Light::default(),
            );
            let shared: Vec<_> = img
                .hits
                .iter()
                .flatten()
                .filter(|h| h.cell == [2, 2, 2])
                .collect();
            assert!(!shared.is_empty(), "{eye:?}");
            assert!(shared.iter().all(|h| h.instance == 0), "{eye:?}");
        }
    }
}

#[test]
fn an_image_without_pixels_renders_nothing() {
    let l = lod(2, &[[1, 1, 1]]);
    let inst = [Instance {
        lod: &l,
        object_to_world: DAffine3::IDENTITY,
        faces: None,
    }];
    for (w, h) in [(0, 5), (5, 0), (0, 0)] {
        let img = render(&inst, &Camera::default(), w, h, &Light::default());
        assert!(img.hits.is_empty() && img.colors.is_empty(), "{w}x{h}");
        assert!(img.all_finite());
    }
}

fn hit(normal: [f32; 3], depth: f64) -> Hit {
    Hit {
        instance: 0,
        voxel: 0,
        cell: [0; 3],
        t: depth,
        view_depth: depth,
        face_normal: normal,
        position: DVec3::new(0.0, 0.0, -depth),
        inside: false,
    }
}

fn image(hits: Vec<Option<Hit>>) -> ReferenceImage {
    let n = hits.len();
    ReferenceImage {
        width: n as u32,
        height: 1,
        colors: hits
            .iter()
            .map(|h| {
                if h.is_some() {
                    [0.5, 0.25, 1.0, 1.0]
                } else {
                    [0.0; 4]
                }
            })
            .collect(),
        hits,
    }
}

#[test]
fn all_finite_checks_every_field() {
    let good = image(vec![Some(hit([0.0, 0.0, 1.0], 2.0)), None]);
    assert!(good.all_finite());
    let mut bad = Vec::new();
    let mut c = good.clone();
    c.colors[1][2] = f32::NAN;
    bad.push(("colour", c));
    for field in 0..4 {
        let mut c = good.clone();
        let h = c.hits[0].as_mut().unwrap();
        match field {
            0 => h.t = f64::INFINITY,
            1 => h.view_depth = f64::NAN,
            2 => h.position.y = f64::NAN,
            _ => h.face_normal[1] = f32::INFINITY,
        }
        bad.push(("hit field", c));
    }
    for (what, img) in bad {
        assert!(!img.all_finite(), "{what}");
    }
}

#[test]
fn normals_and_depth_encode_as_documented() {
    let img = image(vec![
        Some(hit([1.0, 0.0, 0.0], 2.0)),
        Some(hit([0.0, -1.0, 0.0], 4.0)),
        None,
        Some(hit([0.6, 0.0, -0.8], 6.0)),
    ]);
    // n · 0.5 + 0.5, rounded: 1 → 255, 0 → 128, −1 → 0, 0.6 → 204, −0.8 → 25 (0.1 in f32
    // is 0.099999994).
    assert_eq!(
        img.normals_rgba8(),
        [
            255, 128, 128, 255, 128, 0, 128, 255, 0, 0, 0, 0, 204, 128, 25, 255
        ]
    );
    // Nearest white, farthest 0.2 · 255 = 51, linear between (4 → 0.6 · 255 = 153).
    assert_eq!(
        img.depth_rgba8(),
        [
            255, 255, 255, 255, 153, 153, 153, 255, 0, 0, 0, 0, 51, 51, 51, 255
        ]
    );
    // One depth only: everything white.
    let flat = image(vec![
        Some(hit([0.0, 0.0, 1.0], 3.0)),
        Some(hit([0.0, 0.0, 1.0], 3.0)),
    ]);
    assert_eq!(flat.depth_rgba8(), [255; 8]);
    // sRGB colours: linear 0.5 → 188, 0.25 → 137, 1 → 255; alpha straight.
    assert_eq!(&img.to_rgba8()[..4], &[188, 137, 255, 255]);
}
