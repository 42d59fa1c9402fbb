//! Phase 6 of resolution: allocation. The scheduled passes are bound to live resources
//! whose first and last use (schedule indices) and usages come from the slots they fill;
//! live resources with one descriptor whose lifetimes do not overlap then share a
//! physical resource. Byte sizes and the memory report with and without aliasing live
//! here too, since they are what aliasing saves.

use std::collections::{BTreeSet, HashMap};

use super::bind::RawBinding;
use super::ctx::Ctx;
use super::resolved::{
    BoundSlot, MAX_TEXTURE_EDGE, MemoryReport, PhysicalResource, ResolvedPipeline,
    ResolvedResource, ResourceUsage, ScheduledPass,
};
use crate::kinds::{Access, SlotClass, SlotDesc};
use crate::schema::{CountDesc, ResourceDesc, SizeDesc};

impl SizeDesc {
    /// Texel size for a screen of `screen` texels.
    pub fn resolve(&self, screen: (u32, u32)) -> (u32, u32) {
        match *self {
            SizeDesc::Screen => screen,
            SizeDesc::ScreenScaled(f) => {
                let s = |v: u32| ((v as f64 * f as f64).ceil() as u32).clamp(1, MAX_TEXTURE_EDGE);
                (s(screen.0), s(screen.1))
            }
            SizeDesc::Fixed(w, h) => (w, h),
        }
    }
}

impl CountDesc {
    /// Element count for a screen of `screen` texels (with the scale of `ScreenPixelsScaled`
    /// applied per axis, like a texture of [`SizeDesc::ScreenScaled`]).
    pub fn resolve(&self, screen: (u32, u32)) -> u64 {
        match *self {
            CountDesc::ScreenPixels => screen.0 as u64 * screen.1 as u64,
            CountDesc::ScreenPixelsScaled(f) => {
                let (w, h) = SizeDesc::ScreenScaled(f).resolve(screen);
                w as u64 * h as u64
            }
            CountDesc::Fixed(n) => n,
        }
    }
}

impl ResourceDesc {
    /// Bytes at a screen size.
    pub fn bytes(&self, screen: (u32, u32)) -> u64 {
        match self {
            ResourceDesc::Texture { format, size } => {
                let (w, h) = size.resolve(screen);
                w as u64 * h as u64 * format.bytes_per_texel()
            }
            ResourceDesc::Buffer { layout, count } => count.resolve(screen) * layout.element_size(),
        }
    }

    /// Human-readable size at a screen size (`640x480 Rgba32Float`, `307200 x VoxelSlot`).
    pub fn describe(&self, screen: (u32, u32)) -> String {
        match self {
            ResourceDesc::Texture { format, size } => {
                let (w, h) = size.resolve(screen);
                format!("texture {w}x{h} {format:?}")
            }
            ResourceDesc::Buffer { layout, count } => {
                format!("buffer {} x {layout:?}", count.resolve(screen))
            }
        }
    }
}

impl ResolvedPipeline {
    /// Memory of the live resources at a screen size, with and without aliasing.
    pub fn memory(&self, screen: (u32, u32)) -> MemoryReport {
        MemoryReport {
            unaliased: self.resources.iter().map(|r| r.desc.bytes(screen)).sum(),
            aliased: self.physical.iter().map(|p| p.desc.bytes(screen)).sum(),
        }
    }
}

/// The scheduled passes bound to live resources, before allocation.
pub(super) struct Lifetimes {
    /// Live passes in schedule order.
    pub(super) passes: Vec<ScheduledPass>,
    /// Live resources in order of first use, `physical` not yet set.
    pub(super) resources: Vec<ResolvedResource>,
    /// Index of the output in `resources`.
    pub(super) output: usize,
}

impl Ctx<'_> {
    /// Live resources, in order of first use; usages and lifetimes. `order` is the
    /// schedule (pass indices); `output` and `kept` are resource declaration indices, and
    /// live to the end of the frame with a copy usage for readback.
    pub(super) fn lifetimes(
        &self,
        order: &[usize],
        bindings: &[Vec<RawBinding>],
        output: usize,
        kept: &[usize],
    ) -> Lifetimes {
        let desc = self.desc;
        let mut res_map: HashMap<usize, usize> = HashMap::new();
        let mut resources: Vec<ResolvedResource> = Vec::new();
        let mut passes = Vec::new();
        for (si, &p) in order.iter().enumerate() {
            let mut bound = Vec::new();
            for b in &bindings[p] {
                let idx = *res_map.entry(b.resource).or_insert_with(|| {
                    let (name, d) = &desc.resources.0[b.resource];
                    resources.push(ResolvedResource {
                        name: name.clone(),
                        desc: d.clone(),
                        usage: empty_usage(d),
                        first_use: si,
                        last_use: si,
                        physical: usize::MAX,
                    });
                    resources.len() - 1
                });
                let r = &mut resources[idx];
                r.last_use = si;
                r.usage = add_usage(r.usage, &b.slot);
                bound.push(BoundSlot {
                    slot: b.slot,
                    resource: idx,
                });
            }
            passes.push(ScheduledPass {
                name: desc.passes[p].name.clone(),
                kind: desc.passes[p].kind.clone(),
                bindings: bound,
            });
        }
        let output = res_map[&output];
        let kept: Vec<usize> = kept.iter().map(|k| res_map[k]).collect();
        for &r in kept.iter().chain([&output]) {
            resources[r].last_use = passes.len().saturating_sub(1);
            if let ResourceUsage::Texture(u) = &mut resources[r].usage {
                *u |= wgpu_types::TextureUsages::COPY_SRC;
            }
        }
        Lifetimes {
            passes,
            resources,
            output,
        }
    }

    /// Names of the declared resources no live pass touches, in file order.
    pub(super) fn pruned_resources(&self, resources: &[ResolvedResource]) -> Vec<String> {
        let live_names: BTreeSet<&str> = resources.iter().map(|r| r.name.as_str()).collect();
        self.desc
            .resources
            .0
            .iter()
            .filter(|(n, _)| !live_names.contains(n.as_str()))
            .map(|(n, _)| n.clone())
            .collect()
    }
}

