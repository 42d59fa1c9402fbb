//! `DenseDda`: the baseline DDA over a dense 3D texture per visible object.

use serde::{Deserialize, Serialize};

use super::formats::GBUFFER_WRITES;
use super::shared::{default_ray_cast_steps, steps_problems};
use super::spec::{KindSpec, ParamDesc, PassStage, SlotDesc};

/// Parameters of `DenseDda`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct DenseDdaParams {
    /// Most DDA steps (cells) per ray and instance.
    #[serde(default = "default_ray_cast_steps")]
    pub max_steps: u32,
}

impl Default for DenseDdaParams {
    fn default() -> Self {
        Self {
            max_steps: default_ray_cast_steps(),
        }
    }
}

impl KindSpec for DenseDdaParams {
    const PARAMS: &'static [ParamDesc] = &[ParamDesc::new("max_steps", "u32", "at least 1")];
    const NAME: &'static str = "DenseDda";
    const STAGE: PassStage = PassStage::Render;
    const SLOTS: &'static [SlotDesc] = GBUFFER_WRITES;
    fn problems(&self) -> Vec<String> {
        steps_problems(self.max_steps)
    }
}
