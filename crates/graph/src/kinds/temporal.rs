//! `Temporal`: temporal anti-aliasing. The renderer jitters every frame's projection by a
//! sub-pixel offset (Halton 2, 3) while a pipeline has this pass; the pass reprojects its
//! history into the current frame by the G-buffer's position, clamps it to the current
//! colour's 3 × 3 neighbourhood and blends the current frame in.

use serde::{Deserialize, Serialize};

use super::formats::{COLOR_OUT, POSITION};
use super::spec::{KindSpec, PassStage, SlotClass, SlotDesc};

/// Parameters of `Temporal`.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct TemporalParams {
    /// The least weight of the current frame: the history's weight is 1 - 1/(n + 1) for the
    /// n-th frame since a reset, and never above 1 - `blend`.
    #[serde(default = "default_blend")]
    pub blend: f32,
    /// Camera moves longer than this share of the distance to the look-at point (or any
    /// change of lens) reset the history: a cut, not motion.
    #[serde(default = "default_cut")]
    pub cut: f32,
}

fn default_blend() -> f32 {
    0.1
}

fn default_cut() -> f32 {
    0.25
}

impl Default for TemporalParams {
    fn default() -> Self {
        Self {
            blend: default_blend(),
            cut: default_cut(),
        }
    }
}

impl KindSpec for TemporalParams {
    const NAME: &'static str = "Temporal";
    const STAGE: PassStage = PassStage::Render;
    const SLOTS: &'static [SlotDesc] = &[
        SlotDesc::read("current", SlotClass::SampledTexture(COLOR_OUT)),
        SlotDesc::read("position", SlotClass::SampledTexture(POSITION)),
        SlotDesc::write("color", SlotClass::ColorAttachment(COLOR_OUT)),
    ];
    fn problems(&self) -> Vec<String> {
        let mut out = Vec::new();
        if !(self.blend > 0.0 && self.blend <= 1.0) {
            out.push(format!("blend must be in (0, 1], got {}", self.blend));
        }
        if !(self.cut.is_finite() && self.cut > 0.0) {
            out.push(format!("cut must be a number > 0, got {}", self.cut));
        }
        out
    }
}
