//! The error type every loader returns.

use std::fmt;
use std::io;
use std::path::{Path, PathBuf};

/// Everything that can go wrong while loading a model.
///
/// The `Display` text always starts with the file name, followed by `:line` for text
/// formats or `: byte N` for binary formats where the position is known, so that it can be
/// shown to a user as is.
#[derive(Debug, thiserror::Error)]
pub enum LoadError {
    /// The file (or a file it references, such as an MTL library) could not be read or
    /// written. The message includes the operating system's error, so it is not repeated
    /// as a `source()` (an error chain would print it twice).
    #[error("{}: {error}", .path.display())]
    Io {
        /// The file that could not be read or written.
        path: PathBuf,
        /// The operating system's error.
        error: io::Error,
    },
    /// The file's content is malformed.
    #[error("{}: {message}", Location(.path, *.line, *.offset))]
    Parse {
        /// The malformed file.
        path: PathBuf,
        /// 1-based line number (text formats).
        line: Option<usize>,
        /// Byte offset from the start of the file (binary formats).
        offset: Option<u64>,
        /// What is wrong.
        message: String,
    },
    /// The format could not be determined, or is not one this module reads.
    #[error(
        "{}: unsupported model format {ext:?} (expected .obj, .ply, .gltf, .glb, .vox or .raw)",
        .path.display()
    )]
    UnsupportedFormat {
        /// The file.
        path: PathBuf,
        /// Its extension (empty when it has none).
        ext: String,
    },
    /// The file declares (or would produce) more of something than the limits allow.
    #[error("{}: {count} {what} exceeds the limit of {limit}", .path.display())]
    TooLarge {
        /// The file.
        path: PathBuf,
        /// What was counted (for example `"vertices"`).
        what: String,
        /// How many the file declares or produces.
        count: u64,
        /// The limit.
        limit: u64,
    },
    /// The file parsed but holds no triangles / voxels.
    #[error("{}: the file holds no geometry", .path.display())]
    Empty {
        /// The file.
        path: PathBuf,
    },
}

/// `path`, `path:line` or `path: byte N`, for error messages.
struct Location<'a>(&'a Path, Option<usize>, Option<u64>);

impl fmt::Display for Location<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.0.display())?;
        if let Some(line) = self.1 {
            write!(f, ":{line}")?;
        }
        if let Some(offset) = self.2 {
            write!(f, ": byte {offset}")?;
        }
        Ok(())
    }
}

impl LoadError {
    /// The file the error is about.
    pub fn path(&self) -> &Path {
        match self {
            LoadError::Io { path, .. }
            | LoadError::Parse { path, .. }
            | LoadError::UnsupportedFormat { path, .. }
            | LoadError::TooLarge { path, .. }
            | LoadError::Empty { path } => path,
        }
    }

    /// The 1-based line of a parse error in a text format, when known.
    pub fn line(&self) -> Option<usize> {
        match self {
            LoadError::Parse { line, .. } => *line,
            _ => None,
        }
    }

    /// The byte offset of a parse error in a binary format, when known.
    pub fn offset(&self) -> Option<u64> {
        match self {
            LoadError::Parse { offset, .. } => *offset,
            _ => None,
        }
    }

    pub(crate) fn io(path: &Path, source: io::Error) -> Self {
        LoadError::Io {
            path: path.to_path_buf(),
            error: source,
        }
    }

    pub(crate) fn at_line(path: &Path, line: usize, message: impl Into<String>) -> Self {
        LoadError::Parse {
            path: path.to_path_buf(),
            line: Some(line),
            offset: None,
            message: message.into(),
        }
    }

    pub(crate) fn at_offset(path: &Path, offset: u64, message: impl Into<String>) -> Self {
        LoadError::Parse {
            path: path.to_path_buf(),
            line: None,
            offset: Some(offset),
            message: message.into(),
        }
    }

    pub(crate) fn parse(path: &Path, message: impl Into<String>) -> Self {
        LoadError::Parse {
            path: path.to_path_buf(),
            line: None,
            offset: None,
            message: message.into(),
        }
    }

    pub(crate) fn too_large(path: &Path, what: &str, count: u64, limit: u64) -> Self {
        LoadError::TooLarge {
            path: path.to_path_buf(),
            what: what.to_string(),
            count,
            limit,
        }
    }

    pub(crate) fn empty(path: &Path) -> Self {
        LoadError::Empty {
            path: path.to_path_buf(),
        }
    }
}
