//! `RayMarchGBuffer`: the filter's march with each pixel's hit written straight into the
//! G-buffer (no SSBVB, no billboard).

use serde::{Deserialize, Serialize};

use super::formats::{ENTRY, GBUFFER_WRITES};
use super::ray_march_filter::MarchMode;
use super::shared::steps_problems;
use super::spec::{KindSpec, ParamDesc, PassStage, SlotClass, SlotDesc};

/// Parameters of `RayMarchGBuffer`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct RayMarchGBufferParams {
    /// Most DDA steps per ray and instance, as `RayMarchFilter`'s.
    #[serde(default = "default_max_steps")]
    pub max_steps: u32,
    /// How plane crossing times are computed, as `RayMarchFilter`'s (default `Exact`).
    #[serde(default)]
    pub march: MarchMode,
}

fn default_max_steps() -> u32 {
    1024
}

impl Default for RayMarchGBufferParams {
    fn default() -> Self {
        Self {
            max_steps: default_max_steps(),
            march: MarchMode::Exact,
        }
    }
}

impl KindSpec for RayMarchGBufferParams {
    const PARAMS: &'static [ParamDesc] = &[
        ParamDesc::new("max_steps", "u32", "at least 1"),
        ParamDesc::new("march", "Exact | Fast", "either"),
    ];
    const NAME: &'static str = "RayMarchGBuffer";
    const STAGE: PassStage = PassStage::Render;
    const SLOTS: &'static [SlotDesc] = &[
        SlotDesc::read("entry", SlotClass::SampledTexture(ENTRY)),
        GBUFFER_WRITES[0],
        GBUFFER_WRITES[1],
        GBUFFER_WRITES[2],
        GBUFFER_WRITES[3],
        GBUFFER_WRITES[4],
    ];
    fn problems(&self) -> Vec<String> {
        steps_problems(self.max_steps)
    }
}
