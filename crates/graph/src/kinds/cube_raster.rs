//! `CubeRaster`: the baseline that rasterizes one cube per voxel or full octree node.

use serde::{Deserialize, Serialize};

use super::formats::GBUFFER_WRITES;
use super::spec::{KindSpec, ParamDesc, PassStage, SlotDesc};

/// Parameters of `CubeRaster`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct CubeRasterParams {
    /// Merge every completely full octree node into one cube of its size.
    #[serde(default = "yes")]
    pub merge_full_nodes: bool,
}

fn yes() -> bool {
    true
}

impl Default for CubeRasterParams {
    fn default() -> Self {
        Self {
            merge_full_nodes: yes(),
        }
    }
}

impl KindSpec for CubeRasterParams {
    const PARAMS: &'static [ParamDesc] =
        &[ParamDesc::new("merge_full_nodes", "bool", "true or false")];
    const NAME: &'static str = "CubeRaster";
    const STAGE: PassStage = PassStage::Render;
    const SLOTS: &'static [SlotDesc] = GBUFFER_WRITES;
}
