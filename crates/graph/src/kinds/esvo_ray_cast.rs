//! `EsvoRayCast`: Laine & Karras' ESVO traversal through the same sparse voxel octree as
//! `OctreeRayCast`.

use serde::{Deserialize, Serialize};

use super::formats::GBUFFER_WRITES;
use super::shared::{default_ray_cast_steps, steps_problems};
use super::spec::{KindSpec, ParamDesc, PassStage, SlotDesc};

/// Parameters of `EsvoRayCast`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct EsvoRayCastParams {
    /// Most traversal steps (loop iterations: a PUSH, an ADVANCE, or an ADVANCE with its
    /// POP) per ray and instance.
    #[serde(default = "default_ray_cast_steps")]
    pub max_steps: u32,
    /// Trace in a compute shader (one thread per pixel, the hits kept in a per-pixel
    /// buffer) and write the G-buffer in a fullscreen resolve, instead of tracing in the
    /// fragment shader: the same image, for GPUs whose fragment work is slow
    /// (docs/benchmarks.md, the H200).
    #[serde(default)]
    pub compute: bool,
}

impl Default for EsvoRayCastParams {
    fn default() -> Self {
        Self {
            max_steps: default_ray_cast_steps(),
            compute: false,
        }
    }
}

impl KindSpec for EsvoRayCastParams {
    const PARAMS: &'static [ParamDesc] = &[
        ParamDesc::new("max_steps", "u32", "at least 1"),
        ParamDesc::new("compute", "bool", "true or false"),
    ];
    const NAME: &'static str = "EsvoRayCast";
    const STAGE: PassStage = PassStage::Render;
    const SLOTS: &'static [SlotDesc] = GBUFFER_WRITES;
    fn problems(&self) -> Vec<String> {
        steps_problems(self.max_steps)
    }
}
