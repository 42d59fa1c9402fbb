//! The pass kinds: one line each in the `pass_kinds!` list below, and each kind's parameter
//! type with its [`KindSpec`] (stage, slots, parameter checks). Adding a kind here is half of
//! adding a pass; the other half is its implementation, registered in `ssbvb-passes`.

use serde::{Deserialize, Serialize};

use crate::cone_kinds::{ConeCompositeKind, ConeTraceParams};
use crate::pass_kind::{Access, KindSpec, OfKind, PassStage, SlotClass, SlotDesc, pass_kinds};
use crate::schema::{BufferLayout, Format};
use crate::volume_kinds::VolumeSlicesParams;

pass_kinds! {
    /// Rasterizes the proxy meshes of visible objects: per pixel the object-space entry
    /// point and instance id (`entry`), with depth test against `prepass_depth`.
    EmptySpacePrepass = EmptySpacePrepassKind;
    /// Compute, one thread per pixel: marches the sparse lookup from the entry point to the
    /// first voxel and appends it to the SSBVB (`ssbvb`), counting hits into the indirect
    /// draw (`billboard_draw`).
    RayMarchFilter(RayMarchFilterParams);
    /// Draws one billboard per SSBVB entry (vertex pulling) into the G-buffer with
    /// stencil = voxel.
    Billboards(BillboardsParams);
    /// Ordinary triangle meshes into the G-buffer with stencil = triangle.
    Triangles = TrianglesKind;
    /// 3×3 Gaussian over normals with the paper's distance-dependent offset (Eq. 1),
    /// stencil-tested to voxel pixels.
    Smooth(SmoothParams);
    /// Deferred lighting (directional + ambient Blinn-Phong) into the output colour.
    Composite = CompositeKind;
    /// Baseline: per pixel, a plain cell-by-cell Amanatides–Woo DDA over a dense 3D texture
    /// of the visible object's LOD, writing the same G-buffer as the billboards (stencil =
    /// voxel).
    DenseDda(DenseDdaParams);
    /// Baseline: per pixel, a stack-based front-to-back ray cast through the sparse voxel
    /// octree of the visible object down to each instance's LOD level (the reference point
    /// of the paper, cf. Laine & Karras' ESVO), writing the same G-buffer as the billboards
    /// (stencil = voxel).
    OctreeRayCast(OctreeRayCastParams);
    /// Baseline (seed 002, §3.3.1): instanced rasterization of one cube per voxel of each
    /// visible instance's LOD — or, with `merge_full_nodes`, one cube per completely full
    /// octree node — writing the same G-buffer as the billboards (stencil = voxel).
    CubeRaster(CubeRasterParams);
    /// The billboards as a compute splat (Schütz et al.'s compute rasterization, for
    /// adapters with weak raster units): per SSBVB entry, its quad's pixels take the
    /// nearest depth by atomic max, then the lowest entry at that depth, and a fullscreen
    /// resolve writes the same G-buffer as `Billboards` (stencil = voxel).
    SplatBillboards(SplatBillboardsParams);
    /// RastaVox (seed 001): per visible chunk of each instance, the surface voxels of the
    /// coarsest OR-merged LOD within `pixel_error` pixels, at most three masked faces each by
    /// vertex pulling, writing the same G-buffer as the billboards (stencil = voxel).
    RastaVox(RastaVoxParams);
    /// Voxel cone tracing (seed 003, Crassin et al. 2011), fullscreen: per G-buffer pixel,
    /// cones through the pre-filtered scene volume give ambient occlusion and a soft shadow
    /// (`occlusion`) and one diffuse bounce (`indirect`).
    ConeTrace(ConeTraceParams);
    /// Deferred lighting like `Composite`, with the cone tracer's occlusion, shadow and
    /// bounce.
    ConeComposite = ConeCompositeKind;
    /// Volumetric billboards (seed 004): view-aligned slices through every RGBA volume,
    /// back to front, blended "over" the output colour and depth-tested against the
    /// opaque depth.
    VolumeSlices(VolumeSlicesParams);
}

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
/// The G-buffer's geometric normal, octahedral-encoded (see `ssbvb_passes::gbuffer`).
pub(crate) const GEOMETRIC_NORMAL: &[Format] = &[Format::Rg16Float];
pub(crate) const ENTRY: &[Format] = &[Format::Rgba32Float];
pub(crate) const COLOR_OUT: &[Format] = &[
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

/// The G-buffer every geometry pass writes (`ssbvb_passes::gbuffer` documents each slot).
const GBUFFER_WRITES: &[SlotDesc] = &[
    slot!("gbuffer_albedo", Write, SlotClass::ColorAttachment(ALBEDO)),
    slot!(
        "gbuffer_normal",
        Write,
        SlotClass::ColorAttachment(GBUFFER_NORMAL)
    ),
    slot!(
        "gbuffer_position",
        Write,
        SlotClass::ColorAttachment(POSITION)
    ),
    slot!(
        "gbuffer_geometric_normal",
        Write,
        SlotClass::ColorAttachment(GEOMETRIC_NORMAL)
    ),
    slot!(
        "depth_stencil",
        Write,
        SlotClass::DepthStencilAttachment(DEPTH_STENCIL)
    ),
];

/// `max_steps` must be at least 1.
fn steps_problems(max_steps: u32) -> Vec<String> {
    if max_steps == 0 {
        vec!["max_steps must be at least 1".to_string()]
    } else {
        Vec::new()
    }
}

/// `EmptySpacePrepass` has no parameters.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct EmptySpacePrepassKind;

impl KindSpec for EmptySpacePrepassKind {
    const NAME: &'static str = "EmptySpacePrepass";
    const STAGE: PassStage = PassStage::Render;
    const SLOTS: &'static [SlotDesc] = &[
        slot!("entry", Write, SlotClass::ColorAttachment(ENTRY)),
        slot!(
            "prepass_depth",
            Write,
            SlotClass::DepthStencilAttachment(DEPTH)
        ),
    ];
}

