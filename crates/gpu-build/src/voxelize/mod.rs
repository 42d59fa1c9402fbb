//! GPU voxelization of meshes by conservative rasterization (`shaders/gpu_voxelize.wgsl`):
//! every triangle is drawn along the dominant axis of its normal into a 2^L × 2^L viewport,
//! enlarged so that every cell column its projection touches gets a fragment, and each
//! fragment appends the cells of its column that the triangle's plane crosses inside the
//! pixel to a voxel fragment list (atomic slots). The list is then sorted by Morton key
//! ([`GpuRadixSort`]) and each run of equal keys becomes one voxel, its colour and normal the
//! mean of its fragments (`shaders/voxel_fragments.wgsl`). The result is a [`VoxelSet`] like
//! the CPU voxelizer's, so the same preparation (LOD chain, lookups, proxies) follows.
//!
//! The raster path approximates the exact CPU voxelizer (triangle–box overlap in f64), and
//! `ssbvb voxelize --gpu` reports the difference (`differs_from_cpu`): the plane across a
//! whole pixel square adds cells next to silhouettes and sharp corners, and the rasterizer's
//! tie rules on pixel edges a triangle only touches can drop a cell the closed-box test
//! keeps. Degenerate (zero-area) triangles rasterize nothing. [`GpuVoxelizeMethod::Exact`]
//! (`shaders/gpu_voxelize_exact.wgsl`, on adapters with f64 shaders, where it is the default
//! of `voxelize --gpu`) runs the CPU's test itself on the cells near each triangle's plane,
//! one thread per cell column, and gives the CPU's voxel set exactly (tested on every shared
//! mesh up to level 10). Both take colours (material × vertex colour × base-colour texture,
//! bilinear and wrapping as the CPU samples it) at the column centre (`voxelize/inputs.rs`);
//! the CPU takes them at the centroid of the triangle's part in each cell, so textured
//! colours differ by the texture's change across a cell.
//!
//! A fragment list that overflows its buffer is rebuilt larger (the count is exact), and
//! one beyond the device's storage-binding limit is refused with the size it needs, never
//! truncated.

use web_time::Instant;

use glam::DVec3;
use ssbvb_gpu::InitBuffer;
use ssbvb_gpu::{GpuContext, wgpu};
use ssbvb_voxel::model::{Mesh, ObjectSpace};
use ssbvb_voxel::svo::LevelVoxels;
use ssbvb_voxel::voxelize::{VoxelSet, VoxelizeError, mesh_bounds};

use ssbvb_gpu::kernels::radix_sort::{GpuRadixSort, SortBuffers};
use ssbvb_gpu::kernels::scan::GpuScan;
use ssbvb_gpu::kernels::{
    Bind, Kernels, WORKGROUP, bind_buffers, read_words, storage, storage_init, uniform,
};
use ssbvb_gpu::{ResourceError, shaders};

mod inputs;
use inputs::{TriangleInputs, triangle_inputs};

/// The textures' words as a storage buffer (one word when there are none: a binding must
/// hold something).
fn texture_buffer(d: &wgpu::Device, words: &[u32]) -> wgpu::Buffer {
    let words: &[u32] = if words.is_empty() { &[0] } else { words };
    d.init_buffer(&wgpu::util::BufferInitDescriptor {
        label: Some("voxelizer textures"),
        contents: bytemuck::cast_slice(words),
        usage: wgpu::BufferUsages::STORAGE,
    })
}

/// Bytes of one voxel fragment (key, colour, normal).
const FRAGMENT_BYTES: u64 = 16;

/// Columns of the exact test per submission, and triangles of the raster path per
/// submission: a driver resets a device whose submission runs for seconds, and at level 13
/// one submission for a whole mesh would (`docs/reliability.md`, "Long submissions").
const COLUMNS_PER_SUBMISSION: u32 = 1 << 19;
const TRIANGLES_PER_SUBMISSION: u32 = 1 << 15;
/// The first fragment list holds this many fragments per triangle (at least a million).
const FRAGMENTS_PER_TRIANGLE: u64 = 8;

