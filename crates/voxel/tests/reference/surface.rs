//! The reference through face-masked voxels (RastaVox levels): a voxel is hit only
//! through a face in its mask, as rasterizing its masked camera-facing faces draws it.

use glam::{DAffine3, DVec3};
use ssbvb_voxel::camera::Camera;
use ssbvb_voxel::reference::{Instance, Traversal, render, trace_object_ray_faces};
use ssbvb_voxel::shading::Light;
use ssbvb_voxel::surface::{SurfaceModel, face_bit};

use super::{ball_cells, cell_box, id_of, lod};

#[test]
fn a_voxel_is_hit_only_through_its_masked_faces() {
    let l = lod(2, &[[1, 1, 1]]);
    let (lo, hi) = cell_box(2, [1, 1, 1]);
    let c = (lo + hi) * 0.5;
    let mut faces = vec![0u8; 1];
    faces[id_of(&l, [1, 1, 1]) as usize] = face_bit(0, true) as u8;
    let from_px = (DVec3::new(3.0, c.y, c.z), DVec3::NEG_X);
    let from_nx = (DVec3::new(-3.0, c.y, c.z), DVec3::X);
    let from_py = (DVec3::new(c.x, 3.0, c.z), DVec3::NEG_Y);
    let trace = |f: Option<&[u8]>, (o, d): (DVec3, DVec3)| {
        trace_object_ray_faces(&l.lookup, f, o, d, Traversal::Hierarchical)
    };
    let h = trace(Some(&faces), from_px).expect("the +X face is drawn");
    assert_eq!((h.cell, h.face_axis), ([1, 1, 1], 0));
    assert_eq!(h.face_normal, DVec3::X);
    assert!((h.t - (3.0 - hi.x)).abs() < 1e-12);
    assert_eq!(
        trace(Some(&faces), from_nx),
        None,
        "the −X face is not in the mask"
    );
    assert_eq!(trace(Some(&faces), from_py), None, "nor the +Y face");
    // Without masks every face is solid; an all-faces mask is the same as none.
    for ray in [from_px, from_nx, from_py] {
        assert_eq!(trace(None, ray), trace(Some(&[63]), ray));
        assert!(trace(None, ray).is_some());
    }
    // A camera inside sees no face of its own voxel.
    assert_eq!(trace(Some(&[63]), (c, DVec3::X)), None);
    assert!(trace(None, (c, DVec3::X)).unwrap().inside);
    // Through an edge: entered on x and y at once; only the masked one may be reported.
    let edge = (
        DVec3::new(hi.x + 1.0, hi.y + 1.0, c.z),
        DVec3::new(-1.0, -1.0, 0.0),
    );
    let only_y = [face_bit(1, true) as u8];
    assert_eq!(trace(Some(&only_y), edge).unwrap().face_axis, 1);
    assert_eq!(trace(Some(&faces), edge).unwrap().face_axis, 0);
    assert_eq!(trace(None, edge).unwrap().cell, [1, 1, 1]);
}

/// At its finest level a surface model draws what the solid voxels show: every ray that
/// reaches a solid voxel first enters it through a face toward an empty cell.
#[test]
fn the_finest_surface_renders_exactly_as_the_solid_voxels() {
    // A solid ball (interior voxels included, which the surface drops).
    let solid = lod(5, &ball_cells(5, 0.7));
    let surface = SurfaceModel::extract(&solid).unwrap();
    let finest = surface.face_lod_all(0);
    assert!(finest.lod.point_cloud.voxels.len() < solid.point_cloud.voxels.len() / 2);
    let light = Light::default();
    for (i, eye) in [
        DVec3::new(1.9, 1.2, 2.5),
        DVec3::new(0.0, 0.0, 3.0),
        DVec3::new(-2.2, 0.3, -1.7),
    ]
    .into_iter()
    .enumerate()
    {
        let cam = Camera::new(eye, DVec3::ZERO);
        let a = render(
            &[Instance {
                lod: &solid,
                object_to_world: DAffine3::IDENTITY,
                faces: None,
            }],
            &cam,
            64,
            48,
            &light,
        );
        let b = render(
            &[Instance {
                lod: &finest.lod,
                object_to_world: DAffine3::IDENTITY,
                faces: Some(&finest.faces),
            }],
            &cam,
            64,
            48,
            &light,
        );
        assert!(a.coverage() > 500, "camera {i}: {} px", a.coverage());
        let mut same = 0;
        for (ha, hb) in a.hits.iter().zip(&b.hits) {
            match (ha, hb) {
                (None, None) => {}
                (Some(x), Some(y)) => {
                    assert_eq!(
                        (x.cell, x.t, x.face_normal),
                        (y.cell, y.t, y.face_normal),
                        "camera {i}"
                    );
                    same += 1;
                }
                _ => panic!("camera {i}: coverage differs ({ha:?} vs {hb:?})"),
            }
        }
        assert_eq!(same, a.coverage());
    }
}
