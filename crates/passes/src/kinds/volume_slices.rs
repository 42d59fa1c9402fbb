//! `VolumeSlices`: volumetric billboards. Every translucent RGBA volume of the
//! scene is cut into view-aligned slices on the CPU each frame
//! (`ssbvb_voxel::rgba_volume::slicing`: a mip level by distance, a spacing in its
//! texels, all slices of all volumes back to front), and one draw pulls the triangles
//! and blends them premultiplied "over", depth-tested (not written) against the opaque
//! depth, so opaque voxels and triangles hide what is behind them.
//!
//! The slices blend into the pass's own `Rgba16Float` target, cleared each frame, and a
//! fullscreen resolve lays that "over" the output colour ("over" is associative, so this
//! equals blending every slice into the colour). Hundreds of slices blended straight into
//! an 8-bit colour target round at every slice, which made a finer spacing less accurate,
//! not more (docs/architecture.md).
//!
//! The volumes live in one atlas of bricks with aprons
//! (`ssbvb_voxel::rgba_volume::atlas`, built when the pass is made): empty bricks are not
//! stored, and one hardware-filtered fetch per slice fragment gives the CPU reference's
//! trilinear sample (up to the GPU's filter-weight precision). A fragment corrects its
//! alpha from the texel's reference length to the slab its slice stands for along the
//! pixel's ray.

use bytemuck::{Pod, Zeroable};
use glam::DMat4;
use ssbvb_gpu::wgpu;
use ssbvb_gpu::InitBuffer;
use ssbvb_graph::VolumeSlicesParams;
use ssbvb_voxel::rgba_volume::atlas::VolumeAtlas;
use ssbvb_voxel::rgba_volume::slicing::{SliceGeometry, SliceSettings, slice};

use crate::runtime::bindings::PassBindings;
use crate::runtime::registry::{OwnBinding, OwnKind};
use crate::runtime::recorder::{Recorder, slot_format};
use crate::runtime::pipelines::{RenderSpec, pipeline_layout, render_pipeline};
use crate::runtime::registry::{KindNeeds, PassImpl, PassInit};
use crate::runtime::resources::render_target;
use crate::error::PassError;
use crate::runtime::node::PassNode;
use ssbvb_gpu::shaders;

/// What the pass binds itself.
pub const OWN: &[OwnBinding] = &[
    OwnBinding {
        name: "atlas",
        kind: OwnKind::Texture3dFloat,
    },
    OwnBinding {
        name: "atlas_sampler",
        kind: OwnKind::Sampler(wgpu::SamplerBindingType::Filtering),
    },
    OwnBinding {
        name: "brick_table",
        kind: OwnKind::StorageRead,
    },
    OwnBinding {
        name: "slice_volumes",
        kind: OwnKind::StorageRead,
    },
    OwnBinding {
        name: "slice_vertices",
        kind: OwnKind::StorageRead,
    },
    OwnBinding {
        name: "accumulated",
        kind: OwnKind::Texture2dFloat,
    },
];

/// The format the slices accumulate in.
const ACCUMULATION: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;

/// `SliceVolume` in volume_slices.wgsl: one placed volume this frame.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct SliceVolume {
    /// Camera-relative world → object space (column-major).
    to_object: [[f32; 4]; 4],
    /// The level's texels per axis; w: its first brick in `brick_table`.
    dims: [u32; 4],
    /// The level's bricks per axis.
    bricks: [u32; 4],
    /// x: the level's reference length in world units; y: the slice spacing along the
    /// view axis.
    lengths: [f32; 4],
}

/// The compiled pass and its atlas.
pub struct VolumeSlices {
    pipeline: wgpu::RenderPipeline,
    resolve: wgpu::RenderPipeline,
    bindings: PassBindings,
    /// The slices' target at the screen's size, and a 1×1 stand-in bound while it is the
    /// attachment.
    accumulated: Option<(wgpu::TextureView, (u32, u32))>,
    stand_in: wgpu::TextureView,
    view: wgpu::TextureView,
    sampler: wgpu::Sampler,
    table: wgpu::Buffer,
    atlas: VolumeAtlas,
    settings: SliceSettings,
    volumes: Option<wgpu::Buffer>,
    vertices: Option<wgpu::Buffer>,
    /// The last frame's slicing (levels, spacings, slice counts), for reports and tests.
    pub last: SliceGeometry,
}

