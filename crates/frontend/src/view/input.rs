//! Mouse and keyboard → camera: which buttons drag the scene, which keys are held, and
//! what they do to the [`CameraRig`] (orbit: left drag rotates, right/middle drag pans,
//! wheel zooms; fly: WASD + Q/E move, right drag looks, Shift is faster, wheel changes the
//! speed). Events egui claims (a drag that starts on the overlay, typing in a text field)
//! never reach the camera.

use std::collections::HashSet;

use winit::event::{ElementState, MouseButton, MouseScrollDelta};
use winit::keyboard::KeyCode;

use super::camera_control::{CameraMode, CameraRig, MoveInput};

/// Fly speed factor while Shift is held.
const SHIFT_FACTOR: f64 = 4.0;

/// Input state between events.
#[derive(Debug, Default)]
pub struct CameraInput {
    held_keys: HashSet<KeyCode>,
    /// Buttons whose press started over the scene (not over the overlay).
    dragging: HashSet<MouseButton>,
    cursor: Option<(f64, f64)>,
}

impl CameraInput {
    /// A key went down or up. Releases are always taken (no key stays stuck when egui
    /// grabbed the press); presses only when `egui_wants_keys` is false.
    pub fn key(&mut self, code: KeyCode, state: ElementState, egui_wants_keys: bool) {
        match state {
            ElementState::Pressed if !egui_wants_keys => {
                self.held_keys.insert(code);
            }
            ElementState::Released => {
                self.held_keys.remove(&code);
            }
            ElementState::Pressed => {}
        }
    }

    /// A mouse button went down or up; a press over the overlay does not start a drag.
    pub fn button(&mut self, button: MouseButton, state: ElementState, over_overlay: bool) {
        match state {
            ElementState::Pressed if !over_overlay => {
                self.dragging.insert(button);
            }
            ElementState::Pressed => {}
            ElementState::Released => {
                self.dragging.remove(&button);
            }
        }
    }

    /// The cursor moved to `(x, y)` (physical pixels): drags move the camera.
    pub fn cursor_moved(&mut self, x: f64, y: f64, rig: &mut CameraRig, window_height: f64) {
        let Some((lx, ly)) = self.cursor.replace((x, y)) else {
            return;
        };
        let (dx, dy) = (x - lx, y - ly);
        match rig.mode {
            CameraMode::Orbit => {
                if self.dragging.contains(&MouseButton::Left) {
                    rig.orbit.rotate(dx, dy);
                } else if self.dragging.contains(&MouseButton::Right)
                    || self.dragging.contains(&MouseButton::Middle)
                {
                    rig.orbit.pan(dx, dy, window_height, rig.base.fov_y_deg);
                }
            }
            CameraMode::Fly => {
                if self.dragging.contains(&MouseButton::Right) {
                    rig.fly.look(dx, dy);
                }
            }
        }
    }

    /// The cursor left the window: the next move must not jump.
    pub fn cursor_left(&mut self) {
        self.cursor = None;
    }

    /// Wheel: zoom (orbit) or fly speed.
    pub fn wheel(&mut self, delta: MouseScrollDelta, rig: &mut CameraRig) {
        let steps = match delta {
            MouseScrollDelta::LineDelta(_, y) => y as f64,
            // Touchpads: about 50 pixels per notch.
            MouseScrollDelta::PixelDelta(p) => p.y / 50.0,
        };
        match rig.mode {
            CameraMode::Orbit => rig.orbit.zoom(steps),
            CameraMode::Fly => {
                let s = rig.fly_speed * 1.25f64.powf(steps);
                if s.is_finite() && s > 0.0 {
                    rig.fly_speed = s.clamp(1e-4, 1e7);
                }
            }
        }
    }

    /// Whether a Ctrl key is held (Ctrl + left click is the brush).
    pub fn ctrl_held(&self) -> bool {
        self.held_keys.contains(&KeyCode::ControlLeft)
            || self.held_keys.contains(&KeyCode::ControlRight)
    }

    /// Whether a Shift key is held (Ctrl + Shift + Z is redo).
    pub fn shift_held(&self) -> bool {
        self.held_keys.contains(&KeyCode::ShiftLeft)
            || self.held_keys.contains(&KeyCode::ShiftRight)
    }

    /// Movement axes from the held keys.
    pub fn movement(&self) -> MoveInput {
        let axis = |plus: KeyCode, minus: KeyCode| {
            f64::from(u8::from(self.held_keys.contains(&plus)))
                - f64::from(u8::from(self.held_keys.contains(&minus)))
        };
        MoveInput {
            forward: axis(KeyCode::KeyW, KeyCode::KeyS),
            right: axis(KeyCode::KeyD, KeyCode::KeyA),
            up: axis(KeyCode::KeyE, KeyCode::KeyQ),
        }
    }

    /// Advances the fly camera by `dt` seconds of held keys.
    pub fn update(&self, rig: &mut CameraRig, dt: f64) {
        if rig.mode != CameraMode::Fly {
            return;
        }
        let shift = self.held_keys.contains(&KeyCode::ShiftLeft)
            || self.held_keys.contains(&KeyCode::ShiftRight);
        let speed = rig.fly_speed * if shift { SHIFT_FACTOR } else { 1.0 };
        rig.fly.advance(self.movement(), speed, dt);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use ssbvb_voxel::camera::Camera;

    #[test]
    fn drags_over_the_overlay_do_not_move_the_camera() {
        let mut rig = CameraRig::new(Camera::default());
        let before = rig.camera();
        let mut input = CameraInput::default();
        input.button(MouseButton::Left, ElementState::Pressed, true);
        input.cursor_moved(10.0, 10.0, &mut rig, 720.0);
        input.cursor_moved(200.0, 50.0, &mut rig, 720.0);
        assert_eq!(rig.camera(), before);
        input.button(MouseButton::Left, ElementState::Released, true);
        input.button(MouseButton::Left, ElementState::Pressed, false);
        input.cursor_moved(300.0, 50.0, &mut rig, 720.0);
        assert_ne!(rig.camera().position, before.position);
    }

    #[test]
    fn held_keys_fly_and_releases_always_count() {
        let mut rig = CameraRig::new(Camera::default());
        rig.toggle();
        let mut input = CameraInput::default();
        input.key(KeyCode::KeyW, ElementState::Pressed, false);
        let p0 = rig.fly.position;
        input.update(&mut rig, 0.5);
        // Default camera at +3 Z looking at the origin: W moves towards -Z.
        assert!(rig.fly.position.z < p0.z);
        input.key(KeyCode::KeyW, ElementState::Released, true);
        assert_eq!(input.movement(), MoveInput::default());
        // A press egui wants (typing) does not move the camera.
        input.key(KeyCode::KeyW, ElementState::Pressed, true);
        assert_eq!(input.movement(), MoveInput::default());
    }
}
