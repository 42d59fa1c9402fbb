//! `cube_raster`: the instanced cube rasterization baseline (`CubeRaster`;
//! `shaders/cube_raster.wgsl`).
//!
//! A render pass into the G-buffer (the same attachments, formats, clear/load rules,
//! `Greater` depth test and stencil = voxel as the billboards; see
//! [`crate::kinds::triangles`]). For every visible instance it issues ONE instanced draw of
//! its LOD level's cubes — one per voxel, or with `merge_full_nodes` one per completely full
//! octree node ([`CubeList`]) — 18 vertices per cube generated from `vertex_index` (the
//! three faces that can face the camera), the cube read from a storage buffer by
//! `instance_index`. The draw starts at vertex `18 × v`, which tells the shader the visible
//! instance `v` without any per-draw buffer. The fragment shader writes the voxel under the
//! pixel (colour and stored normal from the LOD's sparse lookup), the face as geometric
//! normal, the exact ray–face position and linear depth, so its accuracy compares with the
//! ray casters'. Many objects and every LOD work; instances of one object at one level
//! share a cube buffer.
//!
//! Cube buffers are built lazily per (object, level), the first frame such an instance is
//! visible, and kept for later frames. The benchmark's memory report uses the same
//! numbers without a GPU: [`CubeList::from_lod`] then [`CubeList::len`] (instances) and
//! [`CubeList::bytes`] (instance-buffer bytes, 8 per cube); see also [`cube_list_bytes`].
//!
//! # Limits
//!
//! - Level lists larger than the device's storage-binding limit are refused with
//!   [`PassError::TooLarge`] (8 bytes per cube).
//! - A camera inside a cube sees none of its faces (all face away): unlike the ray
//!   casters, nothing is drawn for that cube.

use std::collections::HashMap;

use ssbvb_gpu::InitBuffer;
use ssbvb_gpu::{GpuContext, wgpu};
use ssbvb_graph::CubeRasterParams;
use ssbvb_voxel::asset::VoxelAsset;
use ssbvb_voxel::cube_list::CubeList;

use crate::runtime::registry::{OwnBinding, OwnKind};
use crate::runtime::recorder::Recorder;
use crate::kinds::gbuffer::{PulledPipeline, STENCIL_VOXEL, begin_gbuffer_pass};
use crate::runtime::registry::{KindNeeds, PassImpl, PassInit};
use crate::error::PassError;
use crate::runtime::node::PassNode;

/// Vertices per cube: two triangles on the camera side of each axis (at most three faces
/// of a box face the camera).
const CUBE_VERTICES: u32 = 18;

/// The cubes of one (object, level) on the GPU.
struct LevelCubes {
    /// Group 1 (`cubes`), which keeps the buffer alive; `None` when the level is empty.
    bind_group: Option<wgpu::BindGroup>,
    /// Instances per draw.
    count: u32,
}

/// What the cube pass binds itself: the cube list of the instance being drawn.
pub const OWN: &[OwnBinding] = &[OwnBinding {
    name: "cubes",
    kind: OwnKind::StorageRead,
}];

/// The compiled cube pass and its cache of uploaded cube lists.
pub struct CubeRaster {
    pipeline: PulledPipeline,
    merge_full_nodes: bool,
    /// (object, level) → its cubes.
    levels: HashMap<(usize, u32), LevelCubes>,
}

/// Instance-buffer bytes of every LOD of `asset` as this pass would upload them (for
/// memory reports; the pass itself only uploads the levels that are drawn).
pub fn cube_list_bytes(asset: &VoxelAsset, merge_full_nodes: bool) -> Result<u64, PassError> {
    asset.lods.iter().try_fold(0u64, |sum, lod| {
        let list = CubeList::from_lod(lod, merge_full_nodes)
            .map_err(|e| PassError::BadScene(format!("CubeRaster: {e}")))?;
        Ok(sum + list.bytes() as u64)
    })
}

