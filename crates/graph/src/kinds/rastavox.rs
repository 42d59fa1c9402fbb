//! `RastaVox`: per visible chunk, the surface voxels of a coarse enough LOD as faces.

use serde::{Deserialize, Serialize};

use super::formats::GBUFFER_WRITES;
use super::shared::one;
use super::spec::{KindSpec, ParamDesc, PassStage, SlotDesc};

/// Parameters of `RastaVox`.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct RastaVoxParams {
    /// The largest projected voxel, in pixels, a chunk's LOD may have (0 = always the
    /// finest; the paper's 1 "with no visible difference").
    #[serde(default = "one")]
    pub pixel_error: f32,
}

/// The largest accepted `pixel_error`: beyond it every chunk is one voxel anyway.
pub const MAX_PIXEL_ERROR: f32 = 4096.0;

impl Default for RastaVoxParams {
    fn default() -> Self {
        Self { pixel_error: one() }
    }
}

impl KindSpec for RastaVoxParams {
    const PARAMS: &'static [ParamDesc] = &[ParamDesc::new(
        "pixel_error",
        "f32",
        "0 to 4096 (MAX_PIXEL_ERROR)",
    )];
    const NAME: &'static str = "RastaVox";
    const STAGE: PassStage = PassStage::Render;
    const SLOTS: &'static [SlotDesc] = GBUFFER_WRITES;
    fn problems(&self) -> Vec<String> {
        if (0.0..=MAX_PIXEL_ERROR).contains(&self.pixel_error) {
            Vec::new()
        } else {
            vec![format!(
                "pixel_error must be a number from 0 to {MAX_PIXEL_ERROR}, got {}",
                self.pixel_error
            )]
        }
    }
}
