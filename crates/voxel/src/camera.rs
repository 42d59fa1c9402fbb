//! The pinhole camera shared by the CPU reference and the GPU passes.
//!
//! # Conventions (the GPU side relies on every one of them)
//!
//! - **World space is right-handed**, +Y up unless [`Camera::up`] says otherwise.
//! - **View space**: the camera sits at the origin and looks down **-Z**; +X is right, +Y
//!   is up ([`Camera::view_matrix`]). `right × up = -forward`.
//! - **Clip / NDC**: wgpu's: x and y in [-1, 1] with +Y up, depth in [0, 1].
//! - **Reversed Z** ([`Camera::projection`]): NDC depth is 1 at the near plane and falls to
//!   0 at the far plane (or at infinity for an infinite projection). Clear depth to 0 and
//!   test with `Greater`. Linear view depth `z_v` (distance along the forward axis) is
//!   recovered from NDC depth `d` as `near · far / (near + d · (far - near))` (finite) or
//!   `near / d` (infinite).
//! - **Images**: row 0 is the top row; pixel `(px, py)` covers `[px, px + 1] × [py, py + 1]`
//!   and rays go through **pixel centres** `(px + 0.5, py + 0.5)`. NDC x = -1 is the left
//!   edge of column 0, NDC y = +1 the top edge of row 0 (exactly what wgpu rasterizes).
//! - The aspect ratio is `width / height`; the field of view is vertical, in degrees.
//!
//! All of it is f64: at 1e7 world units f32 cannot even place a voxel of a level-12 grid.
//! The GPU should keep positions camera-relative and use [`Camera::view_rotation_matrix`]
//! with positions already relative to [`Camera::position`].

use glam::{DMat4, DVec3, DVec4};
use serde::{Deserialize, Serialize};

/// Smallest and largest accepted vertical field of view in degrees: outside this range
/// `tan(fov / 2)` is zero or infinite and rays would turn into NaN.
const FOV_RANGE_DEG: (f64, f64) = (1e-9, 179.999);

/// A pinhole camera (see the module docs for every convention).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Camera {
    /// Eye position in world space.
    pub position: DVec3,
    /// A world-space point the camera looks at (must differ from `position`; if it does not,
    /// the camera looks down -Z).
    pub look_at: DVec3,
    /// Approximate up direction; only its component orthogonal to the view direction is
    /// used. If it is zero or parallel to the view direction a fallback is chosen
    /// ([`Camera::basis`]).
    pub up: DVec3,
    /// Vertical field of view in degrees, clamped to (0, 180).
    pub fov_y_deg: f64,
    /// Near plane distance (> 0) along the forward axis. Only the projection uses it: the
    /// CPU reference casts rays from the eye itself.
    pub near: f64,
    /// Far plane distance along the forward axis; `f64::INFINITY` (or any value not above
    /// `near`) selects the infinite reversed-Z projection.
    pub far: f64,
}

impl Default for Camera {
    /// A camera at (0, 0, 3) looking at the origin with a 45° field of view.
    fn default() -> Self {
        Self::new(DVec3::new(0.0, 0.0, 3.0), DVec3::ZERO)
    }
}

impl Camera {
    /// A camera at `position` looking at `look_at`, +Y up, 45° vertical field of view,
    /// near 0.01, far 1000.
    pub fn new(position: DVec3, look_at: DVec3) -> Self {
        Self {
            position,
            look_at,
            up: DVec3::Y,
            fov_y_deg: 45.0,
            near: 0.01,
            far: 1000.0,
        }
    }

