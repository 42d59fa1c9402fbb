//! Resolution of a pipeline file into a validated, pruned, scheduled DAG with allocated
//! resources (the graph's `bake`, in clear steps):
//!
//! 1. parse (RON syntax errors with line and column; unknown pass kinds all at once);
//! 2. check declarations (duplicates, sizes, parameters) and every pass's bindings against
//!    the slots its kind declares (class, format, layout, attachment sizes);
//! 3. build a petgraph DAG: an edge from each writer of a resource to each reader, and one
//!    for each `after`; writers of one resource must be ordered; cycles are named;
//! 4. prune what does not reach the output, walking back from the output's writers;
//! 5. schedule topologically (file order breaks ties, so schedules are stable);
//! 6. allocate: first/last use per resource, and resources with one descriptor whose
//!    lifetimes do not overlap share a physical resource.

use std::cmp::Reverse;
use std::collections::{BTreeSet, BinaryHeap, HashMap};

use petgraph::graph::{DiGraph, NodeIndex};
use petgraph::visit::EdgeRef;

use crate::error::{GraphError, Loc, PipelineErrors, suggest};
use crate::kinds::{KIND_NAMES, PassKind};
use crate::locate::Locator;
use crate::pass_kind::{Access, SlotClass, SlotDesc};
use crate::schema::{BufferLayout, CountDesc, Format, PipelineDesc, ResourceDesc, SizeDesc};

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
    /// The file as parsed.
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

/// Reads and resolves a pipeline file.
pub fn resolve_file(path: &std::path::Path) -> Result<ResolvedPipeline, PipelineErrors> {
    let file = path.display().to_string();
    match std::fs::read_to_string(path) {
        Ok(src) => resolve_str(&src, &file),
        Err(e) => Err(PipelineErrors {
            file: file.clone(),
            errors: vec![GraphError::Io {
                at: Loc { file, pos: None },
                message: e.to_string(),
            }],
        }),
    }
}

/// Parses and resolves pipeline text; `file` names it in errors.
pub fn resolve_str(src: &str, file: &str) -> Result<ResolvedPipeline, PipelineErrors> {
    let loc = Locator::new(src);
    let desc = parse(src, file, &loc).map_err(|errors| PipelineErrors {
        file: file.to_string(),
        errors,
    })?;
    resolve_parsed(&desc, file, &loc)
}

/// Validates and resolves a pipeline description that has no text (built or edited in
/// code, see [`ResolvedPipeline::edited`]): the same checks as [`resolve_str`], with errors
/// that name the pass and resource but no line.
pub fn resolve_desc(desc: &PipelineDesc, file: &str) -> Result<ResolvedPipeline, PipelineErrors> {
    resolve_parsed(desc, file, &Locator::new(""))
}

fn resolve_parsed(
    desc: &PipelineDesc,
    file: &str,
    loc: &Locator,
) -> Result<ResolvedPipeline, PipelineErrors> {
    let mut ctx = Ctx {
        file,
        loc,
        desc,
        errors: Vec::new(),
    };
    let out = ctx.resolve();
    let mut errors = ctx.errors;
    match out {
        Some(r) if errors.is_empty() => Ok(r),
        _ => {
            errors.sort_by_key(|e| e.loc().pos);
            errors.dedup();
            Err(PipelineErrors {
                file: file.to_string(),
                errors,
            })
        }
    }
}

