//! Pointer input (mouse, pen, touch) as orbit-camera moves: one pointer dragging turns the
//! camera, two pointers pinching move it nearer or farther (as the wheel does).

/// What a pointer event asks of the camera.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Gesture {
    /// Turn by a drag of `(dx, dy)` pixels.
    Turn(f64, f64),
    /// Zoom by wheel units (negative: nearer).
    Zoom(f64),
}

/// The pointers down on the canvas.
#[derive(Debug, Default)]
pub struct Gestures {
    down: Vec<(i32, f64, f64)>,
}

/// Wheel units per pixel of pinch (a pinch as wide as a wheel notch's 100 units moves the
/// camera as far).
const PINCH_UNITS_PER_PIXEL: f64 = 4.0;

impl Gestures {
    /// A pointer went down.
    pub fn down(&mut self, id: i32, x: f64, y: f64) {
        self.up(id);
        self.down.push((id, x, y));
    }

    /// A pointer went up or was cancelled.
    pub fn up(&mut self, id: i32) {
        self.down.retain(|p| p.0 != id);
    }

    /// A pointer moved to `(x, y)`: what the camera should do.
    pub fn moved(&mut self, id: i32, x: f64, y: f64) -> Option<Gesture> {
        let i = self.down.iter().position(|p| p.0 == id)?;
        let (_, ox, oy) = self.down[i];
        let spread = |d: &[(i32, f64, f64)]| (d[0].1 - d[1].1).hypot(d[0].2 - d[1].2);
        let before = (self.down.len() == 2).then(|| spread(&self.down));
        self.down[i] = (id, x, y);
        match (self.down.len(), before) {
            (1, _) => Some(Gesture::Turn(x - ox, y - oy)),
            (2, Some(before)) => Some(Gesture::Zoom(
                (before - spread(&self.down)) * PINCH_UNITS_PER_PIXEL,
            )),
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_pointer_turns_and_two_pinch() {
        let mut g = Gestures::default();
        assert_eq!(g.moved(1, 5.0, 5.0), None);
        g.down(1, 10.0, 10.0);
        assert_eq!(g.moved(1, 14.0, 7.0), Some(Gesture::Turn(4.0, -3.0)));
        g.down(2, 114.0, 7.0);
        // Spreading the fingers from 100 to 150 pixels apart moves nearer.
        assert_eq!(g.moved(2, 164.0, 7.0), Some(Gesture::Zoom(-200.0)));
        assert_eq!(g.moved(1, 39.0, 7.0), Some(Gesture::Zoom(100.0)));
        g.up(2);
        assert_eq!(g.moved(1, 40.0, 9.0), Some(Gesture::Turn(1.0, 2.0)));
        g.up(1);
        assert_eq!(g.moved(1, 0.0, 0.0), None);
    }
}
