//! The closed set of pass kinds, their typed parameters and the slots each declares.
//!
//! A kind declares every resource it touches as a [`SlotDesc`]: name, read or write, and
//! what class of resource (attachment, sampled texture, storage buffer, …) with which
//! formats or layout. Slot names that are shader globals equal the WGSL global names, so
//! `cargo xtask validate-shaders` checks bindings by name through naga reflection. The
//! implementations, with their WGSL file names, are registered in `ssbvb-passes`.

use serde::{Deserialize, Serialize};

use crate::schema::{BufferLayout, Format};

/// Every pass kind, with its parameters (RON: `RayMarchFilter(max_steps: 512)`).
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
pub enum PassKind {
    /// Rasterizes the proxy meshes of visible objects: per pixel the object-space entry
    /// point and instance id (`entry`), with depth test against `prepass_depth`.
    EmptySpacePrepass,
    /// Compute, one thread per pixel: marches the sparse lookup from the entry point to the
    /// first voxel and appends it to the SSBVB (`ssbvb`), counting hits into the indirect
    /// draw (`billboard_draw`).
    RayMarchFilter {
        /// Most DDA steps per ray (cells, pages and empty blocks each count one).
        #[serde(default = "default_max_steps")]
        max_steps: u32,
        /// Append each hit voxel once per frame (the first pixel to reach it claims it)
        /// instead of once per covered pixel. Same image; far fewer billboards when voxels
        /// span many pixels (a level finer than the screen needs is then not required).
        /// Off by default: the paper's SSBVB holds one entry per covered pixel.
        #[serde(default)]
        unique_voxels: bool,
    },
    /// Draws one billboard per SSBVB entry (vertex pulling) into the G-buffer with
    /// stencil = voxel.
    Billboards {
        /// Flat camera-facing quads (the paper) or quads whose fragments intersect the
        /// voxel box exactly (ray–box splatting).
        #[serde(default)]
        mode: BillboardMode,
        /// Scale of the quad relative to the voxel's projected footprint.
        #[serde(default = "one")]
        size_scale: f32,
    },
    /// Ordinary triangle meshes into the G-buffer with stencil = triangle.
    Triangles,
    /// 3×3 Gaussian over normals with the paper's distance-dependent offset (Eq. 1),
    /// stencil-tested to voxel pixels.
    Smooth {
        /// MaxI: the largest sample offset in pixels.
        #[serde(default = "one")]
        max_i: f32,
        /// MinDist: the distance (world units) at and below which the offset is MaxI.
        #[serde(default = "default_min_dist")]
        min_dist: f32,
    },
    /// Deferred lighting (directional + ambient Blinn-Phong) into the output colour.
    Composite,
    /// Baseline: per pixel, a plain cell-by-cell Amanatides–Woo DDA over a dense 3D texture
    /// of the visible object's LOD, writing the same G-buffer as the billboards (stencil =
    /// voxel).
    DenseDda {
        /// Most DDA steps (cells) per ray and instance.
        #[serde(default = "default_dense_max_steps")]
        max_steps: u32,
    },
    /// Baseline: per pixel, a stack-based front-to-back ray cast through the sparse voxel
    /// octree (`Svo`) of the visible object down to each instance's LOD level (the
    /// reference point of the paper, cf. Laine & Karras' ESVO), writing the same G-buffer
    /// as the billboards (stencil = voxel).
    OctreeRayCast {
        /// Most traversal steps (child visits, descents and pops) per ray and instance.
        #[serde(default = "default_dense_max_steps")]
        max_steps: u32,
    },
    /// Baseline (seed 002, §3.3.1): instanced rasterization of one cube per voxel of each
    /// visible instance's LOD — or, with `merge_full_nodes`, one cube per completely full
    /// octree node — writing the same G-buffer as the billboards (stencil = voxel).
    CubeRaster {
        /// Merge every completely full octree node into one cube of its size.
        #[serde(default = "yes")]
        merge_full_nodes: bool,
    },
}

