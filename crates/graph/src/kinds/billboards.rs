//! `Billboards`: one rasterized quad per SSBVB entry, and the parameters `SplatBillboards`
//! shares.

use serde::{Deserialize, Serialize};

use super::formats::GBUFFER_WRITES;
use super::shared::one;
use super::spec::{KindSpec, ParamDesc, PassStage, SlotClass, SlotDesc};
use crate::format::BufferLayout;

/// How billboards are shaded.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize, Serialize)]
pub enum BillboardMode {
    /// A flat quad at the voxel centre's depth (the paper).
    #[default]
    Flat,
    /// Per fragment, the exact ray–voxel-box intersection (depth and face normal).
    RayBox,
    /// No quad: each entry writes only the pixel whose ray found it, with that ray's hit
    /// (its distance and entered face), as the ray casters' resolve does. Exact, and the
    /// cheapest where voxels are about a pixel or smaller. `SplatBillboards` only, and the
    /// filter writing its SSBVB must append every pixel (`unique_voxels: false`) at the
    /// screen's resolution.
    Pixel,
}

/// Parameters of `Billboards`, and of `SplatBillboards` through
/// [`SplatBillboardsParams`](crate::SplatBillboardsParams).
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct BillboardsParams {
    /// Flat camera-facing quads (the paper) or quads whose fragments intersect the voxel
    /// box exactly (ray–box splatting).
    #[serde(default)]
    pub mode: BillboardMode,
    /// Scale of the quad relative to the voxel's projected footprint.
    #[serde(default = "one")]
    pub size_scale: f32,
}

impl Default for BillboardsParams {
    fn default() -> Self {
        Self {
            mode: BillboardMode::Flat,
            size_scale: one(),
        }
    }
}

/// The slots of `Billboards` and `SplatBillboards`: the SSBVB, the billboard draw list read
/// as `draw` (an indirect draw, or a storage buffer), and the G-buffer written.
pub(crate) const fn billboard_slots(draw: SlotClass) -> [SlotDesc; 7] {
    [
        SlotDesc::read("ssbvb", SlotClass::StorageBuffer(BufferLayout::VoxelSlot)),
        SlotDesc::read("billboard_draw", draw),
        GBUFFER_WRITES[0],
        GBUFFER_WRITES[1],
        GBUFFER_WRITES[2],
        GBUFFER_WRITES[3],
        GBUFFER_WRITES[4],
    ]
}

impl KindSpec for BillboardsParams {
    const PARAMS: &'static [ParamDesc] = &[
        ParamDesc::new(
            "mode",
            "Flat | RayBox | Pixel",
            "Flat or RayBox (Pixel is SplatBillboards')",
        ),
        ParamDesc::new("size_scale", "f32", "a positive number"),
    ];
    const NAME: &'static str = "Billboards";
    const STAGE: PassStage = PassStage::Render;
    const SLOTS: &'static [SlotDesc] =
        &billboard_slots(SlotClass::IndirectBuffer(BufferLayout::DrawIndirect));
    fn problems(&self) -> Vec<String> {
        let mut p = self.shared_problems();
        if self.mode == BillboardMode::Pixel {
            p.push(
                "mode: Pixel writes each entry at its own pixel in compute; it is \
                 `SplatBillboards`' (rasterized billboards take Flat or RayBox)"
                    .into(),
            );
        }
        p
    }
}

impl BillboardsParams {
    /// The problems of the parameters both billboard kinds share.
    pub(crate) fn shared_problems(&self) -> Vec<String> {
        if self.size_scale.is_finite() && self.size_scale > 0.0 {
            Vec::new()
        } else {
            vec![format!(
                "size_scale must be a positive number, got {}",
                self.size_scale
            )]
        }
    }
}
