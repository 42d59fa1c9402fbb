//! `dense_dda`: the dense-DDA baseline (`DenseDda`; `shaders/dense_dda.wgsl`).
//!
//! A render pass drawing one fullscreen triangle into the G-buffer (the same attachments,
//! formats, clear/load rules, `Greater` depth test and stencil = voxel as the billboards;
//! see [`crate::kinds::triangles`]): per pixel the fragment shader casts the pixel's ray through
//! every visible instance with a plain cell-by-cell Amanatides–Woo DDA over a **dense**
//! `R32Uint` 3D texture (voxel id + 1, 0 = empty) and writes the nearest hit with its exact
//! depth (`frag_depth`), the voxel's stored normal and the entered face's (`crate::kinds::gbuffer`).
//! The shared smoothing and composite
//! run after it unchanged.
//!
//! Every (object, level) pair a visible instance uses has its dense grid in one `R32Uint`
//! 3D atlas texture (voxel id + 1, 0 = empty): the grids stacked along z, each at the
//! x = y = 0 corner, written page by page from the asset's sparse lookup with
//! `queue.write_texture`. An instance finds its grid's first slice in `dense_slices`
//! (indexed by LOD-table entry; `u32::MAX`: not in the atlas). The atlas is rebuilt, with
//! the union of the old and the new pairs, the first frame a new pair is visible (with the
//! new ones only when the union would pass the device's 3D texture depth).
//!
//! # Limits
//!
//! - Levels above [`MAX_DENSE_LEVEL`] (8: 256³ cells × 4 bytes = 64 MiB) are refused with
//!   [`PassError::TooLarge`], as is an atlas deeper than the device allows.
//! - Cost per pixel: the instances whose boxes its ray enters before its best hit (the
//!   instance hierarchy) × the cells along the ray: no empty-space skipping.

use std::collections::BTreeSet;

use ssbvb_gpu::requirements::max_texture_dimension_3d;
use ssbvb_gpu::{GpuContext, wgpu};
use ssbvb_graph::DenseDdaParams;
use ssbvb_voxel::asset::{PAGE_SIZE, SparseLookup};

use crate::runtime::registry::{OwnBinding, OwnKind};
use crate::runtime::counters::FrameCounters;
use crate::kinds::ray_cast_counters::RayCastCounters;
use crate::runtime::recorder::Recorder;
use crate::kinds::gbuffer::PulledPipeline;
use ssbvb_gpu::scene::GpuScene;
use crate::runtime::registry::{KindNeeds, PassImpl, PassInit};
use crate::error::PassError;
use crate::runtime::node::{CounterSource, PassNode};

/// The finest level a dense texture is built for (256³ `u32` = 64 MiB).
pub const MAX_DENSE_LEVEL: u32 = 8;

/// What the dense-DDA pass binds itself: the atlas of dense grids and each LOD's first
/// slice in it.
pub const OWN: &[OwnBinding] = &[
    OwnBinding {
        name: "dense",
        kind: OwnKind::Texture3dUint,
    },
    OwnBinding {
        name: "dense_slices",
        kind: OwnKind::StorageRead,
    },
    OwnBinding {
        name: "ray_counters",
        kind: OwnKind::StorageReadWrite,
    },
];

/// The compiled dense-DDA pass and its atlas.
pub struct DenseDda {
    pipeline: PulledPipeline,
    atlas: Option<Atlas>,
    counters: RayCastCounters,
}

/// The dense grids of some (object, level) pairs, stacked along z.
struct Atlas {
    pairs: BTreeSet<GridKey>,
    bind_group: wgpu::BindGroup,
}

/// An (object, level) pair: one dense grid of the atlas.
pub type GridKey = (usize, u32);

/// Where each pair's grid starts along z (pairs in order), the atlas's width (the largest
/// grid's edge) and depth (the sum of the edges).
pub fn atlas_layout(pairs: &BTreeSet<GridKey>) -> (Vec<(GridKey, u32)>, u32, u32) {
    let mut z = 0u32;
    let mut width = 1u32;
    let mut out = Vec::with_capacity(pairs.len());
    for &(object, level) in pairs {
        let n = 1u32 << level;
        out.push(((object, level), z));
        z += n;
        width = width.max(n);
    }
    (out, width, z.max(1))
}

