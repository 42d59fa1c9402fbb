//! Several instances in one image, and the PNG outputs.

use glam::{DAffine3, DVec3};
use ssbvb_voxel::camera::Camera;
use ssbvb_voxel::reference::{Instance, ReferenceImage, render};
use ssbvb_voxel::shading::Light;

use crate::{assert_finite, ball_cells, lod, render_one};

#[test]
fn nearest_instance_wins() {
    let l = lod(4, &ball_cells(4, 0.9));
    let instances = [
        Instance {
            lod: &l,
            object_to_world: DAffine3::from_translation(DVec3::new(0.8, 0.0, -1.0)),
            faces: None,
        },
        Instance {
            lod: &l,
            object_to_world: DAffine3::from_translation(DVec3::new(-0.8, 0.2, 0.5)),
            faces: None,
        },
        // A singular transform hides its instance instead of producing NaN.
        Instance {
            lod: &l,
            object_to_world: DAffine3::from_scale(DVec3::ZERO),
            faces: None,
        },
    ];
    let cam = Camera::new(DVec3::new(0.0, 0.5, 6.0), DVec3::ZERO);
    let all = render(&instances, &cam, 64, 48, &Light::default());
    assert_finite(&all);
    let singles: Vec<ReferenceImage> = (0..2)
        .map(|i| render(&instances[i..=i], &cam, 64, 48, &Light::default()))
        .collect();
    let mut from_each = [0; 2];
    for (i, h) in all.hits.iter().enumerate() {
        let a = singles[0].hits[i];
        let b = singles[1].hits[i];
        let want = match (a, b) {
            (Some(a), Some(b)) => Some(if b.t < a.t { (1, b) } else { (0, a) }),
            (Some(a), None) => Some((0, a)),
            (None, Some(b)) => Some((1, b)),
            (None, None) => None,
        };
        match (h, want) {
            (Some(h), Some((inst, w))) => {
                assert_eq!((h.instance, h.voxel, h.t), (inst, w.voxel, w.t));
                from_each[inst as usize] += 1;
            }
            (None, None) => {}
            _ => panic!("pixel {i}: {h:?} vs {want:?}"),
        }
    }
    assert!(from_each[0] > 50 && from_each[1] > 50, "{from_each:?}");
}

/// Many overlapping instances, some placed twice at the same spot (exact ties), through
/// the instance hierarchy: every pixel equals the minimum over one-instance renders (an
/// oracle without the hierarchy), ties to the lower instance index.
#[test]
fn many_overlapping_instances_equal_the_minimum_over_single_renders() {
    let l = lod(4, &ball_cells(4, 0.8));
    let mut transforms = Vec::new();
    let mut seed = 11u64;
    let mut rnd = || {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (seed >> 11) as f64 / (1u64 << 53) as f64
    };
    for i in 0..60 {
        let xf = DAffine3 {
            matrix3: glam::DMat3::from_rotation_y(rnd() * 6.0) * (0.2 + 0.4 * rnd()),
            translation: DVec3::new(rnd() * 6.0 - 3.0, rnd() * 2.0 - 1.0, rnd() * 6.0 - 3.0),
        };
        transforms.push(xf);
        if i % 10 == 3 {
            // The same instance again: every one of its hits ties exactly.
            transforms.push(xf);
        }
    }
    let instances: Vec<Instance> = transforms
        .iter()
        .map(|&object_to_world| Instance {
            lod: &l,
            object_to_world,
            faces: None,
        })
        .collect();
    let cam = Camera::new(DVec3::new(1.0, 3.0, 7.0), DVec3::ZERO);
    let (w, h) = (48, 36);
    let all = render(&instances, &cam, w, h, &Light::default());
    let singles: Vec<ReferenceImage> = (0..instances.len())
        .map(|i| render(&instances[i..=i], &cam, w, h, &Light::default()))
        .collect();
    let mut covered = 0;
    let mut from_duplicate = 0;
    for (p, hit) in all.hits.iter().enumerate() {
        let mut want: Option<(u32, f64, u32)> = None;
        for (i, single) in singles.iter().enumerate() {
            if let Some(s) = single.hits[p] {
                // Strictly nearer only: an equal t keeps the lower index.
                if want.is_none_or(|(_, t, _)| s.t < t) {
                    want = Some((i as u32, s.t, s.voxel));
                }
            }
        }
        let got = hit.map(|h| (h.instance, h.t, h.voxel));
        assert_eq!(got, want, "pixel {p}");
        covered += got.is_some() as usize;
        from_duplicate += got.is_some_and(|(i, ..)| {
            transforms[i as usize] == transforms.get(i as usize + 1).copied().unwrap_or_default()
        }) as usize;
    }
    assert!(covered > 200, "{covered} covered pixels");
    assert!(from_duplicate > 0, "no pixel shows a duplicated instance");
}

#[test]
fn png_outputs_are_written_atomically_and_decode() {
    let l = lod(5, &ball_cells(5, 0.6));
    let cam = Camera::default();
    let img = render_one(&l, DAffine3::IDENTITY, &cam, 32, 24);
    let dir = std::env::temp_dir().join(format!("ssbvb-reference-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for name in ["shaded.png", "normals.png", "depth.png"] {
        let path = dir.join(name);
        match name {
            "shaded.png" => img.to_png(&path),
            "normals.png" => img.normals_to_png(&path),
            _ => img.depth_to_png(&path),
        }
        .unwrap();
        let back = image::open(&path).unwrap().to_rgba8();
        assert_eq!(back.dimensions(), (32, 24));
        // Centre pixel hits the ball, the corner does not.
        assert_eq!(back.get_pixel(16, 12)[3], 255);
        assert_eq!(back.get_pixel(0, 0)[3], 0);
    }
    let leftovers: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().ends_with(".tmp"))
        .collect();
    assert!(leftovers.is_empty(), "temporary files left: {leftovers:?}");
    std::fs::remove_dir_all(&dir).unwrap();
}
