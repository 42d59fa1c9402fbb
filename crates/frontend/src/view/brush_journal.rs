//! The viewer's side of the brush journal (format: `ssbvb_voxel::edit_journal`): where
//! it lives, what is done with a journal found at start (offered in the overlay, restored
//! with `--restore`, set aside with `--discard-journal`), and a journal that cannot be used
//! (another model, a newer version, damage), which is left on disk as it is while the
//! brush refuses to edit — edits that could not be journaled would be lost in a crash.

use std::path::{Path, PathBuf};

use anyhow::{Result, anyhow, bail};
use ssbvb_voxel::edit_journal::{
    JournalContents, JournalOp, JournalWriter, RECORD_BYTES, read_journal,
};

/// What to do with a journal found at start.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum JournalDecision {
    /// Offer it in the overlay (edits wait for the answer).
    Ask,
    /// Replay it (`--restore`).
    Restore,
    /// Set it aside, renamed `….discarded` (`--discard-journal`).
    Discard,
}

/// A simulated crash while journaling (`--inject-crash`, tests): the process aborts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Crash {
    /// Right after record N (from 1) is on disk: killed between operations.
    After(u64),
    /// Half-way through writing record N: killed in the middle of a write.
    Torn(u64),
}

/// Parses `after@N` or `torn@N` (N ≥ 1).
pub fn parse_crash(s: &str) -> Result<Crash, String> {
    let (kind, n) = s
        .split_once('@')
        .ok_or_else(|| format!("expected after@N or torn@N, got `{s}`"))?;
    let n: u64 = n
        .parse()
        .ok()
        .filter(|&n| n >= 1)
        .ok_or_else(|| format!("`{s}`: N must be a record number from 1"))?;
    match kind {
        "after" => Ok(Crash::After(n)),
        "torn" => Ok(Crash::Torn(n)),
        _ => Err(format!("expected after@N or torn@N, got `{s}`")),
    }
}

/// How the session journals.
#[derive(Debug, Clone)]
pub struct JournalOptions {
    /// The journal's file (`None`: no journal, e.g. after a device loss the old brush's
    /// journal is moved over instead).
    pub path: Option<PathBuf>,
    /// What to do with a journal found there.
    pub decision: JournalDecision,
    /// A simulated crash (tests).
    pub crash: Option<Crash>,
}

impl JournalOptions {
    /// No journal.
    pub fn off() -> Self {
        Self {
            path: None,
            decision: JournalDecision::Ask,
            crash: None,
        }
    }
}

/// The journal of the model `input` (loaded at `level` when it is a model file), beside
/// it: `bunny.obj.L8.ssbvb-journal`, `default.ron.ssbvb-journal`.
pub fn default_path(input: &Path, level: Option<u32>) -> PathBuf {
    let name = input
        .file_name()
        .map_or_else(|| "model".into(), |n| n.to_string_lossy().into_owned());
    let name = match level {
        Some(l) => format!("{name}.L{l}.ssbvb-journal"),
        None => format!("{name}.ssbvb-journal"),
    };
    input.with_file_name(name)
}

enum State {
    /// No journal.
    Off,
    /// A journal from an earlier session, waiting for the user's answer.
    Offered {
        path: PathBuf,
        contents: JournalContents,
    },
    /// A journal that cannot be used; edits are refused.
    Blocked { why: String },
    /// Journaling to `path` (created at the first operation).
    Open {
        path: PathBuf,
        writer: Option<JournalWriter>,
    },
}

/// The session's journal.
pub struct Journal {
    state: State,
    objects: u32,
    key: u64,
    crash: Option<Crash>,
    /// Records written this session (for [`Crash`]).
    written: u64,
    /// Operations to replay once the scene is on the GPU (`--restore`).
    pending: Vec<JournalOp>,
    /// What happened at start, for the terminal and the overlay.
    pub notes: Vec<String>,
}

impl Journal {
    /// No journal.
    pub fn off() -> Self {
        Self {
            state: State::Off,
            objects: 0,
            key: 0,
            crash: None,
            written: 0,
            pending: Vec::new(),
            notes: Vec::new(),
        }
    }

