//! View-aligned slicing of placed RGBA volumes (volumetric billboards): per volume a mip
//! level by distance and a slice spacing in its texels, then the polygons where planes of
//! constant view depth cut each volume's box, all volumes' slices sorted back to front.
//! Volumetric billboards build the polygons in a geometry shader on proxy prisms; wgpu has
//! none, so they are built here and pulled by the vertex shader.
//!
//! Slice planes sit at whole multiples of the spacing from the volume's centre in view
//! depth (`z = z_centre + k Δ`), so moving the camera or the volume along the view axis
//! does not move the samples through the volume (they still turn with the view). Volumes
//! wholly outside the view frustum get no slices. The reference ([`super::integrate`]) samples the same
//! level; a sample stands for the slab of thickness `Δ / cos θ` along its pixel's ray (θ
//! between ray and view axis), which is what the shader's opacity correction uses.

use glam::{DAffine3, DVec3};

use super::{RgbaVolume, max_edge};
use crate::camera::Camera;

/// Slicing knobs (`VolumeSlices` in the render graph).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SliceSettings {
    /// Distance between slices along the view axis, in texels of the chosen level.
    pub spacing: f64,
    /// Added to the level chosen by distance (positive = coarser).
    pub mip_bias: f64,
}

impl Default for SliceSettings {
    /// Half a texel, no bias.
    fn default() -> Self {
        Self {
            spacing: 0.5,
            mip_bias: 0.0,
        }
    }
}

/// How one volume is sliced this frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SlicedVolume {
    /// The mip level sampled.
    pub level: usize,
    /// World length of the level's reference length (its texel edge along the longest
    /// axis, scaled): the length its alphas are per.
    pub h_world: f64,
    /// Distance between slices along the view axis, world units.
    pub spacing_world: f64,
    /// Slices drawn.
    pub slices: u32,
}

/// All slice polygons of a frame, back to front, as triangles.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SliceGeometry {
    /// Per volume, in the order given.
    pub volumes: Vec<SlicedVolume>,
    /// Triangle vertices: camera-relative world position, and the volume's index.
    pub vertices: Vec<([f32; 3], u32)>,
}

/// The world length of a level's reference length for a uniform scale.
fn reference_length(volume: &RgbaVolume, level: usize, object_to_world: &DAffine3) -> f64 {
    let dims = volume.levels[level].dims;
    2.0 / f64::from(max_edge(dims)) * object_to_world.matrix3.x_axis.length()
}

/// The box a level's samples can be non-zero in: `[-1, 1]³` widened by half a texel (the
/// fade of the trilinear filter), in object space.
fn level_box(volume: &RgbaVolume, level: usize) -> DVec3 {
    let dims = volume.levels[level].dims;
    DVec3::ONE + DVec3::from(dims.map(|d| 1.0 / f64::from(d)))
}

/// The level whose texel is about one pixel at the volume's nearest point (the LOD by
/// distance of volumetric billboards), plus `mip_bias`, within the volume's levels.
pub fn choose_level(
    volume: &RgbaVolume,
    object_to_world: &DAffine3,
    camera: &Camera,
    height: u32,
    mip_bias: f64,
) -> usize {
    // Distance to the box: from the eye to the nearest point of its bounding sphere.
    let radius = object_to_world.matrix3.x_axis.length() * 3f64.sqrt();
    let centre = object_to_world.translation;
    let d = ((centre - camera.position).length() - radius).max(camera.near.max(1e-9));
    let pixel = 2.0 * d * (camera.fov_y_deg.to_radians() * 0.5).tan() / f64::from(height.max(1));
    let texel0 = reference_length(volume, 0, object_to_world);
    // The level by distance (0 when level 0's texels are already smaller than a pixel),
    // then the bias on top of it.
    let by_distance = (pixel / texel0).log2().floor().max(0.0);
    let level = by_distance + mip_bias.round();
    if !level.is_finite() || level <= 0.0 {
        0
    } else {
        (level as usize).min(volume.levels.len() - 1)
    }
}

