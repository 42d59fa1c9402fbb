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
        // Stamps from before the read: an edit saved while resolving is seen next poll.
        let before = stamps(std::slice::from_ref(&path));
        let current = resolve_file(&path)?;
        let files = files_of(&current);
        let stamp = restamp(&files, std::slice::from_ref(&path), &before);
        Ok(Self {
            path,
            stamp,
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
        match resolve_file(&self.path) {
            Ok(p) => {
                // A changed include list changes the files to watch.
                let files = files_of(&p);
                self.stamp = restamp(&files, &self.files, &now);
                self.files = files;
                self.current = p;
                ReloadOutcome::Reloaded
            }
            Err(e) => {
                // The files it names now are watched too, so that fixing a newly included
                // file reloads.
                let mut files = self.files.clone();
                for f in named_includes(&self.files[0]) {
                    if !files.contains(&f) {
                        files.push(f);
                    }
                }
                self.stamp = restamp(&files, &self.files, &now);
                self.files = files;
                ReloadOutcome::Failed(e)
            }
        }
    }
}

/// The files a pipeline was read from: the file itself (where a renamed file's old path
/// led, [`crate::current_path`]) and those it included.
fn files_of(p: &ResolvedPipeline) -> Vec<PathBuf> {
    p.sources.iter().map(PathBuf::from).collect()
}

/// The files `top` includes directly, as paths (none when it cannot be read or parsed).
fn named_includes(top: &Path) -> Vec<PathBuf> {
    let file = top.display().to_string();
    let text = std::fs::read_to_string(top).unwrap_or_default();
    crate::include::includes_of(&text)
        .iter()
        .map(|n| PathBuf::from(crate::include::include_path(&file, n)))
        .collect()
}

/// The stamps of `files`: those of `seen` taken before the last read (`at`) where a file
/// was watched then, the file's stamp now where it is new.
fn restamp(
    files: &[PathBuf],
    seen: &[PathBuf],
    at: &[Option<(SystemTime, u64)>],
) -> Vec<Option<(SystemTime, u64)>> {
    files
        .iter()
        .map(|f| match seen.iter().position(|s| s == f) {
            Some(i) => at[i],
            None => stamp(f),
        })
        .collect()
}

fn stamps(files: &[PathBuf]) -> Vec<Option<(SystemTime, u64)>> {
    files.iter().map(|f| stamp(f)).collect()
}

fn stamp(path: &Path) -> Option<(SystemTime, u64)> {
    let m = std::fs::metadata(path).ok()?;
    Some((m.modified().ok()?, m.len()))
}