    /// The journal of a session of `objects` editable objects of key `key`, with what is
    /// found at `options.path` read and handled as `options.decision` says.
    pub fn open(options: &JournalOptions, objects: u32, key: u64) -> Self {
        let mut j = Self {
            objects,
            key,
            crash: options.crash,
            ..Self::off()
        };
        let Some(path) = options.path.clone() else {
            return j;
        };
        j.state = State::Open {
            path: path.clone(),
            writer: None,
        };
        if !path.exists() {
            if options.decision == JournalDecision::Restore {
                j.notes.push(format!(
                    "--restore: no journal at {}; nothing to restore",
                    path.display()
                ));
            }
            return j;
        }
        match (read_journal(&path, objects, key), options.decision) {
            (Ok(c), _) if c.ops.is_empty() && c.torn.is_none() => {}
            (Ok(contents), JournalDecision::Ask) => {
                j.notes.push(format!(
                    "{}: {} brush operations of an earlier session were not saved; the \
                     overlay offers to restore them (or pass --restore / --discard-journal)",
                    path.display(),
                    contents.ops.len()
                ));
                j.state = State::Offered { path, contents };
            }
            (Ok(contents), JournalDecision::Restore) => j.restore(path, contents),
            (read, JournalDecision::Discard) => j.discard(&path, read.err()),
            (Err(e), _) => {
                let why = format!(
                    "{e}; it was left as it is and the brush is off: move it away, or pass \
                     --discard-journal to set it aside"
                );
                j.notes.push(why.clone());
                j.state = State::Blocked { why };
            }
        }
        j
    }

    /// Replays `contents` (once the scene is on the GPU) and journals after it.
    fn restore(&mut self, path: PathBuf, contents: JournalContents) {
        if let Some(t) = &contents.torn {
            self.notes.push(format!("{}: {t}", path.display()));
        }
        match JournalWriter::resume(&path, self.objects, contents.valid_bytes) {
            Ok(w) => {
                self.notes.push(format!(
                    "{}: restoring {} brush operations",
                    path.display(),
                    contents.ops.len()
                ));
                self.pending = contents.ops;
                self.state = State::Open {
                    path,
                    writer: Some(w),
                };
            }
            Err(e) => {
                let why = format!("cannot reopen the journal to restore it: {e}");
                self.notes.push(why.clone());
                self.state = State::Blocked { why };
            }
        }
    }

    /// Sets the journal at `path` aside (renamed, never deleted) and starts afresh.
    fn discard(&mut self, path: &Path, problem: Option<ssbvb_voxel::edit_journal::JournalError>) {
        let aside = path.with_extension("ssbvb-journal.discarded");
        match std::fs::rename(path, &aside) {
            Ok(()) => self.notes.push(format!(
                "{}{}: set aside as {}",
                path.display(),
                problem.map_or(String::new(), |e| format!(" ({e})")),
                aside.display()
            )),
            Err(e) => {
                let why = format!("cannot set {} aside: {e}", path.display());
                self.notes.push(why.clone());
                self.state = State::Blocked { why };
            }
        }
    }

    /// The user's answer to the offer: the operations to replay (none when discarded).
    pub fn decide(&mut self, restore: bool) -> Vec<JournalOp> {
        let State::Offered { path, contents } = std::mem::replace(&mut self.state, State::Off)
        else {
            return Vec::new();
        };
        self.state = State::Open {
            path: path.clone(),
            writer: None,
        };
        if restore {
            self.restore(path, contents);
        } else {
            self.discard(&path, None);
        }
        std::mem::take(&mut self.pending)
    }

    /// The operations `--restore` asked to replay (once).
    pub fn take_pending(&mut self) -> Vec<JournalOp> {
        std::mem::take(&mut self.pending)
    }

    /// Whether an earlier session's journal waits for an answer: its operation count.
    pub fn offered(&self) -> Option<usize> {
        match &self.state {
            State::Offered { contents, .. } => Some(contents.ops.len()),
            _ => None,
        }
    }

    /// Appends `op`, synced, before it is shown; refused while an offer waits or the
    /// journal is unusable. Creates the journal at the session's first operation.
    pub fn record(&mut self, op: &JournalOp) -> Result<()> {
        let (path, writer) = match &mut self.state {
            State::Off => return Ok(()),
            State::Offered { .. } => bail!(
                "restore or discard the earlier session's journal first (overlay, or \
                 --restore / --discard-journal)"
            ),
            State::Blocked { why } => bail!("{why}"),
            State::Open { path, writer } => (path, writer),
        };
        if writer.is_none() {
            *writer = Some(
                JournalWriter::create(path, self.objects, self.key).map_err(|e| {
                    anyhow!("cannot start the journal: {e} (--journal FILE puts it elsewhere)")
                })?,
            );
        }
        let Some(w) = writer.as_mut() else {
            bail!("no journal writer");
        };
        self.written += 1;
        match self.crash {
            Some(Crash::Torn(n)) if n == self.written => {
                w.record_torn(op, RECORD_BYTES / 2)?;
                eprintln!("view: crash injected in the middle of journal record {n}");
                std::process::abort();
            }
            _ => {}
        }
        w.record(op)?;
        if self.crash == Some(Crash::After(self.written)) {
            eprintln!("view: crash injected after journal record {}", self.written);
            std::process::abort();
        }
        Ok(())
    }

