//! `SplatBillboards`: the billboards splatted in compute, with `Billboards`' parameters.

use std::ops::Deref;

use serde::{Deserialize, Serialize};

use super::billboards::{BillboardsParams, billboard_slots};
use super::spec::{KindSpec, ParamDesc, PassStage, SlotClass, SlotDesc};
use crate::format::BufferLayout;

/// Parameters of `SplatBillboards`: those of `Billboards`, read and written the same way
/// (`#[serde(transparent)]`: RON `SplatBillboards(mode: RayBox, size_scale: 1.5)`). A
/// newtype rather than the same type so that it implements [`KindSpec`] as its own kind;
/// it derefs to the shared parameters (`params.mode`).
#[derive(Debug, Clone, Copy, PartialEq, Default, Deserialize, Serialize)]
#[serde(transparent)]
pub struct SplatBillboardsParams(pub BillboardsParams);

impl Deref for SplatBillboardsParams {
    type Target = BillboardsParams;

    fn deref(&self) -> &BillboardsParams {
        &self.0
    }
}

impl KindSpec for SplatBillboardsParams {
    const PARAMS: &'static [ParamDesc] = &[
        ParamDesc::new("mode", "Flat | RayBox | Pixel", "any"),
        ParamDesc::new("size_scale", "f32", "a positive number"),
    ];
    const NAME: &'static str = "SplatBillboards";
    const STAGE: PassStage = PassStage::Render;
    // The draw list is read by the splat (the entry count), not used as an indirect draw.
    const SLOTS: &'static [SlotDesc] =
        &billboard_slots(SlotClass::StorageBuffer(BufferLayout::DrawIndirect));
    fn problems(&self) -> Vec<String> {
        self.0.shared_problems()
    }
}