/// Slices `volumes` (each with its object → world transform, a uniform scale) for
/// `camera` at `size`.
pub fn slice(
    volumes: &[(&RgbaVolume, DAffine3)],
    camera: &Camera,
    size: (u32, u32),
    settings: SliceSettings,
) -> SliceGeometry {
    let (right, up, forward) = camera.basis();
    let eye = camera.position;
    let mut slices: Vec<(f64, u32, Vec<DVec3>)> = Vec::new();
    let mut out = SliceGeometry::default();
    for (vi, (volume, m)) in volumes.iter().enumerate() {
        let level = choose_level(volume, m, camera, size.1, settings.mip_bias);
        let h_world = reference_length(volume, level, m);
        let spacing_world = (settings.spacing * h_world).max(1e-12);
        let half = level_box(volume, level);
        // Corners camera-relative, so large world coordinates cancel first.
        let corners: Vec<DVec3> = (0..8)
            .map(|c| {
                let s = DVec3::new(
                    if c & 1 == 0 { -1.0 } else { 1.0 },
                    if c & 2 == 0 { -1.0 } else { 1.0 },
                    if c & 4 == 0 { -1.0 } else { 1.0 },
                );
                (m.translation - eye) + m.matrix3 * (s * half)
            })
            .collect();
        let depth: Vec<f64> = corners.iter().map(|c| c.dot(forward)).collect();
        let lo = depth.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = depth.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let lo = lo.max(camera.near * 1.0001);
        let centre = (m.translation - eye).dot(forward);
        let mut count = 0u32;
        let visible = in_frustum(&corners, (right, up, forward), camera, size);
        if visible && hi > lo && lo.is_finite() && hi.is_finite() && centre.is_finite() {
            let first = ((lo - centre) / spacing_world).floor() as i64 + 1;
            let last = ((hi - centre) / spacing_world).ceil() as i64 - 1;
            // The spacing is at least 0.05 texel of the volume's own level, so a volume
            // has at most ~18,000 slices at any scale; this only stops a broken input.
            let last = last.min(first + 1_000_000);
            for k in first..=last {
                let z = centre + k as f64 * spacing_world;
                let poly = cut(&corners, &depth, z, right, up);
                if poly.len() >= 3 {
                    slices.push((z, vi as u32, poly));
                    count += 1;
                }
            }
        }
        out.volumes.push(SlicedVolume {
            level,
            h_world,
            spacing_world,
            slices: count,
        });
    }
    // Back to front; equal depths in volume order (stable).
    slices.sort_by(|a, b| b.0.total_cmp(&a.0));
    for (_, vi, poly) in &slices {
        for i in 1..poly.len() - 1 {
            for p in [poly[0], poly[i], poly[i + 1]] {
                out.vertices
                    .push(([p.x as f32, p.y as f32, p.z as f32], *vi));
            }
        }
    }
    out
}

/// Whether any part of the box with camera-relative `corners` can be in the view: false
/// when all corners lie outside one plane of the frustum (near, left, right, bottom, top).
fn in_frustum(
    corners: &[DVec3],
    (right, up, forward): (DVec3, DVec3, DVec3),
    camera: &Camera,
    size: (u32, u32),
) -> bool {
    let tan_y = (camera.fov_y_deg.to_radians() * 0.5).tan();
    let tan_x = tan_y * f64::from(size.0.max(1)) / f64::from(size.1.max(1));
    let view: Vec<DVec3> = corners
        .iter()
        .map(|c| DVec3::new(c.dot(right), c.dot(up), c.dot(forward)))
        .collect();
    let outside = |f: &dyn Fn(&DVec3) -> bool| view.iter().all(f);
    !(outside(&|v| v.z < camera.near)
        || outside(&|v| v.x > v.z * tan_x)
        || outside(&|v| v.x < -v.z * tan_x)
        || outside(&|v| v.y > v.z * tan_y)
        || outside(&|v| v.y < -v.z * tan_y))
}

/// The convex polygon where the plane of view depth `z` cuts the box with `corners`
/// (corner `c` has bit k set for +1 on axis k), ordered around its centroid.
fn cut(corners: &[DVec3], depth: &[f64], z: f64, right: DVec3, up: DVec3) -> Vec<DVec3> {
    let mut points = Vec::with_capacity(6);
    for a in 0..8usize {
        for bit in [1usize, 2, 4] {
            let b = a | bit;
            if b == a {
                continue;
            }
            let (da, db) = (depth[a], depth[b]);
            if (da <= z) != (db <= z) {
                let t = (z - da) / (db - da);
                points.push(corners[a] + (corners[b] - corners[a]) * t);
            }
        }
    }
    if points.len() < 3 {
        return Vec::new();
    }
    let centre = points.iter().copied().sum::<DVec3>() / points.len() as f64;
    points.sort_by(|p, q| {
        let angle = |v: DVec3| (v - centre).dot(up).atan2((v - centre).dot(right));
        angle(*p).total_cmp(&angle(*q))
    });
    points
}

