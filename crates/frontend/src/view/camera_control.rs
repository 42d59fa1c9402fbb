//! Orbit and fly cameras: pure math on yaw/pitch angles, turned into the renderer's
//! [`Camera`] each frame. No window types here, so all of it is unit-tested.
//!
//! Angles: `dir(yaw, pitch) = (cos p · sin y, sin p, cos p · cos y)` (+Y up, yaw 0 looks
//! along +Z). The orbit camera sits at `target + distance · dir`; the fly camera looks
//! along `dir`. Pitch is clamped short of ±90° so the view direction never becomes
//! parallel to +Y (the camera basis would otherwise flip or turn NaN at the poles).

use glam::DVec3;
use ssbvb_voxel::camera::Camera;

/// Largest |pitch| in radians (89°).
pub const MAX_PITCH: f64 = 89.0 * std::f64::consts::PI / 180.0;
/// Orbit distance limits (object sizes; the renderer is tested from 1e-3 to 1e7).
pub const DISTANCE_RANGE: (f64, f64) = (1e-3, 1e7);
/// Radians per pixel of mouse movement.
pub const ROTATE_PER_PIXEL: f64 = 0.005;

/// Unit direction of `yaw` / `pitch` (see the module docs).
pub fn dir(yaw: f64, pitch: f64) -> DVec3 {
    DVec3::new(
        pitch.cos() * yaw.sin(),
        pitch.sin(),
        pitch.cos() * yaw.cos(),
    )
}

/// `(yaw, pitch)` of a direction (inverse of [`dir`]); pitch clamped to ±[`MAX_PITCH`].
/// A zero or non-finite vector gives `(0, 0)`.
pub fn angles(v: DVec3) -> (f64, f64) {
    let v = v.normalize_or_zero();
    if v == DVec3::ZERO || !v.is_finite() {
        return (0.0, 0.0);
    }
    let pitch = v.y.clamp(-1.0, 1.0).asin().clamp(-MAX_PITCH, MAX_PITCH);
    // At the poles x and z vanish and atan2(0, 0) = 0: any yaw is right there.
    (v.x.atan2(v.z), pitch)
}

fn clamp_pitch(p: f64) -> f64 {
    if p.is_finite() {
        p.clamp(-MAX_PITCH, MAX_PITCH)
    } else {
        0.0
    }
}

/// Orbit camera: rotates around, zooms towards and pans a target point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Orbit {
    /// The point looked at.
    pub target: DVec3,
    /// Distance from the target.
    pub distance: f64,
    /// Yaw of the target → eye direction.
    pub yaw: f64,
    /// Pitch of the target → eye direction.
    pub pitch: f64,
}

impl Orbit {
    /// The orbit whose eye and target are the camera's.
    pub fn from_camera(camera: &Camera) -> Self {
        let offset = camera.position - camera.look_at;
        let (yaw, pitch) = angles(offset);
        let distance = offset.length();
        Self {
            target: camera.look_at,
            distance: if distance.is_finite() && distance > 0.0 {
                distance.clamp(DISTANCE_RANGE.0, DISTANCE_RANGE.1)
            } else {
                3.0
            },
            yaw,
            pitch,
        }
    }

    /// Eye position.
    pub fn position(&self) -> DVec3 {
        self.target + self.distance * dir(self.yaw, self.pitch)
    }

    /// Rotates by a mouse drag of `(dx, dy)` pixels (drag right: the scene turns right;
    /// drag down: the eye rises).
    pub fn rotate(&mut self, dx: f64, dy: f64) {
        self.yaw -= dx * ROTATE_PER_PIXEL;
        self.pitch = clamp_pitch(self.pitch + dy * ROTATE_PER_PIXEL);
    }

    /// Zooms by `steps` wheel notches (positive = closer), multiplicatively so that
    /// zooming works the same at every scale.
    pub fn zoom(&mut self, steps: f64) {
        let d = self.distance * (-0.15 * steps).exp();
        // An overflow to infinity (or to 0) is still a direction: clamp it. NaN is not.
        if !d.is_nan() {
            self.distance = d.clamp(DISTANCE_RANGE.0, DISTANCE_RANGE.1);
        }
    }

    /// Pans the target by a drag of `(dx, dy)` pixels in a window `height` pixels tall with
    /// vertical field of view `fov_y_deg`: the point under the cursor stays under it (at
    /// the target's depth).
    pub fn pan(&mut self, dx: f64, dy: f64, height: f64, fov_y_deg: f64) {
        let cam = self.camera(&Camera::default());
        let (right, up, _) = cam.basis();
        let world_per_pixel =
            2.0 * self.distance * (fov_y_deg.to_radians() / 2.0).tan() / height.max(1.0);
        let shift = (-dx * right + dy * up) * world_per_pixel;
        if shift.is_finite() {
            self.target += shift;
        }
    }

