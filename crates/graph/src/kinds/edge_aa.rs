//! `EdgeAa`: single-frame anti-aliasing for stills, an FXAA-style post-process of the
//! output colour: where the local contrast is high, it finds the edge's direction and
//! extent from the neighbouring texels and blends each edge pixel with its neighbour
//! across the edge by the share of the pixel the edge line would cover.

use serde::{Deserialize, Serialize};

use super::formats::COLOR_OUT;
use super::spec::{KindSpec, ParamDesc, PassStage, SlotClass, SlotDesc};

/// Parameters of `EdgeAa`.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct EdgeAaParams {
    /// Relative contrast (of the 3 × 3 neighbourhood's brightest luma) below which a pixel
    /// is left alone.
    #[serde(default = "default_threshold")]
    pub threshold: f32,
    /// How much of the sub-pixel blend (a pixel unlike all its neighbours) is applied, 0
    /// to 1.
    #[serde(default = "default_subpixel")]
    pub subpixel: f32,
}

fn default_threshold() -> f32 {
    0.125
}

fn default_subpixel() -> f32 {
    0.75
}

impl Default for EdgeAaParams {
    fn default() -> Self {
        Self {
            threshold: default_threshold(),
            subpixel: default_subpixel(),
        }
    }
}

impl KindSpec for EdgeAaParams {
    const PARAMS: &'static [ParamDesc] = &[
        ParamDesc::new("threshold", "f32", "above 0, at most 1"),
        ParamDesc::new("subpixel", "f32", "0 to 1"),
    ];
    const NAME: &'static str = "EdgeAa";
    const STAGE: PassStage = PassStage::Render;
    const SLOTS: &'static [SlotDesc] = &[
        SlotDesc::read("current", SlotClass::SampledTexture(COLOR_OUT)),
        SlotDesc::write("color", SlotClass::ColorAttachment(COLOR_OUT)),
    ];
    fn problems(&self) -> Vec<String> {
        let mut out = Vec::new();
        if !(self.threshold > 0.0 && self.threshold <= 1.0) {
            out.push(format!(
                "threshold must be in (0, 1], got {}",
                self.threshold
            ));
        }
        if !(0.0..=1.0).contains(&self.subpixel) {
            out.push(format!("subpixel must be in [0, 1], got {}", self.subpixel));
        }
        out
    }
}