/// Parameters of `RayMarchFilter`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct RayMarchFilterParams {
    /// Most DDA steps per ray (cells, pages and empty blocks each count one).
    #[serde(default = "default_max_steps")]
    pub max_steps: u32,
    /// Append each hit voxel once per frame (the first pixel to reach it claims it)
    /// instead of once per covered pixel. Same image; far fewer billboards when voxels
    /// span many pixels (a level finer than the screen needs is then not required).
    /// Off by default: the paper's SSBVB holds one entry per covered pixel.
    #[serde(default)]
    pub unique_voxels: bool,
}

fn default_max_steps() -> u32 {
    1024
}

impl Default for RayMarchFilterParams {
    fn default() -> Self {
        Self {
            max_steps: default_max_steps(),
            unique_voxels: false,
        }
    }
}

impl KindSpec for RayMarchFilterParams {
    const NAME: &'static str = "RayMarchFilter";
    const STAGE: PassStage = PassStage::Compute;
    const SLOTS: &'static [SlotDesc] = &[
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
    fn problems(&self) -> Vec<String> {
        steps_problems(self.max_steps)
    }
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

/// Parameters of `Billboards`.
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

fn one() -> f32 {
    1.0
}

impl Default for BillboardsParams {
    fn default() -> Self {
        Self {
            mode: BillboardMode::Flat,
            size_scale: 1.0,
        }
    }
}

impl KindSpec for BillboardsParams {
    const NAME: &'static str = "Billboards";
    const STAGE: PassStage = PassStage::Render;
    const SLOTS: &'static [SlotDesc] = &[
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
        GBUFFER_WRITES[4],
    ];
    fn problems(&self) -> Vec<String> {
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

/// `Triangles` has no parameters.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct TrianglesKind;

impl KindSpec for TrianglesKind {
    const NAME: &'static str = "Triangles";
    const STAGE: PassStage = PassStage::Render;
    const SLOTS: &'static [SlotDesc] = GBUFFER_WRITES;
}

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
}

fn default_min_dist() -> f32 {
    0.5
}

impl Default for SmoothParams {
    fn default() -> Self {
        Self {
            max_i: 1.0,
            min_dist: default_min_dist(),
        }
    }
}

impl KindSpec for SmoothParams {
    const NAME: &'static str = "Smooth";
    const STAGE: PassStage = PassStage::Render;
    const SLOTS: &'static [SlotDesc] = &[
        slot!("gbuffer_normal", Read, SlotClass::SampledTexture(NORMAL)),
        slot!(
            "depth_stencil",
            Read,
            SlotClass::DepthStencilAttachment(DEPTH_STENCIL)
        ),
        slot!("smoothed_normal", Write, SlotClass::ColorAttachment(NORMAL)),
    ];
    fn problems(&self) -> Vec<String> {
        let mut out = Vec::new();
        if !(self.max_i.is_finite() && self.max_i >= 0.0) {
            out.push(format!("max_i must be a number >= 0, got {}", self.max_i));
        }
        if !(self.min_dist.is_finite() && self.min_dist >= 0.0) {
            out.push(format!(
                "min_dist must be a number >= 0, got {}",
                self.min_dist
            ));
        }
        out
    }
}