/// RON → [`PipelineDesc`]. Unknown pass kinds are found by scanning the text, so all of
/// them are reported at once with suggestions, not only the first serde meets.
fn parse(src: &str, file: &str, loc: &Locator) -> Result<PipelineDesc, Vec<GraphError>> {
    let mut errors = Vec::new();
    for (found, pos, pass) in loc.kinds() {
        if !KIND_NAMES.contains(&found.as_str()) {
            errors.push(GraphError::UnknownKind {
                at: Loc {
                    file: file.to_string(),
                    pos: Some(pos),
                },
                pass: pass.unwrap_or_else(|| "?".to_string()),
                found: found.clone(),
                hint: suggest(&found, KIND_NAMES.iter().copied()),
            });
        }
    }
    match ron::Options::default()
        .with_default_extension(ron::extensions::Extensions::UNWRAP_VARIANT_NEWTYPES)
        .from_str::<PipelineDesc>(src)
    {
        Ok(d) if errors.is_empty() => Ok(d),
        Ok(_) => Err(errors),
        Err(e) => {
            let pos = crate::locate::Position {
                line: e.span.start.line,
                col: e.span.start.col,
            };
            let already = matches!(e.code, ron::Error::NoSuchEnumVariant { outer: Some(ref o), .. } if o == "PassKind");
            if !already || errors.is_empty() {
                let message = match &e.code {
                    ron::Error::NoSuchEnumVariant {
                        expected, found, ..
                    } => format!(
                        "unexpected `{found}`{}",
                        suggest(found, expected.iter().copied())
                    ),
                    other => other.to_string(),
                };
                errors.push(GraphError::Syntax {
                    at: Loc {
                        file: file.to_string(),
                        pos: Some(pos),
                    },
                    message,
                });
            }
            errors.sort_by_key(|e| e.loc().pos);
            Err(errors)
        }
    }
}

struct Ctx<'a> {
    file: &'a str,
    loc: &'a Locator,
    desc: &'a PipelineDesc,
    errors: Vec<GraphError>,
}

/// A validated binding, before pruning: pass index, slot, resource declaration index.
#[derive(Clone)]
struct RawBinding {
    slot: SlotDesc,
    resource: usize,
}

impl<'a> Ctx<'a> {
    fn at(&self, pos: Option<crate::locate::Position>) -> Loc {
        Loc {
            file: self.file.to_string(),
            pos,
        }
    }

