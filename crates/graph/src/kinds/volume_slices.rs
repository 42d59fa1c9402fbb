//! `VolumeSlices`, volumetric billboards: [`VolumeSlicesParams`], the slicing knobs and
//! their ranges. What a slice samples and how the volumes are cut is defined once, in
//! `ssbvb-voxel`'s `rgba_volume` module.

use serde::{Deserialize, Serialize};

use super::formats::{COLOR_OUT, DEPTH_STENCIL};
use super::spec::{KindSpec, ParamDesc, PassStage, SlotClass, SlotDesc};

/// The finest slice spacing accepted, in texels (thinner slices cost without changing the
/// image: the reference converges at a quarter texel).
pub const MIN_SLICE_SPACING: f32 = 0.05;
/// The coarsest slice spacing accepted, in texels.
pub const MAX_SLICE_SPACING: f32 = 8.0;
/// The largest mip bias accepted either way, in levels.
pub const MAX_MIP_BIAS: f32 = 10.0;

/// Parameters of `VolumeSlices`.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct VolumeSlicesParams {
    /// Distance between view-aligned slices, in texels of each volume's chosen level.
    #[serde(default = "default_spacing")]
    pub slice_spacing: f32,
    /// Levels added to the level chosen by distance (positive = coarser, cheaper;
    /// rounded to a whole level).
    #[serde(default)]
    pub mip_bias: f32,
}

fn default_spacing() -> f32 {
    0.5
}

impl Default for VolumeSlicesParams {
    fn default() -> Self {
        Self {
            slice_spacing: default_spacing(),
            mip_bias: 0.0,
        }
    }
}

impl KindSpec for VolumeSlicesParams {
    const PARAMS: &'static [ParamDesc] = &[
        ParamDesc::new("slice_spacing", "f32", "0.05 to 8 texels"),
        ParamDesc::new("mip_bias", "f32", "-10 to 10 levels"),
    ];
    const NAME: &'static str = "VolumeSlices";
    const STAGE: PassStage = PassStage::Render;
    const SLOTS: &'static [SlotDesc] = &[
        SlotDesc::read(
            "depth_stencil",
            SlotClass::DepthStencilAttachment(DEPTH_STENCIL),
        ),
        SlotDesc::write("color", SlotClass::ColorAttachment(COLOR_OUT)),
    ];
    fn problems(&self) -> Vec<String> {
        let mut out = Vec::new();
        if !(MIN_SLICE_SPACING..=MAX_SLICE_SPACING).contains(&self.slice_spacing) {
            out.push(format!(
                "slice_spacing must be from {MIN_SLICE_SPACING} to {MAX_SLICE_SPACING} texels, \
                 got {}",
                self.slice_spacing
            ));
        }
        if !(self.mip_bias.is_finite() && self.mip_bias.abs() <= MAX_MIP_BIAS) {
            out.push(format!(
                "mip_bias must be from -{MAX_MIP_BIAS} to {MAX_MIP_BIAS} levels, got {}",
                self.mip_bias
            ));
        }
        out
    }
}
