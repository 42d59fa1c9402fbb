//! `EmptySpaceCompute`: the empty-space prepass as a compute pass, for adapters whose raster
//! units are slow (the same `entry` as `EmptySpacePrepass`, no depth attachment).

use super::formats::ENTRY;
use super::spec::{KindSpec, PassStage, SlotClass, SlotDesc};

/// `EmptySpaceCompute` has no parameters.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct EmptySpaceComputeKind;

impl KindSpec for EmptySpaceComputeKind {
    const NAME: &'static str = "EmptySpaceCompute";
    const STAGE: PassStage = PassStage::Compute;
    const SLOTS: &'static [SlotDesc] =
        &[SlotDesc::write("entry", SlotClass::StorageTexture(ENTRY))];
    /// The software rasterizer's steps (`shaders/empty_space_compute.wgsl`).
    const ENTRY_POINTS: &'static [&'static str] = &["raster", "large_args", "large", "resolve"];
}
