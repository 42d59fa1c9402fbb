//! The data types a pipeline and the pass kinds both name: texture [`Format`]s and buffer
//! element [`BufferLayout`]s. They depend on nothing else in the crate, so the kinds (which
//! list the formats their slots accept) and the pipeline file (which declares resources of
//! these formats and holds the kinds) both build on them without importing each other.

use serde::{Deserialize, Serialize};

/// Element layouts of buffer resources; WGSL declares the matching structs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Deserialize, Serialize)]
pub enum BufferLayout {
    /// One SSBVB slot: a copied point-cloud entry plus where it came from (32 bytes).
    VoxelSlot,
    /// Indirect draw arguments (`vertex_count, instance_count, first_vertex,
    /// first_instance`, 16 bytes).
    DrawIndirect,
    /// Indirect dispatch arguments (`x, y, z`, 12 bytes).
    DispatchIndirect,
    /// Plain `u32`s.
    U32,
    /// `vec4<f32>`s.
    Vec4F32,
}

impl BufferLayout {
    /// Bytes per element.
    pub fn element_size(self) -> u64 {
        match self {
            BufferLayout::VoxelSlot => 32,
            BufferLayout::DrawIndirect => 16,
            BufferLayout::DispatchIndirect => 12,
            BufferLayout::U32 => 4,
            BufferLayout::Vec4F32 => 16,
        }
    }
}

/// Texture formats a pipeline file may name (a subset of wgpu's, spelled like wgpu's).
#[allow(missing_docs)]
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Deserialize, Serialize)]
pub enum Format {
    R32Uint,
    R32Sint,
    R32Float,
    Rg32Float,
    Rg16Float,
    Rgba8Unorm,
    Rgba8UnormSrgb,
    Bgra8Unorm,
    Bgra8UnormSrgb,
    Rgba16Float,
    Rgba32Float,
    Rgba32Uint,
    Depth32Float,
    Depth24PlusStencil8,
    Depth32FloatStencil8,
}

impl Format {
    /// The wgpu format.
    pub fn to_wgpu(self) -> wgpu_types::TextureFormat {
        use wgpu_types::TextureFormat as T;
        match self {
            Format::R32Uint => T::R32Uint,
            Format::R32Sint => T::R32Sint,
            Format::R32Float => T::R32Float,
            Format::Rg32Float => T::Rg32Float,
            Format::Rg16Float => T::Rg16Float,
            Format::Rgba8Unorm => T::Rgba8Unorm,
            Format::Rgba8UnormSrgb => T::Rgba8UnormSrgb,
            Format::Bgra8Unorm => T::Bgra8Unorm,
            Format::Bgra8UnormSrgb => T::Bgra8UnormSrgb,
            Format::Rgba16Float => T::Rgba16Float,
            Format::Rgba32Float => T::Rgba32Float,
            Format::Rgba32Uint => T::Rgba32Uint,
            Format::Depth32Float => T::Depth32Float,
            Format::Depth24PlusStencil8 => T::Depth24PlusStencil8,
            Format::Depth32FloatStencil8 => T::Depth32FloatStencil8,
        }
    }

    /// Bytes per texel (for memory reports; Depth24PlusStencil8 counted as 4).
    pub fn bytes_per_texel(self) -> u64 {
        match self {
            Format::R32Uint | Format::R32Sint | Format::R32Float => 4,
            Format::Rg16Float => 4,
            Format::Rg32Float => 8,
            Format::Rgba8Unorm | Format::Rgba8UnormSrgb => 4,
            Format::Bgra8Unorm | Format::Bgra8UnormSrgb => 4,
            Format::Rgba16Float => 8,
            Format::Rgba32Float | Format::Rgba32Uint => 16,
            Format::Depth32Float | Format::Depth24PlusStencil8 => 4,
            Format::Depth32FloatStencil8 => 8,
        }
    }
}