/// What the GPU voxelization did.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct GpuVoxelizeStats {
    /// Triangles drawn.
    pub triangles_drawn: u64,
    /// Fragments in the voxel fragment list.
    pub fragments: u64,
    /// Raster passes (more than one when the first fragment list overflowed).
    pub raster_passes: u32,
    /// Raster and fragment-count readback (host wall clock, seconds).
    pub raster_seconds: f64,
    /// Sort, merge and readback of the voxels (seconds).
    pub merge_seconds: f64,
}

/// Which GPU voxelization to run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum GpuVoxelizeMethod {
    /// Conservative rasterization (a near superset of the exact voxels).
    Raster,
    /// The CPU's separating-axis test on every cell of each triangle's bounds, in f64
    /// (`gpu_voxelize_exact.wgsl`; needs `SHADER_F64`): the CPU's voxel set.
    Exact,
}

/// The compiled voxelizer.
pub struct GpuVoxelizer {
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
    /// The exact path, on devices with f64 shaders.
    exact: Option<Kernels>,
    merge: Kernels,
    sort: GpuRadixSort,
    /// Columns of the exact test, and triangles of the raster path, per submission.
    bounds: (u32, u32),
}

fn layout_entry(binding: u32, ty: wgpu::BufferBindingType) -> wgpu::BindGroupLayoutEntry {
    let writes = matches!(ty, wgpu::BufferBindingType::Storage { read_only: false });
    wgpu::BindGroupLayoutEntry {
        binding,
        // Written only by the fragment stage (vertex-stage writes are not portable).
        visibility: if writes {
            wgpu::ShaderStages::FRAGMENT
        } else {
            wgpu::ShaderStages::VERTEX_FRAGMENT
        },
        ty: wgpu::BindingType::Buffer {
            ty,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

impl GpuVoxelizer {
    /// Compiles the raster pipeline and the merge kernels.
    pub fn new(ctx: &GpuContext) -> Result<Self, ResourceError> {
        let file = "gpu_voxelize.wgsl";
        let module = ctx.shader(file, &shaders::source(file)?)?;
        let (pipeline, layout) = ctx.validated(file, |d| {
            let read = wgpu::BufferBindingType::Storage { read_only: true };
            let write = wgpu::BufferBindingType::Storage { read_only: false };
            let layout = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some(file),
                entries: &[
                    layout_entry(0, wgpu::BufferBindingType::Uniform),
                    layout_entry(1, read),
                    layout_entry(2, read),
                    layout_entry(3, write),
                    layout_entry(4, write),
                    layout_entry(5, read),
                    layout_entry(6, read),
                ],
            });
            let pl = d.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some(file),
                bind_group_layouts: &[Some(&layout)],
                immediate_size: 0,
            });
            let pipeline = d.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(file),
                layout: Some(&pl),
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some("vs_main"),
                    compilation_options: Default::default(),
                    buffers: &[],
                },
                primitive: wgpu::PrimitiveState::default(),
                depth_stencil: None,
                multisample: wgpu::MultisampleState::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &module,
                    entry_point: Some("fs_main"),
                    compilation_options: Default::default(),
                    targets: &[Some(wgpu::ColorTargetState {
                        format: wgpu::TextureFormat::R8Unorm,
                        blend: None,
                        write_mask: wgpu::ColorWrites::empty(),
                    })],
                }),
                multiview_mask: None,
                cache: None,
            });
            (pipeline, layout)
        })?;
        use Bind::*;
        let exact = if ctx.has(wgpu::Features::SHADER_F64) {
            Some(Kernels::new(
                ctx,
                "gpu_voxelize_exact.wgsl",
                &[
                    Uniform, Read, Read, ReadWrite, ReadWrite, ReadWrite, Read, Read,
                ],
                &["count_columns", "exact_columns"],
            )?)
        } else {
            None
        };
        Ok(Self {
            pipeline,
            layout,
            exact,
            merge: Kernels::new(
                ctx,
                "voxel_fragments.wgsl",
                &[
                    Uniform, Read, ReadWrite, ReadWrite, ReadWrite, ReadWrite, ReadWrite,
                    ReadWrite, ReadWrite, ReadWrite, ReadWrite,
                ],
                &["fragment_keys", "run_flags", "run_starts", "merge"],
            )?,
            sort: GpuRadixSort::new(ctx)?,
            bounds: (COLUMNS_PER_SUBMISSION, TRIANGLES_PER_SUBMISSION),
        })
    }

    /// The same voxelizer submitting at most `columns` columns of the exact test and
    /// `triangles` triangles of the raster path at a time (at least 1 each; tests use
    /// small bounds to cross them with small meshes).
    pub fn with_submission_bounds(mut self, columns: u32, triangles: u32) -> Self {
        self.bounds = (columns.max(1), triangles.max(1));
        self
    }

    /// Voxelizes `mesh` at `level` on the GPU.
    pub fn voxelize(
        &self,
        ctx: &GpuContext,
        mesh: &Mesh,
        level: u32,
    ) -> Result<(VoxelSet, GpuVoxelizeStats), ResourceError> {
        self.voxelize_with_capacity(ctx, mesh, level, None)
    }

    /// [`GpuVoxelizer::voxelize`] with the first fragment list sized for `capacity`
    /// fragments (default: 8 per triangle, at least a million); a list that overflows is
    /// rebuilt with the exact count.
    pub fn voxelize_with_capacity(
        &self,
        ctx: &GpuContext,
        mesh: &Mesh,
        level: u32,
        capacity: Option<u64>,
    ) -> Result<(VoxelSet, GpuVoxelizeStats), ResourceError> {
        self.voxelize_by(ctx, mesh, level, capacity, GpuVoxelizeMethod::Raster)
    }

    /// Whether this device runs [`GpuVoxelizeMethod::Exact`].
    pub fn has_exact(&self) -> bool {
        self.exact.is_some()
    }

    /// Voxelizes `mesh` at `level` with `method` (an error names the missing feature when
    /// the device cannot run it).
    pub fn voxelize_by(
        &self,
        ctx: &GpuContext,
        mesh: &Mesh,
        level: u32,
        capacity: Option<u64>,
        method: GpuVoxelizeMethod,
    ) -> Result<(VoxelSet, GpuVoxelizeStats), ResourceError> {
        self.voxelize_in(ctx, mesh, level, None, capacity, method)
    }

    /// [`GpuVoxelizer::voxelize_by`] in a given object space (as
    /// [`ssbvb_voxel::voxelize::voxelize_mesh_in`]: an animated mesh keeps the space of its
    /// whole motion; a vertex outside it is an error).
    pub fn voxelize_in(
        &self,
        ctx: &GpuContext,
        mesh: &Mesh,
        level: u32,
        space: Option<ObjectSpace>,
        capacity: Option<u64>,
        method: GpuVoxelizeMethod,
    ) -> Result<(VoxelSet, GpuVoxelizeStats), ResourceError> {
        let (mut set, voxels, stats) =
            self.voxelize_to_gpu(ctx, mesh, level, space, capacity, method)?;
        set.voxels = voxels.read_back(ctx)?;
        Ok((set, stats))
    }

    /// [`GpuVoxelizer::voxelize_in`] leaving the voxels on the GPU ([`GpuVoxels`], for the
    /// LOD build); the returned set holds the object space and the report, no voxels.
    pub fn voxelize_to_gpu(
        &self,
        ctx: &GpuContext,
        mesh: &Mesh,
        level: u32,
        space: Option<ObjectSpace>,
        capacity: Option<u64>,
        method: GpuVoxelizeMethod,
    ) -> Result<(VoxelSet, GpuVoxels, GpuVoxelizeStats), ResourceError> {
        if method == GpuVoxelizeMethod::Exact && self.exact.is_none() {
            return Err(ResourceError::BadScene(
                "the exact GPU voxelization needs f64 shaders (wgpu feature SHADER_F64), \
                 which this adapter lacks"
                    .into(),
            ));
        }
        let max_dim = ctx.device.limits().max_texture_dimension_2d;
        if level > 16 || (1u64 << level) > u64::from(max_dim) {
            return Err(ResourceError::TooLarge(format!(
                "GPU voxelization: level {level} needs a {0}×{0} viewport, above the device's \
                 {max_dim}",
                1u64 << level.min(40)
            )));
        }
        let (lo, hi) = mesh_bounds(mesh).ok_or_else(|| {
            ResourceError::BadScene(
                VoxelizeError::Empty("no triangle with finite vertices".into()).to_string(),
            )
        })?;
        let object_space = match space {
            Some(s) => {
                let inside = |p: DVec3| s.to_object(p).abs().max_element() <= 1.0;
                if !(inside(lo) && inside(hi)) {
                    return Err(ResourceError::BadScene(
                        VoxelizeError::OutsideObjectSpace.to_string(),
                    ));
                }
                s
            }
            None => ObjectSpace::from_bounds(lo, hi),
        };
        let inputs = triangle_inputs(mesh, &object_space, level);
        let triangles = inputs.triangles();
        let report = inputs.report.clone();
        let mut stats = GpuVoxelizeStats {
            triangles_drawn: u64::from(triangles),
            ..Default::default()
        };
        let t0 = Instant::now();
        let limit = ctx.device.limits().max_storage_buffer_binding_size;
        let texture_bytes = 4 * inputs.textures.len() as u64;
        if texture_bytes > limit {
            return Err(ResourceError::TooLarge(format!(
                "GPU voxelization: the mesh's textures take {texture_bytes} bytes, above the \
                 device's storage binding limit of {limit}"
            )));
        }
        let mut capacity = capacity
            .unwrap_or((u64::from(triangles) * FRAGMENTS_PER_TRIANGLE).max(1 << 20))
            .max(1);
        let (fragments, count) = loop {
            capacity = capacity.min(limit / FRAGMENT_BYTES);
            let fragments = storage(&ctx.device, "voxel fragments", capacity * 4);
            let count = match method {
                GpuVoxelizeMethod::Raster => {
                    self.raster(ctx, &inputs, level, &fragments, capacity)?
                }
                GpuVoxelizeMethod::Exact => {
                    self.exact(ctx, &inputs, level, &fragments, capacity)?
                }
            };
            stats.raster_passes += 1;
            if count <= capacity {
                break (fragments, count);
            }
            if count > limit / FRAGMENT_BYTES {
                return Err(ResourceError::TooLarge(format!(
                    "GPU voxelization: level {level} makes {count} voxel fragments ({} MiB), \
                     above the device's storage binding limit of {} MiB",
                    (count * FRAGMENT_BYTES) >> 20,
                    limit >> 20
                )));
            }
            capacity = count;
        };
        stats.fragments = count;
        stats.raster_seconds = t0.elapsed().as_secs_f64();
        let t1 = Instant::now();
        let voxels = self.merge(ctx, &fragments, count as u32, level)?;
        stats.merge_seconds = t1.elapsed().as_secs_f64();
        Ok((
            VoxelSet {
                object_space,
                voxels: LevelVoxels {
                    level,
                    ..Default::default()
                },
                report,
            },
            voxels,
            stats,
        ))
    }

    /// Rasterizes every triangle into `fragments`; returns the fragments made (more than
    /// `capacity` when it overflowed: those beyond were not written).
    #[allow(clippy::too_many_arguments)]
    fn raster(
        &self,
        ctx: &GpuContext,
        inputs: &TriangleInputs,
        level: u32,
        fragments: &wgpu::Buffer,
        capacity: u64,
    ) -> Result<u64, ResourceError> {
        let d = &ctx.device;
        let n = 1u32 << level;
        let init = |label: &str, data: &[f32]| {
            let one = [0f32; 4];
            d.init_buffer(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents: bytemuck::cast_slice(if data.is_empty() { &one } else { data }),
                usage: wgpu::BufferUsages::STORAGE,
            })
        };
        let triangles = inputs.triangles();
        let counter = storage(d, "voxel fragment counter", 1);
        let params = uniform(d, "voxelize", &[triangles, level, capacity as u32, 0]);
        let (corner_buf, color_buf) = (
            init("corners", &inputs.corners),
            init("corner colours", &inputs.colors),
        );
        let uv_buf = init("corner uvs", &inputs.uvs);
        let texture_buf = texture_buffer(d, &inputs.textures);
        ctx.validated("GPU voxelization raster", |d| {
            let target = d.create_texture(&wgpu::TextureDescriptor {
                label: Some("voxelization viewport"),
                size: wgpu::Extent3d {
                    width: n,
                    height: n,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: wgpu::TextureFormat::R8Unorm,
                usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
                view_formats: &[],
            });
            let view = target.create_view(&Default::default());
            let bg = bind_buffers(
                d,
                "voxelize",
                &self.layout,
                &[
                    &params,
                    &corner_buf,
                    &color_buf,
                    fragments,
                    &counter,
                    &uv_buf,
                    &texture_buf,
                ],
            );
            for first in (0..triangles).step_by(self.bounds.1 as usize) {
                let count = (triangles - first).min(self.bounds.1);
                let mut enc = d.create_command_encoder(&Default::default());
                {
                    let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                        label: Some("voxelize"),
                        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                            view: &view,
                            depth_slice: None,
                            resolve_target: None,
                            ops: wgpu::Operations {
                                load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                                store: wgpu::StoreOp::Discard,
                            },
                        })],
                        depth_stencil_attachment: None,
                        timestamp_writes: None,
                        occlusion_query_set: None,
                        multiview_mask: None,
                    });
                    pass.set_pipeline(&self.pipeline);
                    pass.set_bind_group(0, &bg, &[]);
                    pass.draw(3 * first..3 * (first + count), 0..1);
                }
                ctx.submit("raster voxelization", [enc.finish()]);
            }
        })?;
        Ok(u64::from(read_words(ctx, &counter, 0, 1)?[0]))
    }

    /// Runs the exact test over every triangle's cells into `fragments`; returns the
    /// fragments made (as [`GpuVoxelizer::raster`]).
    #[allow(clippy::too_many_arguments)]
    fn exact(
        &self,
        ctx: &GpuContext,
        inputs: &TriangleInputs,
        level: u32,
        fragments: &wgpu::Buffer,
        capacity: u64,
    ) -> Result<u64, ResourceError> {
        let kernels = self.exact.as_ref().expect("checked by the caller");
        let d = &ctx.device;
        let init = |label: &str, bytes: &[u8]| {
            d.init_buffer(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents: if bytes.is_empty() { &[0; 16] } else { bytes },
                usage: wgpu::BufferUsages::STORAGE,
            })
        };
        let triangles = inputs.triangles();
        let counter = storage(d, "voxel fragment counter", 1);
        let offsets = storage(d, "column offsets", u64::from(triangles));
        let verts = init("grid corners", bytemuck::cast_slice(&inputs.grid));
        let cols = init("corner colours", bytemuck::cast_slice(&inputs.colors));
        let uvs = init("corner uvs", bytemuck::cast_slice(&inputs.uvs));
        let textures = texture_buffer(d, &inputs.textures);
        let bind = |params: &wgpu::Buffer| {
            kernels.bind_group(
                d,
                &[
                    params, &verts, &cols, fragments, &counter, &offsets, &uvs, &textures,
                ],
            )
        };
        // Columns per triangle, their offsets, then one thread per column.
        let params = uniform(
            d,
            "exact voxelize",
            &[triangles, level, capacity as u32, 0, 0, 0, 0, 0],
        );
        let mut enc = d.create_command_encoder(&Default::default());
        kernels.dispatch(
            &mut enc,
            "count_columns",
            &bind(&params),
            triangles.div_ceil(WORKGROUP),
        );
        let sums = self.sort.scan().record(d, &mut enc, &offsets, triangles);
        ctx.submit("exact voxelization: counting fragments", [enc.finish()]);
        let columns = read_words(ctx, &sums, GpuScan::total_index(triangles), 1)?[0];
        ctx.validated("exact GPU voxelization", |_| {
            // Bounded submissions: a driver resets a device whose submission runs long.
            for first in (0..columns).step_by(self.bounds.0 as usize) {
                let n = (columns - first).min(self.bounds.0);
                let params = uniform(
                    d,
                    "exact voxelize",
                    &[
                        triangles,
                        level,
                        capacity as u32,
                        columns,
                        first,
                        first + n,
                        0,
                        0,
                    ],
                );
                let mut enc = d.create_command_encoder(&Default::default());
                kernels.dispatch(
                    &mut enc,
                    "exact_columns",
                    &bind(&params),
                    n.div_ceil(WORKGROUP),
                );
                ctx.submit("exact voxelization: fragments", [enc.finish()]);
            }
        })?;
        Ok(u64::from(read_words(ctx, &counter, 0, 1)?[0]))
    }

    /// Sorts the `n` fragments by key and merges each run into a voxel, on the GPU.
    fn merge(
        &self,
        ctx: &GpuContext,
        fragments: &wgpu::Buffer,
        n: u32,
        level: u32,
    ) -> Result<GpuVoxels, ResourceError> {
        let d = &ctx.device;
        if n == 0 {
            return Ok(GpuVoxels::new(d, level, 0));
        }
        let groups = n.div_ceil(WORKGROUP);
        let mut a = SortBuffers::new(d, "fragment keys", u64::from(n));
        let mut b = SortBuffers::new(d, "fragment keys", u64::from(n));
        let flags = storage(d, "fragment runs", u64::from(n));
        let starts = storage(d, "run starts", u64::from(n));
        let dummy = GpuVoxels::new(d, level, 1);
        let params = uniform(d, "merge", &[n, 0]);
        let bind = |keys: &SortBuffers, params: &wgpu::Buffer, out: &GpuVoxels| {
            self.merge.bind_group(
                d,
                &[
                    params,
                    fragments,
                    &keys.lo,
                    &keys.hi,
                    &keys.val,
                    &flags,
                    &starts,
                    &out.key_lo,
                    &out.key_hi,
                    &out.colors,
                    &out.normals,
                ],
            )
        };
        let mut enc = d.create_command_encoder(&Default::default());
        let bg = bind(&a, &params, &dummy);
        self.merge.dispatch(&mut enc, "fragment_keys", &bg, groups);
        ctx.submit("voxel merge: keys", [enc.finish()]);
        // One submission per radix pass: the sort is the longest part of the merge.
        if self
            .sort
            .sort_submitting(ctx, &a, &b, n, 3 * level, "voxel merge: sort pass")
        {
            std::mem::swap(&mut a, &mut b);
        }
        let mut enc = d.create_command_encoder(&Default::default());
        let bg = bind(&a, &params, &dummy);
        self.merge.dispatch(&mut enc, "run_flags", &bg, groups);
        let sums = self.sort.scan().record(d, &mut enc, &flags, n);
        self.merge.dispatch(&mut enc, "run_starts", &bg, groups);
        ctx.submit("voxel merge: runs", [enc.finish()]);
        let runs = read_words(ctx, &sums, GpuScan::total_index(n), 1)?[0];
        let out = GpuVoxels::new(d, level, u64::from(runs));
        let params = uniform(d, "merge", &[n, runs]);
        let mut enc = d.create_command_encoder(&Default::default());
        let bg = bind(&a, &params, &out);
        self.merge
            .dispatch(&mut enc, "merge", &bg, runs.div_ceil(WORKGROUP));
        ctx.submit("voxel merge", [enc.finish()]);
        Ok(out)
    }
}

