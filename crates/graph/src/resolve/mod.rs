//! Resolution of a pipeline file into a validated, pruned, scheduled DAG with allocated
//! resources (the graph's `bake`, in clear steps):
//!
//! 1. parse (RON syntax errors with line and column; unknown pass kinds all at once);
//! 2. check declarations (duplicates, sizes, parameters) and every pass's bindings against
//!    the slots its kind declares (class, format, layout, attachment sizes);
//! 3. build a petgraph DAG: an edge from each writer of a resource to each reader, and one
//!    for each `after`; writers of one resource must be ordered; cycles are named; a pass
//!    that needs something of the passes writing what it reads is checked against them
//!    (`writers`);
//! 4. prune what does not reach the output, walking back from the output's writers;
//! 5. schedule topologically (file order breaks ties, so schedules are stable);
//! 6. allocate: first/last use per resource, and resources with one descriptor whose
//!    lifetimes do not overlap share a physical resource.
//!
//! This module holds the entry points (step 1 is `crate::parse`, per file, with
//! `crate::include` merging the included files); the public result types are in
//! `resolved` and the state the phases share in `ctx`. Each later step is a phase in its
//! own file (`declare`, `bind`, `dag`, `schedule`, `alias`), run in order by
//! `Ctx::resolve`. Every phase records all the errors it finds and the
//! pipeline is only built when there are none, so one run reports every problem of a file.

mod alias;
mod bind;
mod ctx;
mod dag;
mod declare;
mod resolved;
mod schedule;
mod writers;

pub use resolved::{
    BoundSlot, Dependency, MAX_BUFFER_ELEMENTS, MAX_TEXTURE_EDGE, MemoryReport, PhysicalResource,
    ResolvedPipeline, ResolvedResource, ResourceUsage, ScheduledPass,
};

use crate::error::{GraphError, Loc, PipelineErrors};
use crate::include::{ReadSource, Sources};
use crate::schema::PipelineDesc;
use ctx::Ctx;

/// Bundled pipeline files that were renamed so that a technique's name is its file's stem:
/// (old file name, new file name).
pub const RENAMED_FILES: &[(&str, &str)] = &[
    ("ssbvb.ron", "ssbvb_unique.ron"),
    ("octree_ray_cast.ron", "octree.ron"),
];

/// `path`, or where a renamed file ([`RENAMED_FILES`]) went when `path` names the old file
/// and is gone.
pub fn current_path(path: &std::path::Path) -> std::path::PathBuf {
    if !path.exists() {
        let name = path
            .file_name()
            .and_then(|n| n.to_str())
            .unwrap_or_default();
        if let Some((_, new)) = RENAMED_FILES.iter().find(|(old, _)| *old == name) {
            let moved = path.with_file_name(new);
            if moved.is_file() {
                return moved;
            }
        }
    }
    path.to_path_buf()
}

/// Reads and resolves a pipeline file (and the files it includes, relative to it). The old
/// path of a renamed bundled file reads the new one ([`current_path`]).
pub fn resolve_file(path: &std::path::Path) -> Result<ResolvedPipeline, PipelineErrors> {
    let path = &current_path(path);
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

/// Parses and resolves pipeline text; `file` names it in errors, and the files it
/// includes are read from the file system relative to it.
pub fn resolve_str(src: &str, file: &str) -> Result<ResolvedPipeline, PipelineErrors> {
    resolve_str_with(src, file, &crate::include::read_file)
}

/// [`resolve_str`] with the included files read by `read` (given each file's path joined to
/// its includer's folder, [`crate::include::include_path`]).
pub fn resolve_str_with(
    src: &str,
    file: &str,
    read: ReadSource<'_>,
) -> Result<ResolvedPipeline, PipelineErrors> {
    let errs = |errors| PipelineErrors {
        file: file.to_string(),
        errors,
    };
    let (desc, sources) = crate::include::load(src, file, read).map_err(errs)?;
    if desc.output.is_empty() {
        return Err(errs(vec![GraphError::Syntax {
            at: Loc {
                file: file.to_string(),
                pos: None,
            },
            message: "no `output:` (a pipeline names the texture it produces; a file of \
                      shared declarations is included by pipelines, not used alone)"
                .into(),
        }]));
    }
    resolve_parsed(&desc, file, &sources)
}

/// Validates and resolves a pipeline description that has no text (built or edited in
/// code, see [`ResolvedPipeline::edited`]): the same checks as [`resolve_str`], with errors
/// that name the pass and resource but no line. Its `include` list is not read.
pub fn resolve_desc(desc: &PipelineDesc, file: &str) -> Result<ResolvedPipeline, PipelineErrors> {
    resolve_parsed(desc, file, &Sources::single(file, ""))
}

fn resolve_parsed(
    desc: &PipelineDesc,
    file: &str,
    loc: &Sources,
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

impl Ctx<'_> {
    /// The phases in order. Each records the errors it finds; the pipeline is built only
    /// when none did (a later phase may still run after errors, to report more of them).
    fn resolve(&mut self) -> Option<ResolvedPipeline> {
        let declared = self.declare();
        let bindings = self.bind(&declared.resources);
        let dag = self.build_dag(&bindings, &declared.passes);
        self.check_writers_rules(&dag, &bindings);
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
            sources: self.loc.files(),
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
