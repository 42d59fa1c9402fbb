//! A set of compute kernels from one WGSL file that share one explicit bind-group layout
//! (group 0), for the GPU build steps that are not graph passes ([`scan`], [`radix_sort`]
//! and the build steps of `ssbvb-gpu-build`). Explicit rather than automatic layouts, so every entry
//! point takes the same bind group whichever bindings it uses.

use crate::InitBuffer;

use crate::{GpuContext, ResourceError, shaders, wgpu};

pub mod radix_sort;
pub mod scan;

/// Threads per workgroup of every kernel here (`@workgroup_size(256)`).
pub const WORKGROUP: u32 = 256;
/// The largest workgroup count per dispatch dimension WebGPU guarantees.
const MAX_GROUPS_PER_DIM: u32 = 65535;

/// How a binding is used.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Bind {
    /// `var<uniform>`.
    Uniform,
    /// `var<storage, read>`.
    Read,
    /// `var<storage, read_write>`.
    ReadWrite,
}

/// A bind group of `layout` with the whole of `buffers[i]` at binding `i`.
pub fn bind_buffers(
    d: &wgpu::Device,
    label: &str,
    layout: &wgpu::BindGroupLayout,
    buffers: &[&wgpu::Buffer],
) -> wgpu::BindGroup {
    let entries: Vec<wgpu::BindGroupEntry> = buffers
        .iter()
        .enumerate()
        .map(|(i, b)| wgpu::BindGroupEntry {
            binding: i as u32,
            resource: b.as_entire_binding(),
        })
        .collect();
    d.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some(label),
        layout,
        entries: &entries,
    })
}

/// The compiled kernels of one file.
pub struct Kernels {
    layout: wgpu::BindGroupLayout,
    pipelines: Vec<(&'static str, wgpu::ComputePipeline)>,
    file: &'static str,
}

impl Kernels {
    /// Compiles `entries` of `file` with bindings `binds` (binding `i` = `binds[i]`).
    pub fn new(
        ctx: &GpuContext,
        file: &'static str,
        binds: &[Bind],
        entries: &[&'static str],
    ) -> Result<Self, ResourceError> {
        let module = ctx.shader(file, &shaders::source(file)?)?;
        Ok(ctx.validated(file, |d| {
            let layout_entries: Vec<wgpu::BindGroupLayoutEntry> = binds
                .iter()
                .enumerate()
                .map(|(i, b)| wgpu::BindGroupLayoutEntry {
                    binding: i as u32,
                    visibility: wgpu::ShaderStages::COMPUTE,
                    ty: wgpu::BindingType::Buffer {
                        ty: match b {
                            Bind::Uniform => wgpu::BufferBindingType::Uniform,
                            Bind::Read => wgpu::BufferBindingType::Storage { read_only: true },
                            Bind::ReadWrite => {
                                wgpu::BufferBindingType::Storage { read_only: false }
                            }
                        },
                        has_dynamic_offset: false,
                        min_binding_size: None,
                    },
                    count: None,
                })
                .collect();
            let layout = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some(file),
                entries: &layout_entries,
            });
            let pipeline_layout = d.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some(file),
                bind_group_layouts: &[Some(&layout)],
                immediate_size: 0,
            });
            let pipelines = entries
                .iter()
                .map(|&entry| {
                    let p = d.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                        label: Some(entry),
                        layout: Some(&pipeline_layout),
                        module: &module,
                        entry_point: Some(entry),
                        compilation_options: Default::default(),
                        cache: None,
                    });
                    (entry, p)
                })
                .collect();
            Self {
                layout,
                pipelines,
                file,
            }
        })?)
    }

    /// A bind group of `buffers` in binding order.
    pub fn bind_group(&self, d: &wgpu::Device, buffers: &[&wgpu::Buffer]) -> wgpu::BindGroup {
        bind_buffers(d, self.file, &self.layout, buffers)
    }

    /// Dispatches `entry` over `groups` workgroups, split over x and y when above the
    /// per-dimension limit (kernels number their workgroup `x + y · num_workgroups.x` and
    /// return past the count they are given).
    pub fn dispatch(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        entry: &str,
        bind_group: &wgpu::BindGroup,
        groups: u32,
    ) {
        let pipeline = &self
            .pipelines
            .iter()
            .find(|(e, _)| *e == entry)
            .unwrap_or_else(|| panic!("{}: no kernel `{entry}` was compiled", self.file))
            .1;
        if groups == 0 {
            return;
        }
        let x = groups.min(MAX_GROUPS_PER_DIM);
        let y = groups.div_ceil(x);
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(entry),
            timestamp_writes: None,
        });
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, bind_group, &[]);
        pass.dispatch_workgroups(x, y, 1);
    }
}

/// A uniform buffer holding `words`.
pub fn uniform(d: &wgpu::Device, label: &str, words: &[u32]) -> wgpu::Buffer {
    d.init_buffer(&wgpu::util::BufferInitDescriptor {
        label: Some(label),
        contents: bytemuck::cast_slice(words),
        usage: wgpu::BufferUsages::UNIFORM,
    })
}

/// A storage buffer of `len` u32s (at least one), readable back and writable by copies.
pub fn storage(d: &wgpu::Device, label: &str, len: u64) -> wgpu::Buffer {
    d.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: 4 * len.max(1),
        usage: wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_SRC
            | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

/// A storage buffer holding `words`.
pub fn storage_init(d: &wgpu::Device, label: &str, words: &[u32]) -> wgpu::Buffer {
    let one = [0u32];
    d.init_buffer(&wgpu::util::BufferInitDescriptor {
        label: Some(label),
        contents: bytemuck::cast_slice(if words.is_empty() { &one } else { words }),
        usage: wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_SRC
            | wgpu::BufferUsages::COPY_DST,
    })
}

/// Reads `len` u32s of `buffer` from word `offset` back (a blocking copy and map).
pub fn read_words(
    ctx: &GpuContext,
    buffer: &wgpu::Buffer,
    offset: u64,
    len: u64,
) -> Result<Vec<u32>, ResourceError> {
    if len == 0 {
        return Ok(Vec::new());
    }
    let staging = storage(&ctx.device, "read_words", len);
    let mut enc = ctx
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("read_words"),
        });
    enc.copy_buffer_to_buffer(buffer, 4 * offset, &staging, 0, 4 * len);
    ctx.submit("read words", [enc.finish()]);
    let bytes = ctx.read_buffer(&staging)?;
    Ok(bytemuck::cast_slice(&bytes[..4 * len as usize]).to_vec())
}