fn default_max_steps() -> u32 {
    1024
}
fn default_dense_max_steps() -> u32 {
    4096
}
fn yes() -> bool {
    true
}
fn one() -> f32 {
    1.0
}
fn default_min_dist() -> f32 {
    0.5
}

/// How billboards are shaded.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize, Serialize)]
pub enum BillboardMode {
    /// A flat quad at the voxel centre's depth (the paper).
    #[default]
    Flat,
    /// Per fragment, the exact ray–voxel-box intersection (depth and face normal).
    RayBox,
}

/// Names of every pass kind, as written in RON (for suggestions).
pub const KIND_NAMES: &[&str] = &[
    "EmptySpacePrepass",
    "RayMarchFilter",
    "Billboards",
    "Triangles",
    "Smooth",
    "Composite",
    "DenseDda",
    "OctreeRayCast",
    "CubeRaster",
];

/// Whether a slot is read or written by the pass.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Access {
    /// The pass reads the resource (it must have a producer).
    Read,
    /// The pass writes the resource.
    Write,
}

/// What class of resource a slot binds, and which formats or layout it accepts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SlotClass {
    /// A render-pass colour attachment.
    ColorAttachment(&'static [Format]),
    /// A depth(-stencil) attachment; when read, it is read-only and its depth aspect is
    /// also a shader global of the slot's name.
    DepthStencilAttachment(&'static [Format]),
    /// A texture read in a shader (`textureLoad` / `textureSample`).
    SampledTexture(&'static [Format]),
    /// A storage texture.
    StorageTexture(&'static [Format]),
    /// A storage buffer of the given element layout.
    StorageBuffer(BufferLayout),
    /// A buffer of indirect arguments of the given layout.
    IndirectBuffer(BufferLayout),
}

impl SlotClass {
    /// Whether the slot is a texture slot (else a buffer slot).
    pub fn is_texture(&self) -> bool {
        !matches!(
            self,
            SlotClass::StorageBuffer(_) | SlotClass::IndirectBuffer(_)
        )
    }

    /// Formats accepted by a texture slot (empty for buffers).
    pub fn formats(&self) -> &'static [Format] {
        match *self {
            SlotClass::ColorAttachment(f)
            | SlotClass::DepthStencilAttachment(f)
            | SlotClass::SampledTexture(f)
            | SlotClass::StorageTexture(f) => f,
            _ => &[],
        }
    }

    /// Layout required by a buffer slot.
    pub fn layout(&self) -> Option<BufferLayout> {
        match *self {
            SlotClass::StorageBuffer(l) | SlotClass::IndirectBuffer(l) => Some(l),
            _ => None,
        }
    }

    /// Whether the slot is an attachment of a render pass (all must share one size).
    pub fn is_attachment(&self) -> bool {
        matches!(
            self,
            SlotClass::ColorAttachment(_) | SlotClass::DepthStencilAttachment(_)
        )
    }

    /// Short human name for error messages.
    pub fn describe(&self) -> &'static str {
        match self {
            SlotClass::ColorAttachment(_) => "colour attachment",
            SlotClass::DepthStencilAttachment(_) => "depth-stencil attachment",
            SlotClass::SampledTexture(_) => "sampled texture",
            SlotClass::StorageTexture(_) => "storage texture",
            SlotClass::StorageBuffer(_) => "storage buffer",
            SlotClass::IndirectBuffer(_) => "indirect buffer",
        }
    }
}

/// One resource slot a pass kind declares.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SlotDesc {
    /// Slot name; for shader-visible slots also the WGSL global's name.
    pub name: &'static str,
    /// Read or write.
    pub access: Access,
    /// Resource class and accepted formats or layout.
    pub class: SlotClass,
}

impl SlotDesc {
    /// Whether the slot is a global variable in the pass's WGSL (attachments and indirect
    /// buffers are not, except a read-only depth-stencil, whose depth is sampled).
    pub fn is_shader_global(&self) -> bool {
        match self.class {
            SlotClass::ColorAttachment(_) | SlotClass::IndirectBuffer(_) => false,
            SlotClass::DepthStencilAttachment(_) => self.access == Access::Read,
            _ => true,
        }
    }
}