/// A Morton-sorted voxel set on the GPU, in the layout [`crate::lod_build`] reads:
/// what the GPU voxelizer hands to the LOD build without a trip to the host.
pub struct GpuVoxels {
    /// Grid level.
    pub level: u32,
    /// Voxels.
    pub count: u32,
    /// Low words of the Morton codes.
    pub key_lo: wgpu::Buffer,
    /// High words of the Morton codes.
    pub key_hi: wgpu::Buffer,
    /// Linear RGBA, four f32 per voxel.
    pub colors: wgpu::Buffer,
    /// Unit normal, four f32 per voxel (w unused).
    pub normals: wgpu::Buffer,
}

impl GpuVoxels {
    /// Buffers for `count` voxels (at least one word each).
    pub fn new(d: &wgpu::Device, level: u32, count: u64) -> Self {
        Self {
            level,
            count: count as u32,
            key_lo: storage(d, "voxel keys", count),
            key_hi: storage(d, "voxel keys", count),
            colors: storage(d, "voxel colours", 4 * count),
            normals: storage(d, "voxel normals", 4 * count),
        }
    }

    /// Uploads a voxel set.
    pub fn upload(d: &wgpu::Device, voxels: &LevelVoxels) -> Self {
        let lo: Vec<u32> = voxels.codes.iter().map(|&c| c as u32).collect();
        let hi: Vec<u32> = voxels.codes.iter().map(|&c| (c >> 32) as u32).collect();
        let colors: Vec<f32> = voxels.colors.iter().flatten().copied().collect();
        let normals: Vec<f32> = voxels
            .normals
            .iter()
            .flat_map(|n| [n[0], n[1], n[2], 0.0])
            .collect();
        Self {
            level: voxels.level,
            count: voxels.codes.len() as u32,
            key_lo: storage_init(d, "voxel keys", &lo),
            key_hi: storage_init(d, "voxel keys", &hi),
            colors: storage_init(d, "voxel colours", bytemuck::cast_slice(&colors)),
            normals: storage_init(d, "voxel normals", bytemuck::cast_slice(&normals)),
        }
    }

    /// Reads the set back (the CLI's statistics, tests).
    pub fn read_back(&self, ctx: &GpuContext) -> Result<LevelVoxels, ResourceError> {
        let n = u64::from(self.count);
        let lo = read_words(ctx, &self.key_lo, 0, n)?;
        let hi = read_words(ctx, &self.key_hi, 0, n)?;
        let colors = read_words(ctx, &self.colors, 0, 4 * n)?;
        let normals = read_words(ctx, &self.normals, 0, 4 * n)?;
        let f = |w: &[u32]| -> [f32; 4] { std::array::from_fn(|i| f32::from_bits(w[i])) };
        Ok(LevelVoxels {
            level: self.level,
            codes: lo
                .iter()
                .zip(&hi)
                .map(|(&l, &h)| u64::from(l) | u64::from(h) << 32)
                .collect(),
            colors: colors.chunks(4).map(f).collect(),
            normals: normals
                .chunks(4)
                .map(|w| {
                    let v = f(w);
                    [v[0], v[1], v[2]]
                })
                .collect(),
            uvs: vec![[0.0; 2]; n as usize],
        })
    }
}