    fn resolve(&mut self) -> Option<ResolvedPipeline> {
        let desc = self.desc;
        // Declarations.
        let mut res_index: HashMap<&str, usize> = HashMap::new();
        for (i, (name, r)) in desc.resources.0.iter().enumerate() {
            if res_index.insert(name.as_str(), i).is_some() {
                let nth = desc.resources.0[..i]
                    .iter()
                    .filter(|(n, _)| n == name)
                    .count();
                self.errors.push(GraphError::DuplicateResource {
                    at: self.at(self.loc.resource_declarations(name).get(nth).copied()),
                    resource: name.clone(),
                });
            }
            if let Some(message) = resource_problem(r) {
                self.errors.push(GraphError::BadResource {
                    at: self.at(self.loc.resource(name)),
                    resource: name.clone(),
                    message,
                });
            }
        }
        let mut pass_index: HashMap<&str, usize> = HashMap::new();
        for (i, p) in desc.passes.iter().enumerate() {
            if pass_index.insert(p.name.as_str(), i).is_some() {
                let nth = desc.passes[..i].iter().filter(|q| q.name == p.name).count();
                let at = self.at(self.loc.pass_declarations(&p.name).get(nth).copied());
                self.errors.push(GraphError::DuplicatePass {
                    at,
                    pass: p.name.clone(),
                });
            }
            for message in p.kind.parameter_problems() {
                self.errors.push(GraphError::BadParameter {
                    at: self.at(self.loc.pass_field(&p.name, "kind")),
                    pass: p.name.clone(),
                    kind: p.kind.name().to_string(),
                    message,
                });
            }
        }

        // Bindings against slots.
        let bindings: Vec<Vec<RawBinding>> = desc
            .passes
            .iter()
            .map(|p| self.check_bindings(p, &res_index))
            .collect();

        // DAG.
        let mut dag: DiGraph<String, Dependency> = DiGraph::new();
        let nodes: Vec<NodeIndex> = desc
            .passes
            .iter()
            .map(|p| dag.add_node(p.name.clone()))
            .collect();
        let nres = desc.resources.0.len();
        let mut writers: Vec<Vec<usize>> = vec![Vec::new(); nres];
        let mut readers: Vec<Vec<usize>> = vec![Vec::new(); nres];
        for (pi, bs) in bindings.iter().enumerate() {
            for b in bs {
                match b.slot.access {
                    Access::Write => writers[b.resource].push(pi),
                    Access::Read => readers[b.resource].push(pi),
                }
            }
        }
        for r in 0..nres {
            writers[r].dedup();
            readers[r].dedup();
            let name = &desc.resources.0[r].0;
            for &rd in &readers[r] {
                if writers[r].contains(&rd) {
                    self.errors.push(GraphError::ReadWriteSame {
                        at: self.at(self.loc.in_pass(&desc.passes[rd].name, name)),
                        pass: desc.passes[rd].name.clone(),
                        resource: name.clone(),
                    });
                    continue;
                }
                if writers[r].is_empty() {
                    self.errors.push(GraphError::NoProducer {
                        at: self.at(self.loc.in_pass(&desc.passes[rd].name, name)),
                        pass: desc.passes[rd].name.clone(),
                        resource: name.clone(),
                    });
                }
                for &w in &writers[r] {
                    dag.update_edge(nodes[w], nodes[rd], Dependency::Resource(name.clone()));
                }
            }
        }
        for (pi, p) in desc.passes.iter().enumerate() {
            for a in &p.after {
                match pass_index.get(a.as_str()) {
                    Some(&ai) => {
                        dag.update_edge(nodes[ai], nodes[pi], Dependency::After);
                    }
                    None => self.errors.push(GraphError::UnknownAfter {
                        at: self.at(self.loc.in_pass(&p.name, a)),
                        pass: p.name.clone(),
                        after: a.clone(),
                        hint: suggest(a, desc.passes.iter().map(|p| p.name.as_str())),
                    }),
                }
            }
        }

        // Cycles: every strongly connected component with more than one pass, or a self loop.
        let mut cyclic = false;
        for scc in petgraph::algo::tarjan_scc(&dag) {
            let self_loop = scc.len() == 1 && dag.find_edge(scc[0], scc[0]).is_some();
            if scc.len() > 1 || self_loop {
                cyclic = true;
                let cycle = find_cycle(&dag, &scc);
                let first = cycle[0].clone();
                self.errors.push(GraphError::Cycle {
                    at: self.at(self.loc.pass(&first)),
                    cycle,
                });
            }
        }

        // Writers of one resource must be ordered (only meaningful without cycles).
        if !cyclic {
            for (r, w) in writers.iter().enumerate() {
                for i in 0..w.len() {
                    for j in i + 1..w.len() {
                        let (a, b) = (nodes[w[i]], nodes[w[j]]);
                        if !petgraph::algo::has_path_connecting(&dag, a, b, None)
                            && !petgraph::algo::has_path_connecting(&dag, b, a, None)
                        {
                            let second = &desc.passes[w[j]].name;
                            self.errors.push(GraphError::UnorderedWriters {
                                at: self.at(self.loc.in_pass(second, &desc.resources.0[r].0)),
                                resource: desc.resources.0[r].0.clone(),
                                first: desc.passes[w[i]].name.clone(),
                                second: second.clone(),
                            });
                        }
                    }
                }
            }
        }

        // Output.
        let out_at = self.at(self.loc.output());
        let output = match res_index.get(desc.output.as_str()) {
            None => {
                self.errors.push(GraphError::BadOutput {
                    at: out_at,
                    output: desc.output.clone(),
                    message: format!(
                        "is not a declared resource{}",
                        suggest(
                            &desc.output,
                            desc.resources.0.iter().map(|(n, _)| n.as_str())
                        )
                    ),
                });
                None
            }
            Some(&o) => {
                if !matches!(desc.resources.0[o].1, ResourceDesc::Texture { .. }) {
                    self.errors.push(GraphError::BadOutput {
                        at: out_at,
                        output: desc.output.clone(),
                        message: "must be a texture".to_string(),
                    });
                    None
                } else if writers[o].is_empty() {
                    self.errors.push(GraphError::BadOutput {
                        at: out_at,
                        output: desc.output.clone(),
                        message: "is written by no pass".to_string(),
                    });
                    None
                } else {
                    Some(o)
                }
            }
        };
        let mut kept = Vec::new();
        for k in &desc.keep {
            match res_index.get(k.as_str()) {
                Some(&r) if !writers[r].is_empty() => kept.push(r),
                Some(_) => self.errors.push(GraphError::BadOutput {
                    at: self.at(self.loc.resource_declarations(k).last().copied()),
                    output: k.clone(),
                    message: "is kept but written by no pass".to_string(),
                }),
                None => self.errors.push(GraphError::BadOutput {
                    at: self.at(self.loc.output()),
                    output: k.clone(),
                    message: format!(
                        "(in `keep`) is not a declared resource{}",
                        suggest(k, desc.resources.0.iter().map(|(n, _)| n.as_str()))
                    ),
                }),
            }
        }
        if !self.errors.is_empty() || cyclic {
            return None;
        }
        let output = output?;

        // Prune: a pass is live if it writes the output, or writes a resource a live pass
        // touches, or a live pass runs after it (explicit ordering is a promise of effect).
        let mut live = vec![false; desc.passes.len()];
        let mut stack: Vec<usize> = writers[output].clone();
        for &k in &kept {
            stack.extend(writers[k].iter().copied());
        }
        while let Some(p) = stack.pop() {
            if std::mem::replace(&mut live[p], true) {
                continue;
            }
            for b in &bindings[p] {
                stack.extend(writers[b.resource].iter().copied().filter(|&w| !live[w]));
            }
            for e in dag.edges_directed(nodes[p], petgraph::Direction::Incoming) {
                if e.weight() == &Dependency::After && !live[e.source().index()] {
                    stack.push(e.source().index());
                }
            }
        }

        // Schedule: Kahn's algorithm over live passes, smallest file index first.
        let mut indeg = vec![0usize; desc.passes.len()];
        for e in dag.edge_references() {
            if live[e.source().index()] && live[e.target().index()] {
                indeg[e.target().index()] += 1;
            }
        }
        let mut heap: BinaryHeap<Reverse<usize>> = (0..desc.passes.len())
            .filter(|&p| live[p] && indeg[p] == 0)
            .map(Reverse)
            .collect();
        let mut order = Vec::new();
        while let Some(Reverse(p)) = heap.pop() {
            order.push(p);
            for e in dag.edges_directed(nodes[p], petgraph::Direction::Outgoing) {
                let t = e.target().index();
                if live[t] {
                    indeg[t] -= 1;
                    if indeg[t] == 0 {
                        heap.push(Reverse(t));
                    }
                }
            }
        }

        // Live resources, in order of first use; usages and lifetimes.
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
        let physical = allocate(&mut resources, output);

        let pruned_passes = (0..desc.passes.len())
            .filter(|&p| !live[p])
            .map(|p| desc.passes[p].name.clone())
            .collect();
        let live_names: BTreeSet<&str> = resources.iter().map(|r| r.name.as_str()).collect();
        let pruned_resources = desc
            .resources
            .0
            .iter()
            .filter(|(n, _)| !live_names.contains(n.as_str()))
            .map(|(n, _)| n.clone())
            .collect();
        Some(ResolvedPipeline {
            file: self.file.to_string(),
            desc: desc.clone(),
            dag,
            passes,
            resources,
            physical,
            output,
            pruned_passes,
            pruned_resources,
        })
    }

