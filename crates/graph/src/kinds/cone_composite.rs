//! `ConeComposite`: deferred lighting like `Composite`, with voxel cone tracing's
//! occlusion, shadow and bounce.

use super::formats::{ALBEDO, COLOR_OUT, LIGHT, NORMAL, POSITION};
use super::spec::{KindSpec, PassStage, SlotClass, SlotDesc};

/// `ConeComposite` has no parameters.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct ConeCompositeKind;

impl KindSpec for ConeCompositeKind {
    const NAME: &'static str = "ConeComposite";
    const STAGE: PassStage = PassStage::Render;
    const SLOTS: &'static [SlotDesc] = &[
        SlotDesc::read("albedo", SlotClass::SampledTexture(ALBEDO)),
        SlotDesc::read("normal", SlotClass::SampledTexture(NORMAL)),
        SlotDesc::read("position", SlotClass::SampledTexture(POSITION)),
        SlotDesc::read("occlusion", SlotClass::SampledTexture(LIGHT)),
        SlotDesc::read("indirect", SlotClass::SampledTexture(LIGHT)),
        SlotDesc::write("color", SlotClass::ColorAttachment(COLOR_OUT)),
    ];
}
