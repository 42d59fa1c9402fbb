//! Warnings as values: what the engine did instead of what was asked, or why an image may
//! differ from what the caller expects (a missing texture, a level clamped, a budget
//! lowered), each naming the file or field. Callers print them, list them in a report or
//! show them in an overlay; the engine never only logs them.

use serde::Serialize;

/// One warning.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Warning {
    /// What it is about: a file (`assets/models/x.obj`), a field (`objects[2].lod`), a
    /// flag (`--gpu-budget`), or `view` for the camera and scene together.
    pub subject: String,
    /// What happened and what was used instead.
    pub message: String,
}

impl Warning {
    /// A warning about `subject`.
    pub fn new(subject: impl Into<String>, message: impl Into<String>) -> Self {
        Self {
            subject: subject.into(),
            message: message.into(),
        }
    }

    /// A loader's warning line (`file:line: what`, already naming its file): the subject is
    /// the file as the line names it, else `fallback`.
    pub fn from_loader(line: &str, fallback: &str) -> Self {
        let subject = line
            .split_once(": ")
            .map(|(head, _)| head.trim_end_matches(|c: char| c.is_ascii_digit() || c == ':'))
            .filter(|h| !h.is_empty() && !h.contains(' '))
            .unwrap_or(fallback);
        Self {
            subject: subject.to_string(),
            message: line.to_string(),
        }
    }
}

impl std::fmt::Display for Warning {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        // Loader lines already start with their file.
        if self.message.starts_with(&self.subject) {
            write!(f, "{}", self.message)
        } else {
            write!(f, "{}: {}", self.subject, self.message)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn loader_lines_keep_their_file_as_subject_and_print_once() {
        let w = Warning::from_loader("/m/a.obj:3: MTL library \"a.mtl\" not found in /m", "a.obj");
        assert_eq!(w.subject, "/m/a.obj");
        assert_eq!(
            w.to_string(),
            "/m/a.obj:3: MTL library \"a.mtl\" not found in /m"
        );
        let w = Warning::from_loader("texture not loaded: gone.png: no such file", "m.gltf");
        assert_eq!(w.subject, "m.gltf");
        assert_eq!(
            w.to_string(),
            "m.gltf: texture not loaded: gone.png: no such file"
        );
        let w = Warning::new("objects[0].lod", "clamped to 8");
        assert_eq!(w.to_string(), "objects[0].lod: clamped to 8");
    }
}
