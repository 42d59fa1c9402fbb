//! The views of the quality preset: a scene and the cameras of its frames.
//!
//! - `path`: the 64-bunny grid (Auto LOD), an orbit of two degrees, then a dolly toward the
//!   grid's centre to 0.85 of the distance, so instances cross LOD switches;
//! - `hover`: the same grid, the camera moving back and forth by 0.4 % of its distance
//!   across the distance at which the nearest instance that switches level does: where a
//!   user holding the camera still sees Auto LOD pop, if it does;
//! - `bunny`: one bunny at its finest level, the path's orbit and dolly around it.

use std::sync::Arc;

use anyhow::Result;
use glam::DAffine3;
use ssbvb_gpu::scene::{LodPolicy, Scene, VoxelObject, choose_level};
use ssbvb_voxel::asset::VoxelAsset;
use ssbvb_voxel::camera::Camera;

use crate::harness::{bench_camera, bundled_bunny, grid, grid_camera, one_object};

/// The finest level of the bunny asset.
pub(super) const LEVEL: u32 = 8;
/// Bunnies in the grid.
pub(super) const INSTANCES: usize = 64;

/// The path's orbit, in degrees about the vertical through what it looks at, and the
/// distance the dolly ends at (of the start's). Small steps: between frames the image moves
/// by about a pixel at 320 × 240, so what differs from frame to frame beyond the ground
/// truth's change is shimmering and popping, not motion.
const ORBIT_DEG: f64 = 2.0;
const DOLLY_TO: f64 = 0.85;
/// The hover's step, of the camera's distance (every other frame nearer, then farther).
const HOVER_STEP: f64 = 0.004;

/// One view: what is drawn and from where, frame by frame.
pub(super) struct QualityView {
    /// `path`, `hover` or `bunny`.
    pub name: &'static str,
    pub scene: Scene,
    pub asset: Arc<VoxelAsset>,
    /// One camera per frame; the first is also the still frame's.
    pub cameras: Vec<Camera>,
}

/// The three views with `frames` cameras each (at least 2), for `size`.
pub(super) fn views(frames: usize, size: (u32, u32)) -> Result<Vec<QualityView>> {
    let n = frames.max(2);
    let (asset, _) = bundled_bunny(LEVEL)?;
    let grid_scene = Scene {
        objects: vec![VoxelObject {
            asset: asset.clone(),
            instances: grid(INSTANCES),
            lod: LodPolicy::AUTO,
        }],
        ..Default::default()
    };
    let base = grid_camera(INSTANCES);
    let path = (0..n).map(|i| path_camera(&base, i, n)).collect();
    let hover = hover_cameras(&grid(INSTANCES), LodPolicy::AUTO, LEVEL, &base, size, n);
    let bunny_base = bench_camera();
    Ok(vec![
        QualityView {
            name: "path",
            scene: grid_scene.clone(),
            asset: asset.clone(),
            cameras: path,
        },
        QualityView {
            name: "hover",
            scene: grid_scene,
            asset: asset.clone(),
            cameras: hover,
        },
        QualityView {
            name: "bunny",
            scene: one_object(&asset, LodPolicy::AUTO),
            asset,
            cameras: (0..n).map(|i| path_camera(&bunny_base, i, n)).collect(),
        },
    ])
}

/// Frame `i` of `n` on the path: the first half the orbit, the second half the dolly
/// toward what the camera looks at.
pub(super) fn path_camera(base: &Camera, i: usize, n: usize) -> Camera {
    let half = n.div_ceil(2).max(1);
    let orbit_steps = i.min(half - 1);
    let angle = ORBIT_DEG.to_radians() * orbit_steps as f64 / (half - 1).max(1) as f64;
    let offset = glam::DQuat::from_rotation_y(angle) * (base.position - base.look_at);
    let dolly = if i < half {
        1.0
    } else {
        1.0 - (1.0 - DOLLY_TO) * (i + 1 - half) as f64 / (n - half).max(1) as f64
    };
    Camera {
        position: base.look_at + offset * dolly,
        ..*base
    }
}

