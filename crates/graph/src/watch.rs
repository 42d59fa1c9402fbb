//! Re-resolving a pipeline file when it changes on disk, keeping the last good one.

use std::path::{Path, PathBuf};
use std::time::SystemTime;

use crate::error::PipelineErrors;
use crate::resolve::{ResolvedPipeline, resolve_file};

/// What [`PipelineWatcher::poll`] found.
#[derive(Debug)]
pub enum ReloadOutcome {
    /// The file did not change.
    Unchanged,
    /// The file changed and resolved: [`PipelineWatcher::current`] is the new pipeline.
    Reloaded,
    /// The file changed but has errors: the previous pipeline stays current.
    Failed(PipelineErrors),
}

/// Holds the current pipeline of a file and reloads it when the file's modification time
/// or length changes.
#[derive(Debug)]
pub struct PipelineWatcher {
    path: PathBuf,
    stamp: Option<(SystemTime, u64)>,
    current: ResolvedPipeline,
}

impl PipelineWatcher {
    /// Resolves `path` once; fails if the first version is already invalid.
    pub fn new(path: impl AsRef<Path>) -> Result<Self, PipelineErrors> {
        let path = path.as_ref().to_path_buf();
        let stamp = stamp(&path);
        let current = resolve_file(&path)?;
        Ok(Self {
            path,
            stamp,
            current,
        })
    }

    /// The last pipeline that resolved.
    pub fn current(&self) -> &ResolvedPipeline {
        &self.current
    }

    /// The watched file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Checks the file and re-resolves it if it changed.
    pub fn poll(&mut self) -> ReloadOutcome {
        let now = stamp(&self.path);
        if now == self.stamp {
            return ReloadOutcome::Unchanged;
        }
        self.stamp = now;
        match resolve_file(&self.path) {
            Ok(p) => {
                self.current = p;
                ReloadOutcome::Reloaded
            }
            Err(e) => ReloadOutcome::Failed(e),
        }
    }
}

fn stamp(path: &Path) -> Option<(SystemTime, u64)> {
    let m = std::fs::metadata(path).ok()?;
    Some((m.modified().ok()?, m.len()))
}
