//! RGBA volumes from their three sources: the procedural cloud, a voxel model with palette
//! alpha, a mesh with fractional coverage; and the bad inputs they refuse.

use ssbvb_voxel::model::{Model, VoxelModel};
use ssbvb_voxel::rgba_volume::sources::{
    Cloud, from_density, from_mesh_coverage, from_voxel_model,
};
use ssbvb_voxel::rgba_volume::{RgbaVolumeError, unquantize};

fn alphas(v: &ssbvb_voxel::rgba_volume::RgbaVolume) -> Vec<f32> {
    let l = &v.levels[0];
    let d = l.dims.map(i64::from);
    let mut out = Vec::new();
    for z in 0..d[2] {
        for y in 0..d[1] {
            for x in 0..d[0] {
                out.push(unquantize(l.texel([x, y, z]))[3]);
            }
        }
    }
    out
}

#[test]
fn the_cloud_is_translucent_sparse_and_reproducible() {
    let cloud = Cloud::default();
    let v = cloud.volume(32).unwrap();
    assert_eq!(v, cloud.volume(32).unwrap());
    let other = Cloud { seed: 2, ..cloud }.volume(32).unwrap();
    assert_ne!(v, other);
    let a = alphas(&v);
    let translucent = a.iter().filter(|&&x| x > 0.0 && x < 0.9).count();
    let empty = a.iter().filter(|&&x| x == 0.0).count();
    // Measured: 5,757 translucent (none above alpha 0.39: density 8 over a texel of
    // 1/16) and 27,011 empty texels of 32,768.
    assert!(translucent > 4000 && empty > 20000, "{translucent} {empty}");
    assert!(a.iter().all(|&x| x < 0.45), "denser than density 8 allows");
    // Its corners are clear, its bricks partly removed.
    assert_eq!(a[0], 0.0);
    let l = &v.levels[0];
    assert!(l.stored_bricks() < l.table.len(), "{}", l.stored_bricks());
}

#[test]
fn bad_densities_are_refused_with_their_texel() {
    let nan = from_density([4; 3], |p| {
        (if p.x > 0.5 { f32::NAN } else { 1.0 }, [1.0; 3])
    });
    assert_eq!(
        nan,
        Err(RgbaVolumeError::NonFinite {
            what: "density or colour",
            texel: [3, 0, 0]
        })
    );
    let negative = from_density([4; 3], |_| (-1.0, [1.0; 3]));
    assert!(matches!(
        negative,
        Err(RgbaVolumeError::OutOfRange {
            what: "density",
            ..
        })
    ));
    assert_eq!(
        from_density([0, 4, 4], |_| (1.0, [1.0; 3])),
        Err(RgbaVolumeError::BadSize([0, 4, 4]))
    );
    let err = from_density([4; 3], |_| (f32::INFINITY, [1.0; 3])).unwrap_err();
    assert!(err.to_string().contains("texel [0, 0, 0]"), "{err}");
}

#[test]
fn palette_alpha_carries_into_the_texels_and_no_alpha_is_opaque() {
    // A 4×4×4 block: the lower half half-transparent red, the upper half opaque blue.
    let mut m = VoxelModel {
        voxels: Vec::new(),
        colors: Vec::new(),
    };
    for z in 0..4 {
        for y in 0..4 {
            for x in 0..4 {
                m.voxels.push([x, y, z]);
                m.colors.push(if y < 2 {
                    [1.0, 0.0, 0.0, 0.5]
                } else {
                    [0.0, 0.0, 1.0, 1.0]
                });
            }
        }
    }
    let v = from_voxel_model(&m, 4).unwrap();
    let l = &v.levels[0];
    assert_eq!(unquantize(l.texel([1, 0, 1])), unquantize([128, 0, 0, 128]));
    assert_eq!(l.texel([1, 3, 1]), [0, 0, 255, 255]);
    // Twice as fine: each voxel covers 8 texels of half its edge: alpha 1 - 0.5^½ (75 of
    // 255), so a ray through a voxel's two texels keeps the voxel's transmittance.
    let fine = from_voxel_model(&m, 8).unwrap();
    assert_eq!(fine.levels[0].texel([2, 1, 5]), [75, 0, 0, 75]);
    assert_eq!(fine.levels[0].texel([7, 7, 7]), [0, 0, 255, 255]);
    // Half as fine: a texel averages 8 voxels by coverage: alpha sums to the full texel.
    let coarse = from_voxel_model(&m, 2).unwrap();
    assert_eq!(coarse.levels[0].texel([0, 1, 0])[3], 255);
    assert!(from_voxel_model(&m, 0).is_err());
}

#[test]
fn a_mesh_becomes_solid_inside_and_fractional_at_its_surface() {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/models/bunny.obj");
    let Model::Mesh(mesh) = ssbvb_voxel::load::load_model(&path).unwrap() else {
        panic!("the bunny is a mesh");
    };
    let v = from_mesh_coverage(&mesh, 4).unwrap();
    let a = alphas(&v);
    let full = a.iter().filter(|&&x| x == 1.0).count();
    let part = a.iter().filter(|&&x| x > 0.0 && x < 1.0).count();
    let none = a.iter().filter(|&&x| x == 0.0).count();
    // Measured: 483 full, 822 partial, 2,791 empty texels of 4,096.
    assert!(
        full > 300 && part > 500 && none > 2000,
        "{full} {part} {none}"
    );
    // A corner of the grid is outside.
    let l = &v.levels[0];
    assert_eq!(l.texel([0, 0, 0])[3], 0);
    assert!(matches!(
        from_mesh_coverage(&mesh, 8),
        Err(RgbaVolumeError::BadSize(_))
    ));
}