impl DenseDda {
    /// The (object, level) pairs of the visible instances; levels above
    /// [`MAX_DENSE_LEVEL`] are refused.
    fn needed(scene: &GpuScene) -> Result<BTreeSet<GridKey>, PassError> {
        let mut pairs = BTreeSet::new();
        for v in &scene.visible {
            if v.level > MAX_DENSE_LEVEL {
                return Err(PassError::TooLarge(format!(
                    "DenseDda: object {} at level {} needs a dense {n}³ texture ({} MiB); the \
                     dense baseline supports levels up to {MAX_DENSE_LEVEL} (256³, 64 MiB)",
                    v.object,
                    v.level,
                    ((1u64 << (3 * v.level)) * 4) >> 20,
                    n = 1u64 << v.level,
                )));
            }
            pairs.insert((v.object, v.level));
        }
        Ok(pairs)
    }

    /// Builds the atlas of `pairs` and its bind group.
    fn build(&self, rec: &Recorder<'_>, pairs: BTreeSet<GridKey>) -> Result<Atlas, PassError> {
        let ctx = rec.gpu;
        let scene = rec.scene;
        let (layout, width, depth) = atlas_layout(&pairs);
        let max = ctx.device.limits().max_texture_dimension_3d;
        if depth > max || width > max {
            return Err(PassError::TooLarge(format!(
                "DenseDda: the visible levels need a {width}×{width}×{depth} atlas; the device \
                 allows 3D textures up to {max}: use fewer levels (a fixed LOD)"
            )));
        }
        let label = "dense_dda atlas";
        let texture = ctx.validated(label, |d| {
            d.create_texture(&wgpu::TextureDescriptor {
                label: Some(label),
                size: wgpu::Extent3d {
                    width,
                    height: width,
                    depth_or_array_layers: depth,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D3,
                format: wgpu::TextureFormat::R32Uint,
                usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
                view_formats: &[],
            })
        })?;
        let lod_count = scene.lod_bounds.len().max(1);
        let mut slices = vec![u32::MAX; lod_count];
        for ((object, level), z) in layout {
            let lod = &scene.scene.objects[object].asset.lods[level as usize];
            write_grid(ctx, &texture, z, &lod.lookup);
            slices[scene.lod_base[object] as usize + level as usize] = z;
        }
        let view = texture.create_view(&Default::default());
        let bind_group = ctx.validated(label, |d| {
            let slices = ssbvb_gpu::InitBuffer::init_buffer(
                d,
                &wgpu::util::BufferInitDescriptor {
                    label: Some("dense_dda slices"),
                    contents: bytemuck::cast_slice(&slices),
                    usage: wgpu::BufferUsages::STORAGE,
                },
            );
            self.pipeline.bindings.own_bind_group(
                d,
                "dense_dda",
                &[
                    ("dense", wgpu::BindingResource::TextureView(&view)),
                    ("dense_slices", slices.as_entire_binding()),
                    ("ray_counters", self.counters.binding()),
                ],
            )
        })??;
        Ok(Atlas { pairs, bind_group })
    }
}

/// Writes a lookup's dense grid (voxel id + 1, 0 empty) into the atlas from slice `z0`,
/// one 16³ block at a time (empty blocks stay zero). Cells come in Morton order, which
/// keeps each block's cells together and makes the `i`-th cell voxel `i`.
fn write_grid(ctx: &GpuContext, texture: &wgpu::Texture, z0: u32, lookup: &SparseLookup) {
    let n = 1u32 << lookup.level;
    // A block's extent (levels below 4: the grid is smaller than a block).
    let e = n.min(PAGE_SIZE);
    let mut block = vec![0u32; (e * e * e) as usize];
    let write = |origin: [u32; 3], block: &[u32]| {
        ctx.queue.write_texture(
            wgpu::TexelCopyTextureInfo {
                texture,
                mip_level: 0,
                origin: wgpu::Origin3d {
                    x: origin[0] * e,
                    y: origin[1] * e,
                    z: z0 + origin[2] * e,
                },
                aspect: wgpu::TextureAspect::All,
            },
            bytemuck::cast_slice(block),
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(e * 4),
                rows_per_image: Some(e),
            },
            wgpu::Extent3d {
                width: e,
                height: e,
                depth_or_array_layers: e,
            },
        );
    };
    let mut current: Option<[u32; 3]> = None;
    for (id, c) in lookup.cells().into_iter().enumerate() {
        let b = c.map(|v| v / e);
        if current.is_some_and(|cur| cur != b) {
            write(current.unwrap_or_default(), &block);
            block.fill(0);
        }
        current = Some(b);
        let l = c.map(|v| v % e);
        block[(l[0] + e * (l[1] + e * l[2])) as usize] = id as u32 + 1;
    }
    if let Some(cur) = current {
        write(cur, &block);
    }
}

