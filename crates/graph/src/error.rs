//! Errors of pipeline resolution. Every variant names the pass and resource involved and
//! where in the file the problem is.

use std::fmt;

use crate::locate::Position;

/// A place in a pipeline file: the file name and, where known, line and column.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Loc {
    /// File name as given by the caller (a path, or `<memory>`).
    pub file: String,
    /// Line and column, when the name could be found in the text.
    pub pos: Option<Position>,
}

impl fmt::Display for Loc {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.pos {
            Some(p) => write!(f, "{}:{}", self.file, p),
            None => f.write_str(&self.file),
        }
    }
}

/// One problem found in a pipeline file.
#[allow(missing_docs)]
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum GraphError {
    #[error("{at}: cannot read file: {message}")]
    Io { at: Loc, message: String },
    #[error("{at}: syntax error: {message}")]
    Syntax { at: Loc, message: String },
    #[error("{at}: include: {message}")]
    Include { at: Loc, message: String },
    #[error("{at}: pass `{pass}`: unknown pass kind `{found}`{hint}")]
    UnknownKind {
        at: Loc,
        pass: String,
        found: String,
        hint: String,
    },
    #[error("{at}: pass `{pass}` is declared more than once")]
    DuplicatePass { at: Loc, pass: String },
    #[error("{at}: resource `{resource}` is declared more than once")]
    DuplicateResource { at: Loc, resource: String },
    #[error("{at}: resource `{resource}`: {message}")]
    BadResource {
        at: Loc,
        resource: String,
        message: String,
    },
    #[error("{at}: pass `{pass}` ({kind}): {message}")]
    BadParameter {
        at: Loc,
        pass: String,
        kind: String,
        message: String,
    },
    #[error(
        "{at}: pass `{pass}` uses resource `{resource}`, which is not declared in `resources`{hint}"
    )]
    UnknownResource {
        at: Loc,
        pass: String,
        resource: String,
        hint: String,
    },
    #[error(
        "{at}: pass `{pass}` ({kind}) has no slot `{slot}` among its {access}; its {access} are: {expected}"
    )]
    UnknownSlot {
        at: Loc,
        pass: String,
        kind: String,
        slot: String,
        access: &'static str,
        expected: String,
    },
    #[error("{at}: pass `{pass}` ({kind}) binds slot `{slot}` twice")]
    DuplicateSlot {
        at: Loc,
        pass: String,
        kind: String,
        slot: String,
    },
    #[error("{at}: pass `{pass}` ({kind}) does not bind its {access} slot `{slot}` ({class})")]
    MissingSlot {
        at: Loc,
        pass: String,
        kind: String,
        slot: String,
        access: &'static str,
        class: &'static str,
    },
    #[error(
        "{at}: pass `{pass}` slot `{slot}` needs a {expected}, but resource `{resource}` is a {found}"
    )]
    ClassMismatch {
        at: Loc,
        pass: String,
        slot: String,
        resource: String,
        expected: &'static str,
        found: &'static str,
    },
    #[error(
        "{at}: pass `{pass}` slot `{slot}` accepts formats {accepted}, but resource `{resource}` is {found}"
    )]
    FormatMismatch {
        at: Loc,
        pass: String,
        slot: String,
        resource: String,
        found: String,
        accepted: String,
    },
    #[error(
        "{at}: pass `{pass}` slot `{slot}` needs buffer layout {expected}, but resource `{resource}` has layout {found}"
    )]
    LayoutMismatch {
        at: Loc,
        pass: String,
        slot: String,
        resource: String,
        found: String,
        expected: String,
    },
    #[error(
        "{at}: pass `{pass}`: attachments `{first}` ({first_size}) and `{second}` ({second_size}) differ in size; a render pass needs one size"
    )]
    AttachmentSizeMismatch {
        at: Loc,
        pass: String,
        first: String,
        first_size: String,
        second: String,
        second_size: String,
    },
    #[error("{at}: pass `{pass}` both reads and writes resource `{resource}`")]
    ReadWriteSame {
        at: Loc,
        pass: String,
        resource: String,
    },
    #[error("{at}: pass `{pass}` reads resource `{resource}`, but no pass writes it")]
    NoProducer {
        at: Loc,
        pass: String,
        resource: String,
    },
    #[error(
        "{at}: resource `{resource}` is written by passes `{first}` and `{second}` with no order between them; add `after: [\"{first}\"]` to `{second}` (or the reverse)"
    )]
    UnorderedWriters {
        at: Loc,
        resource: String,
        first: String,
        second: String,
    },
    #[error("{at}: pass `{pass}` runs after `{after}`, which is not a pass{hint}")]
    UnknownAfter {
        at: Loc,
        pass: String,
        after: String,
        hint: String,
    },
    #[error("{at}: cycle between passes: {}", cycle.join(" -> "))]
    Cycle { at: Loc, cycle: Vec<String> },
    #[error("{at}: output `{output}` {message}")]
    BadOutput {
        at: Loc,
        output: String,
        message: String,
    },
}

