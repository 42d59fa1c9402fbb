//! What the kinds' texture slots accept, named once: the formats of each attachment and
//! texture that several kinds share, and the G-buffer every geometry pass writes.

use super::spec::{SlotClass, SlotDesc};
use crate::format::Format;

pub(crate) const DEPTH_STENCIL: &[Format] =
    &[Format::Depth32FloatStencil8, Format::Depth24PlusStencil8];
pub(crate) const DEPTH: &[Format] = &[Format::Depth32Float];
/// Linear RGBA8 albedo packed in a `u32` (`pack4x8unorm`): WebGPU counts an `Rgba8Unorm`
/// attachment as 8 bytes per sample, an `R32Uint` as 4, and the G-buffer's colour
/// attachments must fit 32 bytes.
pub(crate) const ALBEDO: &[Format] = &[Format::R32Uint];
pub(crate) const NORMAL: &[Format] = &[Format::Rgba16Float, Format::Rgba32Float];
pub(crate) const POSITION: &[Format] = &[Format::Rgba32Float];
/// The G-buffer's shading normal: 8 bytes, so that the four colour attachments fit
/// WebGPU's 32 bytes per sample (4 + 8 + 16 + 4, albedo packed in a `u32`).
pub(crate) const GBUFFER_NORMAL: &[Format] = &[Format::Rgba16Float];
/// The G-buffer's geometric normal, octahedral-encoded (see `ssbvb_passes::kinds::gbuffer`).
pub(crate) const GEOMETRIC_NORMAL: &[Format] = &[Format::Rg16Float];
pub(crate) const ENTRY: &[Format] = &[Format::Rgba32Float];
pub(crate) const COLOR_OUT: &[Format] = &[
    Format::Rgba8UnormSrgb,
    Format::Bgra8UnormSrgb,
    Format::Rgba8Unorm,
    Format::Bgra8Unorm,
    Format::Rgba16Float,
];
/// The cone tracer's targets: `occlusion` (r: AO, g: shadow) and `indirect` (rgb).
pub const LIGHT: &[Format] = &[Format::Rgba16Float];

/// The G-buffer every geometry pass writes (`ssbvb_passes::kinds::gbuffer` documents each slot).
pub(crate) const GBUFFER_WRITES: &[SlotDesc] = &[
    SlotDesc::write("gbuffer_albedo", SlotClass::ColorAttachment(ALBEDO)),
    SlotDesc::write("gbuffer_normal", SlotClass::ColorAttachment(GBUFFER_NORMAL)),
    SlotDesc::write("gbuffer_position", SlotClass::ColorAttachment(POSITION)),
    SlotDesc::write(
        "gbuffer_geometric_normal",
        SlotClass::ColorAttachment(GEOMETRIC_NORMAL),
    ),
    SlotDesc::write(
        "depth_stencil",
        SlotClass::DepthStencilAttachment(DEPTH_STENCIL),
    ),
];
