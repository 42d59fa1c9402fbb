//! Procedural mesh animation for dynamic objects: a deformation of a mesh's vertices as a
//! function of time (re-voxelized every frame on the GPU), and the object space that holds
//! the whole motion, so the voxels keep their size and place from frame to frame.

use glam::{DVec3, Vec3};
use serde::{Deserialize, Serialize};

use crate::model::{Mesh, ObjectSpace};
use crate::voxelize::mesh_bounds;

/// How a mesh moves.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum MeshAnimation {
    /// A twist about the vertical (model +Y) axis through the bounding box's centre: a
    /// vertex at height fraction `h ∈ [0, 1]` of the box turns by
    /// `degrees_per_second · t · h` (the base stays, the top turns most).
    Twist {
        /// Turn of the top per second, in degrees.
        degrees_per_second: f64,
    },
}

impl MeshAnimation {
    /// Whether the parameters are usable (finite); a message naming the parameter if not.
    pub fn problem(&self) -> Option<String> {
        match *self {
            MeshAnimation::Twist { degrees_per_second } if !degrees_per_second.is_finite() => {
                Some(format!(
                    "Twist degrees_per_second must be a finite number, got {degrees_per_second}"
                ))
            }
            MeshAnimation::Twist { .. } => None,
        }
    }

    /// The mesh at time `t` seconds (only the positions move; normals are the voxelizer's
    /// business, from the faces). `None` when the mesh has no usable vertex.
    pub fn deform(&self, mesh: &Mesh, t: f64) -> Option<Mesh> {
        let (lo, hi) = mesh_bounds(mesh)?;
        let centre = (lo + hi) * 0.5;
        let height = hi.y - lo.y;
        let MeshAnimation::Twist { degrees_per_second } = *self;
        let positions = mesh
            .positions
            .iter()
            .map(|p| {
                let p = p.as_dvec3();
                if !p.is_finite() {
                    return p.as_vec3();
                }
                let h = if height > 0.0 {
                    (p.y - lo.y) / height
                } else {
                    0.0
                };
                let angle = (degrees_per_second * t * h).to_radians();
                let (s, c) = angle.sin_cos();
                let (x, z) = (p.x - centre.x, p.z - centre.z);
                Vec3::new(
                    (centre.x + c * x - s * z) as f32,
                    p.y as f32,
                    (centre.z + s * x + c * z) as f32,
                )
            })
            .collect();
        Some(Mesh {
            positions,
            ..mesh.clone()
        })
    }

    /// An object space holding the mesh at every time: the box around the cylinder the
    /// twist sweeps (the largest horizontal distance from the axis, with a margin for the
    /// rounding of the turned vertices).
    pub fn object_space(&self, mesh: &Mesh) -> Option<ObjectSpace> {
        let (lo, hi) = mesh_bounds(mesh)?;
        let centre = (lo + hi) * 0.5;
        let mut r = 0.0f64;
        for t in &mesh.triangles {
            for &i in t {
                if let Some(p) = mesh.positions.get(i as usize).filter(|p| p.is_finite()) {
                    let d = p.as_dvec3() - centre;
                    r = r.max(d.x.hypot(d.z));
                }
            }
        }
        let r = r * (1.0 + 1e-6) + 1e-9;
        Some(ObjectSpace::from_bounds(
            DVec3::new(centre.x - r, lo.y, centre.z - r),
            DVec3::new(centre.x + r, hi.y, centre.z + r),
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::voxelize::voxelize_mesh_in;

    fn slab() -> Mesh {
        // A 2 × 1 × 0.2 box of 12 triangles, base at y = 0.
        let p = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
        let v = vec![
            p(-1.0, 0.0, -0.1),
            p(1.0, 0.0, -0.1),
            p(1.0, 1.0, -0.1),
            p(-1.0, 1.0, -0.1),
            p(-1.0, 0.0, 0.1),
            p(1.0, 0.0, 0.1),
            p(1.0, 1.0, 0.1),
            p(-1.0, 1.0, 0.1),
        ];
        let tris = vec![
            [0, 2, 1],
            [0, 3, 2],
            [4, 5, 6],
            [4, 6, 7],
            [0, 1, 5],
            [0, 5, 4],
            [3, 6, 2],
            [3, 7, 6],
            [0, 4, 7],
            [0, 7, 3],
            [1, 2, 6],
            [1, 6, 5],
        ];
        Mesh {
            positions: v,
            triangles: tris,
            ..Default::default()
        }
    }

    #[test]
    fn a_twist_turns_the_top_and_keeps_the_base_and_the_radius() {
        let m = slab();
        let a = MeshAnimation::Twist {
            degrees_per_second: 90.0,
        };
        let d = a.deform(&m, 1.0).unwrap();
        // Base (y = 0) unchanged; top (y = 1) turned by 90° about the centre (0, z = 0).
        assert_eq!(d.positions[0], m.positions[0]);
        let top = d.positions[2];
        assert!(
            (top.x - 0.1).abs() < 1e-6 && (top.z - 1.0).abs() < 1e-6,
            "{top:?}"
        );
        assert_eq!(a.deform(&m, 0.0).unwrap().positions, m.positions);
        for (p, q) in m.positions.iter().zip(&d.positions) {
            let r = |v: &Vec3| v.x.hypot(v.z);
            assert!((r(p) - r(q)).abs() < 1e-5 && p.y == q.y);
        }
        assert!(a.problem().is_none());
        assert!(
            MeshAnimation::Twist {
                degrees_per_second: f64::NAN
            }
            .problem()
            .unwrap()
            .contains("degrees_per_second")
        );
    }

    #[test]
    fn every_frame_voxelizes_in_the_motions_space_and_not_outside_it() {
        let m = slab();
        let a = MeshAnimation::Twist {
            degrees_per_second: 120.0,
        };
        let space = a.object_space(&m).unwrap();
        for t in [0.0, 0.4, 1.3, 7.7] {
            let d = a.deform(&m, t).unwrap();
            let set = voxelize_mesh_in(&d, 4, Some(space), &crate::progress::NoProgress).unwrap();
            assert_eq!(set.object_space, space);
            assert!(!set.voxels.is_empty());
        }
        // A square block's own space cannot hold it turned by 45° (its corners reach √2).
        let mut block = slab();
        for p in &mut block.positions {
            p.z *= 10.0;
        }
        let turned = a.deform(&block, 45.0 / 120.0).unwrap();
        let own = crate::voxelize::mesh_object_space(&block).unwrap();
        let r = voxelize_mesh_in(&turned, 4, Some(own), &crate::progress::NoProgress);
        assert!(
            matches!(r, Err(crate::voxelize::VoxelizeError::OutsideObjectSpace)),
            "{:?}",
            r.map(|s| s.voxels.len())
        );
        let space = a.object_space(&block).unwrap();
        assert!(voxelize_mesh_in(&turned, 4, Some(space), &crate::progress::NoProgress).is_ok());
    }
}
