//! `Smooth`: the distance-dependent Gaussian over the voxel pixels' normals.

use serde::{Deserialize, Serialize};

use super::formats::{DEPTH_STENCIL, GBUFFER_NORMAL, NORMAL};
use super::shared::one;
use super::spec::{KindSpec, ParamDesc, PassStage, SlotClass, SlotDesc};

/// Parameters of `Smooth`.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SmoothParams {
    /// MaxI: the largest sample offset in pixels.
    #[serde(default = "one")]
    pub max_i: f32,
    /// MinDist: the distance (world units) at and below which the offset is MaxI.
    #[serde(default = "default_min_dist")]
    pub min_dist: f32,
    /// Copy the depth into a texture of the pass's own before smoothing, rather than
    /// sample the depth-stencil it stencil-tests against. Devices that cannot do the latter
    /// (GL, WebGL: no read-only depth-stencil attachments) always copy; `true` makes any
    /// device do it (the same image, one pass more).
    #[serde(default)]
    pub copy_depth: bool,
}

fn default_min_dist() -> f32 {
    0.5
}

impl Default for SmoothParams {
    fn default() -> Self {
        Self {
            max_i: one(),
            min_dist: default_min_dist(),
            copy_depth: false,
        }
    }
}

impl KindSpec for SmoothParams {
    const PARAMS: &'static [ParamDesc] = &[
        ParamDesc::new("max_i", "f32", "at least 0"),
        ParamDesc::new("min_dist", "f32", "at least 0"),
        ParamDesc::new("copy_depth", "bool", "true or false"),
    ];
    const NAME: &'static str = "Smooth";
    const STAGE: PassStage = PassStage::Render;
    const SLOTS: &'static [SlotDesc] = &[
        SlotDesc::read("gbuffer_normal", SlotClass::SampledTexture(NORMAL)),
        SlotDesc::read(
            "depth_stencil",
            SlotClass::DepthStencilAttachment(DEPTH_STENCIL),
        ),
        SlotDesc::write("smoothed_normal", SlotClass::ColorAttachment(NORMAL)),
    ];
    fn problems(&self) -> Vec<String> {
        eq1_problems(self.max_i, self.min_dist)
    }
}

/// Problems with Eq. 1's parameters (both smoothing kinds take them).
fn eq1_problems(max_i: f32, min_dist: f32) -> Vec<String> {
    let mut out = Vec::new();
    if !(max_i.is_finite() && max_i >= 0.0) {
        out.push(format!("max_i must be a number >= 0, got {max_i}"));
    }
    if !(min_dist.is_finite() && min_dist >= 0.0) {
        out.push(format!("min_dist must be a number >= 0, got {min_dist}"));
    }
    out
}

/// Parameters of `SmoothCompute`: `Smooth`'s, for the compute form (which samples the
/// depth and reads the stencil as textures, so it has no depth copy to ask for).
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SmoothComputeParams {
    /// MaxI: the largest sample offset in pixels.
    #[serde(default = "one")]
    pub max_i: f32,
    /// MinDist: the distance (world units) at and below which the offset is MaxI.
    #[serde(default = "default_min_dist")]
    pub min_dist: f32,
}

impl Default for SmoothComputeParams {
    fn default() -> Self {
        Self {
            max_i: one(),
            min_dist: default_min_dist(),
        }
    }
}

impl KindSpec for SmoothComputeParams {
    const PARAMS: &'static [ParamDesc] = &[
        ParamDesc::new("max_i", "f32", "at least 0"),
        ParamDesc::new("min_dist", "f32", "at least 0"),
    ];
    const NAME: &'static str = "SmoothCompute";
    const STAGE: PassStage = PassStage::Compute;
    const SLOTS: &'static [SlotDesc] = &[
        SlotDesc::read("gbuffer_normal", SlotClass::SampledTexture(NORMAL)),
        SlotDesc::read("depth_stencil", SlotClass::SampledTexture(DEPTH_STENCIL)),
        // Written as a storage texture: the G-buffer's 8-byte normal.
        SlotDesc::write("smoothed_normal", SlotClass::StorageTexture(GBUFFER_NORMAL)),
    ];
    fn problems(&self) -> Vec<String> {
        eq1_problems(self.max_i, self.min_dist)
    }
}