impl GraphError {
    /// Where the error is.
    pub fn loc(&self) -> &Loc {
        use GraphError::*;
        match self {
            Io { at, .. }
            | Syntax { at, .. }
            | Include { at, .. }
            | UnknownKind { at, .. }
            | DuplicatePass { at, .. }
            | DuplicateResource { at, .. }
            | BadResource { at, .. }
            | BadParameter { at, .. }
            | UnknownResource { at, .. }
            | UnknownSlot { at, .. }
            | DuplicateSlot { at, .. }
            | MissingSlot { at, .. }
            | ClassMismatch { at, .. }
            | FormatMismatch { at, .. }
            | LayoutMismatch { at, .. }
            | AttachmentSizeMismatch { at, .. }
            | ReadWriteSame { at, .. }
            | NoProducer { at, .. }
            | UnorderedWriters { at, .. }
            | UnknownAfter { at, .. }
            | Cycle { at, .. }
            | BadOutput { at, .. } => at,
        }
    }
}

/// Every problem of one file, reported together (sorted by position).
#[derive(Debug, Clone, PartialEq)]
pub struct PipelineErrors {
    /// The file.
    pub file: String,
    /// The problems, at least one.
    pub errors: Vec<GraphError>,
}

impl fmt::Display for PipelineErrors {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let n = self.errors.len();
        writeln!(
            f,
            "{}: {} error{} in pipeline",
            self.file,
            n,
            if n == 1 { "" } else { "s" }
        )?;
        for e in &self.errors {
            writeln!(f, "  {e}")?;
        }
        Ok(())
    }
}

impl std::error::Error for PipelineErrors {}

/// `"; did you mean `x`?"` when a known name is close to `found`, plus the known names.
pub fn suggest<'a>(found: &str, known: impl IntoIterator<Item = &'a str>) -> String {
    let known: Vec<&str> = known.into_iter().collect();
    let best = known
        .iter()
        .map(|k| {
            (
                strsim::damerau_levenshtein(&found.to_lowercase(), &k.to_lowercase()),
                *k,
            )
        })
        .min();
    let list = known
        .iter()
        .map(|k| format!("`{k}`"))
        .collect::<Vec<_>>()
        .join(", ");
    match best {
        Some((d, k)) if d <= 3.max(found.len() / 3) => {
            format!("; did you mean `{k}`? (known: {list})")
        }
        _ if !known.is_empty() => format!(" (known: {list})"),
        _ => String::new(),
    }
}

#[cfg(test)]
mod tests {
    use super::suggest;

    #[test]
    fn suggestions_within_a_third_of_the_name_or_three_edits() {
        // 12 letters: up to 4 edits suggest (12 / 3), 5 or more only list.
        let known = ["abcdefghwxyz", "zzzzzzzzzzzz"];
        assert_eq!(
            suggest("abcdefghijkl", known),
            "; did you mean `abcdefghwxyz`? (known: `abcdefghwxyz`, `zzzzzzzzzzzz`)"
        );
        assert_eq!(
            suggest("abcdefghijkl", ["abcdefgwxyzz"]),
            " (known: `abcdefgwxyzz`)"
        );
        // Short names: three edits still suggest, case is ignored.
        assert_eq!(
            suggest("Flt", ["flat"]),
            "; did you mean `flat`? (known: `flat`)"
        );
        assert_eq!(suggest("x", ["abcd"]), " (known: `abcd`)");
        assert_eq!(suggest("x", []), "");
    }
}
