//! The state every resolution phase shares. Its own file so that the phases (each an
//! `impl Ctx` block) and the driver in `mod.rs` import it without importing each other.

use crate::error::{GraphError, Loc};
use crate::include::{At, Sources};
use crate::schema::PipelineDesc;

/// State shared by the resolution phases: the input and the errors found so far. Each
/// phase is an `impl Ctx` block in its own file.
pub(super) struct Ctx<'a> {
    pub(super) file: &'a str,
    /// Where each declaration is written (the including file and those it includes).
    pub(super) loc: &'a Sources,
    pub(super) desc: &'a PipelineDesc,
    pub(super) errors: Vec<GraphError>,
}

impl Ctx<'_> {
    /// A location in the file it is in (the pipeline's own file without a position).
    pub(super) fn at(&self, at: Option<At>) -> Loc {
        self.loc.loc(at)
    }
}