fn empty_usage(d: &ResourceDesc) -> ResourceUsage {
    match d {
        ResourceDesc::Texture { .. } => ResourceUsage::Texture(wgpu_types::TextureUsages::empty()),
        // Buffers are cleared and may be read back for statistics and tests.
        ResourceDesc::Buffer { .. } => ResourceUsage::Buffer(
            wgpu_types::BufferUsages::COPY_DST | wgpu_types::BufferUsages::COPY_SRC,
        ),
    }
}

fn add_usage(u: ResourceUsage, slot: &SlotDesc) -> ResourceUsage {
    use wgpu_types::{BufferUsages as B, TextureUsages as T};
    match u {
        ResourceUsage::Texture(t) => ResourceUsage::Texture(
            t | match slot.class {
                SlotClass::ColorAttachment(_) => T::RENDER_ATTACHMENT,
                SlotClass::DepthStencilAttachment(_) if slot.access == Access::Read => {
                    T::RENDER_ATTACHMENT | T::TEXTURE_BINDING
                }
                SlotClass::DepthStencilAttachment(_) => T::RENDER_ATTACHMENT,
                SlotClass::SampledTexture(_) => T::TEXTURE_BINDING,
                SlotClass::StorageTexture(_) => T::STORAGE_BINDING,
                _ => T::empty(),
            },
        ),
        ResourceUsage::Buffer(b) => ResourceUsage::Buffer(
            b | match slot.class {
                SlotClass::StorageBuffer(_) => B::STORAGE,
                SlotClass::IndirectBuffer(_) => B::INDIRECT,
                _ => B::empty(),
            },
        ),
    }
}

/// Greedy interval allocation: resources in order of first use take the first physical
/// resource with the same descriptor that is free (its last alias ended earlier). The
/// output is never shared (it must survive the frame for presentation or readback).
pub(super) fn allocate(resources: &mut [ResolvedResource], output: usize) -> Vec<PhysicalResource> {
    let mut physical: Vec<PhysicalResource> = Vec::new();
    let mut busy_until: Vec<usize> = Vec::new();
    let mut order: Vec<usize> = (0..resources.len()).collect();
    order.sort_by_key(|&i| (resources[i].first_use, i));
    for i in order {
        let r = &resources[i];
        let slot = if i == output {
            None
        } else {
            (0..physical.len()).find(|&p| {
                physical[p].desc == r.desc
                    && busy_until[p] < r.first_use
                    && !physical[p].aliases.contains(&output)
            })
        };
        let p = match slot {
            Some(p) => {
                physical[p].usage = union_usage(physical[p].usage, r.usage);
                physical[p].aliases.push(i);
                busy_until[p] = r.last_use;
                p
            }
            None => {
                physical.push(PhysicalResource {
                    desc: r.desc.clone(),
                    usage: r.usage,
                    aliases: vec![i],
                });
                busy_until.push(r.last_use);
                physical.len() - 1
            }
        };
        resources[i].physical = p;
    }
    // Every alias must be created with the union of the usages.
    for r in resources.iter_mut() {
        r.usage = physical[r.physical].usage;
    }
    physical
}

fn union_usage(a: ResourceUsage, b: ResourceUsage) -> ResourceUsage {
    match (a, b) {
        (ResourceUsage::Texture(x), ResourceUsage::Texture(y)) => ResourceUsage::Texture(x | y),
        (ResourceUsage::Buffer(x), ResourceUsage::Buffer(y)) => ResourceUsage::Buffer(x | y),
        (a, _) => a,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use wgpu_types::{BufferUsages as B, TextureUsages as T};

    #[test]
    fn storage_textures_and_unions_of_aliased_usages() {
        // No registered kind has a storage-texture slot yet; the usage is still derived.
        let slot = SlotDesc {
            name: "s",
            access: Access::Write,
            class: SlotClass::StorageTexture(&[]),
        };
        assert_eq!(
            add_usage(ResourceUsage::Texture(T::COPY_SRC), &slot),
            ResourceUsage::Texture(T::COPY_SRC | T::STORAGE_BINDING)
        );
        // Resources sharing memory need every usage of each.
        assert_eq!(
            union_usage(
                ResourceUsage::Texture(T::RENDER_ATTACHMENT | T::COPY_SRC),
                ResourceUsage::Texture(T::TEXTURE_BINDING | T::COPY_SRC)
            ),
            ResourceUsage::Texture(T::RENDER_ATTACHMENT | T::TEXTURE_BINDING | T::COPY_SRC)
        );
        assert_eq!(
            union_usage(
                ResourceUsage::Buffer(B::STORAGE | B::COPY_DST),
                ResourceUsage::Buffer(B::INDIRECT | B::COPY_DST)
            ),
            ResourceUsage::Buffer(B::STORAGE | B::INDIRECT | B::COPY_DST)
        );
    }
}
