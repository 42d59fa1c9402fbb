//! Pipelines that share declarations: a pipeline file may name other files in `include:`,
//! whose resources and passes it takes before its own. A resource or pass of the including
//! file with the name of an included one replaces it (a variant changes one pass of a
//! form); a file without `output:` holds only shared declarations (by convention in
//! `pipelines/shared/`) and is included, not resolved alone.
//!
//! Includes are read through a [`ReadSource`] (the file system natively, fetched text in the
//! browser), relative to the including file, and nest. Every declaration keeps the file it
//! came from ([`Sources`]), so an error names the file and line where the problem is.

use std::collections::HashMap;

use crate::error::{GraphError, Loc};
use crate::locate::{Locator, Position};
use crate::schema::PipelineDesc;

/// Reads an included file by its path (already joined to the including file's folder).
pub type ReadSource<'a> = &'a dyn Fn(&str) -> Result<String, String>;

/// A place in one of the files a pipeline was read from: the file's index in [`Sources`]
/// and the position in it.
pub type At = (usize, Position);

/// The files a pipeline was read from (the including file first) and which file each pass,
/// resource and the output came from.
#[derive(Debug, Default)]
pub struct Sources {
    files: Vec<(String, Locator)>,
    pass_from: HashMap<String, usize>,
    resource_from: HashMap<String, usize>,
    output_from: Option<usize>,
}

impl Sources {
    /// One file (or a description with no text, `src` empty).
    pub fn single(file: &str, src: &str) -> Self {
        Self {
            files: vec![(file.to_string(), Locator::new(src))],
            ..Self::default()
        }
    }

    /// The names of the files read, the including file first.
    pub fn files(&self) -> Vec<String> {
        self.files.iter().map(|(f, _)| f.clone()).collect()
    }

    /// The location of `at` (a file of these sources), else the first file without a line.
    pub fn loc(&self, at: Option<At>) -> Loc {
        match at {
            Some((i, pos)) => Loc {
                file: self.files[i].0.clone(),
                pos: Some(pos),
            },
            None => Loc {
                file: self.files.first().map(|f| f.0.clone()).unwrap_or_default(),
                pos: None,
            },
        }
    }

    fn pass_file(&self, pass: &str) -> usize {
        self.pass_from.get(pass).copied().unwrap_or(0)
    }

    fn resource_file(&self, name: &str) -> usize {
        self.resource_from.get(name).copied().unwrap_or(0)
    }

    fn in_file(&self, i: usize, pos: Option<Position>) -> Option<At> {
        pos.map(|p| (i, p))
    }

    /// Every place pass `pass` is declared in its file (more than one for a duplicate).
    pub fn pass_declarations(&self, pass: &str) -> Vec<At> {
        let i = self.pass_file(pass);
        let found = self.files[i].1.pass_declarations(pass);
        found.into_iter().map(|p| (i, p)).collect()
    }

    /// Every place resource `name` is declared in its file.
    pub fn resource_declarations(&self, name: &str) -> Vec<At> {
        let i = self.resource_file(name);
        let found = self.files[i].1.resource_declarations(name);
        found.into_iter().map(|p| (i, p)).collect()
    }

    /// Where pass `pass` is declared.
    pub fn pass(&self, pass: &str) -> Option<At> {
        let i = self.pass_file(pass);
        self.in_file(i, self.files[i].1.pass(pass))
    }

    /// Where resource `name` is declared.
    pub fn resource(&self, name: &str) -> Option<At> {
        let i = self.resource_file(name);
        self.in_file(i, self.files[i].1.resource(name))
    }

    /// Where pass `pass` mentions `name`, else the pass itself.
    pub fn in_pass(&self, pass: &str, name: &str) -> Option<At> {
        let i = self.pass_file(pass);
        self.in_file(i, self.files[i].1.in_pass(pass, name))
    }

    /// Where the field `field:` of pass `pass` is, else the pass itself.
    pub fn pass_field(&self, pass: &str, field: &str) -> Option<At> {
        let i = self.pass_file(pass);
        self.in_file(i, self.files[i].1.pass_field(pass, field))
    }

