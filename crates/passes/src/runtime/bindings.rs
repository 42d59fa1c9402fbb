//! A pass's bind group 1, built from what the pass declares instead of by hand.
//!
//! Binding numbers: first the kind's shader-visible slots in the order the kind declares
//! them (`PassKind::slots`, binding = position among them), then the pass's own resources
//! ([`OwnBinding`]: samplers, caches it uploads, per-mesh uniforms) in the order of its
//! [`super::registry::Registration::own`] list. Binding types come from the slot class, the
//! access and the format of the resource actually bound (sample type, filterability), so a
//! pass names its resources and never a number. `cargo xtask validate-shaders` checks that
//! each WGSL global of those names sits at `@group(1) @binding(position)`.

use ssbvb_gpu::{GpuContext, wgpu};
use ssbvb_graph::{Access, PassStage, ResolvedPipeline, ResourceDesc, ScheduledPass, SlotClass};

use super::recorder::Recorder;
use super::registry::{OwnBinding, OwnKind};
use super::resources::texture_format;
use crate::error::PassError;

/// The bind group index of a pass's own bindings (group 0 is the scene).
pub const PASS_GROUP: u32 = 1;

/// The names bound in group 1 of a kind, in binding order (shader-visible slots, then
/// `own`).
pub fn binding_names(slots: &[ssbvb_graph::SlotDesc], own: &[OwnBinding]) -> Vec<&'static str> {
    slots
        .iter()
        .filter(|s| s.is_shader_global())
        .map(|s| s.name)
        .chain(own.iter().map(|o| o.name))
        .collect()
}

/// The layout of a pass's group 1 and the names in binding order.
pub struct PassBindings {
    /// The bind group layout.
    pub layout: wgpu::BindGroupLayout,
    /// Graph slots, in binding order.
    slots: Vec<(&'static str, SlotClass)>,
    /// Own bindings, after the slots.
    own: &'static [OwnBinding],
    /// The bindings in the layout when not all are (`PassBindings::used_only`).
    used: Option<Vec<u32>>,
}

/// A resource given for an own binding when the bind group is made.
pub type OwnResource<'a> = (&'static str, wgpu::BindingResource<'a>);

fn visibility(stage: PassStage, writable_storage: bool) -> wgpu::ShaderStages {
    match stage {
        PassStage::Compute => wgpu::ShaderStages::COMPUTE,
        // Vertex shaders may not write storage. Compute too: a render pass kind may run
        // compute work before its draw on the same group (SplatBillboards).
        PassStage::Render if writable_storage => {
            wgpu::ShaderStages::FRAGMENT | wgpu::ShaderStages::COMPUTE
        }
        PassStage::Render => wgpu::ShaderStages::VERTEX_FRAGMENT | wgpu::ShaderStages::COMPUTE,
    }
}

fn storage(read_only: bool, min_size: Option<u64>) -> wgpu::BindingType {
    wgpu::BindingType::Buffer {
        ty: wgpu::BufferBindingType::Storage { read_only },
        has_dynamic_offset: false,
        min_binding_size: min_size.and_then(wgpu::BufferSize::new),
    }
}

impl PassBindings {
    /// The layout of `pass`'s group 1: its kind's shader-visible slots (types from the
    /// formats bound in `pipeline`), then `own`.
    pub fn new(
        ctx: &GpuContext,
        pipeline: &ResolvedPipeline,
        pass: &ScheduledPass,
        own: &'static [OwnBinding],
    ) -> Self {
        Self::used_only(ctx, pipeline, pass, own, None)
    }

