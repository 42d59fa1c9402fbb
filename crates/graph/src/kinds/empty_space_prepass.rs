//! `EmptySpacePrepass`: the proxy meshes' entry points, the ray march's starting points.

use super::formats::{DEPTH, ENTRY};
use super::spec::{KindSpec, PassStage, SlotClass, SlotDesc};

/// `EmptySpacePrepass` has no parameters.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct EmptySpacePrepassKind;

impl KindSpec for EmptySpacePrepassKind {
    const NAME: &'static str = "EmptySpacePrepass";
    const STAGE: PassStage = PassStage::Render;
    const SLOTS: &'static [SlotDesc] = &[
        SlotDesc::write("entry", SlotClass::ColorAttachment(ENTRY)),
        SlotDesc::write("prepass_depth", SlotClass::DepthStencilAttachment(DEPTH)),
    ];
}