    /// Checks one pass's bindings against its kind's slots; returns the valid ones.
    fn check_bindings(
        &mut self,
        p: &crate::schema::PassDesc,
        res_index: &HashMap<&str, usize>,
    ) -> Vec<RawBinding> {
        let desc = self.desc;
        let slots = p.kind.slots();
        let kind = p.kind.name().to_string();
        let mut out: Vec<RawBinding> = Vec::new();
        let mut attachments: Vec<(String, SizeDesc)> = Vec::new();
        for (access, list, word) in [
            (Access::Read, &p.reads, "reads"),
            (Access::Write, &p.writes, "writes"),
        ] {
            let mut seen = BTreeSet::new();
            for b in &list.0 {
                let at = self.at(self.loc.in_pass(&p.name, &b.resource));
                let Some(slot) = slots
                    .iter()
                    .find(|s| s.name == b.slot && s.access == access)
                else {
                    let expected: Vec<_> = slots
                        .iter()
                        .filter(|s| s.access == access)
                        .map(|s| format!("`{}`", s.name))
                        .collect();
                    let expected = if expected.is_empty() {
                        "none".to_string()
                    } else {
                        expected.join(", ")
                    };
                    self.errors.push(GraphError::UnknownSlot {
                        at: self.at(self.loc.in_pass(&p.name, &b.slot)),
                        pass: p.name.clone(),
                        kind: kind.clone(),
                        slot: b.slot.clone(),
                        access: word,
                        expected,
                    });
                    continue;
                };
                if !seen.insert(b.slot.clone()) {
                    self.errors.push(GraphError::DuplicateSlot {
                        at,
                        pass: p.name.clone(),
                        kind: kind.clone(),
                        slot: b.slot.clone(),
                    });
                    continue;
                }
                let Some(&ri) = res_index.get(b.resource.as_str()) else {
                    self.errors.push(GraphError::UnknownResource {
                        at,
                        pass: p.name.clone(),
                        resource: b.resource.clone(),
                        hint: suggest(
                            &b.resource,
                            desc.resources.0.iter().map(|(n, _)| n.as_str()),
                        ),
                    });
                    continue;
                };
                let r = &desc.resources.0[ri].1;
                let ok = match (r, slot.class) {
                    (ResourceDesc::Texture { format, size }, c) if c.is_texture() => {
                        if c.is_attachment() {
                            attachments.push((b.resource.clone(), *size));
                        }
                        if !c.formats().contains(format) {
                            self.errors.push(GraphError::FormatMismatch {
                                at,
                                pass: p.name.clone(),
                                slot: slot.name.to_string(),
                                resource: b.resource.clone(),
                                found: format!("{format:?}"),
                                accepted: fmt_formats(c.formats()),
                            });
                            false
                        } else {
                            true
                        }
                    }
                    (ResourceDesc::Buffer { layout, .. }, c) if !c.is_texture() => {
                        let want = c.layout().unwrap_or(*layout);
                        if want != *layout {
                            self.errors.push(GraphError::LayoutMismatch {
                                at,
                                pass: p.name.clone(),
                                slot: slot.name.to_string(),
                                resource: b.resource.clone(),
                                found: format!("{layout:?}"),
                                expected: format!("{want:?}"),
                            });
                            false
                        } else {
                            true
                        }
                    }
                    (r, c) => {
                        self.errors.push(GraphError::ClassMismatch {
                            at,
                            pass: p.name.clone(),
                            slot: slot.name.to_string(),
                            resource: b.resource.clone(),
                            expected: c.describe(),
                            found: match r {
                                ResourceDesc::Texture { .. } => "texture",
                                ResourceDesc::Buffer { .. } => "buffer",
                            },
                        });
                        false
                    }
                };
                if ok {
                    out.push(RawBinding {
                        slot: *slot,
                        resource: ri,
                    });
                }
            }
        }
        for s in slots {
            let bound = match s.access {
                Access::Read => p.reads.0.iter().any(|b| b.slot == s.name),
                Access::Write => p.writes.0.iter().any(|b| b.slot == s.name),
            };
            if !bound {
                self.errors.push(GraphError::MissingSlot {
                    at: self.at(self.loc.pass(&p.name)),
                    pass: p.name.clone(),
                    kind: kind.clone(),
                    slot: s.name.to_string(),
                    access: if s.access == Access::Read {
                        "read"
                    } else {
                        "write"
                    },
                    class: s.class.describe(),
                });
            }
        }
        if let Some((first, fs)) = attachments.first() {
            for (name, s) in &attachments[1..] {
                if s != fs {
                    self.errors.push(GraphError::AttachmentSizeMismatch {
                        at: self.at(self.loc.in_pass(&p.name, name)),
                        pass: p.name.clone(),
                        first: first.clone(),
                        first_size: format!("{fs:?}"),
                        second: name.clone(),
                        second_size: format!("{s:?}"),
                    });
                }
            }
        }
        out
    }
}

