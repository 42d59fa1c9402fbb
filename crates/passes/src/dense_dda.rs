//! `dense_dda`: the dense-DDA baseline (`DenseDda`; `shaders/dense_dda.wgsl`).
//!
//! A render pass drawing one fullscreen triangle into the G-buffer (the same attachments,
//! formats, clear/load rules, `Greater` depth test and stencil = voxel as the billboards;
//! see [`crate::triangles`]): per pixel the fragment shader casts the pixel's ray through
//! every visible instance with a plain cell-by-cell Amanatides–Woo DDA over a **dense**
//! `R32Uint` 3D texture (voxel id + 1, 0 = empty) and writes the nearest hit with its exact
//! depth (`frag_depth`) and the entered face's normal. The shared smoothing and composite
//! run after it unchanged.
//!
//! The dense texture of an (object, level) pair is built lazily, the first frame it is
//! needed, from the asset's sparse lookup: each resident 16³ page is written with
//! `queue.write_texture` into a zero-initialized texture, then cached for later frames.
//!
//! # Limits
//!
//! - Levels above [`MAX_DENSE_LEVEL`] (8: 256³ cells × 4 bytes = 64 MiB) are refused with
//!   [`PassError::TooLarge`].
//! - One dense texture is bound per frame, so every visible instance must belong to the
//!   same object and use the same LOD level (e.g. `LodPolicy::Fixed`); otherwise the frame
//!   fails with [`PassError::BadScene`].
//! - Cost is O(instances × cells along the ray) per pixel: no empty-space skipping.

use std::collections::HashMap;

use ssbvb_gpu::requirements::max_texture_dimension_3d;
use ssbvb_gpu::{GpuContext, wgpu};
use ssbvb_graph::DenseDdaParams;
use ssbvb_voxel::asset::{EMPTY_PAGE, PAGE_CELLS, PAGE_SIZE, SparseLookup};

use crate::bindings::{OwnBinding, OwnKind};
use crate::frame::Recorder;
use crate::gbuffer::PulledPipeline;
use crate::gpu_scene::GpuScene;
use crate::registry::{KindNeeds, PassImpl, PassInit};
use crate::{PassError, PassNode};

/// The finest level a dense texture is built for (256³ `u32` = 64 MiB).
pub const MAX_DENSE_LEVEL: u32 = 8;

/// What the dense-DDA pass binds itself: the dense texture of the visible level.
pub const OWN: &[OwnBinding] = &[OwnBinding {
    name: "dense",
    kind: OwnKind::Texture3dUint,
}];

/// The compiled dense-DDA pass and its cache of dense textures.
pub struct DenseDda {
    pipeline: PulledPipeline,
    /// `(object, level)` → dense texture view.
    textures: HashMap<(usize, u32), wgpu::TextureView>,
}

impl DenseDda {
    /// The (object, level) every visible instance uses, or `None` when nothing is visible.
    fn chosen(scene: &GpuScene) -> Result<Option<(usize, u32)>, PassError> {
        let Some(first) = scene.visible.first() else {
            return Ok(None);
        };
        let key = (first.object, first.level);
        if let Some(other) = scene.visible.iter().find(|v| (v.object, v.level) != key) {
            return Err(PassError::BadScene(format!(
                "DenseDda binds one dense texture per frame: every visible instance must use \
                 the same object and level, but object {} level {} and object {} level {} are \
                 both visible (use one object and a fixed LOD)",
                key.0, key.1, other.object, other.level
            )));
        }
        if key.1 > MAX_DENSE_LEVEL {
            return Err(PassError::TooLarge(format!(
                "DenseDda: object {} at level {} needs a dense {n}³ texture ({} MiB); the \
                 dense baseline supports levels up to {MAX_DENSE_LEVEL} (256³, 64 MiB)",
                key.0,
                key.1,
                ((1u64 << (3 * key.1)) * 4) >> 20,
                n = 1u64 << key.1,
            )));
        }
        Ok(Some(key))
    }
}

