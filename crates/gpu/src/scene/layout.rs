//! Mirrors of the WGSL structs of group 0 (`shaders/common.inc.wgsl`; `cargo xtask
//! validate-shaders` checks each against its WGSL twin) and what an upload reports.

use bytemuck::{Pod, Zeroable};
use ssbvb_voxel::asset::{GPU_COLOR_BYTES, GPU_NORMAL_BYTES, GPU_VOXEL_BYTES};
use wgpu;

/// Mirror of WGSL `Frame`.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub struct FrameUniform {
    /// Camera-relative world → clip.
    pub view_proj: [[f32; 4]; 4],
    /// Clip → camera-relative world.
    pub inv_view_proj: [[f32; 4]; 4],
    /// Camera-relative world → view.
    pub view: [[f32; 4]; 4],
    /// View → clip (reversed Z). Positions far from the camera go object → view (per
    /// instance, composed in f64) → clip, never through large camera-relative world
    /// coordinates whose f32 rounding exceeds a pixel.
    pub proj: [[f32; 4]; 4],
    /// Right axis scaled by the half-width of the view at distance 1.
    pub cam_right: [f32; 4],
    /// Up axis scaled by the half-height of the view at distance 1.
    pub cam_up: [f32; 4],
    /// Forward axis.
    pub cam_forward: [f32; 4],
    /// width, height, 1/width, 1/height.
    pub screen: [f32; 4],
    /// Towards the light (xyz), ambient (w).
    pub light_dir: [f32; 4],
    /// Light colour (rgb), specular (w).
    pub light_color: [f32; 4],
    /// shininess, near, far (0 = infinite), visible instance count.
    pub shine_near_far_count: [f32; 4],
    /// Sub-pixel jitter in pixels (xy; `proj` sheared to match), zw 0.
    pub jitter: [f32; 4],
    /// The scene's word stream ([`super::SceneBindings`]): log2 of its words per binding,
    /// its first colour word, its first normal word, 0 (set by [`super::GpuScene::update`]).
    pub streams: [u32; 4],
    /// x: 1 when no visible instance's proxy is drawn by its back faces, so that a texel's
    /// nearest proxy entry in the empty-space prepass is where its ray first meets any
    /// instance's proxy (set by [`super::GpuScene::update`]); yzw 0.
    pub prepass: [u32; 4],
}

/// Mirror of WGSL `Instance` (224 bytes).
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub struct InstanceUniform {
    /// Object → camera-relative world.
    pub object_to_world: [[f32; 4]; 4],
    /// Object → view, composed in f64 (its translation is the instance's view-space
    /// origin: lateral offsets stay small and exact however far the instance is).
    pub object_to_view: [[f32; 4]; 4],
    /// Camera-relative world → object.
    pub world_to_object: [[f32; 4]; 4],
    /// Camera in object space (xyz), world size of a cell (w).
    pub camera_object: [f32; 4],
    /// Index into the LOD table.
    pub lod: u32,
    /// Grid level of that LOD.
    pub level: u32,
    /// Bit 0: camera inside the proxy.
    pub flags: u32,
    /// Index of the instance in the whole scene.
    pub scene_index: u32,
}

/// Mirror of WGSL `BvhNode` (32 bytes): one node of the hierarchy over the visible
/// instances' camera-relative world boxes (`ssbvb_voxel::instance_bvh`, rebuilt per frame).
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable, PartialEq)]
pub struct GpuBvhNode {
    /// Box minimum (rounded down to f32).
    pub lo: [f32; 3],
    /// Left child, or `LEAF | visible instance index`.
    pub left: u32,
    /// Box maximum (rounded up to f32).
    pub hi: [f32; 3],
    /// Right child (0 for a leaf).
    pub right: u32,
}

/// `LodInfo::page_base` of a LOD resident whole (WGSL `NO_PAGES`).
pub const NO_PAGES: u32 = u32::MAX;

/// Mirror of WGSL `LodInfo` (36 bytes; entry `i` is words `9i..9i + 9` of the scene's
/// word stream).
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable, PartialEq, Eq)]
pub struct LodInfo {
    /// Grid level.
    pub level: u32,
    /// Depth of the lookup tree ([`ssbvb_voxel::lookup::tree_depth`]).
    pub depth: u32,
    /// First voxel in the attribute buffers.
    pub voxel_offset: u32,
    /// The LOD's root node in the lookup-node buffer.
    pub node_offset: u32,
    /// The scene object this LOD belongs to (which octree the octree baseline reads).
    pub object: u32,
    /// log2 of the words per binding of the word stream (LOD table, colours, normals).
    pub chunk_bits: u32,
    /// log2 of the nodes per binding of the lookup-node stream.
    pub node_chunk_bits: u32,
    /// Under a budget: the global id of the LOD's first page, or `NO_PAGES` (`u32::MAX`)
    /// when the LOD is resident whole.
    pub page_base: u32,
    /// Under a budget: the LOD's first page node, relative to its root.
    pub first_page_node: u32,
}

