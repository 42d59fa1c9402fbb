//! `cone_trace`: voxel cone tracing (`ConeTrace`; `shaders/cone_trace.wgsl`): light from
//! the voxels.
//!
//! At construction the pass builds the pre-filtered scene volume on the CPU
//! ([`ssbvb_voxel::lighting::volume::RadianceVolume`], isotropic mips) from every instance
//! of every voxel object, lit by the scene's light, and uploads it as one mipmapped
//! `Rgba16Float` 3D texture. Each frame a fullscreen draw reads the G-buffer (albedo for
//! coverage, normal, camera-relative position) and writes `occlusion` (r: AO, g: light
//! visibility) and `indirect` (one-bounce radiance); `ConeComposite` lights with them.
//! Voxel and triangle pixels alike receive; voxel objects alone occlude and emit.
//!
//! # Limits
//!
//! - The volume is built from the objects' CPU assets, once: objects whose voxels change on
//!   the GPU (dynamic objects) and scenes paged under a GPU budget are refused
//!   ([`PassImpl::WHOLE_LEVELS`]); the light is the scene's at construction.
//! - Resolution is a knob (cells along the scene's longest axis, at most
//!   `MAX_VOLUME_RESOLUTION`); a scene much wider than tall wastes none of it, but a sparse
//!   scene spread far gets coarse cells: AO of detail smaller than a cell is lost.

use bytemuck::{Pod, Zeroable};
use glam::DVec3;
use ssbvb_gpu::requirements::max_texture_dimension_3d;
use ssbvb_gpu::{GpuContext, wgpu};
use ssbvb_graph::ConeTraceParams;
use ssbvb_voxel::lighting::cone_directions;
use ssbvb_voxel::lighting::volume::{RadianceVolume, VolumeInstance, mip_dims};

use crate::error::PassError;
use crate::runtime::bindings::PassBindings;
use crate::runtime::node::PassNode;
use crate::runtime::pipelines::{RenderSpec, pipeline_layout, render_pipeline};
use crate::runtime::recorder::{Recorder, slot_format};
use crate::runtime::registry::{KindNeeds, PassImpl, PassInit};
use crate::runtime::registry::{OwnBinding, OwnKind};
use ssbvb_gpu::scene::Scene;
use ssbvb_gpu::shaders;

/// Distance of the cone origins from the receiver along its normal, in finest cells: the
/// receiver's own cell and the solid behind it are opaque, and a trilinear lookup reaches a
/// cell further: 1 cell over-occludes voxel receivers, 3 start to miss contact occlusion
/// (AO error against Monte Carlo, docs/benchmarks.md).
pub const START_OFFSET_CELLS: f32 = 2.0;
/// Distance of a cone's first sample from its origin, in finest cells.
pub const FIRST_SAMPLE_CELLS: f32 = 1.0;

/// What the pass binds itself: the volume, its trilinear sampler and the constants.
pub const OWN: &[OwnBinding] = &[
    OwnBinding {
        name: "volume",
        kind: OwnKind::Texture3dFloat,
    },
    OwnBinding {
        name: "volume_sampler",
        kind: OwnKind::Sampler(wgpu::SamplerBindingType::Filtering),
    },
    OwnBinding {
        name: "cone",
        kind: OwnKind::Uniform,
    },
];

/// `Cone` in `cone_trace.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub struct ConeUniform {
    origin: [f32; 4],
    inv_extent: [f32; 4],
    knobs: [f32; 4],
    misc: [f32; 4],
    dirs: [[f32; 4]; 64],
}

/// The compiled pass and its volume.
pub struct ConeTrace {
    pipeline: wgpu::RenderPipeline,
    bindings: PassBindings,
    view: wgpu::TextureView,
    sampler: wgpu::Sampler,
    uniform: wgpu::Buffer,
    constants: ConeUniform,
    /// The volume's low corner in world space (made camera-relative each frame).
    origin: DVec3,
    /// Bytes of the volume texture (all mips).
    pub volume_bytes: u64,
    /// Cells per axis of the finest level.
    pub dims: [u32; 3],
}