/// Whether a pass runs as a render pass or a compute pass.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PassStage {
    /// Render pass (vertex + fragment entry points).
    Render,
    /// Compute pass.
    Compute,
}

const DEPTH_STENCIL: &[Format] = &[Format::Depth32FloatStencil8, Format::Depth24PlusStencil8];
const DEPTH: &[Format] = &[Format::Depth32Float];
const ALBEDO: &[Format] = &[Format::Rgba8Unorm];
const NORMAL: &[Format] = &[Format::Rgba16Float, Format::Rgba32Float];
const POSITION: &[Format] = &[Format::Rgba32Float];
const ENTRY: &[Format] = &[Format::Rgba32Float];
const COLOR_OUT: &[Format] = &[
    Format::Rgba8UnormSrgb,
    Format::Bgra8UnormSrgb,
    Format::Rgba8Unorm,
    Format::Bgra8Unorm,
    Format::Rgba16Float,
];

macro_rules! slot {
    ($name:literal, $access:ident, $class:expr) => {
        SlotDesc {
            name: $name,
            access: Access::$access,
            class: $class,
        }
    };
}

const GBUFFER_WRITES: [SlotDesc; 4] = [
    slot!("gbuffer_albedo", Write, SlotClass::ColorAttachment(ALBEDO)),
    slot!("gbuffer_normal", Write, SlotClass::ColorAttachment(NORMAL)),
    slot!(
        "gbuffer_position",
        Write,
        SlotClass::ColorAttachment(POSITION)
    ),
    slot!(
        "depth_stencil",
        Write,
        SlotClass::DepthStencilAttachment(DEPTH_STENCIL)
    ),
];