/// `Composite` has no parameters.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct CompositeKind;

impl KindSpec for CompositeKind {
    const NAME: &'static str = "Composite";
    const STAGE: PassStage = PassStage::Render;
    const SLOTS: &'static [SlotDesc] = &[
        slot!("albedo", Read, SlotClass::SampledTexture(ALBEDO)),
        slot!("normal", Read, SlotClass::SampledTexture(NORMAL)),
        slot!("position", Read, SlotClass::SampledTexture(POSITION)),
        slot!("color", Write, SlotClass::ColorAttachment(COLOR_OUT)),
    ];
}

fn default_ray_cast_steps() -> u32 {
    4096
}

/// Parameters of `DenseDda`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct DenseDdaParams {
    /// Most DDA steps (cells) per ray and instance.
    #[serde(default = "default_ray_cast_steps")]
    pub max_steps: u32,
}

impl Default for DenseDdaParams {
    fn default() -> Self {
        Self {
            max_steps: default_ray_cast_steps(),
        }
    }
}

impl KindSpec for DenseDdaParams {
    const NAME: &'static str = "DenseDda";
    const STAGE: PassStage = PassStage::Render;
    const SLOTS: &'static [SlotDesc] = GBUFFER_WRITES;
    fn problems(&self) -> Vec<String> {
        steps_problems(self.max_steps)
    }
}

/// Parameters of `OctreeRayCast`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct OctreeRayCastParams {
    /// Most traversal steps (child visits, descents and pops) per ray and instance.
    #[serde(default = "default_ray_cast_steps")]
    pub max_steps: u32,
}

impl Default for OctreeRayCastParams {
    fn default() -> Self {
        Self {
            max_steps: default_ray_cast_steps(),
        }
    }
}

impl KindSpec for OctreeRayCastParams {
    const NAME: &'static str = "OctreeRayCast";
    const STAGE: PassStage = PassStage::Render;
    const SLOTS: &'static [SlotDesc] = GBUFFER_WRITES;
    fn problems(&self) -> Vec<String> {
        steps_problems(self.max_steps)
    }
}

/// Parameters of `CubeRaster`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct CubeRasterParams {
    /// Merge every completely full octree node into one cube of its size.
    #[serde(default = "yes")]
    pub merge_full_nodes: bool,
}

fn yes() -> bool {
    true
}

impl Default for CubeRasterParams {
    fn default() -> Self {
        Self {
            merge_full_nodes: true,
        }
    }
}

impl KindSpec for CubeRasterParams {
    const NAME: &'static str = "CubeRaster";
    const STAGE: PassStage = PassStage::Render;
    const SLOTS: &'static [SlotDesc] = GBUFFER_WRITES;
}

/// Parameters of `RastaVox`.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct RastaVoxParams {
    /// The largest projected voxel, in pixels, a chunk's LOD may have (0 = always the
    /// finest; the paper's 1 "with no visible difference").
    #[serde(default = "one")]
    pub pixel_error: f32,
}