/// A dense `R32Uint` texture of a lookup (voxel id + 1, 0 empty), written page by page.
fn dense_texture(ctx: &GpuContext, lookup: &SparseLookup) -> Result<wgpu::TextureView, PassError> {
    let n = 1u32 << lookup.level;
    let label = format!("dense_dda texture level {}", lookup.level);
    let texture = ctx.validated(&label, |d| {
        d.create_texture(&wgpu::TextureDescriptor {
            label: Some(&label),
            size: wgpu::Extent3d {
                width: n,
                height: n,
                depth_or_array_layers: n,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D3,
            format: wgpu::TextureFormat::R32Uint,
            usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        })
    })?;
    // A page's extent (levels below 4: the grid is smaller than its single page).
    let e = n.min(PAGE_SIZE);
    let ppa = lookup.pages_per_axis;
    let mut block = vec![0u32; (e * e * e) as usize];
    for pz in 0..ppa {
        for py in 0..ppa {
            for px in 0..ppa {
                let page = lookup.page_table[(px + ppa * (py + ppa * pz)) as usize];
                if page == EMPTY_PAGE {
                    continue;
                }
                let src = &lookup.pool[page as usize * PAGE_CELLS..][..PAGE_CELLS];
                for z in 0..e {
                    for y in 0..e {
                        let s = (PAGE_SIZE * (y + PAGE_SIZE * z)) as usize;
                        let t = (e * (y + e * z)) as usize;
                        block[t..t + e as usize].copy_from_slice(&src[s..s + e as usize]);
                    }
                }
                ctx.queue.write_texture(
                    wgpu::TexelCopyTextureInfo {
                        texture: &texture,
                        mip_level: 0,
                        origin: wgpu::Origin3d {
                            x: px * PAGE_SIZE,
                            y: py * PAGE_SIZE,
                            z: pz * PAGE_SIZE,
                        },
                        aspect: wgpu::TextureAspect::All,
                    },
                    bytemuck::cast_slice(&block),
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
            }
        }
    }
    Ok(texture.create_view(&Default::default()))
}

impl PassImpl for DenseDda {
    type Params = DenseDdaParams;
    const SHADER: &'static str = "dense_dda.wgsl";
    const OWN: &'static [OwnBinding] = OWN;
    const NEEDS: KindNeeds = KindNeeds {
        limit: Some(max_texture_dimension_3d(1 << MAX_DENSE_LEVEL)),
        ..KindNeeds::NONE
    };

    /// Compiles the pipeline for the formats bound to `pass`; `max_steps` becomes the WGSL
    /// override `MAX_STEPS`.
    fn new(init: &PassInit<'_>, params: &DenseDdaParams) -> Result<Self, PassError> {
        let max_steps = params.max_steps;
        Ok(Self {
            pipeline: PulledPipeline::new::<Self>(init, &[("MAX_STEPS", f64::from(max_steps))])?,
            textures: HashMap::new(),
        })
    }
}

impl PassNode for DenseDda {
    fn record(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        rec: &mut Recorder<'_>,
    ) -> Result<(), PassError> {
        let chosen = Self::chosen(rec.scene)?;
        let bind_group = match chosen {
            Some((object, level)) => {
                let view = match self.textures.entry((object, level)) {
                    std::collections::hash_map::Entry::Occupied(e) => e.into_mut(),
                    std::collections::hash_map::Entry::Vacant(e) => {
                        let lod = &rec.scene.scene.objects[object].asset.lods[level as usize];
                        e.insert(dense_texture(rec.gpu, &lod.lookup)?)
                    }
                };
                Some(self.pipeline.bindings.own_bind_group(
                    &rec.gpu.device,
                    "dense_dda",
                    &[("dense", wgpu::BindingResource::TextureView(view))],
                )?)
            }
            None => None,
        };
        self.pipeline
            .record_fullscreen(encoder, rec, bind_group.as_ref());
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn shader_declares_max_steps_and_the_voxel_stencil() {
        // Bindings and struct layouts are checked by `cargo xtask validate-shaders`.
        let src = crate::shaders::source("dense_dda.wgsl").unwrap();
        assert!(src.contains("override MAX_STEPS: u32"));
        assert!(src.contains("const STENCIL_VOXEL: u32 = 1u;"));
        assert_eq!(crate::gbuffer::STENCIL_VOXEL, 1);
    }
}