    /// The camera (field of view and planes from `base`).
    pub fn camera(&self, base: &Camera) -> Camera {
        Camera {
            position: self.position(),
            look_at: self.target,
            up: DVec3::Y,
            ..*base
        }
    }
}

/// Fly camera: free position, looks along `dir(yaw, pitch)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fly {
    /// Eye position.
    pub position: DVec3,
    /// View yaw.
    pub yaw: f64,
    /// View pitch.
    pub pitch: f64,
}

/// Movement keys held, as axes in -1..=1.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct MoveInput {
    /// W (+1) / S (-1): along the view direction.
    pub forward: f64,
    /// D (+1) / A (-1): along the camera's right.
    pub right: f64,
    /// E (+1) / Q (-1): along world +Y.
    pub up: f64,
}

impl Fly {
    /// The fly camera at the camera's eye, looking where it looks.
    pub fn from_camera(camera: &Camera) -> Self {
        let (yaw, pitch) = angles(camera.look_at - camera.position);
        Self {
            position: camera.position,
            yaw,
            pitch,
        }
    }

    /// Unit view direction.
    pub fn forward(&self) -> DVec3 {
        dir(self.yaw, self.pitch)
    }

    /// Horizontal right vector (never zero: pitch is clamped).
    pub fn right(&self) -> DVec3 {
        self.forward().cross(DVec3::Y).normalize_or(DVec3::X)
    }

    /// Mouse-look by `(dx, dy)` pixels (right: turn right; up: look up).
    pub fn look(&mut self, dx: f64, dy: f64) {
        self.yaw -= dx * ROTATE_PER_PIXEL;
        self.pitch = clamp_pitch(self.pitch - dy * ROTATE_PER_PIXEL);
    }

    /// Moves for `dt` seconds at `speed` units per second.
    pub fn advance(&mut self, input: MoveInput, speed: f64, dt: f64) {
        let v = input.forward * self.forward() + input.right * self.right() + input.up * DVec3::Y;
        let step = v.normalize_or_zero() * speed * dt;
        if step.is_finite() {
            self.position += step;
        }
    }

    /// The camera (field of view and planes from `base`).
    pub fn camera(&self, base: &Camera) -> Camera {
        Camera {
            position: self.position,
            look_at: self.position + self.forward(),
            up: DVec3::Y,
            ..*base
        }
    }
}

/// Which camera drives the view.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CameraMode {
    /// [`Orbit`].
    Orbit,
    /// [`Fly`].
    Fly,
}

/// Both cameras, kept in step when switching so the view does not jump.
#[derive(Debug, Clone, Copy)]
pub struct CameraRig {
    /// The active one.
    pub mode: CameraMode,
    /// Orbit state.
    pub orbit: Orbit,
    /// Fly state.
    pub fly: Fly,
    /// Field of view and planes.
    pub base: Camera,
    /// Fly speed in world units per second (Shift: ×4).
    pub fly_speed: f64,
}

impl CameraRig {
    /// Starts in orbit mode at `camera`.
    pub fn new(camera: Camera) -> Self {
        let orbit = Orbit::from_camera(&camera);
        Self {
            mode: CameraMode::Orbit,
            orbit,
            fly: Fly::from_camera(&camera),
            base: camera,
            // About a third of the starting distance per second: a few seconds to reach the
            // target whatever the scene's scale.
            fly_speed: (orbit.distance / 3.0).max(1e-3),
        }
    }

    /// The current camera.
    pub fn camera(&self) -> Camera {
        match self.mode {
            CameraMode::Orbit => self.orbit.camera(&self.base),
            CameraMode::Fly => self.fly.camera(&self.base),
        }
    }

    /// Switches mode, starting the new camera where the old one is.
    pub fn set_mode(&mut self, mode: CameraMode) {
        if mode == self.mode {
            return;
        }
        match mode {
            CameraMode::Fly => self.fly = Fly::from_camera(&self.orbit.camera(&self.base)),
            CameraMode::Orbit => {
                // Keep the orbit distance: the new target is that far ahead of the eye.
                let f = self.fly.forward();
                self.orbit.target = self.fly.position + f * self.orbit.distance;
                let (yaw, pitch) = angles(-f);
                self.orbit.yaw = yaw;
                self.orbit.pitch = pitch;
            }
        }
        self.mode = mode;
    }