impl VolumeSlices {
    /// Bytes of the atlas and its brick tables on the GPU.
    pub fn atlas_bytes(&self) -> u64 {
        u64::from(self.atlas.dims[0])
            * u64::from(self.atlas.dims[1])
            * u64::from(self.atlas.dims[2])
            * 4
            + self.atlas.table.len() as u64 * 4
    }
}

/// Whether `m`'s linear part is a rotation times one positive scale.
fn uniform_scale(m: &glam::DAffine3) -> bool {
    let c = [m.matrix3.x_axis, m.matrix3.y_axis, m.matrix3.z_axis];
    let s = c[0].length();
    let tol = 1e-6 * s;
    s > 0.0
        && s.is_finite()
        && c.iter().all(|a| (a.length() - s).abs() <= tol)
        && c[0].dot(c[1]).abs() <= tol * s
        && c[1].dot(c[2]).abs() <= tol * s
        && c[0].dot(c[2]).abs() <= tol * s
}

fn upload_atlas(
    ctx: &ssbvb_gpu::GpuContext,
    atlas: &VolumeAtlas,
) -> (wgpu::Texture, wgpu::Buffer) {
    let d = &ctx.device;
    let size = wgpu::Extent3d {
        width: atlas.dims[0],
        height: atlas.dims[1],
        depth_or_array_layers: atlas.dims[2],
    };
    let texture = d.create_texture(&wgpu::TextureDescriptor {
        label: Some("volume atlas"),
        size,
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D3,
        format: wgpu::TextureFormat::Rgba8Unorm,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    ctx.queue.write_texture(
        wgpu::TexelCopyTextureInfo {
            texture: &texture,
            mip_level: 0,
            origin: wgpu::Origin3d::ZERO,
            aspect: wgpu::TextureAspect::All,
        },
        bytemuck::cast_slice(&atlas.texels),
        wgpu::TexelCopyBufferLayout {
            offset: 0,
            bytes_per_row: Some(atlas.dims[0] * 4),
            rows_per_image: Some(atlas.dims[1]),
        },
        size,
    );
    // Never empty: a binding needs at least one word.
    let mut table = atlas.table.clone();
    table.push(ssbvb_voxel::rgba_volume::EMPTY_BRICK);
    let table = d.init_buffer(&wgpu::util::BufferInitDescriptor {
        label: Some("volume brick table"),
        contents: bytemuck::cast_slice(&table),
        usage: wgpu::BufferUsages::STORAGE,
    });
    (texture, table)
}

fn accumulation_target(ctx: &ssbvb_gpu::GpuContext, size: (u32, u32)) -> wgpu::TextureView {
    render_target(
        &ctx.device,
        "volume slices",
        size,
        ACCUMULATION,
        wgpu::TextureUsages::TEXTURE_BINDING,
    )
    .create_view(&Default::default())
}

/// The pixels the slices can cover (x, y, width, height), so that the resolve touches only
/// those: the screen when a slice vertex is behind the eye, `None` when nothing is drawn.
fn screen_rect(
    g: &SliceGeometry,
    camera: &ssbvb_voxel::camera::Camera,
    size: (u32, u32),
) -> Option<[u32; 4]> {
    if g.vertices.is_empty() || size.0 == 0 || size.1 == 0 {
        return None;
    }
    let full = Some([0, 0, size.0, size.1]);
    let vp = camera.view_projection(f64::from(size.0) / f64::from(size.1));
    let (mut lo, mut hi) = (glam::DVec2::splat(f64::INFINITY), glam::DVec2::splat(f64::NEG_INFINITY));
    for (p, _) in &g.vertices {
        let w = camera.position + glam::DVec3::new(p[0].into(), p[1].into(), p[2].into());
        let c = vp * w.extend(1.0);
        if c.w.is_nan() || c.w <= 1e-9 {
            return full;
        }
        let ndc = glam::DVec2::new(c.x / c.w, c.y / c.w);
        lo = lo.min(ndc);
        hi = hi.max(ndc);
    }
    // NDC y up, pixels y down; one pixel of margin for rasterization rounding.
    let px = |x: f64, y: f64| {
        (
            ((x * 0.5 + 0.5) * f64::from(size.0)).clamp(0.0, f64::from(size.0)),
            ((0.5 - y * 0.5) * f64::from(size.1)).clamp(0.0, f64::from(size.1)),
        )
    };
    let (x0, y1) = px(lo.x, lo.y);
    let (x1, y0) = px(hi.x, hi.y);
    let x0 = (x0.floor() as u32).saturating_sub(1);
    let y0 = (y0.floor() as u32).saturating_sub(1);
    let x1 = ((x1.ceil() as u32) + 1).min(size.0);
    let y1 = ((y1.ceil() as u32) + 1).min(size.1);
    (x1 > x0 && y1 > y0).then_some([x0, y0, x1 - x0, y1 - y0])
}

/// A storage buffer holding `bytes` (at least 16), grown when too small.
fn fill(
    ctx: &ssbvb_gpu::GpuContext,
    slot: &mut Option<wgpu::Buffer>,
    label: &str,
    bytes: &[u8],
) {
    let need = (bytes.len() as u64).max(16);
    if slot.as_ref().is_none_or(|b| b.size() < need) {
        *slot = Some(ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size: need.next_power_of_two(),
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        }));
    }
    if !bytes.is_empty() {
        ctx.queue.write_buffer(slot.as_ref().unwrap(), 0, bytes);
    }
}