    /// At the end of the session: with nothing unsaved the journal is removed, otherwise
    /// kept; the line says which.
    pub fn finish(&mut self, unsaved: u64) -> Option<String> {
        let State::Open {
            path,
            writer: Some(_),
        } = &self.state
        else {
            return None;
        };
        if unsaved == 0 {
            let _ = std::fs::remove_file(path);
            return None;
        }
        Some(format!(
            "{unsaved} unsaved brush operations are kept in {}; open the same model with \
             --brush --restore to get them back",
            path.display()
        ))
    }

    /// One line for the overlay.
    pub fn line(&self) -> String {
        match &self.state {
            State::Off => "journal: off".into(),
            State::Offered { path, .. } => format!("journal: {} (not restored)", path.display()),
            State::Blocked { why } => format!("journal unusable: {why}"),
            State::Open { path, .. } => format!("journal: {}", path.display()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use ssbvb_voxel::edit::Edit;

    fn edit() -> JournalOp {
        JournalOp::Edit {
            object: 0,
            edit: Edit::RemoveSphere {
                center: (0.0, 0.0, 0.0),
                radius: 0.1,
            },
        }
    }

    fn options(path: &Path, decision: JournalDecision) -> JournalOptions {
        JournalOptions {
            path: Some(path.to_path_buf()),
            decision,
            crash: None,
        }
    }

    #[test]
    fn a_session_journals_offers_restores_and_removes_when_saved() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("m.obj.L8.ssbvb-journal");
        assert_eq!(
            default_path(&dir.path().join("m.obj"), Some(8)),
            path,
            "beside the model"
        );
        // Nothing is written until the first operation.
        let mut j = Journal::open(&options(&path, JournalDecision::Ask), 1, 7);
        assert!(!path.exists());
        j.record(&edit()).unwrap();
        j.record(&JournalOp::Undo).unwrap();
        assert!(j.finish(2).unwrap().contains("2 unsaved brush operations"));
        // The next session is offered them, and edits wait for the answer.
        let mut j = Journal::open(&options(&path, JournalDecision::Ask), 1, 7);
        assert_eq!(j.offered(), Some(2));
        assert!(j.record(&edit()).is_err());
        assert_eq!(j.decide(true), vec![edit(), JournalOp::Undo]);
        j.record(&JournalOp::Redo).unwrap();
        // --restore replays all three; saved, the journal goes.
        let mut j = Journal::open(&options(&path, JournalDecision::Restore), 1, 7);
        assert_eq!(j.take_pending().len(), 3);
        j.record(&edit()).unwrap();
        assert_eq!(j.finish(0), None);
        assert!(!path.exists());
    }

    #[test]
    fn an_unusable_journal_is_left_whole_and_blocks_edits_until_set_aside() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("m.ron.ssbvb-journal");
        let mut j = Journal::open(&options(&path, JournalDecision::Ask), 1, 7);
        j.record(&edit()).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        // Another model (key 8).
        let mut other = Journal::open(&options(&path, JournalDecision::Restore), 1, 8);
        let e = other.record(&edit()).unwrap_err().to_string();
        assert!(e.contains("written for another model") && e.contains("--discard-journal"));
        assert_eq!(std::fs::read(&path).unwrap(), bytes);
        assert!(other.take_pending().is_empty());
        // Discarded: renamed aside, and a new journal starts.
        let mut fresh = Journal::open(&options(&path, JournalDecision::Discard), 1, 8);
        let aside = dir.path().join("m.ron.ssbvb-journal.discarded");
        assert_eq!(std::fs::read(&aside).unwrap(), bytes);
        fresh.record(&edit()).unwrap();
        assert!(path.exists());
        // Crash specs.
        assert_eq!(parse_crash("after@3"), Ok(Crash::After(3)));
        assert_eq!(parse_crash("torn@1"), Ok(Crash::Torn(1)));
        assert!(parse_crash("torn@0").is_err() && parse_crash("late@2").is_err());
    }
}
