//! The state every resolution phase shares. Its own file so that the phases (each an
//! `impl Ctx` block) and the driver in `mod.rs` import it without importing each other.

use crate::error::{GraphError, Loc};
use crate::locate::{Locator, Position};
use crate::schema::PipelineDesc;

/// State shared by the resolution phases: the input and the errors found so far. Each
/// phase is an `impl Ctx` block in its own file.
pub(super) struct Ctx<'a> {
    pub(super) file: &'a str,
    pub(super) loc: &'a Locator,
    pub(super) desc: &'a PipelineDesc,
    pub(super) errors: Vec<GraphError>,
}

impl Ctx<'_> {
    /// A location in this file.
    pub(super) fn at(&self, pos: Option<Position>) -> Loc {
        Loc {
            file: self.file.to_string(),
            pos,
        }
    }
}