impl PassImpl for VolumeSlices {
    type Params = VolumeSlicesParams;
    const SHADER: &'static str = "volume_slices.wgsl";
    const OWN: &'static [OwnBinding] = OWN;
    // Depth-tested against a read-only depth-stencil, which it does not sample.
    const NEEDS: KindNeeds = KindNeeds::NONE;

    fn new(init: &PassInit<'_>, params: &VolumeSlicesParams) -> Result<Self, PassError> {
        let (ctx, scene, pipeline, pass) = (init.ctx, init.scene, init.pipeline, init.pass);
        let d = &ctx.device;
        // Texel lengths and the level by distance assume a uniform scale (no shear).
        for v in &scene.scene.volumes {
            for (j, m) in v.instances.iter().enumerate() {
                if !uniform_scale(m) {
                    return Err(PassError::BadScene(format!(
                        "pass `{}`: volume `{}` instance {j} is scaled unevenly or sheared; \
                         volumes take a rotation, one scale and a translation",
                        pass.name, v.name
                    )));
                }
            }
        }
        let volumes: Vec<_> = scene.scene.volumes.iter().map(|v| &*v.volume).collect();
        let limit = d.limits().max_texture_dimension_3d;
        let atlas = VolumeAtlas::build(&volumes, limit)
            .map_err(|e| PassError::TooLarge(format!("pass `{}`: {e}", pass.name)))?;
        let (texture, table) = upload_atlas(ctx, &atlas);
        // Only the levels' places are needed from here on, not the texels.
        let atlas = VolumeAtlas {
            texels: Vec::new(),
            ..atlas
        };
        let view = texture.create_view(&Default::default());
        let sampler = d.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("volume atlas"),
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            ..Default::default()
        });
        let source = shaders::source_for("volume_slices.wgsl", &scene.bindings)?;
        let module = ctx.shader("volume_slices.wgsl", &source)?;
        // Only the bindings the shaders read: the depth-stencil slot is the pass's read-only
        // depth test, not a texture the shaders sample, so the pass also runs where a
        // texture may not be bound and attached at once (GL).
        let entries = ["vs_main", "fs_main", "vs_resolve", "fs_resolve"];
        let mut used = shaders::used_bindings("volume_slices.wgsl", &source, &entries, 1)?.concat();
        used.sort_unstable();
        used.dedup();
        let bindings = PassBindings::used_only(ctx, pipeline, pass, OWN, Some(&used));
        let layout = pipeline_layout(d, "volume_slices", scene, Some(&bindings));
        // Premultiplied "over", back to front: dst = src + (1 - src.a) dst.
        let over = wgpu::BlendComponent {
            src_factor: wgpu::BlendFactor::One,
            dst_factor: wgpu::BlendFactor::OneMinusSrcAlpha,
            operation: wgpu::BlendOperation::Add,
        };
        let blended = |format| {
            [Some(wgpu::ColorTargetState {
                format,
                blend: Some(wgpu::BlendState {
                    color: over,
                    alpha: over,
                }),
                write_mask: wgpu::ColorWrites::ALL,
            })]
        };
        let targets = blended(ACCUMULATION);
        let resolve_targets = blended(slot_format(ctx, pipeline, pass, "color"));
        let depth_stencil = wgpu::DepthStencilState {
            format: slot_format(ctx, pipeline, pass, "depth_stencil"),
            depth_write_enabled: Some(false),
            // Reversed Z: in front of the opaque surface is greater.
            depth_compare: Some(wgpu::CompareFunction::Greater),
            stencil: wgpu::StencilState {
                read_mask: 0,
                write_mask: 0,
                ..Default::default()
            },
            bias: Default::default(),
        };
        let pipeline = render_pipeline(
            d,
            &RenderSpec {
                depth_stencil: Some(depth_stencil),
                ..RenderSpec::new("volume_slices", &module, &layout, &targets)
            },
        );
        let resolve = render_pipeline(
            d,
            &RenderSpec {
                vs_entry: "vs_resolve",
                fs_entry: "fs_resolve",
                ..RenderSpec::new(
                    "volume_slices resolve",
                    &module,
                    &layout,
                    &resolve_targets,
                )
            },
        );
        let stand_in = accumulation_target(ctx, (1, 1));
        Ok(Self {
            pipeline,
            resolve,
            bindings,
            accumulated: None,
            stand_in,
            view,
            sampler,
            table,
            atlas,
            settings: SliceSettings {
                spacing: f64::from(params.slice_spacing),
                mip_bias: f64::from(params.mip_bias),
            },
            volumes: None,
            vertices: None,
            last: SliceGeometry::default(),
        })
    }
}