    /// Orthonormal `(right, up, forward)` basis, right-handed (`right × up = -forward`).
    ///
    /// Never NaN: a zero or non-finite view direction falls back to -Z; an up vector that
    /// is zero, non-finite or (nearly) parallel to the view direction is replaced by the
    /// world axis least aligned with the view direction (X, Y, Z order on ties).
    pub fn basis(&self) -> (DVec3, DVec3, DVec3) {
        let forward = normalize_or(self.look_at - self.position, DVec3::NEG_Z);
        let up_hint = normalize_or(self.up, DVec3::Y);
        let mut right = forward.cross(up_hint);
        // 1e-9 rad of separation still gives a usable, accurate cross product in f64;
        // below that the right vector is mostly rounding noise.
        if right.length_squared() <= 1e-18 {
            let a = forward.abs();
            let axis = if a.x <= a.y && a.x <= a.z {
                DVec3::X
            } else if a.y <= a.z {
                DVec3::Y
            } else {
                DVec3::Z
            };
            right = forward.cross(axis);
        }
        let right = right.normalize();
        let up = right.cross(forward).normalize();
        (right, up, forward)
    }

    /// The vertical field of view in radians after clamping to a usable range.
    fn fov_y_rad(&self) -> f64 {
        let deg = if self.fov_y_deg.is_finite() {
            self.fov_y_deg
        } else {
            45.0
        };
        deg.clamp(FOV_RANGE_DEG.0, FOV_RANGE_DEG.1).to_radians()
    }

    /// The ray through the centre of pixel `(px, py)` of a `width × height` image (row 0
    /// at the top): `(origin, direction)` in world space, direction normalized. The origin
    /// is the eye position.
    pub fn ray(&self, px: u32, py: u32, width: u32, height: u32) -> (DVec3, DVec3) {
        self.ray_at(px as f64 + 0.5, py as f64 + 0.5, width, height)
    }

    /// The ray through the continuous image position `(x, y)` in pixels (`(0, 0)` is the
    /// top-left corner of the image, `(px + 0.5, py + 0.5)` the centre of pixel `(px, py)`).
    pub fn ray_at(&self, x: f64, y: f64, width: u32, height: u32) -> (DVec3, DVec3) {
        self.pixel_rays(width, height).ray_at(x, y)
    }

    /// A ray generator for a `width × height` image that computes the basis once; its rays
    /// are bit-identical to [`Camera::ray`]'s.
    pub fn pixel_rays(&self, width: u32, height: u32) -> PixelRays {
        let (right, up, forward) = self.basis();
        let (w, h) = (width.max(1) as f64, height.max(1) as f64);
        let tan_half = (self.fov_y_rad() * 0.5).tan();
        PixelRays {
            origin: self.position,
            right,
            up,
            forward,
            width: w,
            height: h,
            tan_x: tan_half * (w / h),
            tan_y: tan_half,
        }
    }

    /// World → view matrix (right-handed, camera at the origin looking down -Z).
    pub fn view_matrix(&self) -> DMat4 {
        let (r, u, f) = self.basis();
        let p = self.position;
        DMat4::from_cols(
            DVec4::new(r.x, u.x, -f.x, 0.0),
            DVec4::new(r.y, u.y, -f.y, 0.0),
            DVec4::new(r.z, u.z, -f.z, 0.0),
            DVec4::new(-r.dot(p), -u.dot(p), f.dot(p), 1.0),
        )
    }

    /// The rotation part of [`Camera::view_matrix`]: maps camera-relative world positions
    /// (`world - position`) to view space. Use this on the GPU with camera-relative
    /// positions so large world coordinates never reach f32.
    pub fn view_rotation_matrix(&self) -> DMat4 {
        let (r, u, f) = self.basis();
        DMat4::from_cols(
            DVec4::new(r.x, u.x, -f.x, 0.0),
            DVec4::new(r.y, u.y, -f.y, 0.0),
            DVec4::new(r.z, u.z, -f.z, 0.0),
            DVec4::W,
        )
    }

    /// Whether [`Camera::projection`] is the infinite one (`far` not finite or not above
    /// `near`).
    pub fn is_infinite(&self) -> bool {
        let near = self.sanitized_near();
        !(self.far.is_finite() && self.far > near)
    }