impl CubeRaster {
    /// Builds and uploads the cubes of `asset`'s LOD `level`.
    fn upload(
        &self,
        ctx: &GpuContext,
        asset: &VoxelAsset,
        level: u32,
    ) -> Result<LevelCubes, PassError> {
        let lod = asset.lods.get(level as usize).ok_or_else(|| {
            PassError::BadScene(format!("CubeRaster: the asset has no level {level}"))
        })?;
        let list = CubeList::from_lod(lod, self.merge_full_nodes)
            .map_err(|e| PassError::BadScene(format!("CubeRaster: {e}")))?;
        if list.is_empty() {
            return Ok(LevelCubes {
                bind_group: None,
                count: 0,
            });
        }
        let limit = ctx.device.limits().max_storage_buffer_binding_size;
        let count = u32::try_from(list.len())
            .ok()
            .filter(|_| list.bytes() as u64 <= limit);
        let Some(count) = count else {
            return Err(PassError::TooLarge(format!(
                "CubeRaster: level {level} has {} cubes ({} MiB), above the device's storage \
                 binding limit of {} MiB",
                list.len(),
                list.bytes() >> 20,
                limit >> 20
            )));
        };
        let bind_group = ctx.validated("cube_raster cubes", |d| {
            let buffer = d.init_buffer(&wgpu::util::BufferInitDescriptor {
                label: Some("cube_raster cubes"),
                contents: bytemuck::cast_slice(&list.cubes),
                usage: wgpu::BufferUsages::STORAGE,
            });
            self.pipeline.bindings.own_bind_group(
                d,
                "cube_raster cubes",
                &[("cubes", buffer.as_entire_binding())],
            )
        })??;
        Ok(LevelCubes {
            bind_group: Some(bind_group),
            count,
        })
    }
}

impl PassImpl for CubeRaster {
    type Params = CubeRasterParams;
    const SHADER: &'static str = "cube_raster.wgsl";
    const OWN: &'static [OwnBinding] = OWN;
    const NEEDS: KindNeeds = KindNeeds::new(wgpu::DownlevelFlags::empty(), 1);

    /// Compiles the pipeline for the formats bound to `pass`.
    const WHOLE_LEVELS: bool = true;

    fn new(init: &PassInit<'_>, params: &CubeRasterParams) -> Result<Self, PassError> {
        let merge_full_nodes = params.merge_full_nodes;
        // No culling: faces that do not see the camera are collapsed in the vertex shader
        // (winding-independent, so mirrored transforms work too).
        Ok(Self {
            pipeline: PulledPipeline::new::<Self>(init, &[])?,
            merge_full_nodes,
            levels: HashMap::new(),
        })
    }
}

impl PassNode for CubeRaster {
    fn record(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        rec: &mut Recorder<'_>,
    ) -> Result<(), PassError> {
        for v in &rec.scene.visible {
            if !self.levels.contains_key(&(v.object, v.level)) {
                let asset = &rec.scene.scene.objects[v.object].asset;
                let cubes = self.upload(rec.gpu, asset, v.level)?;
                self.levels.insert((v.object, v.level), cubes);
            }
        }
        // The visible index travels in the first vertex: it must stay a u32 vertex index.
        let visible = u32::try_from(rec.scene.visible.len())
            .ok()
            .filter(|&n| n.checked_mul(CUBE_VERTICES).is_some())
            .ok_or_else(|| PassError::TooLarge("CubeRaster: too many visible instances".into()))?;
        // Always begin the pass, so its clears happen even when nothing is visible.
        let mut pass = begin_gbuffer_pass(encoder, rec, STENCIL_VOXEL);
        pass.set_pipeline(&self.pipeline.pipeline);
        pass.set_bind_group(0, &rec.scene.bind_group, &[]);
        for (i, v) in (0..visible).zip(&rec.scene.visible) {
            let cubes = &self.levels[&(v.object, v.level)];
            if let Some(bg) = &cubes.bind_group {
                pass.set_bind_group(1, bg, &[]);
                let first = i * CUBE_VERTICES;
                pass.draw(first..first + CUBE_VERTICES, 0..cubes.count);
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn shader_declares_the_cubes_as_the_voxel_crate_packs_them() {
        let src = ssbvb_gpu::shaders::source("cube_raster.wgsl").unwrap();
        assert!(src.contains("var<storage, read> cubes: array<Cube>"));
        assert!(src.contains("vi / 18u"));
        assert_eq!(super::CUBE_VERTICES, 18);
        assert_eq!(
            std::mem::size_of::<ssbvb_voxel::cube_list::Cube>(),
            ssbvb_voxel::cube_list::CUBE_BYTES
        );
        assert_eq!(ssbvb_voxel::cube_list::CUBE_BYTES, 8, "Cube is two u32s");
    }
}
