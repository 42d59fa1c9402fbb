//! `RayMarchFilter`: the compute pass that fills the SSBVB with the first voxel per pixel.

use serde::{Deserialize, Serialize};

use super::formats::ENTRY;
use super::shared::steps_problems;
use super::spec::{KindSpec, ParamDesc, PassStage, SlotClass, SlotDesc};
use crate::format::BufferLayout;

/// Parameters of `RayMarchFilter`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct RayMarchFilterParams {
    /// Most DDA steps per ray (cells, pages and empty blocks each count one).
    #[serde(default = "default_max_steps")]
    pub max_steps: u32,
    /// Append each hit voxel once per frame (the first pixel to reach it claims it)
    /// instead of once per covered pixel. Same image; far fewer billboards when voxels
    /// span many pixels (a level finer than the screen needs is then not required).
    /// Off by default: the paper's SSBVB holds one entry per covered pixel.
    #[serde(default)]
    pub unique_voxels: bool,
    /// How plane crossing times are computed (default `Exact`).
    #[serde(default)]
    pub march: MarchMode,
    /// Removed: the second proxy layer (an experiment, no faster than the walk by screen
    /// tiles; its code is at revision 8c208c3). Still read so that files writing
    /// `peel: false` load; `true` is refused.
    #[serde(default)]
    pub peel: bool,
}

/// The arithmetic of the filter's march (`RayMarchFilter(march: ...)`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize, Serialize)]
pub enum MarchMode {
    /// The CPU reference's rules in f32: every plane time by division, cells corrected
    /// against them, edge and corner ties resolved; bit-identical hits with the reference
    /// on the tested views.
    #[default]
    Exact,
    /// Reciprocal direction, accumulated plane times, uncorrected cell estimates, ties
    /// not resolved: fewer operations per step, a little accuracy lost
    /// (docs/benchmarks.md).
    Fast,
}

fn default_max_steps() -> u32 {
    1024
}

impl Default for RayMarchFilterParams {
    fn default() -> Self {
        Self {
            max_steps: default_max_steps(),
            unique_voxels: false,
            march: MarchMode::Exact,
            peel: false,
        }
    }
}

impl KindSpec for RayMarchFilterParams {
    const PARAMS: &'static [ParamDesc] = &[
        ParamDesc::new("max_steps", "u32", "at least 1"),
        ParamDesc::new("unique_voxels", "bool", "true or false"),
        ParamDesc::new("march", "Exact | Fast", "either"),
        ParamDesc::new("peel", "bool", "false (removed)"),
    ];
    const NAME: &'static str = "RayMarchFilter";
    const STAGE: PassStage = PassStage::Compute;
    const SLOTS: &'static [SlotDesc] = &[
        SlotDesc::read("entry", SlotClass::SampledTexture(ENTRY)),
        SlotDesc::write("ssbvb", SlotClass::StorageBuffer(BufferLayout::VoxelSlot)),
        SlotDesc::write(
            "billboard_draw",
            SlotClass::StorageBuffer(BufferLayout::DrawIndirect),
        ),
    ];
    /// `clear_draw` resets the indirect draw before `main` appends the hits to it.
    const ENTRY_POINTS: &'static [&'static str] = &["clear_draw", "main"];
    fn problems(&self) -> Vec<String> {
        let mut p = steps_problems(self.max_steps);
        if self.peel {
            p.push(
                "peel: true was removed (the second proxy layer, an experiment no faster \
                 than the walk by screen tiles; its code is at revision 8c208c3): leave \
                 peel out"
                    .into(),
            );
        }
        p
    }
}