/// Where a proxy mesh lives in the shared proxy buffers.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ProxyRange {
    /// First index.
    pub first_index: u32,
    /// Index count.
    pub index_count: u32,
    /// Added to every index.
    pub base_vertex: i32,
}

/// One instance that survived culling this frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VisibleInstance {
    /// Index in the scene's flattened instance list.
    pub scene_index: u32,
    /// Which object it belongs to.
    pub object: usize,
    /// Chosen level.
    pub level: u32,
    /// Its proxy in the proxy buffers.
    pub proxy: ProxyRange,
    /// The level whose proxy that is: its own, or a coarser one under a budget or where
    /// the view does not resolve its bricks (`visibility::proxy_detail`).
    pub proxy_level: u32,
    /// The camera is inside its proxy (the prepass fills the screen behind it).
    pub camera_inside: bool,
    /// The prepass draws its proxy's back faces: the camera is inside the proxy or the
    /// near plane may cut it (elsewhere a back face never wins the depth test).
    pub back_faces: bool,
}

/// GPU bytes of one object's asset (all LODs), for reports.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
pub struct ObjectMemory {
    /// Voxels of all levels.
    pub voxels: u64,
    /// Voxel attributes: colour plus normal ([`GPU_VOXEL_BYTES`] per voxel; the cell is
    /// implied by the lookup).
    pub point_cloud_bytes: u64,
    /// Of `point_cloud_bytes`: the colours.
    pub color_bytes: u64,
    /// Of `point_cloud_bytes`: the normals.
    pub normal_bytes: u64,
    /// Lookup trees (12-byte nodes).
    pub lookup_bytes: u64,
    /// Proxy meshes.
    pub proxy_bytes: u64,
}

impl ObjectMemory {
    /// What one LOD level takes on the GPU (an object holds every level of its asset).
    pub fn of_lod(lod: &ssbvb_voxel::asset::LodLevel) -> Self {
        let n = lod.point_cloud.voxels.len() as u64;
        Self {
            voxels: n,
            point_cloud_bytes: n * GPU_VOXEL_BYTES,
            color_bytes: n * GPU_COLOR_BYTES,
            normal_bytes: n * GPU_NORMAL_BYTES,
            lookup_bytes: lod.lookup.bytes() as u64,
            proxy_bytes: (lod.proxy.positions.len() * 16 + lod.proxy.triangles.len() * 12) as u64,
        }
    }

    /// Adds `other` field by field.
    pub fn add(&mut self, other: &Self) {
        self.voxels += other.voxels;
        self.point_cloud_bytes += other.point_cloud_bytes;
        self.color_bytes += other.color_bytes;
        self.normal_bytes += other.normal_bytes;
        self.lookup_bytes += other.lookup_bytes;
        self.proxy_bytes += other.proxy_bytes;
    }

    /// Sum.
    pub fn total(&self) -> u64 {
        self.point_cloud_bytes + self.lookup_bytes + self.proxy_bytes
    }

    /// Lookup plus attributes per voxel (0 without voxels).
    pub fn bytes_per_voxel(&self) -> f64 {
        if self.voxels == 0 {
            0.0
        } else {
            (self.point_cloud_bytes + self.lookup_bytes) as f64 / self.voxels as f64
        }
    }
}

/// A triangle object on the GPU.
pub struct GpuTriangleMesh {
    /// Interleaved position (xyz) + normal (xyz) f32 vertices.
    pub vertices: wgpu::Buffer,
    /// u32 indices.
    pub indices: wgpu::Buffer,
    /// Index count.
    pub index_count: u32,
    /// Per-mesh uniform (model matrix camera-relative, normal matrix, colour), 160 bytes.
    pub uniform: wgpu::Buffer,
}

/// Mirror of WGSL `Mesh` in triangles.wgsl.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub struct MeshUniform {
    /// Model → camera-relative world.
    pub model: [[f32; 4]; 4],
    /// Inverse transpose of the model's linear part (as a 4×4).
    pub normal_matrix: [[f32; 4]; 4],
    /// Linear RGBA albedo.
    pub color: [f32; 4],
    /// Padding to 16-byte multiple of a dynamic offset friendly size.
    pub pad: [f32; 4],
}