impl VolumeSlices {
    /// Slices every placed volume for this frame's camera and uploads the slices' volumes
    /// and vertices; returns the geometry and the vertex count. A view whose slices exceed
    /// the device's storage binding is refused, naming the volume that draws most.
    fn upload_slices(
        &mut self,
        rec: &Recorder<'_>,
    ) -> Result<(SliceGeometry, u32), PassError> {
        let camera = rec.scene.camera;
        let placed: Vec<_> = rec
            .scene
            .scene
            .volumes
            .iter()
            .flat_map(|v| v.instances.iter().map(move |m| (&*v.volume, *m)))
            .collect();
        let geometry = slice(&placed, &camera, rec.screen, self.settings);
        // Instances of volume object k follow each other: its atlas levels are `k`'s.
        let owners: Vec<usize> = rec
            .scene
            .scene
            .volumes
            .iter()
            .enumerate()
            .flat_map(|(k, v)| std::iter::repeat_n(k, v.instances.len()))
            .collect();
        let uniforms: Vec<SliceVolume> = geometry
            .volumes
            .iter()
            .zip(&placed)
            .zip(&owners)
            .map(|((s, (_, m)), &k)| {
                let l = self.atlas.levels[k][s.level];
                // Camera-relative world → object, composed in f64.
                let rel = glam::DAffine3::from_translation(camera.position);
                let to_object = DMat4::from(m.inverse() * rel).as_mat4();
                SliceVolume {
                    to_object: to_object.to_cols_array_2d(),
                    dims: [l.dims[0], l.dims[1], l.dims[2], l.table_offset],
                    bricks: [l.bricks[0], l.bricks[1], l.bricks[2], 0],
                    lengths: [s.h_world as f32, s.spacing_world as f32, 0.0, 0.0],
                }
            })
            .collect();
        // Position bits and the volume's index, read as u32 in the shader.
        let vertices: Vec<[u32; 4]> = geometry
            .vertices
            .iter()
            .map(|(p, v)| [p[0].to_bits(), p[1].to_bits(), p[2].to_bits(), *v])
            .collect();
        let bytes = vertices.len() as u64 * 16;
        let limit = rec.gpu.device.limits().max_storage_buffer_binding_size;
        if bytes > limit {
            let (k, most) = geometry
                .volumes
                .iter()
                .zip(&owners)
                .max_by_key(|(s, _)| s.slices)
                .map(|(s, &k)| (k, s.slices))
                .unwrap_or_default();
            return Err(PassError::TooLarge(format!(
                "pass `{}`: this view's volume slices take {bytes} bytes, beyond the device's \
                 {limit} per binding (volume `{}` alone draws {most} slices); raise \
                 slice_spacing or mip_bias, or show fewer volumes",
                rec.pass.name,
                rec.scene.scene.volumes.get(k).map_or("?", |v| v.name.as_str())
            )));
        }
        fill(
            rec.gpu,
            &mut self.volumes,
            "slice volumes",
            bytemuck::cast_slice(&uniforms),
        );
        fill(
            rec.gpu,
            &mut self.vertices,
            "slice vertices",
            bytemuck::cast_slice(&vertices),
        );
        Ok((geometry, vertices.len() as u32))
    }
}

