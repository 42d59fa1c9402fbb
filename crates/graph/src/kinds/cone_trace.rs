//! `ConeTrace`, voxel cone tracing: [`ConeTraceParams`], its knobs and their ranges. What
//! the cones estimate is defined once, in `ssbvb-voxel`'s `lighting` module; the lighting
//! that uses it is `ConeComposite`.

use serde::{Deserialize, Serialize};

use super::formats::{ALBEDO, LIGHT, NORMAL, POSITION};
use super::spec::{KindSpec, ParamDesc, PassStage, SlotClass, SlotDesc};

/// The most diffuse cones per pixel.
pub const MAX_CONES: u32 = 64;
/// The finest scene volume accepted (cells along its longest axis; 512³ texels of 8 bytes
/// are 1 GiB).
pub const MAX_VOLUME_RESOLUTION: u32 = 512;

/// Parameters of `ConeTrace`.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ConeTraceParams {
    /// Diffuse cones per pixel (AO and bounce), spread cosine-weighted over the normal's
    /// hemisphere.
    #[serde(default = "default_cones")]
    pub cones: u32,
    /// Full apex angle of each diffuse cone, degrees.
    #[serde(default = "default_aperture")]
    pub aperture: f32,
    /// How far the diffuse cones reach (world units): the AO and bounce radius.
    #[serde(default = "default_max_distance")]
    pub max_distance: f32,
    /// A step along a cone is `step_scale` times the cone's diameter there (1: the knee
    /// of cost against AO error measured in docs/benchmarks.md).
    #[serde(default = "default_step_scale")]
    pub step_scale: f32,
    /// Full apex angle of the shadow cone towards the light, degrees (the light's angular
    /// size).
    #[serde(default = "default_shadow_aperture")]
    pub shadow_aperture: f32,
    /// Cells of the scene volume along its longest axis.
    #[serde(default = "default_resolution")]
    pub resolution: u32,
}

fn default_cones() -> u32 {
    9
}
fn default_aperture() -> f32 {
    60.0
}
fn default_max_distance() -> f32 {
    0.5
}
fn default_step_scale() -> f32 {
    1.0
}
fn default_shadow_aperture() -> f32 {
    6.0
}
fn default_resolution() -> u32 {
    128
}

impl Default for ConeTraceParams {
    fn default() -> Self {
        Self {
            cones: default_cones(),
            aperture: default_aperture(),
            max_distance: default_max_distance(),
            step_scale: default_step_scale(),
            shadow_aperture: default_shadow_aperture(),
            resolution: default_resolution(),
        }
    }
}

impl KindSpec for ConeTraceParams {
    const PARAMS: &'static [ParamDesc] = &[
        ParamDesc::new("cones", "u32", "1 to 64 (MAX_CONES)"),
        ParamDesc::new("aperture", "f32", "degrees, above 0 and below 180"),
        ParamDesc::new("max_distance", "f32", "a positive number (world units)"),
        ParamDesc::new("step_scale", "f32", "0.05 to 4"),
        ParamDesc::new("shadow_aperture", "f32", "degrees, above 0 and below 180"),
        ParamDesc::new("resolution", "u32", "8 to 512 (MAX_VOLUME_RESOLUTION)"),
    ];
    const NAME: &'static str = "ConeTrace";
    const STAGE: PassStage = PassStage::Render;
    const SLOTS: &'static [SlotDesc] = &[
        SlotDesc::read("albedo", SlotClass::SampledTexture(ALBEDO)),
        SlotDesc::read("normal", SlotClass::SampledTexture(NORMAL)),
        SlotDesc::read("position", SlotClass::SampledTexture(POSITION)),
        SlotDesc::write("occlusion", SlotClass::ColorAttachment(LIGHT)),
        SlotDesc::write("indirect", SlotClass::ColorAttachment(LIGHT)),
    ];
    fn problems(&self) -> Vec<String> {
        let mut out = Vec::new();
        if !(1..=MAX_CONES).contains(&self.cones) {
            out.push(format!(
                "cones must be from 1 to {MAX_CONES}, got {}",
                self.cones
            ));
        }
        let angle = |name: &str, v: f32, out: &mut Vec<String>| {
            if !(v > 0.0 && v < 180.0) {
                out.push(format!(
                    "{name} must be an angle in degrees above 0 and below 180, got {v}"
                ));
            }
        };
        angle("aperture", self.aperture, &mut out);
        angle("shadow_aperture", self.shadow_aperture, &mut out);
        if !(self.max_distance.is_finite() && self.max_distance > 0.0) {
            out.push(format!(
                "max_distance must be a positive number (world units), got {}",
                self.max_distance
            ));
        }
        if !(self.step_scale.is_finite() && self.step_scale >= 0.05 && self.step_scale <= 4.0) {
            out.push(format!(
                "step_scale must be from 0.05 to 4, got {}",
                self.step_scale
            ));
        }
        if !(8..=MAX_VOLUME_RESOLUTION).contains(&self.resolution) {
            out.push(format!(
                "resolution must be from 8 to {MAX_VOLUME_RESOLUTION}, got {}",
                self.resolution
            ));
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_valid_and_each_bad_knob_is_named() {
        assert!(ConeTraceParams::default().problems().is_empty());
        let bad = [
            (
                ConeTraceParams {
                    cones: 0,
                    ..Default::default()
                },
                "cones",
            ),
            (
                ConeTraceParams {
                    cones: 65,
                    ..Default::default()
                },
                "cones",
            ),
            (
                ConeTraceParams {
                    aperture: 0.0,
                    ..Default::default()
                },
                "aperture",
            ),
            (
                ConeTraceParams {
                    aperture: 180.0,
                    ..Default::default()
                },
                "aperture",
            ),
            (
                ConeTraceParams {
                    aperture: f32::NAN,
                    ..Default::default()
                },
                "aperture",
            ),
            (
                ConeTraceParams {
                    shadow_aperture: -1.0,
                    ..Default::default()
                },
                "shadow_aperture",
            ),
            (
                ConeTraceParams {
                    max_distance: -0.5,
                    ..Default::default()
                },
                "max_distance",
            ),
            (
                ConeTraceParams {
                    max_distance: 0.0,
                    ..Default::default()
                },
                "max_distance",
            ),
            (
                ConeTraceParams {
                    max_distance: f32::INFINITY,
                    ..Default::default()
                },
                "max_distance",
            ),
            (
                ConeTraceParams {
                    step_scale: 0.0,
                    ..Default::default()
                },
                "step_scale",
            ),
            (
                ConeTraceParams {
                    resolution: 4,
                    ..Default::default()
                },
                "resolution",
            ),
            (
                ConeTraceParams {
                    resolution: 513,
                    ..Default::default()
                },
                "resolution",
            ),
        ];
        for (p, name) in bad {
            let problems = p.problems();
            assert_eq!(problems.len(), 1, "{p:?}: {problems:?}");
            assert!(problems[0].starts_with(name), "{problems:?}");
        }
        let edge = ConeTraceParams {
            cones: MAX_CONES,
            aperture: 179.0,
            resolution: MAX_VOLUME_RESOLUTION,
            ..Default::default()
        };
        assert!(edge.problems().is_empty());
    }
}