    /// Where the `output:` field that counts is.
    pub fn output(&self) -> Option<At> {
        let i = self.output_from.unwrap_or(0);
        self.in_file(i, self.files[i].1.output())
    }

    /// `own` (read from file `ix`) over `included` (what its includes declared): its
    /// resources and passes replace those of the same name in place; the rest come first,
    /// so the schedule's ties (file order) and the resources' order are those of the file
    /// written whole with its own declarations before the shared ones.
    fn apply(&mut self, own: PipelineDesc, mut included: PipelineDesc, ix: usize) -> PipelineDesc {
        let mut out = PipelineDesc::default();
        for (name, desc) in own.resources.0 {
            let from_include = self.resource_from.get(&name).is_some_and(|&f| f != ix);
            self.resource_from.insert(name.clone(), ix);
            match included.resources.0.iter_mut().find(|(n, _)| *n == name) {
                Some(slot) if from_include => slot.1 = desc,
                _ => out.resources.0.push((name, desc)),
            }
        }
        out.resources.0.extend(included.resources.0);
        for pass in own.passes {
            let from_include = self.pass_from.get(&pass.name).is_some_and(|&f| f != ix);
            self.pass_from.insert(pass.name.clone(), ix);
            match included.passes.iter_mut().find(|p| p.name == pass.name) {
                Some(slot) if from_include => *slot = pass,
                _ => out.passes.push(pass),
            }
        }
        out.passes.extend(included.passes);
        out.output = if own.output.is_empty() {
            included.output
        } else {
            self.output_from = Some(ix);
            own.output
        };
        out.keep = own.keep;
        for k in included.keep {
            if !out.keep.contains(&k) {
                out.keep.push(k);
            }
        }
        out
    }
}

/// The path of `name` included by `file`: relative to `file`'s folder (a path or a URL),
/// with `.` and `..` taken out where a folder before them can be (so that a file reached
/// by two ways is one file, and a loop is seen).
pub fn include_path(file: &str, name: &str) -> String {
    if name.starts_with('/') || name.contains("://") {
        return normalise(name);
    }
    let file = file.replace('\\', "/");
    match file.rfind('/') {
        Some(i) => normalise(&format!("{}/{name}", &file[..i])),
        None => normalise(name),
    }
}

/// `path` with `/` for `\\` and without `.` and the `..` that follow a folder.
fn normalise(path: &str) -> String {
    let path = path.replace('\\', "/");
    let mut parts: Vec<&str> = Vec::new();
    for part in path.split('/') {
        match part {
            "." => {}
            ".." if parts
                .last()
                .is_some_and(|p| !p.is_empty() && *p != ".." && !p.ends_with(':')) =>
            {
                parts.pop();
            }
            _ => parts.push(part),
        }
    }
    parts.join("/")
}

/// The files `src` includes, as written (empty when it includes none or does not parse):
/// what a reader that cannot block (the browser) fetches before resolving.
pub fn includes_of(src: &str) -> Vec<String> {
    crate::parse::parse_only(src).map_or_else(Vec::new, |d| d.include)
}

/// How deep includes may nest (a deeper chain is an error at the include that goes past).
pub const MAX_INCLUDE_DEPTH: usize = 16;

/// The largest included file read (a pipeline file is a few kilobytes).
pub const MAX_INCLUDE_BYTES: u64 = 1 << 20;

/// Reads `src` (named `file`) and every file it includes, merged into one description.
pub(crate) fn load(
    src: &str,
    file: &str,
    read: ReadSource<'_>,
) -> Result<(PipelineDesc, Sources), Vec<GraphError>> {
    let file = normalise(file);
    let mut walk = Walk {
        read,
        stack: vec![file.clone()],
        sources: Sources::default(),
        errors: Vec::new(),
    };
    let merged = walk.file(src, &file);
    match merged {
        Some(desc) if walk.errors.is_empty() => Ok((desc, walk.sources)),
        _ => Err(walk.errors),
    }
}

/// The state of one [`load`]: the includes being read (to see a loop), the files read
/// and the errors found.
struct Walk<'a> {
    read: ReadSource<'a>,
    stack: Vec<String>,
    sources: Sources,
    errors: Vec<GraphError>,
}

