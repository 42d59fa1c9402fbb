//! Parameter defaults and checks that several kinds share.

/// The serde default of a scale or pixel size that is 1 unless written.
pub(super) fn one() -> f32 {
    1.0
}

/// The serde default of `max_steps` of the per-pixel ray casts (`DenseDda`,
/// `OctreeRayCast`, `EsvoRayCast`).
pub(super) fn default_ray_cast_steps() -> u32 {
    4096
}

/// `max_steps` must be at least 1.
pub(super) fn steps_problems(max_steps: u32) -> Vec<String> {
    if max_steps == 0 {
        vec!["max_steps must be at least 1".to_string()]
    } else {
        Vec::new()
    }
}
