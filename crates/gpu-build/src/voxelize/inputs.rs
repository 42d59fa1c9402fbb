//! What the GPU voxelizer uploads per drawable triangle: its corners in grid units (f32
//! for the raster path, f64 for the exact one, mapped exactly as the CPU voxelizer maps
//! them), its corner colours (material base colour × vertex colour) and texture coordinates
//! with the index of its material's base-colour texture, and every texture's texels
//! (`shaders/voxel_texture.inc.wgsl` samples them). Materials, vertex colours and uvs are
//! resolved as the CPU voxelizer resolves them (`ssbvb_voxel::voxelize`): a triangle
//! without a material entry uses material 0; vertex colours and uvs count only when every
//! vertex has one; a malformed texture samples as white.

use glam::DVec3;
use ssbvb_voxel::model::{Material, Mesh, ObjectSpace, Texture};
use ssbvb_voxel::voxelize::VoxelizeReport;

/// Words of one texture's header in [`TriangleInputs::textures`]: first texel word,
/// width, height, unused.
const HEADER_WORDS: usize = 4;

/// The voxelizer's per-triangle inputs.
#[derive(Debug, Clone, Default, PartialEq)]
pub(super) struct TriangleInputs {
    /// Per corner: x, y, z (grid units), 1.
    pub corners: Vec<f32>,
    /// Per corner: linear RGBA (material × vertex colour).
    pub colors: Vec<f32>,
    /// Per corner: u, v, the texture's index (−1: none), 0.
    pub uvs: Vec<f32>,
    /// Per corner: x, y, z (grid units) in f64.
    pub grid: Vec<f64>,
    /// A header of [`HEADER_WORDS`] per texture, then the texels (RGBA8, one word each).
    pub textures: Vec<u32>,
    /// What was skipped, counted as the CPU voxelizer counts it.
    pub report: VoxelizeReport,
}

impl TriangleInputs {
    /// Triangles in the lists.
    pub fn triangles(&self) -> u32 {
        (self.corners.len() / 12) as u32
    }
}

/// Whether the CPU voxelizer samples `t` (else it counts as white).
fn usable(t: &Texture) -> bool {
    t.width > 0
        && t.height > 0
        && (t.texels.len() as u64) >= u64::from(t.width) * u64::from(t.height)
}

/// The inputs of `mesh` voxelized at `level` in `space`.
pub(super) fn triangle_inputs(mesh: &Mesh, space: &ObjectSpace, level: u32) -> TriangleInputs {
    let half = (1u64 << level) as f64 * 0.5;
    let mut out = TriangleInputs {
        report: VoxelizeReport {
            triangles: mesh.triangles.len() as u64,
            ..Default::default()
        },
        ..Default::default()
    };
    // Texture index per material (usable textures only), headers then texels.
    let textured: Vec<Option<&Texture>> = mesh
        .materials
        .iter()
        .map(|m| m.base_color_texture.as_ref().filter(|t| usable(t)))
        .collect();
    let count = textured.iter().flatten().count();
    let mut index: Vec<Option<f32>> = Vec::with_capacity(textured.len());
    out.textures = vec![0; HEADER_WORDS * count];
    let mut k = 0usize;
    for t in &textured {
        let Some(t) = t else {
            index.push(None);
            continue;
        };
        let first = out.textures.len() as u32;
        out.textures[HEADER_WORDS * k..HEADER_WORDS * (k + 1)]
            .copy_from_slice(&[first, t.width, t.height, 0]);
        let n = (u64::from(t.width) * u64::from(t.height)) as usize;
        out.textures
            .extend(t.texels[..n].iter().map(|c| u32::from_le_bytes(*c)));
        index.push(Some(k as f32));
        k += 1;
    }
    let n = mesh.positions.len();
    let (with_uvs, with_colors) = (mesh.uvs.len() == n, mesh.colors.len() == n);
    for (ti, t) in mesh.triangles.iter().enumerate() {
        let Some(p) = t
            .iter()
            .map(|&i| mesh.positions.get(i as usize))
            .collect::<Option<Vec<_>>>()
        else {
            out.report.skipped_bad_index += 1;
            continue;
        };
        if p.iter().any(|p| !p.is_finite()) {
            out.report.skipped_non_finite += 1;
            continue;
        }
        let g: Vec<DVec3> = p
            .iter()
            .map(|p| (space.to_object(p.as_dvec3()) + 1.0) * half)
            .collect();
        if (g[1] - g[0]).cross(g[2] - g[0]) == DVec3::ZERO {
            out.report.degenerate += 1;
        }
        let m = mesh.triangle_materials.get(ti).copied().unwrap_or(0) as usize;
        let material = mesh.materials.get(m).unwrap_or(&Material::DEFAULT);
        let texture = index.get(m).copied().flatten().filter(|_| with_uvs);
        for (k, gk) in g.iter().enumerate() {
            let v = t[k] as usize;
            out.corners
                .extend([gk.x as f32, gk.y as f32, gk.z as f32, 1.0]);
            out.grid.extend([gk.x, gk.y, gk.z]);
            let vc = if with_colors {
                mesh.colors[v]
            } else {
                [1.0; 4]
            };
            out.colors
                .extend((0..4).map(|c| material.base_color[c] * vc[c]));
            let uv = if with_uvs {
                mesh.uvs[v]
            } else {
                glam::Vec2::ZERO
            };
            out.uvs.extend([uv.x, uv.y, texture.unwrap_or(-1.0), 0.0]);
        }
    }
    out
}
