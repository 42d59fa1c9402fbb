//! The result of resolution: the scheduled passes, the live and physical resources and the
//! limits the declarations are checked against. The phases build these; nothing here
//! depends on them.

use petgraph::graph::DiGraph;

use crate::kinds::{Access, PassKind, SlotDesc};
use crate::schema::{PipelineDesc, ResourceDesc};

/// Largest fixed texture edge a pipeline may ask for.
pub const MAX_TEXTURE_EDGE: u32 = 16384;
/// Largest fixed buffer element count a pipeline may ask for.
pub const MAX_BUFFER_ELEMENTS: u64 = 1 << 31;

/// Why an edge exists in the pass DAG.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Dependency {
    /// The target reads (or also writes) a resource the source writes.
    Resource(String),
    /// The target names the source in `after`.
    After,
}

/// A slot of a scheduled pass bound to a live resource.
#[derive(Debug, Clone, PartialEq)]
pub struct BoundSlot {
    /// The slot as the kind declares it.
    pub slot: SlotDesc,
    /// Index into [`ResolvedPipeline::resources`].
    pub resource: usize,
}

/// A live pass, in schedule order.
#[derive(Debug, Clone, PartialEq)]
pub struct ScheduledPass {
    /// Pass name.
    pub name: String,
    /// Kind and parameters.
    pub kind: PassKind,
    /// Every slot of the kind, bound.
    pub bindings: Vec<BoundSlot>,
}

impl ScheduledPass {
    /// The resource bound to slot `slot`.
    pub fn resource_of(&self, slot: &str) -> Option<usize> {
        self.bindings
            .iter()
            .find(|b| b.slot.name == slot)
            .map(|b| b.resource)
    }
}

/// How a live resource is used, derived from the slots it is bound to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ResourceUsage {
    /// Texture usages.
    Texture(wgpu_types::TextureUsages),
    /// Buffer usages.
    Buffer(wgpu_types::BufferUsages),
}

/// A live resource.
#[derive(Debug, Clone, PartialEq)]
pub struct ResolvedResource {
    /// Resource name.
    pub name: String,
    /// As declared.
    pub desc: ResourceDesc,
    /// Union of the usages of every slot it is bound to (plus copies for readback).
    pub usage: ResourceUsage,
    /// Index in the schedule of the first pass that touches it.
    pub first_use: usize,
    /// Index in the schedule of the last pass that touches it (the output lives to the end).
    pub last_use: usize,
    /// Index of the physical resource it is allocated to (shared when aliased).
    pub physical: usize,
}

/// A physical resource that one or more live resources alias.
#[derive(Debug, Clone, PartialEq)]
pub struct PhysicalResource {
    /// Descriptor shared by every resource aliased onto it.
    pub desc: ResourceDesc,
    /// Union of their usages.
    pub usage: ResourceUsage,
    /// Indices of the resources aliased onto it, in schedule order.
    pub aliases: Vec<usize>,
}

/// The pipeline after validation, pruning, scheduling and allocation.
#[derive(Debug, Clone)]
pub struct ResolvedPipeline {
    /// File it came from.
    pub file: String,
    /// Every file it was read from: `file` first, then the files it includes.
    pub sources: Vec<String>,
    /// The file as parsed, holding what its included files declare.
    pub desc: PipelineDesc,
    /// The DAG of all declared passes (node weight: pass name), edges with reasons.
    pub dag: DiGraph<String, Dependency>,
    /// Live passes in schedule order.
    pub passes: Vec<ScheduledPass>,
    /// Live resources (indices are stable for the life of this value).
    pub resources: Vec<ResolvedResource>,
    /// Physical resources after aliasing.
    pub physical: Vec<PhysicalResource>,
    /// Index of the output in `resources`.
    pub output: usize,
    /// Passes that do not contribute to the output.
    pub pruned_passes: Vec<String>,
    /// Resources no live pass touches.
    pub pruned_resources: Vec<String>,
}

/// Byte sizes for one screen size.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MemoryReport {
    /// Bytes if every live resource had its own allocation.
    pub unaliased: u64,
    /// Bytes of the physical resources after aliasing.
    pub aliased: u64,
}

impl ResolvedPipeline {
    /// Index of a live resource by name.
    pub fn resource(&self, name: &str) -> Option<usize> {
        self.resources.iter().position(|r| r.name == name)
    }

    /// A plain-text report: schedule, resources with sizes, aliasing and pruned items.
    pub fn describe(&self, screen: (u32, u32)) -> String {
        use std::fmt::Write;
        let mut s = String::new();
        let _ = writeln!(
            s,
            "pipeline {} (screen {}x{})",
            self.file, screen.0, screen.1
        );
        let _ = writeln!(s, "schedule:");
        for (i, p) in self.passes.iter().enumerate() {
            let reads: Vec<_> = p
                .bindings
                .iter()
                .filter(|b| b.slot.access == Access::Read)
                .map(|b| self.resources[b.resource].name.as_str())
                .collect();
            let writes: Vec<_> = p
                .bindings
                .iter()
                .filter(|b| b.slot.access == Access::Write)
                .map(|b| self.resources[b.resource].name.as_str())
                .collect();
            let _ = writeln!(
                s,
                "  {i}. {} ({}) reads [{}] writes [{}]",
                p.name,
                p.kind.name(),
                reads.join(", "),
                writes.join(", ")
            );
        }
        let _ = writeln!(s, "resources:");
        for (i, r) in self.resources.iter().enumerate() {
            let shared = &self.physical[r.physical].aliases;
            let alias = if shared.len() > 1 {
                let others: Vec<_> = shared
                    .iter()
                    .filter(|&&j| j != i)
                    .map(|&j| self.resources[j].name.as_str())
                    .collect();
                format!(", shares memory with {}", others.join(", "))
            } else {
                String::new()
            };
            let _ = writeln!(
                s,
                "  {}: {} ({} bytes), passes {}..={}{}{}",
                r.name,
                r.desc.describe(screen),
                r.desc.bytes(screen),
                r.first_use,
                r.last_use,
                if i == self.output { ", output" } else { "" },
                alias
            );
        }
        let m = self.memory(screen);
        let _ = writeln!(
            s,
            "memory: {} bytes in {} physical resources ({} bytes without aliasing, {} saved)",
            m.aliased,
            self.physical.len(),
            m.unaliased,
            m.unaliased - m.aliased
        );
        let list = |v: &[String]| {
            if v.is_empty() {
                "none".to_string()
            } else {
                v.join(", ")
            }
        };
        let _ = writeln!(s, "pruned passes: {}", list(&self.pruned_passes));
        let _ = writeln!(s, "pruned resources: {}", list(&self.pruned_resources));
        s
    }
}
