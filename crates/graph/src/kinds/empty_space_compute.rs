//! `EmptySpaceCompute`: the empty-space prepass as a compute pass, for adapters whose raster
//! units are slow (the same `entry` as `EmptySpacePrepass`, no depth attachment).

use serde::{Deserialize, Serialize};

use super::formats::ENTRY;
use super::spec::{KindSpec, ParamDesc, PassStage, SlotClass, SlotDesc};

/// Parameters of `EmptySpaceCompute`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct EmptySpaceComputeParams {
    /// Texels of a triangle's rectangle above which the triangle gets a workgroup of its
    /// own instead of one thread; by default chosen per adapter class (a CPU adapter runs
    /// best with almost none, a GPU's threads should not walk thousands of texels).
    #[serde(default)]
    pub large_pixels: Option<u32>,
}

impl KindSpec for EmptySpaceComputeParams {
    const PARAMS: &'static [ParamDesc] = &[ParamDesc::new(
        "large_pixels",
        "Option<u32>",
        "None (4096 on CPU adapters, 256 elsewhere) or at least 1",
    )];
    const NAME: &'static str = "EmptySpaceCompute";
    const STAGE: PassStage = PassStage::Compute;
    const SLOTS: &'static [SlotDesc] =
        &[SlotDesc::write("entry", SlotClass::StorageTexture(ENTRY))];
    /// The software rasterizer's steps (`shaders/empty_space_compute.wgsl`).
    const ENTRY_POINTS: &'static [&'static str] = &["raster", "large_args", "large", "resolve"];
    fn problems(&self) -> Vec<String> {
        match self.large_pixels {
            Some(0) => vec!["large_pixels must be at least 1".into()],
            _ => Vec::new(),
        }
    }
}
