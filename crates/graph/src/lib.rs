//! `ssbvb-graph`: the RON render-graph format and its resolution into a scheduled DAG.
//!
//! A pipeline file declares **resources** (textures with a format and a size relative to
//! the screen or fixed; buffers with an element layout and a count) and **passes** (a name,
//! a [`PassKind`] with typed parameters, and the resources bound to the kind's read and
//! write slots). Edges come from the data: a pass that reads a resource runs after every
//! pass that writes it. [`resolve_str`] / [`resolve_file`] validate everything (collecting
//! every error of a file, each with pass, resource, line and column), prune what does not
//! reach the `output`, schedule the rest topologically and alias transient resources whose
//! lifetimes do not overlap. [`PipelineWatcher`] re-resolves a file that changed on disk
//! and keeps the last good pipeline on error.
//!
//! The crate needs no GPU (it depends on `wgpu-types` only), so all of this is unit-tested
//! on any machine. Executing a resolved pipeline is `ssbvb-passes`' job.

pub mod edit;
pub mod error;
pub mod format;
pub mod include;
pub mod kinds;
pub mod locate;
mod parse;
pub mod resolve;
pub mod schema;
pub mod watch;

pub use error::{GraphError, Loc, PipelineErrors, suggest};
pub use format::{BufferLayout, Format};
pub use kinds::*;
pub use locate::Position;
pub use resolve::{
    BoundSlot, Dependency, MemoryReport, PhysicalResource, RENAMED_FILES, ResolvedPipeline,
    ResolvedResource, ResourceUsage, ScheduledPass, current_path, resolve_desc, resolve_file,
    resolve_str, resolve_str_with,
};
pub use schema::{Binding, Bindings, CountDesc, PassDesc, PipelineDesc, ResourceDesc, SizeDesc};
pub use watch::{PipelineWatcher, ReloadOutcome};
