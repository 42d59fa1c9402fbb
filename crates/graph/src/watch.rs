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

/// Holds the current pipeline of a file and reloads it when the modification time or
/// length of the file or of a file it includes changes.
#[derive(Debug)]
pub struct PipelineWatcher {
    path: PathBuf,
    stamp: Vec<Option<(SystemTime, u64)>>,
    /// The files the stamp covers: the pipeline's and those it included when last read.
    files: Vec<PathBuf>,
    current: ResolvedPipeline,
}

impl PipelineWatcher {
    /// Resolves `path` once; fails if the first version is already invalid.
    pub fn new(path: impl AsRef<Path>) -> Result<Self, PipelineErrors> {
        let path = path.as_ref().to_path_buf();
        let current = resolve_file(&path)?;
        let files = files_of(&path, &current);
        Ok(Self {
            path,
            stamp: stamps(&files),
            files,
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

    /// Checks the file and those it includes, and re-resolves it if one changed.
    pub fn poll(&mut self) -> ReloadOutcome {
        let now = stamps(&self.files);
        if now == self.stamp {
            return ReloadOutcome::Unchanged;
        }
        self.stamp = now;
        match resolve_file(&self.path) {
            Ok(p) => {
                // A changed include list changes the files to watch.
                self.files = files_of(&self.path, &p);
                self.stamp = stamps(&self.files);
                self.current = p;
                ReloadOutcome::Reloaded
            }
            Err(e) => ReloadOutcome::Failed(e),
        }
    }
}

/// The pipeline's file and the files it included.
fn files_of(path: &Path, p: &ResolvedPipeline) -> Vec<PathBuf> {
    let mut files = vec![path.to_path_buf()];
    files.extend(p.sources.iter().skip(1).map(PathBuf::from));
    files
}

fn stamps(files: &[PathBuf]) -> Vec<Option<(SystemTime, u64)>> {
    files.iter().map(|f| stamp(f)).collect()
}

fn stamp(path: &Path) -> Option<(SystemTime, u64)> {
    let m = std::fs::metadata(path).ok()?;
    Some((m.modified().ok()?, m.len()))
}
