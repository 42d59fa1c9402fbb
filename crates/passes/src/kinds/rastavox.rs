//! `rastavox`: RastaVox on the same data (`RastaVox`; `shaders/rastavox.wgsl`).
//!
//! The first frame an (object, level) is visible, its surface model is built on the GPU
//! ([`SurfaceBuilder`]: 4-byte surface voxels with face masks in chunks of at most 256³,
//! the OR-merged LOD chain) and kept. Every frame, per visible instance, the chunks the
//! camera sees get their pixel-error LOD ([`select_chunks`]) and one instanced draw each:
//! 18 vertices per voxel (at most three faces face a viewer), faces not in the voxel's mask
//! collapsed, into the G-buffer with the billboards' attachments and stencil = voxel (see
//! [`crate::kinds::triangles`] for the rules). The per-frame draw table (instance, LOD grid level,
//! chunk origin) is the only upload.
//!
//! # Limits
//!
//! - No MSAA: the shared G-buffer is single-sampled (smoothing and the composite read
//!   exact per-pixel positions and normals; resolving them would average unlike things).
//! - A camera inside a voxel sees none of its faces, as with the cube rasterizer.
//! - Point clouds beyond the device's storage-binding limit are refused
//!   ([`PassError::TooLarge`]).

use std::collections::HashMap;

use glam::DAffine3;
use ssbvb_gpu::{GpuContext, wgpu};
use ssbvb_graph::RastaVoxParams;
use ssbvb_voxel::surface::select_chunks;

use crate::runtime::registry::{OwnBinding, OwnKind};
use crate::runtime::recorder::Recorder;
use crate::kinds::gbuffer::{PulledPipeline, STENCIL_VOXEL, begin_gbuffer_pass};
use crate::runtime::registry::{KindNeeds, PassImpl, PassInit};
use ssbvb_gpu_build::surface_build::{GpuSurface, SurfaceBuilder};
use crate::error::PassError;
use crate::runtime::node::PassNode;

/// Vertices per voxel: two triangles on the camera side of each axis.
const VOXEL_VERTICES: u32 = 18;
/// Bytes of one draw-table entry (WGSL `Draw`).
const DRAW_BYTES: u64 = 32;

/// What the pass binds itself: the draw table and the drawn LOD's voxels and attributes.
pub const OWN: &[OwnBinding] = &[
    OwnBinding {
        name: "draws",
        kind: OwnKind::StorageRead,
    },
    OwnBinding {
        name: "surface",
        kind: OwnKind::StorageRead,
    },
    OwnBinding {
        name: "attrs",
        kind: OwnKind::StorageRead,
    },
];

/// One draw of one frame.
struct Draw {
    model: (usize, u32),
    k: usize,
    first: u32,
    count: u32,
}

/// The compiled pass, its surface models and its draw table.
pub struct RastaVox {
    pipeline: PulledPipeline,
    pixel_error: f32,
    builder: Option<SurfaceBuilder>,
    /// (object, level) → its surface model.
    models: HashMap<(usize, u32), GpuSurface>,
    /// The draw table and its capacity in entries.
    draws: Option<(wgpu::Buffer, u64)>,
    /// (object, level, LOD) → group 1 over the current draw table.
    groups: HashMap<(usize, u32, usize), wgpu::BindGroup>,
}

impl PassImpl for RastaVox {
    type Params = RastaVoxParams;
    const SHADER: &'static str = "rastavox.wgsl";
    const OWN: &'static [OwnBinding] = OWN;
    const NEEDS: KindNeeds = KindNeeds::new(wgpu::DownlevelFlags::COMPUTE_SHADERS, 3);
    const WHOLE_LEVELS: bool = true;

    fn new(init: &PassInit<'_>, params: &RastaVoxParams) -> Result<Self, PassError> {
        Ok(Self {
            pipeline: PulledPipeline::new::<Self>(init, &[])?,
            pixel_error: params.pixel_error,
            builder: None,
            models: HashMap::new(),
            draws: None,
            groups: HashMap::new(),
        })
    }
}

impl RastaVox {
    /// Builds the surface models of the (object, level) pairs visible this frame.
    fn build_missing(&mut self, rec: &Recorder<'_>) -> Result<(), PassError> {
        for v in &rec.scene.visible {
            let key = (v.object, v.level);
            if self.models.contains_key(&key) {
                continue;
            }
            if self.builder.is_none() {
                self.builder = Some(SurfaceBuilder::new(rec.gpu)?);
            }
            let asset = &rec.scene.scene.objects[v.object].asset;
            let lod = asset.lods.get(v.level as usize).ok_or_else(|| {
                PassError::BadScene(format!("RastaVox: the asset has no level {}", v.level))
            })?;
            let builder = self.builder.as_ref().expect("created above");
            let model = builder.build(rec.gpu, lod)?;
            self.models.insert(key, model);
        }
        Ok(())
    }

