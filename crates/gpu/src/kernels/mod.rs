//! A set of compute kernels from one WGSL file whose bindings (group 0) are declared once,
//! for the GPU build steps that are not graph passes ([`scan`], [`radix_sort`] and the build
//! steps of `ssbvb-gpu-build`). A caller binds the file's whole list of buffers once
//! ([`KernelBindGroups`]); each entry point gets a layout of only the bindings it uses
//! (found by naga's validator, as wgpu finds them), so a file may declare more storage
//! buffers than a device allows per stage (WebGPU: 8) as long as no one kernel uses more.

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
    entries: Vec<Kernel>,
    file: &'static str,
}

/// One entry point: the bindings it uses, their layout and its pipeline.
struct Kernel {
    name: &'static str,
    used: Vec<u32>,
    layout: wgpu::BindGroupLayout,
    pipeline: wgpu::ComputePipeline,
}

/// A file's buffers bound for each of its kernels (see [`Kernels::bind_group`]).
pub struct KernelBindGroups {
    groups: Vec<(&'static str, wgpu::BindGroup)>,
}

impl Kernels {
    /// Compiles `entries` of `file` with bindings `binds` (binding `i` = `binds[i]`); an
    /// error naming the kernel when one uses more storage buffers than the device allows.
    pub fn new(
        ctx: &GpuContext,
        file: &'static str,
        binds: &[Bind],
        entries: &[&'static str],
    ) -> Result<Self, ResourceError> {
        let source = shaders::source(file)?;
        let used = shaders::used_bindings(file, &source, entries, 0)?;
        let limit = ctx.device.limits().max_storage_buffers_per_shader_stage;
        for (entry, used) in entries.iter().zip(&used) {
            let storage = used
                .iter()
                .filter(|&&b| binds.get(b as usize).is_some_and(|b| *b != Bind::Uniform))
                .count() as u32;
            if storage > limit {
                return Err(ResourceError::TooLarge(format!(
                    "{file}: kernel `{entry}` uses {storage} storage buffers; the device \
                     allows {limit} per shader stage (max_storage_buffers_per_shader_stage)"
                )));
            }
            if let Some(b) = used.iter().find(|&&b| b as usize >= binds.len()) {
                return Err(ResourceError::Shader(format!(
                    "{file}: kernel `{entry}` uses binding {b}, {} are declared",
                    binds.len()
                )));
            }
        }
        let module = ctx.shader(file, &source)?;
        Ok(ctx.validated(file, |d| {
            let entries = entries
                .iter()
                .zip(used)
                .map(|(&name, used)| {
                    let layout_entries: Vec<wgpu::BindGroupLayoutEntry> = used
                        .iter()
                        .map(|&i| layout_entry(i, binds[i as usize]))
                        .collect();
                    let layout = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                        label: Some(name),
                        entries: &layout_entries,
                    });
                    let pipeline_layout =
                        d.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                            label: Some(name),
                            bind_group_layouts: &[Some(&layout)],
                            immediate_size: 0,
                        });
                    let pipeline = d.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                        label: Some(name),
                        layout: Some(&pipeline_layout),
                        module: &module,
                        entry_point: Some(name),
                        compilation_options: Default::default(),
                        cache: None,
                    });
                    Kernel {
                        name,
                        used,
                        layout,
                        pipeline,
                    }
                })
                .collect();
            Self { entries, file }
        })?)
    }

    /// `buffers` in binding order (`buffers[i]` at binding `i`), bound for every kernel:
    /// each gets the ones it uses.
    pub fn bind_group(&self, d: &wgpu::Device, buffers: &[&wgpu::Buffer]) -> KernelBindGroups {
        let groups = self
            .entries
            .iter()
            .map(|k| {
                let entries: Vec<wgpu::BindGroupEntry> = k
                    .used
                    .iter()
                    .map(|&i| wgpu::BindGroupEntry {
                        binding: i,
                        resource: buffers[i as usize].as_entire_binding(),
                    })
                    .collect();
                let group = d.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some(k.name),
                    layout: &k.layout,
                    entries: &entries,
                });
                (k.name, group)
            })
            .collect();
        KernelBindGroups { groups }
    }

    /// Dispatches `entry` over `groups` workgroups, split over x and y when above the
    /// per-dimension limit (kernels number their workgroup `x + y · num_workgroups.x` and
    /// return past the count they are given).
    pub fn dispatch(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        entry: &str,
        bind_groups: &KernelBindGroups,
        groups: u32,
    ) {
        let found = self
            .entries
            .iter()
            .zip(&bind_groups.groups)
            .find(|(k, _)| k.name == entry)
            .unwrap_or_else(|| panic!("{}: no kernel `{entry}` was compiled", self.file));
        let (pipeline, bind_group) = (&found.0.pipeline, &found.1.1);
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

/// The layout entry of binding `i`, used as `bind`.
fn layout_entry(i: u32, bind: Bind) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding: i,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: match bind {
                Bind::Uniform => wgpu::BufferBindingType::Uniform,
                Bind::Read => wgpu::BufferBindingType::Storage { read_only: true },
                Bind::ReadWrite => wgpu::BufferBindingType::Storage { read_only: false },
            },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
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
