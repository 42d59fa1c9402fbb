//! Cameras for content: an orbit around a target, and the framing of a scene (every voxel
//! instance's box in view), so a program handed voxels needs no camera arithmetic of its
//! own.

use glam::DVec3;
use ssbvb_gpu::scene::Scene;
use ssbvb_voxel::asset::VoxelAsset;
use ssbvb_voxel::camera::Camera;

/// A camera on a sphere of `distance` around `target`: `azimuth_deg` about +Y from +Z
/// (90° looks from +X), `elevation_deg` above the horizontal plane (clamped to ±89.9° so
/// the view never aligns with up), +Y up, with a `fov_y_deg` field of view (clamped to
/// 1°..179°; 45° when not a number) and no far plane.
pub fn orbit(
    target: DVec3,
    distance: f64,
    azimuth_deg: f64,
    elevation_deg: f64,
    fov_y_deg: f64,
) -> Camera {
    let (az, el) = (
        azimuth_deg.to_radians(),
        elevation_deg.clamp(-89.9, 89.9).to_radians(),
    );
    let dir = DVec3::new(el.cos() * az.sin(), el.sin(), el.cos() * az.cos());
    let distance = if distance.is_finite() && distance > 0.0 {
        distance
    } else {
        1.0
    };
    let fov_y_deg = if fov_y_deg.is_finite() {
        fov_y_deg.clamp(1.0, 179.0)
    } else {
        45.0
    };
    Camera {
        fov_y_deg,
        near: (distance * 1e-3).max(1e-6),
        far: f64::INFINITY,
        ..Camera::new(target + dir * distance, target)
    }
}

/// The object-space box of an asset's voxels: its finest level's occupied cells (the whole
/// `[-1, 1]³` when it holds none).
pub fn occupied_box(asset: &VoxelAsset) -> (DVec3, DVec3) {
    let Some(lod) = asset.lods.last() else {
        return (DVec3::NEG_ONE, DVec3::ONE);
    };
    let mut lo = [u32::MAX; 3];
    let mut hi = [0u32; 3];
    for v in &lod.point_cloud.voxels {
        let c = v.cell();
        for k in 0..3 {
            lo[k] = lo[k].min(c[k]);
            hi[k] = hi[k].max(c[k]);
        }
    }
    if lo[0] == u32::MAX {
        return (DVec3::NEG_ONE, DVec3::ONE);
    }
    let cell = 2.0 / f64::from(1u32 << lod.level.min(31));
    let corner = |c: [u32; 3], add: f64| {
        DVec3::new(f64::from(c[0]), f64::from(c[1]), f64::from(c[2])) * cell - 1.0 + add * cell
    };
    (corner(lo, 0.0), corner(hi, 1.0))
}

/// The centre and radius of a sphere holding every voxel instance's occupied box
/// ([`occupied_box`] placed by the instance); `None` for a scene without voxel instances.
pub fn bounding_sphere(scene: &Scene) -> Option<(DVec3, f64)> {
    let mut lo = DVec3::splat(f64::INFINITY);
    let mut hi = DVec3::splat(f64::NEG_INFINITY);
    for o in &scene.objects {
        let (blo, bhi) = occupied_box(&o.asset);
        for xf in &o.instances {
            for i in 0..8 {
                let corner = DVec3::new(
                    if i & 1 == 0 { blo.x } else { bhi.x },
                    if i & 2 == 0 { blo.y } else { bhi.y },
                    if i & 4 == 0 { blo.z } else { bhi.z },
                );
                let p = xf.transform_point3(corner);
                lo = lo.min(p);
                hi = hi.max(p);
            }
        }
    }
    if !lo.is_finite() || !hi.is_finite() {
        return None;
    }
    Some(((lo + hi) * 0.5, ((hi - lo) * 0.5).length().max(1e-9)))
}

/// A camera that frames every voxel instance of `scene` (the boxes of their voxels, not of
/// their grids): it looks at the centre of their bounding sphere from 30° of azimuth and 20° of elevation, far enough that the sphere
/// fits the `fov_y_deg` field of view. Without voxel instances: [`Camera::default`].
pub fn frame_scene(scene: &Scene, fov_y_deg: f64) -> Camera {
    let Some((center, radius)) = bounding_sphere(scene) else {
        return Camera::default();
    };
    let half = (fov_y_deg.clamp(1.0, 179.0) * 0.5).to_radians();
    orbit(center, radius / half.sin() * 1.05, 30.0, 20.0, fov_y_deg)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DAffine3;

    #[test]
    fn an_orbit_looks_at_its_target_from_its_angles() {
        let c = orbit(DVec3::new(1.0, 2.0, 3.0), 5.0, 90.0, 0.0, 40.0);
        assert!(
            (c.position - DVec3::new(6.0, 2.0, 3.0)).length() < 1e-9,
            "{c:?}"
        );
        let top = orbit(DVec3::ZERO, 2.0, 0.0, 90.0, 40.0);
        assert!(top.position.y > 1.99 && top.position.y < 2.0, "{top:?}");
        assert!(
            orbit(DVec3::ZERO, f64::NAN, 0.0, 0.0, 40.0)
                .position
                .is_finite()
        );
    }

    /// Every corner of every instance's voxel box projects inside the framed view, and the
    /// box is the voxels', not the grid's.
    #[test]
    fn framing_keeps_every_instance_box_in_view() {
        let mut scene = Scene::default();
        assert_eq!(frame_scene(&scene, 45.0), Camera::default());
        // One voxel, cell (0, 0, 0) of a level-2 grid: the box [-1, -0.5]³.
        let asset = crate::test_support::one_voxel(2);
        scene.objects.push(ssbvb_gpu::scene::VoxelObject {
            asset,
            instances: vec![
                DAffine3::from_translation(DVec3::new(10.0, 0.0, 0.0)),
                DAffine3::from_scale(DVec3::splat(0.5)),
            ],
            lod: ssbvb_gpu::scene::LodPolicy::Fixed(0),
        });
        let (blo, bhi) = occupied_box(&scene.objects[0].asset);
        assert_eq!((blo, bhi), (DVec3::NEG_ONE, DVec3::splat(-0.5)));
        // The sphere holds the two placed voxel boxes, x 9..9.5 and -0.5..-0.25 (not the
        // grids' boxes, whose centre would be (4.5, 0, 0)).
        let (center, _) = bounding_sphere(&scene).unwrap();
        assert!(
            (center - DVec3::new(4.5, -0.625, -0.625)).length() < 1e-12,
            "{center}"
        );
        let cam = frame_scene(&scene, 45.0);
        let (right, up, fwd) = cam.basis();
        let tan = (45f64.to_radians() * 0.5).tan();
        for xf in &scene.objects[0].instances {
            for i in 0..8 {
                let c = DVec3::new(
                    if i & 1 == 0 { blo.x } else { bhi.x },
                    if i & 2 == 0 { blo.y } else { bhi.y },
                    if i & 4 == 0 { blo.z } else { bhi.z },
                );
                let d = xf.transform_point3(c) - cam.position;
                let z = d.dot(fwd);
                assert!(z > 0.0);
                assert!(d.dot(up).abs() / z <= tan, "corner {c} leaves the view");
                assert!(d.dot(right).abs() / z <= tan * 100.0);
            }
        }
    }
}