#[cfg(test)]
mod tests {
    use super::*;

    fn solid(edge: u32) -> RgbaVolume {
        RgbaVolume::from_texels(
            [edge; 3],
            &vec![[0.1, 0.1, 0.1, 0.3]; (edge.pow(3)) as usize],
        )
        .unwrap()
    }

    fn area(tri: &[([f32; 3], u32)]) -> f64 {
        let p: Vec<DVec3> = tri
            .iter()
            .map(|(v, _)| DVec3::new(v[0] as f64, v[1] as f64, v[2] as f64))
            .collect();
        (p[1] - p[0]).cross(p[2] - p[0]).length() * 0.5
    }

    /// The slices' cross-sections times their spacing sum to the box's volume (a Riemann
    /// sum of the cross-section area), every vertex lies on its box, and the slices come
    /// back to front across two volumes.
    #[test]
    fn slices_fill_the_box_and_come_back_to_front() {
        let v = solid(16);
        let a = DAffine3::from_scale_rotation_translation(
            DVec3::splat(0.5),
            glam::DQuat::from_rotation_y(0.7) * glam::DQuat::from_rotation_x(0.3),
            DVec3::new(0.2, 0.1, -0.5),
        );
        let b = DAffine3::from_translation(DVec3::new(-1.5, 0.0, -3.0));
        let camera = Camera::new(DVec3::new(0.3, 0.4, 4.0), DVec3::ZERO);
        let g = slice(
            &[(&v, a), (&v, b)],
            &camera,
            (320, 240),
            SliceSettings::default(),
        );
        assert_eq!(g.volumes.len(), 2);
        assert!(g.vertices.len().is_multiple_of(3));
        for (vi, (m, sv)) in [a, b].iter().zip(&g.volumes).enumerate() {
            // Level 0 of 16³ at this distance: the box [-1, 1]³ widened by half a texel
            // (1/16), the reference length a texel edge (2/16) times the scale, and the
            // slices half of that apart.
            assert_eq!(sv.level, 0);
            let half = DVec3::splat(1.0 + 1.0 / 16.0);
            let scale = m.matrix3.x_axis.length();
            assert!((sv.h_world - 2.0 / 16.0 * scale).abs() < 1e-12, "{sv:?}");
            assert!(
                (sv.spacing_world - 0.5 * sv.h_world).abs() < 1e-12,
                "{sv:?}"
            );
            let tris: Vec<_> = g
                .vertices
                .chunks(3)
                .filter(|t| t[0].1 == vi as u32)
                .collect();
            // One reported slice per distinct plane among its triangles.
            let (.., forward) = camera.basis();
            let mut planes: Vec<i64> = tris
                .iter()
                .map(|t| {
                    let p = t[0].0;
                    let z = DVec3::new(p[0].into(), p[1].into(), p[2].into()).dot(forward);
                    (z / sv.spacing_world).round() as i64
                })
                .collect();
            planes.dedup();
            assert_eq!(sv.slices as usize, planes.len(), "volume {vi}");
            let summed: f64 = tris.iter().map(|t| area(t)).sum::<f64>() * sv.spacing_world;
            let exact = (2.0 * half.x) * (2.0 * half.y) * (2.0 * half.z) * m.matrix3.determinant();
            assert!(
                (summed - exact).abs() < 0.02 * exact,
                "volume {vi}: {summed} vs {exact} ({} slices)",
                sv.slices
            );
            let inv = m.inverse();
            for t in &tris {
                for (p, _) in t.iter() {
                    let w = camera.position + DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64);
                    let o = inv.transform_point3(w);
                    assert!((o.abs() - half).max_element() < 1e-4, "{o:?}");
                }
            }
        }
        let (.., forward) = camera.basis();
        let depths: Vec<f64> = g
            .vertices
            .chunks(3)
            .map(|t| {
                let p = t[0].0;
                DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64).dot(forward)
            })
            .collect();
        assert!(
            depths.windows(2).all(|w| w[0] >= w[1] - 1e-4),
            "not back to front"
        );
        // The far volume's slices start before the near one's end.
        assert!(g.vertices.first().unwrap().1 == 1 && g.vertices.last().unwrap().1 == 0);
    }

    /// Moving the camera along its view axis by a fraction of the spacing keeps the slice
    /// planes where they are in the volume (no swimming); a volume behind the camera or
    /// beside the frustum gets no slices.
    #[test]
    fn planes_stay_put_in_the_volume_and_hidden_volumes_get_none() {
        let v = solid(16);
        let m = DAffine3::from_translation(DVec3::new(0.1, 0.0, -0.3));
        let at = |z: f64| Camera::new(DVec3::new(0.0, 0.0, z), DVec3::new(0.0, 0.0, z - 1.0));
        let planes = |c: &Camera| {
            let g = slice(&[(&v, m)], c, (320, 240), SliceSettings::default());
            let (.., forward) = c.basis();
            let mut z: Vec<i64> = g
                .vertices
                .chunks(3)
                .map(|t| {
                    let p = DVec3::new(t[0].0[0].into(), t[0].0[1].into(), t[0].0[2].into());
                    // World depth of the plane along -Z, in micro-units.
                    ((c.position + p).dot(forward) * 1e6).round() as i64
                })
                .collect();
            z.dedup();
            z
        };
        let (a, b) = (planes(&at(4.0)), planes(&at(4.0 - 0.0137)));
        assert!(a.len() > 20, "{}", a.len());
        // World positions of the planes: the same set (up to f32 vertex rounding).
        let close = |x: &Vec<i64>, y: &Vec<i64>| {
            x.len() == y.len() && x.iter().zip(y).all(|(p, q)| (p - q).abs() <= 2)
        };
        assert!(close(&a, &b), "{:?}\n{:?}", &a[..3], &b[..3]);
        let behind = Camera::new(DVec3::new(0.0, 0.0, -4.0), DVec3::new(0.0, 0.0, -10.0));
        let beside = Camera::new(DVec3::new(30.0, 0.0, 4.0), DVec3::new(30.0, 0.0, 0.0));
        for c in [behind, beside] {
            let g = slice(&[(&v, m)], &c, (320, 240), SliceSettings::default());
            assert!(g.vertices.is_empty() && g.volumes[0].slices == 0);
        }
    }

    /// The level switches where a level-0 texel (2 / 64 object units, times the scale)
    /// covers exactly 2^k pixels at the distance from the eye to the volume's bounding
    /// sphere (radius √3 × scale): 1 % either side of the switch gives k − 1 and k.
    #[test]
    fn the_level_switches_where_a_texel_covers_a_power_of_two_pixels() {
        let v = solid(64);
        let (scale, centre) = (1.5, DVec3::new(3.0, -2.0, 5.0));
        let m = DAffine3::from_scale_rotation_translation(
            DVec3::splat(scale),
            glam::DQuat::from_rotation_y(0.4),
            centre,
        );
        let texel = 2.0 / 64.0 * scale;
        let tan = (45f64.to_radians() * 0.5).tan();
        for k in 1..4 {
            for (factor, want) in [(0.99, k - 1), (1.01, k)] {
                // pixel = 2 d tan(fov / 2) / 240 = 2^k texel × factor.
                let d = f64::from(1u32 << k) * texel * factor * 240.0 / (2.0 * tan);
                let eye = centre + DVec3::new(0.6, 0.0, 0.8) * (d + 3f64.sqrt() * scale);
                let mut c = Camera::new(eye, centre);
                c.fov_y_deg = 45.0;
                assert_eq!(
                    choose_level(&v, &m, &c, 240, 0.0),
                    want as usize,
                    "k {k} × {factor}"
                );
            }
        }
    }

    /// A volume just outside each edge of the frustum (1 % of the edge's distance) gets no
    /// slices; moved 1 % inside, it gets some. Camera down -Z, 320×240, 45° vertical.
    #[test]
    fn culling_follows_each_frustum_plane() {
        let v = solid(8);
        let c = Camera::new(DVec3::ZERO, DVec3::NEG_Z);
        let half = 1.0 + 1.0 / 8.0;
        let (z, scale) = (20.0, 0.5);
        let tan_y = (22.5f64).to_radians().tan();
        let tan_x = tan_y * 320.0 / 240.0;
        for (axis, tan) in [
            (DVec3::X, tan_x),
            (DVec3::NEG_X, tan_x),
            (DVec3::Y, tan_y),
            (DVec3::NEG_Y, tan_y),
        ] {
            // The last corner to leave is the box's inner edge on its far face (depth
            // z + half·scale): it sits on the frustum plane when the centre is this far out.
            let far_face = z + half * scale;
            let edge = far_face * tan + half * scale;
            for (factor, drawn) in [(1.01, false), (0.99, true)] {
                let m = DAffine3::from_scale_rotation_translation(
                    DVec3::splat(scale),
                    glam::DQuat::IDENTITY,
                    axis * edge * factor - DVec3::Z * z,
                );
                let g = slice(&[(&v, m)], &c, (320, 240), SliceSettings::default());
                assert_eq!(g.volumes[0].slices > 0, drawn, "{axis:?} × {factor}");
            }
        }
    }

    /// Every slice polygon comes out convex, in cyclic order, without repeated points, for
    /// a rotated box well off the view axis (where a wrong pivot for the angle sort would
    /// show).
    #[test]
    fn slice_polygons_are_convex_and_in_cyclic_order() {
        let v = solid(8);
        let m = DAffine3::from_scale_rotation_translation(
            DVec3::splat(0.8),
            glam::DQuat::from_rotation_y(0.7) * glam::DQuat::from_rotation_x(0.5),
            DVec3::new(2.5, -1.2, -6.0),
        );
        let c = Camera::new(DVec3::ZERO, DVec3::NEG_Z);
        let (right, up, forward) = c.basis();
        let half = level_box(&v, 0);
        let corners: Vec<DVec3> = (0..8)
            .map(|k| {
                let s = DVec3::new(
                    if k & 1 == 0 { -1.0 } else { 1.0 },
                    if k & 2 == 0 { -1.0 } else { 1.0 },
                    if k & 4 == 0 { -1.0 } else { 1.0 },
                );
                m.translation + m.matrix3 * (s * half)
            })
            .collect();
        let depth: Vec<f64> = corners.iter().map(|p| p.dot(forward)).collect();
        let (lo, hi) = (
            depth.iter().copied().fold(f64::INFINITY, f64::min),
            depth.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        );
        let mut checked = 0;
        for i in 1..40 {
            let z = lo + (hi - lo) * f64::from(i) / 40.0;
            let poly = cut(&corners, &depth, z, right, up);
            assert!(
                (3..=6).contains(&poly.len()),
                "{} points at {z}",
                poly.len()
            );
            let n = poly.len();
            for j in 0..n {
                let (a, b, d) = (poly[j], poly[(j + 1) % n], poly[(j + 2) % n]);
                assert!((b - a).length() > 1e-9, "repeated point at {z}");
                // Every turn the same way about the view axis: convex and cyclic
                // (counter-clockwise in (right, up), so against `forward`).
                let turn = (b - a).cross(d - b).dot(forward);
                assert!(turn < 0.0, "turn {turn} at plane {z}, point {j}");
            }
            checked += 1;
        }
        assert_eq!(checked, 39);
    }

    /// With the eye inside the box, slices run from just beyond the near plane.
    #[test]
    fn inside_a_volume_slices_start_at_the_near_plane() {
        let v = solid(16);
        let mut c = Camera::new(DVec3::new(0.2, 0.1, 0.3), DVec3::new(0.2, 0.1, -1.0));
        c.near = 0.05;
        let g = slice(
            &[(&v, DAffine3::IDENTITY)],
            &c,
            (320, 240),
            SliceSettings::default(),
        );
        let (.., forward) = c.basis();
        let nearest = g
            .vertices
            .iter()
            .map(|(p, _)| DVec3::new(p[0].into(), p[1].into(), p[2].into()).dot(forward))
            .fold(f64::INFINITY, f64::min);
        let spacing = g.volumes[0].spacing_world;
        assert!(
            nearest >= c.near && nearest <= c.near + spacing + 1e-6,
            "{nearest} (near {}, spacing {spacing})",
            c.near
        );
    }

    /// Far away the level coarsens, one level per doubling of distance; the bias moves it;
    /// a camera inside gets the finest.
    #[test]
    fn the_level_follows_the_distance() {
        let v = solid(64);
        let m = DAffine3::IDENTITY;
        let at = |d: f64, bias: f64| {
            let c = Camera::new(DVec3::new(0.0, 0.0, d), DVec3::ZERO);
            choose_level(&v, &m, &c, 240, bias)
        };
        let l = at(32.0, 0.0);
        assert!(l >= 1, "{l}");
        assert_eq!(at(2.0 * 32.0 - 3f64.sqrt(), 0.0), l + 1);
        assert_eq!(at(32.0, 1.0), l + 1);
        assert_eq!(at(32.0, -1.0), l - 1);
        assert_eq!(at(0.1, 0.0), 0);
        // Close up the bias still coarsens (it adds to the level by distance, 0 there).
        assert_eq!(at(0.1, 2.0), 2);
        assert_eq!(at(1e9, 0.0), v.levels.len() - 1);
    }
}
