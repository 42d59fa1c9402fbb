//! Decoded accessor values.

/// Accessor values widened to `f64` (which holds every glTF component type exactly).
pub(super) struct Values {
    pub(super) data: Vec<f64>,
    pub(super) components: usize,
    pub(super) count: usize,
}

impl Values {
    /// Component `c` of element `i` (0 when out of range).
    pub(super) fn get(&self, i: usize, c: usize) -> f64 {
        self.data
            .get(i * self.components + c)
            .copied()
            .unwrap_or(0.0)
    }
}