fn fmt_formats(f: &[Format]) -> String {
    f.iter()
        .map(|f| format!("{f:?}"))
        .collect::<Vec<_>>()
        .join(" | ")
}

fn resource_problem(r: &ResourceDesc) -> Option<String> {
    match r {
        ResourceDesc::Texture { size, .. } => match *size {
            SizeDesc::ScreenScaled(f) if !(f.is_finite() && f > 0.0 && f <= 16.0) => {
                Some(format!("ScreenScaled factor must be in (0, 16], got {f}"))
            }
            SizeDesc::Fixed(w, h)
                if w == 0 || h == 0 || w > MAX_TEXTURE_EDGE || h > MAX_TEXTURE_EDGE =>
            {
                Some(format!(
                    "Fixed size must be 1..={MAX_TEXTURE_EDGE} texels per side, got {w}x{h}"
                ))
            }
            _ => None,
        },
        ResourceDesc::Buffer { count, layout } => match *count {
            CountDesc::ScreenPixelsScaled(f) if !(f.is_finite() && f > 0.0 && f <= 16.0) => Some(
                format!("ScreenPixelsScaled factor must be in (0, 16], got {f}"),
            ),
            CountDesc::Fixed(n) if n == 0 || n > MAX_BUFFER_ELEMENTS => Some(format!(
                "Fixed count must be 1..={MAX_BUFFER_ELEMENTS}, got {n}"
            )),
            CountDesc::Fixed(n) if *layout == BufferLayout::DrawIndirect && n != 1 => Some(
                format!("a DrawIndirect buffer holds one draw, got count {n}"),
            ),
            _ => None,
        },
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
fn allocate(resources: &mut [ResolvedResource], output: usize) -> Vec<PhysicalResource> {
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

/// One simple cycle inside a strongly connected component, as pass names, closed
/// (the first name repeated at the end).
fn find_cycle(dag: &DiGraph<String, Dependency>, scc: &[NodeIndex]) -> Vec<String> {
    let inside: BTreeSet<NodeIndex> = scc.iter().copied().collect();
    let start = *scc.iter().min().expect("non-empty component");
    // Breadth-first search from `start` back to `start` inside the component.
    let mut prev: HashMap<NodeIndex, NodeIndex> = HashMap::new();
    let mut queue = std::collections::VecDeque::from([start]);
    let mut end = None;
    'bfs: while let Some(n) = queue.pop_front() {
        let mut next: Vec<NodeIndex> = dag.neighbors(n).filter(|m| inside.contains(m)).collect();
        next.sort();
        for m in next {
            if m == start {
                end = Some(n);
                break 'bfs;
            }
            if let std::collections::hash_map::Entry::Vacant(e) = prev.entry(m) {
                e.insert(n);
                queue.push_back(m);
            }
        }
    }
    let mut path = vec![start];
    let mut n = end.unwrap_or(start);
    let mut back = Vec::new();
    while n != start {
        back.push(n);
        n = prev[&n];
    }
    path.extend(back.into_iter().rev());
    path.push(start);
    path.into_iter().map(|n| dag[n].clone()).collect()
}
