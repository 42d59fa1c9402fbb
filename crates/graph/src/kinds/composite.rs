//! `Composite`: deferred lighting of the G-buffer into the output colour.

use super::formats::{ALBEDO, COLOR_OUT, NORMAL, POSITION};
use super::spec::{KindSpec, PassStage, SlotClass, SlotDesc};
use crate::format::Format;

/// `Composite` has no parameters.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct CompositeKind;

impl KindSpec for CompositeKind {
    const NAME: &'static str = "Composite";
    const STAGE: PassStage = PassStage::Render;
    const SLOTS: &'static [SlotDesc] = &[
        SlotDesc::read("albedo", SlotClass::SampledTexture(ALBEDO)),
        SlotDesc::read("normal", SlotClass::SampledTexture(NORMAL)),
        SlotDesc::read("position", SlotClass::SampledTexture(POSITION)),
        SlotDesc::write("color", SlotClass::ColorAttachment(COLOR_OUT)),
    ];
}

/// `CompositeCompute` has no parameters.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct CompositeComputeKind;

impl KindSpec for CompositeComputeKind {
    const NAME: &'static str = "CompositeCompute";
    const STAGE: PassStage = PassStage::Compute;
    const SLOTS: &'static [SlotDesc] = &[
        SlotDesc::read("albedo", SlotClass::SampledTexture(ALBEDO)),
        SlotDesc::read("normal", SlotClass::SampledTexture(NORMAL)),
        SlotDesc::read("position", SlotClass::SampledTexture(POSITION)),
        // sRGB formats cannot be storage textures: the shader encodes.
        SlotDesc::write("color", SlotClass::StorageTexture(&[Format::Rgba8Unorm])),
    ];
}
