//! What is rendered: voxel objects (an asset with instances), triangle objects, a light.

use std::sync::Arc;

use glam::{DAffine3, DVec3};
use ssbvb_voxel::asset::VoxelAsset;
use ssbvb_voxel::shading::Light;

/// How an object's LOD is chosen each frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LodPolicy {
    /// Always this level (clamped to the levels the asset has).
    Fixed(u32),
    /// Per instance, the coarsest level whose cell projects to at most `pixel_error`
    /// pixels (at the instance's nearest bounding-sphere point), plus `bias` levels
    /// (positive = finer). The pixel-error criterion of RastaVox; `pixel_error` 0 (or
    /// less) means the finest level.
    Auto {
        /// Levels added to the chosen one.
        bias: i32,
        /// Largest projected cell size in pixels (1 = about a pixel per voxel).
        pixel_error: f64,
    },
}

impl LodPolicy {
    /// `Auto` with a pixel error of 1 and no bias.
    pub const AUTO: LodPolicy = LodPolicy::Auto {
        bias: 0,
        pixel_error: 1.0,
    };
}

/// A voxel asset placed one or more times.
#[derive(Debug, Clone)]
pub struct VoxelObject {
    /// The prepared asset (shared by all its instances).
    pub asset: Arc<VoxelAsset>,
    /// Object space → world, one per instance.
    pub instances: Vec<DAffine3>,
    /// LOD choice.
    pub lod: LodPolicy,
}

/// A translucent RGBA volume (volumetric billboard) placed one or more times; drawn by
/// `VolumeSlices` after the opaque frame.
#[derive(Debug, Clone)]
pub struct VolumeObject {
    /// What it is called in errors and reports (its scene entry).
    pub name: String,
    /// The mipmapped, bricked volume.
    pub volume: Arc<ssbvb_voxel::rgba_volume::RgbaVolume>,
    /// Object space [-1, 1]³ → world (uniform scale), one per instance.
    pub instances: Vec<DAffine3>,
}

/// An ordinary triangle mesh drawn into the same G-buffer (stencil = triangle).
#[derive(Debug, Clone)]
pub struct TriangleObject {
    /// Vertex positions in model space.
    pub positions: Vec<[f32; 3]>,
    /// Per-vertex normals in model space (same length as positions).
    pub normals: Vec<[f32; 3]>,
    /// Triangles.
    pub indices: Vec<u32>,
    /// Linear RGBA albedo.
    pub color: [f32; 4],
    /// Model → world.
    pub transform: DAffine3,
}

impl TriangleObject {
    /// A square in the XZ plane of half-size `half` centred at `center`, facing +Y.
    pub fn ground_plane(center: DVec3, half: f32, color: [f32; 4]) -> Self {
        Self {
            positions: vec![
                [-half, 0.0, -half],
                [half, 0.0, -half],
                [half, 0.0, half],
                [-half, 0.0, half],
            ],
            normals: vec![[0.0, 1.0, 0.0]; 4],
            indices: vec![0, 2, 1, 0, 3, 2],
            color,
            transform: DAffine3::from_translation(center),
        }
    }
}

/// Everything one frame draws.
#[derive(Debug, Clone, Default)]
pub struct Scene {
    /// Voxel objects.
    pub objects: Vec<VoxelObject>,
    /// Triangle objects.
    pub triangles: Vec<TriangleObject>,
    /// The light (the same model as the CPU reference).
    pub light: Light,
    /// Translucent RGBA volumes.
    pub volumes: Vec<VolumeObject>,
}

impl Scene {
    /// The voxel instances of every object: more than one makes the ray casters walk the
    /// instances' hierarchy (the variant their first frame is likely to need).
    pub fn voxel_instances(&self) -> usize {
        self.objects.iter().map(|o| o.instances.len()).sum()
    }
}