/// `base` moved toward what it looks at, to `f` of its distance.
fn dollied(base: &Camera, f: f64) -> Camera {
    Camera {
        position: base.look_at + (base.position - base.look_at) * f,
        ..*base
    }
}

/// The hover's cameras: alternately farther and nearer by [`HOVER_STEP`] around the
/// distance (between 0.6 and 1 of `base`'s) at which the instance nearest the camera whose
/// Auto LOD level changes over that range switches; the first camera is the farther one.
/// `instances` are drawn with `lod` up to `max_level`.
pub(super) fn hover_cameras(
    instances: &[DAffine3],
    lod: LodPolicy,
    max_level: u32,
    base: &Camera,
    size: (u32, u32),
    n: usize,
) -> Vec<Camera> {
    let level = |xf, f| choose_level(lod, xf, &dollied(base, f), size, max_level);
    let mut by_distance: Vec<_> = instances.iter().collect();
    by_distance.sort_by(|a, b| {
        let d = |x: &DAffine3| (x.translation - base.position).length();
        d(a).total_cmp(&d(b))
    });
    let (near, far) = (0.6, 1.0);
    let centre = by_distance
        .iter()
        .find(|xf| level(xf, near) != level(xf, far))
        .map(|xf| {
            // The level falls as f grows: bisect for where it does.
            let (mut lo, mut hi) = (near, far);
            let at_lo = level(xf, lo);
            for _ in 0..60 {
                let mid = 0.5 * (lo + hi);
                if level(xf, mid) == at_lo {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            0.5 * (lo + hi)
        })
        .unwrap_or(0.5 * (near + far));
    (0..n)
        .map(|i| {
            let side = if i % 2 == 0 { 1.0 } else { -1.0 };
            dollied(base, centre * (1.0 + side * HOVER_STEP))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use glam::DVec3;

    use super::*;

    #[test]
    fn the_path_orbits_then_dollies_in() {
        let base = Camera::new(DVec3::new(0.0, 3.0, 10.0), DVec3::ZERO);
        let n = 8;
        let d0 = (base.position - base.look_at).length();
        let cams: Vec<Camera> = (0..n).map(|i| path_camera(&base, i, n)).collect();
        assert_eq!(cams[0].position, base.position);
        for c in &cams[..4] {
            assert!(((c.position - c.look_at).length() - d0).abs() < 1e-9);
        }
        // The orbit's whole angle over the first four frames, then the dolly.
        let turned = cams[3].position.x.atan2(cams[3].position.z).to_degrees();
        assert!((turned - ORBIT_DEG).abs() < 1e-9, "{turned}");
        let last = (cams[n - 1].position - base.look_at).length();
        assert!((last - DOLLY_TO * d0).abs() < 1e-9, "{last} vs {d0}");
        for w in cams[4..].windows(2) {
            let d = |c: &Camera| (c.position - c.look_at).length();
            assert!(d(&w[1]) < d(&w[0]));
        }
    }

    /// The hover straddles a level switch of an instance: every frame's level differs from
    /// the frame before's when each chooses afresh.
    #[test]
    fn the_hover_crosses_a_level_switch_every_frame() {
        let instances = grid(INSTANCES);
        let base = grid_camera(INSTANCES);
        let size = (320, 240);
        let cams = hover_cameras(&instances, LodPolicy::AUTO, LEVEL, &base, size, 6);
        let switching = instances.iter().any(|xf| {
            let l: Vec<u32> = cams
                .iter()
                .map(|c| choose_level(LodPolicy::AUTO, xf, c, size, LEVEL))
                .collect();
            l.windows(2).all(|w| w[0] + 1 == w[1] || w[1] + 1 == w[0])
        });
        assert!(switching, "no instance switches level every frame");
        let d = |c: &Camera| (c.position - c.look_at).length();
        let ratio = d(&cams[0]) / d(&cams[1]);
        assert!((ratio - 1.004 / 0.996).abs() < 1e-9, "{ratio}");
    }
}