    /// `near`, made positive and finite (1e-6 when it is not).
    fn sanitized_near(&self) -> f64 {
        if self.near > 0.0 && self.near.is_finite() {
            self.near
        } else {
            1e-6
        }
    }

    /// Reversed-Z perspective projection for a viewport of the given aspect
    /// (`width / height`): view space → clip space, NDC depth 1 at `near`, 0 at `far`
    /// (0 at infinity when [`Camera::is_infinite`]).
    ///
    /// With `z` the view-space z (negative in front of the camera), `n`/`f` the planes and
    /// `c = 1 / tan(fov_y / 2)`:
    /// `clip = (c / aspect · x, c · y, A · z + B, -z)` with `A = n / (f - n)`,
    /// `B = n · f / (f - n)`; infinite: `A = 0`, `B = n`.
    pub fn projection(&self, aspect: f64) -> DMat4 {
        let aspect = if aspect > 0.0 && aspect.is_finite() {
            aspect
        } else {
            1.0
        };
        let c = 1.0 / (self.fov_y_rad() * 0.5).tan();
        let n = self.sanitized_near();
        let (a, b) = if self.is_infinite() {
            (0.0, n)
        } else {
            let f = self.far;
            (n / (f - n), n * f / (f - n))
        };
        DMat4::from_cols(
            DVec4::new(c / aspect, 0.0, 0.0, 0.0),
            DVec4::new(0.0, c, 0.0, 0.0),
            DVec4::new(0.0, 0.0, a, -1.0),
            DVec4::new(0.0, 0.0, b, 0.0),
        )
    }

    /// `projection(aspect) · view_matrix()`.
    pub fn view_projection(&self, aspect: f64) -> DMat4 {
        self.projection(aspect) * self.view_matrix()
    }

    /// Linear view depth (distance along the forward axis) from a reversed-Z NDC depth
    /// written with [`Camera::projection`]. Depth 0 (far plane / infinity) maps to `far`
    /// or `f64::INFINITY`.
    pub fn linear_depth(&self, ndc_depth: f64) -> f64 {
        let n = self.sanitized_near();
        if self.is_infinite() {
            if ndc_depth > 0.0 {
                n / ndc_depth
            } else {
                f64::INFINITY
            }
        } else {
            let f = self.far;
            n * f / (n + ndc_depth * (f - n))
        }
    }
}

/// Generates the rays of [`Camera::ray`] for one image size (see [`Camera::pixel_rays`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PixelRays {
    origin: DVec3,
    right: DVec3,
    up: DVec3,
    forward: DVec3,
    width: f64,
    height: f64,
    tan_x: f64,
    tan_y: f64,
}

impl PixelRays {
    /// The ray through the centre of pixel `(px, py)` (row 0 at the top).
    pub fn ray(&self, px: u32, py: u32) -> (DVec3, DVec3) {
        self.ray_at(px as f64 + 0.5, py as f64 + 0.5)
    }

    /// The ray through the continuous image position `(x, y)` in pixels.
    pub fn ray_at(&self, x: f64, y: f64) -> (DVec3, DVec3) {
        let ndc_x = x / self.width * 2.0 - 1.0;
        let ndc_y = 1.0 - y / self.height * 2.0;
        let dir = self.forward + self.right * (ndc_x * self.tan_x) + self.up * (ndc_y * self.tan_y);
        (self.origin, normalize_or(dir, self.forward))
    }

    /// The camera's forward axis (view depth = `t · dot(dir, forward)`).
    pub fn forward(&self) -> DVec3 {
        self.forward
    }
}