impl PassKind {
    /// The kind's name as written in RON.
    pub fn name(&self) -> &'static str {
        match self {
            PassKind::EmptySpacePrepass => "EmptySpacePrepass",
            PassKind::RayMarchFilter { .. } => "RayMarchFilter",
            PassKind::Billboards { .. } => "Billboards",
            PassKind::Triangles => "Triangles",
            PassKind::Smooth { .. } => "Smooth",
            PassKind::Composite => "Composite",
            PassKind::DenseDda { .. } => "DenseDda",
            PassKind::OctreeRayCast { .. } => "OctreeRayCast",
            PassKind::CubeRaster { .. } => "CubeRaster",
        }
    }

    /// One instance of every kind with default parameters (for registries and tools).
    pub fn all_defaults() -> Vec<PassKind> {
        vec![
            PassKind::EmptySpacePrepass,
            PassKind::RayMarchFilter {
                max_steps: default_max_steps(),
                unique_voxels: false,
            },
            PassKind::Billboards {
                mode: BillboardMode::Flat,
                size_scale: 1.0,
            },
            PassKind::Triangles,
            PassKind::Smooth {
                max_i: 1.0,
                min_dist: default_min_dist(),
            },
            PassKind::Composite,
            PassKind::DenseDda {
                max_steps: default_dense_max_steps(),
            },
            PassKind::OctreeRayCast {
                max_steps: default_dense_max_steps(),
            },
            PassKind::CubeRaster {
                merge_full_nodes: yes(),
            },
        ]
    }

    /// Render or compute.
    pub fn stage(&self) -> PassStage {
        match self {
            PassKind::RayMarchFilter { .. } => PassStage::Compute,
            _ => PassStage::Render,
        }
    }

    /// Entry points the kind's WGSL must define.
    pub fn entry_points(&self) -> &'static [&'static str] {
        match self.stage() {
            PassStage::Compute => &["clear_draw", "main"],
            PassStage::Render => &["vs_main", "fs_main"],
        }
    }

    /// The slots the kind declares.
    pub fn slots(&self) -> &'static [SlotDesc] {
        const EMPTY_SPACE: &[SlotDesc] = &[
            slot!("entry", Write, SlotClass::ColorAttachment(ENTRY)),
            slot!(
                "prepass_depth",
                Write,
                SlotClass::DepthStencilAttachment(DEPTH)
            ),
        ];
        const FILTER: &[SlotDesc] = &[
            slot!("entry", Read, SlotClass::SampledTexture(ENTRY)),
            slot!(
                "ssbvb",
                Write,
                SlotClass::StorageBuffer(BufferLayout::VoxelSlot)
            ),
            slot!(
                "billboard_draw",
                Write,
                SlotClass::StorageBuffer(BufferLayout::DrawIndirect)
            ),
        ];
        const BILLBOARDS: &[SlotDesc] = &[
            slot!(
                "ssbvb",
                Read,
                SlotClass::StorageBuffer(BufferLayout::VoxelSlot)
            ),
            slot!(
                "billboard_draw",
                Read,
                SlotClass::IndirectBuffer(BufferLayout::DrawIndirect)
            ),
            GBUFFER_WRITES[0],
            GBUFFER_WRITES[1],
            GBUFFER_WRITES[2],
            GBUFFER_WRITES[3],
        ];
        const SMOOTH: &[SlotDesc] = &[
            slot!("gbuffer_normal", Read, SlotClass::SampledTexture(NORMAL)),
            slot!(
                "depth_stencil",
                Read,
                SlotClass::DepthStencilAttachment(DEPTH_STENCIL)
            ),
            slot!("smoothed_normal", Write, SlotClass::ColorAttachment(NORMAL)),
        ];
        const COMPOSITE: &[SlotDesc] = &[
            slot!("albedo", Read, SlotClass::SampledTexture(ALBEDO)),
            slot!("normal", Read, SlotClass::SampledTexture(NORMAL)),
            slot!("position", Read, SlotClass::SampledTexture(POSITION)),
            slot!("color", Write, SlotClass::ColorAttachment(COLOR_OUT)),
        ];
        match self {
            PassKind::EmptySpacePrepass => EMPTY_SPACE,
            PassKind::RayMarchFilter { .. } => FILTER,
            PassKind::Billboards { .. } => BILLBOARDS,
            PassKind::Triangles
            | PassKind::DenseDda { .. }
            | PassKind::OctreeRayCast { .. }
            | PassKind::CubeRaster { .. } => &GBUFFER_WRITES,
            PassKind::Smooth { .. } => SMOOTH,
            PassKind::Composite => COMPOSITE,
        }
    }

    /// Problems with the kind's parameters (empty when they are valid).
    pub fn parameter_problems(&self) -> Vec<String> {
        let mut out = Vec::new();
        match *self {
            PassKind::RayMarchFilter { max_steps: 0, .. }
            | PassKind::DenseDda { max_steps: 0 }
            | PassKind::OctreeRayCast { max_steps: 0 } => {
                out.push("max_steps must be at least 1".to_string());
            }
            PassKind::Billboards { size_scale, .. }
                if !(size_scale.is_finite() && size_scale > 0.0) =>
            {
                out.push(format!(
                    "size_scale must be a positive number, got {size_scale}"
                ));
            }
            PassKind::Smooth { max_i, min_dist } => {
                if !(max_i.is_finite() && max_i >= 0.0) {
                    out.push(format!("max_i must be a number >= 0, got {max_i}"));
                }
                if !(min_dist.is_finite() && min_dist >= 0.0) {
                    out.push(format!("min_dist must be a number >= 0, got {min_dist}"));
                }
            }
            _ => {}
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kind_names_match_variants() {
        let names: Vec<_> = PassKind::all_defaults().iter().map(|k| k.name()).collect();
        assert_eq!(names, KIND_NAMES);
    }

    #[test]
    fn slot_names_are_unique_per_kind() {
        for k in PassKind::all_defaults() {
            let mut names: Vec<_> = k.slots().iter().map(|s| s.name).collect();
            names.sort();
            names.dedup();
            assert_eq!(names.len(), k.slots().len(), "{}", k.name());
        }
    }
}