/// The volume instances of every object of `scene`, at every placement.
pub fn volume_instances(scene: &Scene) -> Vec<VolumeInstance<'_>> {
    scene
        .objects
        .iter()
        .flat_map(|o| {
            o.instances.iter().map(|&m| VolumeInstance {
                asset: &o.asset,
                object_to_world: m,
            })
        })
        .collect()
}

/// The targets are the screen or a whole fraction of it (`ScreenScaled(1/k)`): texel q
/// lights pixel q·k, a mapping the composite and the measurement share. Any other size
/// would leave pixels no texel traces.
fn check_target_size(
    pipeline: &ssbvb_graph::ResolvedPipeline,
    pass: &ssbvb_graph::ScheduledPass,
) -> Result<(), PassError> {
    use ssbvb_graph::{ResourceDesc, SizeDesc};
    for slot in ["occlusion", "indirect"] {
        let Some(r) = pass.resource_of(slot).map(|i| &pipeline.resources[i]) else {
            continue;
        };
        let ResourceDesc::Texture { size, .. } = r.desc else {
            continue;
        };
        let whole = match size {
            SizeDesc::Screen => true,
            SizeDesc::ScreenScaled(f) => {
                let k = 1.0 / f64::from(f);
                f > 0.0 && f <= 1.0 && (k - k.round()).abs() < 1e-6
            }
            SizeDesc::Fixed(..) => false,
        };
        if !whole {
            return Err(PassError::BadScene(format!(
                "pass `{}`: its target `{}` is {size:?}; cone tracing needs `Screen` or \
                 `ScreenScaled(1/k)` for a whole k (0.5, 0.25, ...)",
                pass.name, r.name
            )));
        }
    }
    Ok(())
}

fn upload(ctx: &GpuContext, v: &RadianceVolume) -> Result<wgpu::Texture, PassError> {
    let limit = ctx.device.limits().max_texture_dimension_3d;
    if v.dims.iter().any(|&d| d > limit) {
        return Err(PassError::TooLarge(format!(
            "the cone tracer's scene volume of {:?} cells exceeds the device's 3D texture \
             size {limit}; lower `resolution`",
            v.dims
        )));
    }
    let texture = ctx.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("cone volume"),
        size: wgpu::Extent3d {
            width: v.dims[0],
            height: v.dims[1],
            depth_or_array_layers: v.dims[2],
        },
        mip_level_count: v.mips.len() as u32,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D3,
        format: wgpu::TextureFormat::Rgba16Float,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    for (k, texels) in v.mips.iter().enumerate() {
        let [w, h, d] = mip_dims(v.dims, k as u32);
        let bytes: Vec<u8> = texels
            .iter()
            .flat_map(|t| t.map(|c| half::f16::from_f32(c).to_bits()))
            .flat_map(u16::to_le_bytes)
            .collect();
        ctx.queue.write_texture(
            wgpu::TexelCopyTextureInfo {
                texture: &texture,
                mip_level: k as u32,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            &bytes,
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(w * 8),
                rows_per_image: Some(h),
            },
            wgpu::Extent3d {
                width: w,
                height: h,
                depth_or_array_layers: d,
            },
        );
    }
    Ok(texture)
}

impl PassImpl for ConeTrace {
    type Params = ConeTraceParams;
    const SHADER: &'static str = "cone_trace.wgsl";
    const OWN: &'static [OwnBinding] = OWN;
    const NEEDS: KindNeeds = KindNeeds {
        limit: Some(max_texture_dimension_3d(
            ssbvb_graph::MAX_VOLUME_RESOLUTION as u64,
        )),
        ..KindNeeds::NONE
    };
    const WHOLE_LEVELS: bool = true;