impl Walk<'_> {
    /// `src` merged with what it includes; `None` when it does not parse.
    fn file(&mut self, src: &str, file: &str) -> Option<PipelineDesc> {
        let loc = Locator::new(src);
        let own = match crate::parse::parse(src, file, &loc) {
            Ok(d) => d,
            Err(e) => {
                self.errors.extend(e);
                return None;
            }
        };
        let ix = self.sources.files.len();
        self.sources.files.push((file.to_string(), loc));
        let mut merged = PipelineDesc::default();
        for name in &own.include {
            let at = Loc {
                file: file.to_string(),
                pos: self.sources.files[ix].1.include_entry(name),
            };
            let path = include_path(file, name);
            // A file already read by another include is merged once: its declarations
            // are in, and an override made over them stays.
            if self.sources.files.iter().any(|(f, _)| *f == path) && !self.stack.contains(&path) {
                continue;
            }
            let problem = if self.stack.contains(&path) {
                Some(format!(
                    "`{path}` includes itself ({} -> {path})",
                    self.stack.join(" -> ")
                ))
            } else if self.stack.len() > MAX_INCLUDE_DEPTH {
                Some(format!(
                    "includes nest deeper than {MAX_INCLUDE_DEPTH} files at `{path}`"
                ))
            } else {
                None
            };
            if let Some(message) = problem {
                self.errors.push(GraphError::Include { at, message });
                continue;
            }
            let text = match (self.read)(&path) {
                Ok(t) => t,
                Err(message) => {
                    self.errors.push(GraphError::Include {
                        at,
                        message: format!("cannot read `{path}`: {message}"),
                    });
                    continue;
                }
            };
            self.stack.push(path.clone());
            let included = self.file(&text, &path);
            self.stack.pop();
            if let Some(d) = included {
                merge_into(&mut merged, d);
            }
        }
        Some(self.sources.apply(own, merged, ix))
    }
}

/// Appends an included file's merged declarations: one of a name an earlier include
/// declared replaces it (the later include wins); the rest, duplicates within the file
/// included, are appended for the resolver to report. Where each came from was recorded
/// when its own file was applied ([`Sources::apply`], which runs for included files first).
fn merge_into(into: &mut PipelineDesc, d: PipelineDesc) {
    let earlier: Vec<String> = into.resources.0.iter().map(|(n, _)| n.clone()).collect();
    let mut replaced: Vec<String> = Vec::new();
    for (name, desc) in d.resources.0 {
        let slot = into.resources.0.iter_mut().find(|(n, _)| *n == name);
        match slot {
            Some(slot) if earlier.contains(&name) && !replaced.contains(&name) => {
                slot.1 = desc;
                replaced.push(name);
            }
            _ => into.resources.0.push((name, desc)),
        }
    }
    let earlier: Vec<String> = into.passes.iter().map(|p| p.name.clone()).collect();
    let mut replaced: Vec<String> = Vec::new();
    for pass in d.passes {
        let slot = into.passes.iter_mut().find(|p| p.name == pass.name);
        match slot {
            Some(slot) if earlier.contains(&pass.name) && !replaced.contains(&pass.name) => {
                replaced.push(pass.name.clone());
                *slot = pass;
            }
            _ => into.passes.push(pass),
        }
    }
    if !d.output.is_empty() {
        into.output = d.output;
    }
    for k in d.keep {
        if !into.keep.contains(&k) {
            into.keep.push(k);
        }
    }
}

/// Reads included files from the file system: regular files of at most
/// [`MAX_INCLUDE_BYTES`] (not a device, a pipe or a folder).
pub fn read_file(path: &str) -> Result<String, String> {
    let meta = std::fs::metadata(path).map_err(|e| e.to_string())?;
    if !meta.is_file() {
        return Err("not a regular file".into());
    }
    if meta.len() > MAX_INCLUDE_BYTES {
        return Err(format!(
            "{} bytes, more than a pipeline file holds ({MAX_INCLUDE_BYTES})",
            meta.len()
        ));
    }
    std::fs::read_to_string(path).map_err(|e| e.to_string())
}
