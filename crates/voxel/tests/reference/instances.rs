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
        },
        Instance {
            lod: &l,
            object_to_world: DAffine3::from_translation(DVec3::new(-0.8, 0.2, 0.5)),
        },
        // A singular transform hides its instance instead of producing NaN.
        Instance {
            lod: &l,
            object_to_world: DAffine3::from_scale(DVec3::ZERO),
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