/// The largest accepted `pixel_error`: beyond it every chunk is one voxel anyway.
pub const MAX_PIXEL_ERROR: f32 = 4096.0;

impl Default for RastaVoxParams {
    fn default() -> Self {
        Self { pixel_error: 1.0 }
    }
}

impl KindSpec for RastaVoxParams {
    const NAME: &'static str = "RastaVox";
    const STAGE: PassStage = PassStage::Render;
    const SLOTS: &'static [SlotDesc] = GBUFFER_WRITES;
    fn problems(&self) -> Vec<String> {
        if (0.0..=MAX_PIXEL_ERROR).contains(&self.pixel_error) {
            Vec::new()
        } else {
            vec![format!(
                "pixel_error must be a number from 0 to {MAX_PIXEL_ERROR}, got {}",
                self.pixel_error
            )]
        }
    }
}

/// Parameters of `SplatBillboards` (the same as `Billboards`).
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SplatBillboardsParams {
    /// Flat quads at the voxel centre's depth (the paper) or exact ray–box depth per pixel.
    #[serde(default)]
    pub mode: BillboardMode,
    /// Scale of the quad relative to the voxel's projected footprint.
    #[serde(default = "one")]
    pub size_scale: f32,
}

impl Default for SplatBillboardsParams {
    fn default() -> Self {
        Self {
            mode: BillboardMode::Flat,
            size_scale: 1.0,
        }
    }
}

impl KindSpec for SplatBillboardsParams {
    const NAME: &'static str = "SplatBillboards";
    const STAGE: PassStage = PassStage::Render;
    const SLOTS: &'static [SlotDesc] = &[
        slot!(
            "ssbvb",
            Read,
            SlotClass::StorageBuffer(BufferLayout::VoxelSlot)
        ),
        // Read by the splat (the entry count), not used as an indirect draw.
        slot!(
            "billboard_draw",
            Read,
            SlotClass::StorageBuffer(BufferLayout::DrawIndirect)
        ),
        GBUFFER_WRITES[0],
        GBUFFER_WRITES[1],
        GBUFFER_WRITES[2],
        GBUFFER_WRITES[3],
        GBUFFER_WRITES[4],
    ];
    fn problems(&self) -> Vec<String> {
        BillboardsParams {
            mode: self.mode,
            size_scale: self.size_scale,
        }
        .problems()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kind_names_match_variants_and_specs() {
        let names: Vec<_> = PassKind::all_defaults().iter().map(|k| k.name()).collect();
        assert_eq!(names, KIND_NAMES);
        let spec_names = [
            EmptySpacePrepassKind::NAME,
            RayMarchFilterParams::NAME,
            BillboardsParams::NAME,
            TrianglesKind::NAME,
            SmoothParams::NAME,
            CompositeKind::NAME,
            DenseDdaParams::NAME,
            OctreeRayCastParams::NAME,
            CubeRasterParams::NAME,
            SplatBillboardsParams::NAME,
            RastaVoxParams::NAME,
            ConeTraceParams::NAME,
            ConeCompositeKind::NAME,
            VolumeSlicesParams::NAME,
        ];
        assert_eq!(spec_names, KIND_NAMES);
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

    #[test]
    fn parameters_are_found_only_in_their_kind() {
        let k = PassKind::RayMarchFilter(RayMarchFilterParams {
            max_steps: 0,
            unique_voxels: true,
        });
        assert_eq!(RayMarchFilterParams::of_kind(&k).unwrap().max_steps, 0);
        assert!(DenseDdaParams::of_kind(&k).is_none());
        assert!(CompositeKind::of_kind(&PassKind::Composite).is_some());
        assert!(CompositeKind::of_kind(&k).is_none());
        assert_eq!(k.parameter_problems(), ["max_steps must be at least 1"]);
        assert_eq!(k.stage(), PassStage::Compute);
        assert!(PassKind::Composite.parameter_problems().is_empty());
    }
}
