//! In-memory models as loaded from files, before voxelization.

use glam::{DVec3, Vec2, Vec3};

/// A triangle soup with optional per-vertex attributes, as read from OBJ / PLY / glTF.
///
/// All attribute vectors are either empty or have exactly `positions.len()` entries.
#[derive(Debug, Clone, Default)]
pub struct Mesh {
    /// Vertex positions in the file's own units.
    pub positions: Vec<Vec3>,
    /// Per-vertex normals (may be empty; then face normals are used).
    pub normals: Vec<Vec3>,
    /// Per-vertex texture coordinates (may be empty).
    pub uvs: Vec<Vec2>,
    /// Per-vertex linear RGBA colours in [0, 1] (may be empty).
    pub colors: Vec<[f32; 4]>,
    /// Triangles as indices into the vertex arrays.
    pub triangles: Vec<[u32; 3]>,
    /// Per-triangle material index into `materials` (may be empty: all use material 0).
    pub triangle_materials: Vec<u32>,
    /// Materials (base colour factor and optional base colour texture).
    pub materials: Vec<Material>,
}

/// A surface material: what the voxelizer needs to colour a voxel.
#[derive(Debug, Clone)]
pub struct Material {
    /// Linear RGBA base colour factor.
    pub base_color: [f32; 4],
    /// Optional base colour texture (sRGB-decoded to linear RGBA8 is the loader's job).
    pub base_color_texture: Option<Texture>,
}

impl Material {
    /// The material of triangles that name none: light grey, untextured.
    pub const DEFAULT: Material = Material {
        base_color: [0.8, 0.8, 0.8, 1.0],
        base_color_texture: None,
    };
}

impl Default for Material {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// An RGBA8 texture (row 0 at the top, as images are stored), sampled with wrap-around.
#[derive(Debug, Clone)]
pub struct Texture {
    /// Width in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
    /// `width * height` RGBA8 texels, linear colour.
    pub texels: Vec<[u8; 4]>,
}

/// A set of unit voxel cubes with colours, as read from a voxel file (`.vox`, raw grid).
///
/// Each voxel is the cube `[p, p + 1]` in the model's integer coordinates (after the
/// file's scene-graph transforms have been applied).
#[derive(Debug, Clone, Default)]
pub struct VoxelModel {
    /// Integer minimum corner of each voxel cube.
    pub voxels: Vec<[i32; 3]>,
    /// Linear RGBA colour of each voxel (same length as `voxels`).
    pub colors: Vec<[f32; 4]>,
}

/// Either kind of loaded model.
#[derive(Debug, Clone)]
pub enum Model {
    /// A triangle mesh (surface voxelization applies).
    Mesh(Mesh),
    /// A voxel model (resampled onto the target grid).
    Voxels(VoxelModel),
}

/// The mapping from a model's own coordinates into object space [-1, 1]³.
///
/// The axis-aligned bounding box centre maps to the origin and its largest extent to
/// [-1, 1] (uniform scale). A grid of level L has 2^L cells per axis covering [-1, 1]³;
/// cell `(i, j, k)` covers `[-1 + i·s, -1 + (i+1)·s]` per axis with `s = 2 / 2^L`.
/// Acceptance checks rebuild this convention independently: do not change it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ObjectSpace {
    /// Bounding-box centre in model coordinates.
    pub center: DVec3,
    /// Model units → object units (`2 / largest extent`).
    pub scale: f64,
}

impl ObjectSpace {
    /// Object space of an axis-aligned box `[min, max]` in model coordinates.
    /// A degenerate (zero-extent) box gets scale 1 so nothing divides by zero.
    pub fn from_bounds(min: DVec3, max: DVec3) -> Self {
        let extent = (max - min).max_element();
        let scale = if extent > 0.0 && extent.is_finite() {
            2.0 / extent
        } else {
            1.0
        };
        Self {
            center: (min + max) * 0.5,
            scale,
        }
    }

    /// Model coordinates → object space.
    pub fn to_object(&self, p: DVec3) -> DVec3 {
        (p - self.center) * self.scale
    }
}

/// Edge length of one cell of a level-`level` grid in object units (`2 / 2^level`).
pub fn cell_size(level: u32) -> f64 {
    2.0 / (1u64 << level) as f64
}