impl PassImpl for DenseDda {
    type Params = DenseDdaParams;
    const SHADER: &'static str = "dense_dda.wgsl";
    const OWN: &'static [OwnBinding] = OWN;
    const NEEDS: KindNeeds = KindNeeds {
        limit: Some(max_texture_dimension_3d(1 << MAX_DENSE_LEVEL)),
        // The counters are written in the fragment shader.
        ..KindNeeds::new(wgpu::DownlevelFlags::FRAGMENT_WRITABLE_STORAGE, 2)
    };

    /// Compiles the pipeline for the formats bound to `pass`; `max_steps` becomes the WGSL
    /// override `MAX_STEPS`.
    const WHOLE_LEVELS: bool = true;

    fn new(init: &PassInit<'_>, params: &DenseDdaParams) -> Result<Self, PassError> {
        let max_steps = params.max_steps;
        Ok(Self {
            pipeline: PulledPipeline::counting::<Self>(init, &[("MAX_STEPS", f64::from(max_steps))])?,
            atlas: None,
            counters: RayCastCounters::new(init.ctx),
        })
    }
}

impl PassNode for DenseDda {
    fn record(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        rec: &mut Recorder<'_>,
    ) -> Result<(), PassError> {
        let needed = Self::needed(rec.scene)?;
        let missing = self
            .atlas
            .as_ref()
            .is_none_or(|a| !needed.is_subset(&a.pairs));
        if missing && !needed.is_empty() {
            let mut union = needed.clone();
            if let Some(a) = &self.atlas {
                union.extend(a.pairs.iter().copied());
            }
            let max = rec.gpu.device.limits().max_texture_dimension_3d;
            // Keep what was built unless the atlas would grow past the device's depth.
            let pairs = if atlas_layout(&union).2 <= max {
                union
            } else {
                needed.clone()
            };
            self.atlas = Some(self.build(rec, pairs)?);
        }
        let bind_group = self
            .atlas
            .as_ref()
            .filter(|_| !needed.is_empty())
            .map(|a| &a.bind_group);
        self.counters.begin_frame(encoder, rec.counting);
        self.pipeline.record_fullscreen(encoder, rec, bind_group);
        Ok(())
    }

    fn counters(&self, frame: &CounterSource<'_>, out: &mut FrameCounters) -> Result<(), PassError> {
        if let Some(c) = self.counters.read(frame.gpu)? {
            out.ray_cast_rays = Some(c.rays);
            out.dda_steps_per_ray = c.steps_per_ray;
            out.node_words_per_step = c.words_per_step;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn shader_declares_max_steps_and_the_voxel_stencil() {
        // Bindings and struct layouts are checked by `cargo xtask validate-shaders`.
        let src = ssbvb_gpu::shaders::source("dense_dda.wgsl").unwrap();
        assert!(src.contains("override MAX_STEPS: u32"));
        assert!(src.contains("const STENCIL_VOXEL: u32 = 1u;"));
        assert_eq!(crate::kinds::gbuffer::STENCIL_VOXEL, 1);
    }

    #[test]
    fn atlas_stacks_the_grids_along_z() {
        let pairs: std::collections::BTreeSet<(usize, u32)> =
            [(1, 3), (0, 5), (0, 2)].into_iter().collect();
        let (layout, width, depth) = super::atlas_layout(&pairs);
        assert_eq!(layout, vec![((0, 2), 0), ((0, 5), 4), ((1, 3), 36)]);
        assert_eq!((width, depth), (32, 44));
        assert_eq!(super::atlas_layout(&Default::default()), (vec![], 1, 1));
    }
}