    fn new(init: &PassInit<'_>, params: &ConeTraceParams) -> Result<Self, PassError> {
        let (ctx, scene, pipeline, pass) = (init.ctx, init.scene, init.pipeline, init.pass);
        let d = &ctx.device;
        check_target_size(pipeline, pass)?;
        let volume = RadianceVolume::build(
            &volume_instances(&scene.scene),
            &scene.scene.light,
            params.resolution,
        );
        let texture = upload(ctx, &volume)?;
        let view = texture.create_view(&Default::default());
        let sampler = d.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("cone volume"),
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            mipmap_filter: wgpu::MipmapFilterMode::Linear,
            ..Default::default()
        });
        let extent = DVec3::from(volume.dims.map(f64::from)) * volume.cell;
        let tan_half = |deg: f32| (f64::from(deg).to_radians() * 0.5).tan() as f32;
        let mut dirs = [[0f32; 4]; 64];
        for (slot, d) in dirs.iter_mut().zip(cone_directions(params.cones)) {
            *slot = [d[0], d[1], d[2], 0.0];
        }
        let constants = ConeUniform {
            origin: [0.0, 0.0, 0.0, volume.cell as f32],
            inv_extent: [
                (1.0 / extent.x) as f32,
                (1.0 / extent.y) as f32,
                (1.0 / extent.z) as f32,
                volume.exact_levels().saturating_sub(1) as f32,
            ],
            knobs: [
                params.max_distance,
                tan_half(params.aperture),
                params.step_scale,
                tan_half(params.shadow_aperture),
            ],
            misc: [
                params.cones as f32,
                START_OFFSET_CELLS,
                FIRST_SAMPLE_CELLS,
                0.0,
            ],
            dirs,
        };
        let uniform = d.create_buffer(&wgpu::BufferDescriptor {
            label: Some("cone constants"),
            size: std::mem::size_of::<ConeUniform>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let module = ctx.shader("cone_trace.wgsl", &shaders::source_for("cone_trace.wgsl", &scene.bindings)?)?;
        let bindings = PassBindings::new(ctx, pipeline, pass, OWN);
        let layout = pipeline_layout(d, "cone_trace", scene, Some(&bindings));
        let targets = [
            Some(slot_format(ctx, pipeline, pass, "occlusion").into()),
            Some(slot_format(ctx, pipeline, pass, "indirect").into()),
        ];
        let pipeline = render_pipeline(
            d,
            &RenderSpec::new("cone_trace", &module, &layout, &targets),
        );
        Ok(Self {
            pipeline,
            bindings,
            view,
            sampler,
            uniform,
            constants,
            origin: volume.origin,
            volume_bytes: volume.bytes(),
            dims: volume.dims,
        })
    }
}

impl PassNode for ConeTrace {
    fn record(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        rec: &mut Recorder<'_>,
    ) -> Result<(), PassError> {
        // Camera-relative like every GPU position (subtracted in f64).
        let o = self.origin - rec.scene.camera.position;
        self.constants.origin[..3].copy_from_slice(&[o.x as f32, o.y as f32, o.z as f32]);
        // Targets smaller than the G-buffer (e.g. `ScreenScaled(0.5)`) trace one pixel of
        // each block.
        let target = rec.texture("occlusion").texture.width().max(1);
        let gbuffer = rec.texture("albedo").texture.width();
        self.constants.misc[3] = (gbuffer as f32 / target as f32).round().max(1.0);
        rec.gpu
            .queue
            .write_buffer(&self.uniform, 0, bytemuck::bytes_of(&self.constants));
        let bg = self.bindings.bind_group(
            rec,
            &[
                ("volume", wgpu::BindingResource::TextureView(&self.view)),
                (
                    "volume_sampler",
                    wgpu::BindingResource::Sampler(&self.sampler),
                ),
                ("cone", self.uniform.as_entire_binding()),
            ],
        )?;
        rec.draw_fullscreen(
            encoder,
            &[
                rec.color_attachment("occlusion"),
                rec.color_attachment("indirect"),
            ],
            &self.pipeline,
            &bg,
        );
        Ok(())
    }
}
