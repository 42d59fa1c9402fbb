//! `OctreeRayCast`: the baseline ray cast through the sparse voxel octree.

use serde::{Deserialize, Serialize};

use super::formats::GBUFFER_WRITES;
use super::shared::{default_ray_cast_steps, steps_problems};
use super::spec::{KindSpec, ParamDesc, PassStage, SlotDesc};

/// Parameters of `OctreeRayCast`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct OctreeRayCastParams {
    /// Most traversal steps (child visits, descents and pops) per ray and instance.
    #[serde(default = "default_ray_cast_steps")]
    pub max_steps: u32,
    /// Trace in a compute shader (one thread per pixel, the hits kept in a per-pixel
    /// buffer) and write the G-buffer in a fullscreen resolve, instead of tracing in the
    /// fragment shader: the same image, for GPUs whose fragment work is slow
    /// (docs/benchmarks.md, the H200).
    #[serde(default)]
    pub compute: bool,
}

impl Default for OctreeRayCastParams {
    fn default() -> Self {
        Self {
            max_steps: default_ray_cast_steps(),
            compute: false,
        }
    }
}

impl KindSpec for OctreeRayCastParams {
    const PARAMS: &'static [ParamDesc] = &[
        ParamDesc::new("max_steps", "u32", "at least 1"),
        ParamDesc::new("compute", "bool", "true or false"),
    ];
    const NAME: &'static str = "OctreeRayCast";
    const STAGE: PassStage = PassStage::Render;
    const SLOTS: &'static [SlotDesc] = GBUFFER_WRITES;
    fn problems(&self) -> Vec<String> {
        steps_problems(self.max_steps)
    }
}