impl PassNode for VolumeSlices {
    fn record(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        rec: &mut Recorder<'_>,
    ) -> Result<(), PassError> {
        let camera = rec.scene.camera;
        let (geometry, vertex_count) = self.upload_slices(rec)?;
        let ds = rec.texture("depth_stencil");
        let size = (ds.texture.width(), ds.texture.height());
        if self.accumulated.as_ref().is_none_or(|(_, s)| *s != size) {
            self.accumulated = Some((accumulation_target(rec.gpu, size), size));
        }
        let accumulated = &self.accumulated.as_ref().unwrap().0;
        let group = |read: &wgpu::TextureView| {
            self.bindings.bind_group(
                rec,
                &[
                    ("atlas", wgpu::BindingResource::TextureView(&self.view)),
                    ("atlas_sampler", wgpu::BindingResource::Sampler(&self.sampler)),
                    ("brick_table", self.table.as_entire_binding()),
                    (
                        "slice_volumes",
                        self.volumes.as_ref().unwrap().as_entire_binding(),
                    ),
                    (
                        "slice_vertices",
                        self.vertices.as_ref().unwrap().as_entire_binding(),
                    ),
                    ("accumulated", wgpu::BindingResource::TextureView(read)),
                ],
            )
        };
        // Slices into the accumulation target (cleared), the stand-in bound meanwhile.
        let slices_group = group(&self.stand_in)?;
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some(&rec.pass.name),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: accumulated,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &ds.view,
                depth_ops: None,
                stencil_ops: None,
            }),
            // The pass's time spans both render passes: it begins here, ends in the resolve.
            timestamp_writes: rec
                .render_timestamps()
                .map(|t| wgpu::RenderPassTimestampWrites {
                    end_of_pass_write_index: None,
                    ..t
                }),
            ..Default::default()
        });
        if vertex_count > 0 {
            pass.set_bind_group(0, &rec.scene.bind_group, &[]);
            pass.set_bind_group(1, &slices_group, &[]);
            pass.set_pipeline(&self.pipeline);
            pass.draw(0..vertex_count, 0..1);
        }
        drop(pass);
        // Their sum "over" the output colour.
        let resolve_group = group(accumulated)?;
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some(&rec.pass.name),
            color_attachments: &[rec.color_attachment("color")],
            timestamp_writes: rec
                .render_timestamps()
                .map(|t| wgpu::RenderPassTimestampWrites {
                    beginning_of_pass_write_index: None,
                    ..t
                }),
            ..Default::default()
        });
        if let Some([x, y, w, h]) = screen_rect(&geometry, &camera, size) {
            pass.set_scissor_rect(x, y, w, h);
            pass.set_bind_group(0, &rec.scene.bind_group, &[]);
            pass.set_bind_group(1, &resolve_group, &[]);
            pass.set_pipeline(&self.resolve);
            pass.draw(0..3, 0..1);
        }
        drop(pass);
        self.last = geometry;
        Ok(())
    }
}
