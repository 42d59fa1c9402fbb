//! A placement of an object or volume as written in a scene file.

use glam::{DAffine3, DQuat, DVec3};
use serde::Deserialize;

/// One placement of an object.
#[derive(Debug, Deserialize, Clone, Copy)]
#[serde(deny_unknown_fields)]
pub struct InstanceDesc {
    /// World position of the object-space origin.
    #[serde(default)]
    pub translation: (f64, f64, f64),
    /// Rotation about +Y in degrees.
    #[serde(default)]
    pub rotation_y_deg: f64,
    /// Uniform scale (object space [-1, 1]³ becomes [-scale, scale]³).
    #[serde(default = "one")]
    pub scale: f64,
}

/// The default of a field that defaults to 1.
pub(crate) fn one() -> f64 {
    1.0
}

impl InstanceDesc {
    /// Object → world.
    pub fn transform(&self) -> DAffine3 {
        DAffine3::from_scale_rotation_translation(
            DVec3::splat(self.scale),
            DQuat::from_rotation_y(self.rotation_y_deg.to_radians()),
            DVec3::new(self.translation.0, self.translation.1, self.translation.2),
        )
    }
}