/// `v / |v|`, or `fallback` when `v` is zero, tiny or not finite.
pub(crate) fn normalize_or(v: DVec3, fallback: DVec3) -> DVec3 {
    let len = v.length();
    if len > 1e-300 && len.is_finite() {
        v / len
    } else {
        fallback
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn assert_orthonormal(cam: &Camera) {
        let (r, u, f) = cam.basis();
        for v in [r, u, f] {
            assert!(v.is_finite(), "{cam:?}");
            assert!((v.length() - 1.0).abs() < 1e-12, "{cam:?}");
        }
        assert!(r.dot(u).abs() < 1e-12 && r.dot(f).abs() < 1e-12 && u.dot(f).abs() < 1e-12);
        assert!((r.cross(u) + f).length() < 1e-12, "not right-handed");
    }

    #[test]
    fn basis_is_orthonormal_even_when_degenerate() {
        let mut cam = Camera::new(DVec3::new(1.0, 2.0, 3.0), DVec3::ZERO);
        assert_orthonormal(&cam);
        let (r, u, f) = Camera::default().basis();
        assert_eq!((r, u, f), (DVec3::X, DVec3::Y, DVec3::NEG_Z));
        // Looking straight down / up the up vector.
        cam.position = DVec3::new(0.0, 5.0, 0.0);
        assert_orthonormal(&cam);
        cam.position = DVec3::new(0.0, -5.0, 0.0);
        assert_orthonormal(&cam);
        // Zero up, zero view direction, NaN up.
        cam.up = DVec3::ZERO;
        assert_orthonormal(&cam);
        cam.look_at = cam.position;
        assert_orthonormal(&cam);
        cam.up = DVec3::NAN;
        assert_orthonormal(&cam);
    }

    #[test]
    fn rays_go_through_pixel_centres_and_project_back_onto_them() {
        let cams = [
            Camera::new(DVec3::new(0.3, -2.0, 4.0), DVec3::new(0.1, 0.2, -0.3)),
            Camera {
                fov_y_deg: 90.0,
                ..Camera::new(DVec3::new(0.0, 7.0, 0.0), DVec3::ZERO)
            },
            Camera {
                far: f64::INFINITY,
                up: DVec3::new(0.0, 0.0, 1.0),
                ..Camera::new(DVec3::new(1e7, 1e7, 1e7), DVec3::new(1e7 + 1.0, 1e7, 1e7))
            },
        ];
        for cam in cams {
            let (w, h) = (37u32, 23u32);
            let vp = cam.view_projection(w as f64 / h as f64);
            let (_, _, forward) = cam.basis();
            for (px, py) in [(0, 0), (36, 22), (18, 11), (5, 17)] {
                let (o, d) = cam.ray(px, py, w, h);
                assert!((d.length() - 1.0).abs() < 1e-12);
                let t = 0.5;
                let p = o + d * t;
                let clip = vp * p.extend(1.0);
                let ndc = clip.truncate() / clip.w;
                let x = (ndc.x + 1.0) * 0.5 * w as f64;
                let y = (1.0 - ndc.y) * 0.5 * h as f64;
                assert!((x - (px as f64 + 0.5)).abs() < 1e-6, "{cam:?} {px} {x}");
                assert!((y - (py as f64 + 0.5)).abs() < 1e-6, "{cam:?} {py} {y}");
                // Reversed-Z depth decodes back into the linear view depth.
                let z_view = t * d.dot(forward);
                assert!(
                    (cam.linear_depth(ndc.z) - z_view).abs() < 1e-6 * z_view,
                    "{cam:?}"
                );
            }
        }
    }

    #[test]
    fn reversed_z_maps_near_to_one_and_far_to_zero() {
        let cam = Camera {
            near: 0.5,
            far: 100.0,
            ..Camera::default()
        };
        let p = cam.projection(1.5);
        let depth = |z: f64| {
            let c = p * DVec4::new(0.0, 0.0, -z, 1.0);
            c.z / c.w
        };
        assert!((depth(0.5) - 1.0).abs() < 1e-15);
        assert!(depth(100.0).abs() < 1e-15);
        assert!(depth(10.0) > depth(20.0));
        let inf = Camera {
            far: f64::INFINITY,
            ..cam
        };
        assert!(inf.is_infinite());
        let p = inf.projection(1.5);
        let c = p * DVec4::new(0.0, 0.0, -0.5, 1.0);
        assert!((c.z / c.w - 1.0).abs() < 1e-15);
        let c = p * DVec4::new(0.0, 0.0, -1e300, 1.0);
        assert!(c.z / c.w < 1e-299);
        assert_eq!(inf.linear_depth(0.0), f64::INFINITY);
        // Garbage parameters never produce NaN matrices.
        let bad = Camera {
            fov_y_deg: f64::NAN,
            near: -1.0,
            far: f64::NAN,
            ..cam
        };
        assert!(
            bad.projection(f64::NAN)
                .to_cols_array()
                .iter()
                .all(|v| v.is_finite())
        );
        let (_, d) = bad.ray(0, 0, 0, 0);
        assert!(d.is_finite());
    }

    /// A view direction parallel to `up` takes the world axis least aligned with it
    /// (X, Y, Z order on ties), as documented: the resulting right vectors, exactly.
    #[test]
    fn a_degenerate_up_takes_the_least_aligned_world_axis() {
        for (forward, up, right) in [
            (DVec3::NEG_Y, DVec3::Y, DVec3::Z),
            (DVec3::NEG_X, DVec3::X, DVec3::NEG_Z),
            (DVec3::NEG_Z, DVec3::Z, DVec3::NEG_Y),
            // Least aligned is Y (0.1 < 0.7): right = forward x Y.
            (
                DVec3::new(0.7, 0.1, 0.7),
                DVec3::new(0.7, 0.1, 0.7),
                DVec3::ZERO,
            ),
        ] {
            let cam = Camera {
                up,
                ..Camera::new(DVec3::ZERO, forward)
            };
            let (r, _, f) = cam.basis();
            let want = if right == DVec3::ZERO {
                f.cross(DVec3::Y).normalize()
            } else {
                right
            };
            assert!((r - want).length() < 1e-12, "{forward}: {r} vs {want}");
        }
    }

    /// The rotation matrix maps camera-relative points as the full view matrix maps the
    /// points themselves.
    #[test]
    fn the_view_rotation_is_the_view_matrix_without_its_translation() {
        let cam = Camera::new(DVec3::new(3.0, -2.0, 5.0), DVec3::new(-1.0, 0.5, 0.25));
        let (v, rot) = (cam.view_matrix(), cam.view_rotation_matrix());
        for p in [
            DVec3::ZERO,
            DVec3::new(1.0, 2.0, 3.0),
            DVec3::new(-7.0, 0.5, 9.0),
        ] {
            let a = v.transform_point3(p);
            let b = rot.transform_point3(p - cam.position);
            assert!((a - b).length() < 1e-12, "{p}: {a} vs {b}");
        }
        // A point ahead of the camera is at negative view z.
        assert!(rot.transform_point3(cam.look_at - cam.position).z < 0.0);
    }

    /// Planes and aspect outside their ranges fall back as documented: near 0, NaN or
    /// infinite becomes 1e-6; far not above near is infinite; a zero, negative or
    /// infinite aspect is 1.
    #[test]
    fn unusable_planes_and_aspects_fall_back() {
        let base = Camera::default();
        for near in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            let cam = Camera {
                near,
                far: f64::INFINITY,
                ..base
            };
            // Infinite projection: B = n.
            assert_eq!(cam.projection(1.0).w_axis.z, 1e-6, "near {near}");
        }
        let equal = Camera {
            near: 2.0,
            far: 2.0,
            ..base
        };
        assert!(equal.is_infinite());
        let finite = Camera {
            near: 2.0,
            far: 2.5,
            ..base
        };
        assert!(!finite.is_infinite());
        let one = base.projection(1.0);
        for aspect in [0.0, -2.0, f64::INFINITY, f64::NAN] {
            assert_eq!(base.projection(aspect), one, "aspect {aspect}");
        }
        assert_ne!(base.projection(2.0), one);
    }
}
