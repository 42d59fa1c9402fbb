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
//!
//! This module holds the public result types, the entry points and step 1; each later
//! step is a phase in its own file (`declare`, `bind`, `dag`, `schedule`, `alias`), run
//! in order by `Ctx::resolve`. Every phase records all the errors it finds and the
//! pipeline is only built when there are none, so one run reports every problem of a file.

mod alias;
mod bind;
mod dag;
mod declare;
mod schedule;

use petgraph::graph::DiGraph;

use crate::error::{GraphError, Loc, PipelineErrors, suggest};
use crate::kinds::{KIND_NAMES, PassKind};
use crate::locate::Locator;
use crate::pass_kind::{Access, SlotDesc};
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

/// State shared by the resolution phases: the input and the errors found so far. Each
/// phase is an `impl Ctx` block in its own file.
struct Ctx<'a> {
    file: &'a str,
    loc: &'a Locator,
    desc: &'a PipelineDesc,
    errors: Vec<GraphError>,
}

impl Ctx<'_> {
    /// A location in this file.
    fn at(&self, pos: Option<crate::locate::Position>) -> Loc {
        Loc {
            file: self.file.to_string(),
            pos,
        }
    }

    /// The phases in order. Each records the errors it finds; the pipeline is built only
    /// when none did (a later phase may still run after errors, to report more of them).
    fn resolve(&mut self) -> Option<ResolvedPipeline> {
        let declared = self.declare();
        let bindings = self.bind(&declared.resources);
        let dag = self.build_dag(&bindings, &declared.passes);
        let roots = self.roots(&declared.resources, &dag.writers);
        if !self.errors.is_empty() || dag.cyclic {
            return None;
        }
        let output = roots.output?;
        let live = dag.live(&bindings, output, &roots.kept);
        let order = dag.schedule(&live);
        let mut used = self.lifetimes(&order, &bindings, output, &roots.kept);
        let physical = alias::allocate(&mut used.resources, used.output);
        Some(ResolvedPipeline {
            file: self.file.to_string(),
            desc: self.desc.clone(),
            pruned_passes: self.pruned_passes(&live),
            pruned_resources: self.pruned_resources(&used.resources),
            dag: dag.graph,
            passes: used.passes,
            resources: used.resources,
            physical,
            output: used.output,
        })
    }
}
