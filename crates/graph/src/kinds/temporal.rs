//! `Temporal`: temporal anti-aliasing. The renderer jitters every frame's projection by a
//! sub-pixel offset (Halton 2, 3) while a pipeline has this pass; the pass reprojects its
//! history into the current frame by the G-buffer's position, clamps it to the current
//! colour's 3 × 3 neighbourhood (in motion: its variance clip, or the 4 × 4 block's bounds
//! where it moved less than a pixel) and blends the current frame in, with a larger share
//! where the history moved.

use serde::{Deserialize, Serialize};

use super::formats::{COLOR_OUT, POSITION};
use super::spec::{KindSpec, ParamDesc, PassStage, SlotClass, SlotDesc};

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
    /// The current frame's least weight where the history moved by a pixel or more since
    /// the frame before (between no motion and a pixel: from `blend` in proportion). A
    /// moving history is resampled every frame, and its blur accumulates; the current
    /// frame's larger share bounds it.
    #[serde(default = "default_motion_blend")]
    pub motion_blend: f32,
    /// Reproject each pixel with the motion of the nearest surface in its 3 x 3
    /// neighbourhood, so that a silhouette's soft edge moves with the object instead of
    /// leaving a ghost on the background (`false`: each pixel's own surface).
    #[serde(default = "default_true")]
    pub dilate: bool,
    /// In motion, blend the current frame resampled to the pixel centre (undoing its
    /// jitter) rather than as drawn: a jittered frame is the image shifted by up to half a
    /// pixel, and in motion its share of the output is large.
    #[serde(default = "default_true")]
    pub unjitter: bool,
    /// Levels finer than Auto LOD would draw each instance at while this pass runs (0 to
    /// [`MAX_LOD_BIAS`]): the jittered frames resolve detail below a pixel, as a texture's
    /// mip bias does under temporal anti-aliasing, and a pop between finer levels moves
    /// less of the image. Instances at a fixed level keep it.
    #[serde(default)]
    pub lod_bias: u32,
    /// Where the history moved by a pixel or more, its bounds (and those of the current
    /// frame's resample to the pixel centre) are the current colour's 3 x 3 neighbourhood
    /// narrowed to this many standard deviations about its mean, per luminance, chroma and
    /// coverage channel (a variance clamp; between no motion and a pixel the bounds widen
    /// in proportion to the 4 x 4 block's). Pipelines that leave it out get 0.75, the
    /// bundled files' value. Above 0, at most
    /// [`MAX_VARIANCE_CLIP`]: nine samples lie within √8 standard deviations of their mean,
    /// so 3 leaves the neighbourhood's min–max bounds as they are.
    #[serde(default = "default_variance_clip")]
    pub variance_clip: f32,
}

/// The largest [`TemporalParams::lod_bias`]: each level has 4× the voxels of the one before.
pub const MAX_LOD_BIAS: u32 = 3;

/// The largest [`TemporalParams::variance_clip`]: the min–max bounds, unnarrowed.
pub const MAX_VARIANCE_CLIP: f32 = 3.0;

fn default_variance_clip() -> f32 {
    0.75
}

fn default_true() -> bool {
    true
}

fn default_blend() -> f32 {
    0.1
}

fn default_cut() -> f32 {
    0.25
}

fn default_motion_blend() -> f32 {
    0.5
}

impl Default for TemporalParams {
    fn default() -> Self {
        Self {
            blend: default_blend(),
            cut: default_cut(),
            motion_blend: default_motion_blend(),
            dilate: true,
            unjitter: true,
            lod_bias: 0,
            variance_clip: default_variance_clip(),
        }
    }
}

impl KindSpec for TemporalParams {
    const PARAMS: &'static [ParamDesc] = &[
        ParamDesc::new("blend", "f32", "above 0, at most 1"),
        ParamDesc::new("cut", "f32", "a positive number"),
        ParamDesc::new("motion_blend", "f32", "blend to 1"),
        ParamDesc::new("dilate", "bool", "true or false"),
        ParamDesc::new("unjitter", "bool", "true or false"),
        ParamDesc::new("lod_bias", "u32", "0 to 3 (MAX_LOD_BIAS)"),
        ParamDesc::new(
            "variance_clip",
            "f32",
            "above 0, at most 3 (MAX_VARIANCE_CLIP)",
        ),
    ];
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
        if !(self.motion_blend >= self.blend && self.motion_blend <= 1.0) {
            out.push(format!(
                "motion_blend must be in [blend, 1] = [{}, 1], got {}",
                self.blend, self.motion_blend
            ));
        }
        if !(self.cut.is_finite() && self.cut > 0.0) {
            out.push(format!("cut must be a number > 0, got {}", self.cut));
        }
        if self.lod_bias > MAX_LOD_BIAS {
            out.push(format!(
                "lod_bias must be in [0, {MAX_LOD_BIAS}], got {}",
                self.lod_bias
            ));
        }
        if !(self.variance_clip > 0.0 && self.variance_clip <= MAX_VARIANCE_CLIP) {
            out.push(format!(
                "variance_clip must be in (0, {MAX_VARIANCE_CLIP}], got {}",
                self.variance_clip
            ));
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn params(blend: f32, cut: f32, motion_blend: f32) -> TemporalParams {
        TemporalParams {
            blend,
            cut,
            motion_blend,
            ..Default::default()
        }
    }

    #[test]
    fn the_defaults_are_valid_and_each_bad_value_is_named() {
        assert!(TemporalParams::default().problems().is_empty());
        assert!(
            params(0.1, 0.25, 0.1).problems().is_empty(),
            "motion_blend = blend"
        );
        assert!(params(0.1, 0.25, 1.0).problems().is_empty());
        let one = |p: TemporalParams, what: &str| {
            let problems = p.problems();
            assert_eq!(problems.len(), 1, "{problems:?}");
            assert!(problems[0].starts_with(what), "{problems:?}");
        };
        one(params(0.0, 0.25, 0.5), "blend must be in (0, 1]");
        one(params(0.1, 0.0, 0.5), "cut must be");
        one(params(0.1, f32::INFINITY, 0.5), "cut must be");
        one(
            params(0.3, 0.25, 0.2),
            "motion_blend must be in [blend, 1] = [0.3, 1], got 0.2",
        );
        one(params(0.1, 0.25, 1.5), "motion_blend must be");
        one(params(0.1, 0.25, f32::NAN), "motion_blend must be");
        one(
            TemporalParams {
                lod_bias: 4,
                ..Default::default()
            },
            "lod_bias must be in [0, 3], got 4",
        );
        for bad in [0.0, -1.0, 3.5, f32::NAN] {
            one(
                TemporalParams {
                    variance_clip: bad,
                    ..Default::default()
                },
                "variance_clip must be in (0, 3], got",
            );
        }
        let three = TemporalParams {
            lod_bias: 3,
            ..Default::default()
        };
        assert!(three.problems().is_empty());
        // Read from RON without it: the default.
        let p: TemporalParams = ron::from_str("(blend: 0.2, cut: 0.5)").unwrap();
        assert_eq!(p.motion_blend, 0.5);
        assert!(p.dilate && p.unjitter);
        assert_eq!(p.lod_bias, 0);
        assert_eq!(p.variance_clip, 0.75);
    }
}