    /// [`PassBindings::new`] with only the bindings in `used` (when given) in the layout:
    /// those a shader specialized for its data reads (each counts against the device's
    /// per-stage limits). Binding numbers stay the declared positions; the bind groups
    /// leave the others out.
    pub fn used_only(
        ctx: &GpuContext,
        pipeline: &ResolvedPipeline,
        pass: &ScheduledPass,
        own: &'static [OwnBinding],
        used: Option<&[u32]>,
    ) -> Self {
        let stage = pass.kind.stage();
        let mut entries = Vec::new();
        let mut slots = Vec::new();
        for slot in pass.kind.slots().iter().filter(|s| s.is_shader_global()) {
            let binding = entries.len() as u32;
            let resource = pass.resource_of(slot.name).map(|r| &pipeline.resources[r]);
            let ty = match (slot.class, resource.map(|r| &r.desc)) {
                (SlotClass::StorageBuffer(layout), _) => {
                    storage(slot.access == Access::Read, Some(layout.element_size()))
                }
                (_, Some(ResourceDesc::Texture { format, .. })) => {
                    let format = texture_format(ctx, *format);
                    texture_binding(ctx, slot.class, slot.access, format)
                }
                // The graph bound every slot to a resource of its class.
                _ => unreachable!("slot `{}` of pass `{}` is unbound", slot.name, pass.name),
            };
            let writable = slot.access == Access::Write;
            entries.push(wgpu::BindGroupLayoutEntry {
                binding,
                visibility: visibility(stage, writable),
                ty,
                count: None,
            });
            slots.push((slot.name, slot.class));
        }
        for o in own {
            let binding = entries.len() as u32;
            let (ty, writable) = match o.kind {
                OwnKind::Sampler(t) => (wgpu::BindingType::Sampler(t), false),
                OwnKind::StorageRead => (storage(true, None), false),
                OwnKind::StorageReadWrite => (storage(false, None), true),
                OwnKind::Uniform => (
                    wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: false,
                        min_binding_size: None,
                    },
                    false,
                ),
                OwnKind::Texture3dUint => (
                    wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Uint,
                        view_dimension: wgpu::TextureViewDimension::D3,
                        multisampled: false,
                    },
                    false,
                ),
                OwnKind::Texture3dFloat => (
                    wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Float { filterable: true },
                        view_dimension: wgpu::TextureViewDimension::D3,
                        multisampled: false,
                    },
                    false,
                ),
                OwnKind::Texture2dFloat => (
                    wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Float { filterable: true },
                        view_dimension: wgpu::TextureViewDimension::D2,
                        multisampled: false,
                    },
                    false,
                ),
                OwnKind::Texture2dUint => (
                    wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Uint,
                        view_dimension: wgpu::TextureViewDimension::D2,
                        multisampled: false,
                    },
                    false,
                ),
            };
            entries.push(wgpu::BindGroupLayoutEntry {
                binding,
                visibility: visibility(stage, writable),
                ty,
                count: None,
            });
        }
        if let Some(used) = used {
            entries.retain(|e| used.contains(&e.binding));
        }
        let layout = ctx
            .device
            .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some(&pass.name),
                entries: &entries,
            });
        Self {
            layout,
            slots,
            own,
            used: used.map(<[u32]>::to_vec),
        }
    }

    /// Whether binding `b` is in the layout.
    fn has(&self, b: u32) -> bool {
        self.used.as_ref().is_none_or(|u| u.contains(&b))
    }

    /// Whether the group has any binding (a pass without one binds no group 1).
    pub fn is_empty(&self) -> bool {
        self.slots.is_empty() && self.own.is_empty()
    }

    /// The bind group for this frame: each slot's resource from `rec`, each own binding
    /// from `own` by name (every one must be given).
    pub fn bind_group(
        &self,
        rec: &Recorder<'_>,
        own: &[OwnResource<'_>],
    ) -> Result<wgpu::BindGroup, PassError> {
        let mut entries = Vec::with_capacity(self.slots.len() + self.own.len());
        for (i, (name, class)) in self.slots.iter().enumerate() {
            if !self.has(i as u32) {
                continue;
            }
            let resource = match class {
                SlotClass::StorageBuffer(_) => rec.buffer(name).as_entire_binding(),
                // A depth(-stencil) texture is sampled through its depth aspect (only
                // those have a depth view).
                SlotClass::DepthStencilAttachment(_) | SlotClass::SampledTexture(_) => {
                    let t = rec.texture(name);
                    wgpu::BindingResource::TextureView(t.depth_view.as_ref().unwrap_or(&t.view))
                }
                _ => wgpu::BindingResource::TextureView(&rec.texture(name).view),
            };
            entries.push(wgpu::BindGroupEntry {
                binding: i as u32,
                resource,
            });
        }
        for (j, o) in self.own.iter().enumerate() {
            let binding = (self.slots.len() + j) as u32;
            if !self.has(binding) {
                continue;
            }
            let (_, resource) = own.iter().find(|(n, _)| *n == o.name).ok_or_else(|| {
                PassError::Bindings(format!(
                    "pass `{}`: own binding `{}` was not given",
                    rec.pass.name, o.name
                ))
            })?;
            entries.push(wgpu::BindGroupEntry {
                binding,
                resource: resource.clone(),
            });
        }
        Ok(rec
            .gpu
            .device
            .create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some(&rec.pass.name),
                layout: &self.layout,
                entries: &entries,
            }))
    }

    /// A bind group of own resources only (a pass whose group 1 has no graph slots, built
    /// outside a frame, e.g. once per uploaded cache).
    pub fn own_bind_group(
        &self,
        device: &wgpu::Device,
        label: &str,
        own: &[OwnResource<'_>],
    ) -> Result<wgpu::BindGroup, PassError> {
        if !self.slots.is_empty() {
            return Err(PassError::Bindings(format!(
                "{label}: the group has graph slots; make it per frame"
            )));
        }
        let mut entries = Vec::with_capacity(self.own.len());
        for (j, o) in self.own.iter().enumerate() {
            if !self.has(j as u32) {
                continue;
            }
            let (_, resource) = own.iter().find(|(n, _)| *n == o.name).ok_or_else(|| {
                PassError::Bindings(format!("{label}: own binding `{}` was not given", o.name))
            })?;
            entries.push(wgpu::BindGroupEntry {
                binding: j as u32,
                resource: resource.clone(),
            });
        }
        Ok(device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(label),
            layout: &self.layout,
            entries: &entries,
        }))
    }
}

/// The binding type of a texture slot for the format actually bound.
fn texture_binding(
    ctx: &GpuContext,
    class: SlotClass,
    access: Access,
    format: wgpu::TextureFormat,
) -> wgpu::BindingType {
    match class {
        // Write-only where written: WebGPU allows read-write storage only for the
        // single-channel 32-bit formats.
        SlotClass::StorageTexture(_) => wgpu::BindingType::StorageTexture {
            access: match access {
                Access::Write => wgpu::StorageTextureAccess::WriteOnly,
                Access::Read => wgpu::StorageTextureAccess::ReadOnly,
            },
            format,
            view_dimension: wgpu::TextureViewDimension::D2,
        },
        _ => {
            // Depth as an unfilterable float (`texture_2d<f32>`, `.x`): GLSL has no texel
            // fetch from depth textures, and no pass compares depth in a sampler.
            let sample_type = if format.is_depth_stencil_format() {
                wgpu::TextureSampleType::Float { filterable: false }
            } else {
                match format.sample_type(None, Some(ctx.device.features())) {
                    Some(t) => t,
                    None => wgpu::TextureSampleType::Float { filterable: false },
                }
            };
            wgpu::BindingType::Texture {
                sample_type,
                view_dimension: wgpu::TextureViewDimension::D2,
                multisampled: false,
            }
        }
    }
}