    /// Toggles between orbit and fly.
    pub fn toggle(&mut self) {
        self.set_mode(match self.mode {
            CameraMode::Orbit => CameraMode::Fly,
            CameraMode::Fly => CameraMode::Orbit,
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: DVec3, b: DVec3, eps: f64) -> bool {
        (a - b).length() < eps
    }

    #[test]
    fn orbit_round_trip_keeps_eye_and_target() {
        for (pos, at) in [
            (DVec3::new(1.9, 0.9, 2.7), DVec3::new(0.0, -0.15, 0.0)),
            (DVec3::new(-5.0, 2.0, -1.0), DVec3::new(1.0, 1.0, 1.0)),
            (DVec3::new(0.0, 0.0, 3.0), DVec3::ZERO),
            (DVec3::new(1e6, 3.0, -2e6), DVec3::new(1e6, 0.0, -2e6 + 5.0)),
        ] {
            let cam = Camera::new(pos, at);
            let o = Orbit::from_camera(&cam);
            let back = o.camera(&cam);
            assert!(
                close(back.position, pos, 1e-9 * pos.length().max(1.0)),
                "{pos} -> {}",
                back.position
            );
            assert_eq!(back.look_at, at);
        }
    }

    #[test]
    fn orbit_rotation_keeps_distance_and_target() {
        let mut o = Orbit::from_camera(&Camera::default());
        let d0 = o.distance;
        o.rotate(120.0, -40.0);
        assert!(((o.position() - o.target).length() - d0).abs() < 1e-12);
        assert_eq!(o.target, DVec3::ZERO);
    }

    #[test]
    fn orbit_at_the_poles_has_no_nan() {
        let mut o = Orbit::from_camera(&Camera::default());
        // Far more than a half turn up, then down: pitch must stop short of ±90°.
        for dy in [1e6, -1e6, f64::MAX, f64::NAN] {
            o.rotate(0.0, dy);
            assert!(o.pitch.abs() <= MAX_PITCH);
            let cam = o.camera(&Camera::default());
            let (r, u, f) = cam.basis();
            assert!(r.is_finite() && u.is_finite() && f.is_finite());
            assert!(cam.position.is_finite());
        }
        // A camera looking straight down still gives a finite orbit.
        let straight_down = Camera::new(DVec3::new(0.0, 5.0, 0.0), DVec3::ZERO);
        let o = Orbit::from_camera(&straight_down);
        assert!(o.position().is_finite() && o.pitch.abs() <= MAX_PITCH);
    }

    #[test]
    fn zoom_is_multiplicative_and_clamped() {
        let mut o = Orbit::from_camera(&Camera::default());
        o.zoom(1.0);
        o.zoom(-1.0);
        assert!((o.distance - 3.0).abs() < 1e-12);
        o.zoom(1e6);
        assert_eq!(o.distance, DISTANCE_RANGE.0);
        o.zoom(-1e6);
        assert_eq!(o.distance, DISTANCE_RANGE.1);
    }

    #[test]
    fn pan_moves_target_sideways() {
        let mut o = Orbit::from_camera(&Camera::default());
        o.pan(100.0, 0.0, 720.0, 45.0);
        // Camera at +Z looking at the origin: right is +X; dragging right moves the scene
        // right, i.e. the target left.
        assert!(o.target.x < 0.0 && o.target.y.abs() < 1e-12 && o.target.z.abs() < 1e-12);
    }

    #[test]
    fn fly_moves_along_view_direction() {
        let cam = Camera::new(DVec3::new(1.0, 2.0, 3.0), DVec3::new(0.0, 0.0, 0.0));
        let mut f = Fly::from_camera(&cam);
        let want = (cam.look_at - cam.position).normalize();
        assert!(close(f.forward(), want, 1e-12));
        let start = f.position;
        f.advance(
            MoveInput {
                forward: 1.0,
                ..Default::default()
            },
            2.0,
            0.5,
        );
        assert!(close(f.position - start, want, 1e-12));
        // Strafing is perpendicular to the view and horizontal.
        let p = f.position;
        f.advance(
            MoveInput {
                right: 1.0,
                ..Default::default()
            },
            1.0,
            1.0,
        );
        let d = f.position - p;
        assert!(d.dot(want).abs() < 1e-12 && d.y.abs() < 1e-12);
        // The fly camera looks where it moves.
        let c = f.camera(&cam);
        assert!(close((c.look_at - c.position).normalize(), want, 1e-12));
    }

    #[test]
    fn fly_look_clamps_pitch() {
        let mut f = Fly::from_camera(&Camera::default());
        f.look(0.0, -1e9);
        assert!(f.pitch <= MAX_PITCH && f.forward().is_finite());
        assert!(f.right().is_finite() && f.right().length() > 0.99);
        f.look(0.0, f64::INFINITY);
        assert!(f.forward().is_finite());
    }

    #[test]
    fn switching_modes_keeps_the_view() {
        let cam = Camera::new(DVec3::new(1.9, 0.9, 2.7), DVec3::new(0.0, -0.15, 0.0));
        let mut rig = CameraRig::new(cam);
        let before = rig.camera();
        rig.toggle();
        assert_eq!(rig.mode, CameraMode::Fly);
        let fly = rig.camera();
        assert!(close(fly.position, before.position, 1e-9));
        let fwd = |c: &Camera| (c.look_at - c.position).normalize();
        assert!(close(fwd(&fly), fwd(&before), 1e-9));
        rig.toggle();
        let back = rig.camera();
        assert!(close(back.position, before.position, 1e-9));
        assert!(close(back.look_at, before.look_at, 1e-9));
    }
}
