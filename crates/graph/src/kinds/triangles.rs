//! `Triangles`: ordinary triangle meshes into the G-buffer.

use super::formats::GBUFFER_WRITES;
use super::spec::{KindSpec, PassStage, SlotDesc};

/// `Triangles` has no parameters.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct TrianglesKind;

impl KindSpec for TrianglesKind {
    const NAME: &'static str = "Triangles";
    const STAGE: PassStage = PassStage::Render;
    const SLOTS: &'static [SlotDesc] = GBUFFER_WRITES;
}