    /// The draw table for this frame (entries as WGSL `Draw`) and the draws.
    fn plan(&self, rec: &Recorder<'_>) -> (Vec<u32>, Vec<Draw>) {
        let transforms: Vec<DAffine3> = rec
            .scene
            .scene
            .objects
            .iter()
            .flat_map(|o| o.instances.iter().copied())
            .collect();
        let mut table = Vec::new();
        let mut draws = Vec::new();
        for (vi, v) in rec.scene.visible.iter().enumerate() {
            let model = &self.models[&(v.object, v.level)];
            let Some(xf) = transforms.get(v.scene_index as usize) else {
                continue;
            };
            let chunks = select_chunks(
                model.level,
                model.chunk_log2,
                &model.bounds,
                xf,
                &rec.scene.camera,
                rec.screen,
                self.pixel_error,
            );
            for c in chunks {
                let [first, count] = model.levels[c.k].ranges[c.chunk];
                if count == 0 {
                    continue;
                }
                let shift = model.chunk_log2 - c.k as u32;
                let origin = model.chunks[c.chunk].map(|x| x << shift);
                table.extend([
                    vi as u32,
                    model.level - c.k as u32,
                    0,
                    0,
                    origin[0],
                    origin[1],
                    origin[2],
                    0,
                ]);
                draws.push(Draw {
                    model: (v.object, v.level),
                    k: c.k,
                    first,
                    count,
                });
            }
        }
        (table, draws)
    }

    /// Uploads the draw table, growing it (and dropping the groups bound to the old one)
    /// when it does not fit.
    fn upload_table(&mut self, ctx: &GpuContext, table: &[u32]) -> &wgpu::Buffer {
        let entries = (table.len() as u64 * 4).div_ceil(DRAW_BYTES).max(1);
        if self.draws.as_ref().is_none_or(|(_, cap)| *cap < entries) {
            let cap = entries.next_power_of_two();
            let buffer = ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("rastavox draws"),
                size: cap * DRAW_BYTES,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            self.draws = Some((buffer, cap));
            self.groups.clear();
        }
        let (buffer, _) = self.draws.as_ref().expect("set above");
        if !table.is_empty() {
            ctx.queue
                .write_buffer(buffer, 0, bytemuck::cast_slice(table));
        }
        buffer
    }
}

impl PassNode for RastaVox {
    fn record(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        rec: &mut Recorder<'_>,
    ) -> Result<(), PassError> {
        self.build_missing(rec)?;
        let (table, draws) = self.plan(rec);
        // The draw index travels in the first vertex: it must stay a u32 vertex index.
        if u32::try_from(draws.len())
            .ok()
            .and_then(|n| n.checked_mul(VOXEL_VERTICES))
            .is_none()
        {
            return Err(PassError::TooLarge("RastaVox: too many chunk draws".into()));
        }
        let table_buffer = self.upload_table(rec.gpu, &table).clone();
        for dr in &draws {
            let key = (dr.model.0, dr.model.1, dr.k);
            if self.groups.contains_key(&key) {
                continue;
            }
            let level = &self.models[&dr.model].levels[dr.k];
            let group = rec.gpu.validated("rastavox group", |d| {
                self.pipeline.bindings.own_bind_group(
                    d,
                    "rastavox",
                    &[
                        ("draws", table_buffer.as_entire_binding()),
                        ("surface", level.surface.as_entire_binding()),
                        ("attrs", level.attrs.as_entire_binding()),
                    ],
                )
            })??;
            self.groups.insert(key, group);
        }
        // Always begin the pass, so its clears happen even when nothing is visible.
        let mut pass = begin_gbuffer_pass(encoder, rec, STENCIL_VOXEL);
        pass.set_pipeline(&self.pipeline.pipeline);
        pass.set_bind_group(0, &rec.scene.bind_group, &[]);
        for (i, dr) in draws.iter().enumerate() {
            pass.set_bind_group(1, &self.groups[&(dr.model.0, dr.model.1, dr.k)], &[]);
            let first = i as u32 * VOXEL_VERTICES;
            pass.draw(first..first + VOXEL_VERTICES, dr.first..dr.first + dr.count);
        }
        Ok(())
    }
}
