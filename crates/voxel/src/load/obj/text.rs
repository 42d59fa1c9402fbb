//! Lexing shared by OBJ and MTL: joined lines, tokens, keywords and numbers.

use std::borrow::Cow;
use std::path::Path;

use crate::load::error::LoadError;

/// Parses up to `out.len()` whitespace-separated finite numbers (stopping at a `#`
/// comment) and returns how many there were. Extra numbers are an error.
pub(super) fn numbers(
    rest: &[u8],
    out: &mut [f32],
    path: &Path,
    line: usize,
) -> Result<usize, LoadError> {
    let mut n = 0;
    for tok in tokens(rest) {
        if tok[0] == b'#' {
            break;
        }
        let value = parse_f32(tok).ok_or_else(|| {
            LoadError::at_line(
                path,
                line,
                format!("{:?} is not a finite number", String::from_utf8_lossy(tok)),
            )
        })?;
        match out.get_mut(n) {
            Some(slot) => *slot = value,
            None => {
                return Err(LoadError::at_line(
                    path,
                    line,
                    format!("too many numbers (at most {})", out.len()),
                ));
            }
        }
        n += 1;
    }
    Ok(n)
}

pub(super) fn parse_f32(tok: &[u8]) -> Option<f32> {
    std::str::from_utf8(tok)
        .ok()?
        .parse::<f32>()
        .ok()
        .filter(|v| v.is_finite())
}

pub(super) fn tokens(line: &[u8]) -> impl Iterator<Item = &[u8]> {
    line.split(|b| b.is_ascii_whitespace())
        .filter(|t| !t.is_empty())
}

pub(super) fn trim(s: &[u8]) -> &[u8] {
    s.trim_ascii()
}

/// Splits a trimmed, non-empty line into its keyword and the rest.
pub(super) fn split_keyword(line: &[u8]) -> (&[u8], &[u8]) {
    match line.iter().position(|b| b.is_ascii_whitespace()) {
        Some(i) => (&line[..i], &line[i..]),
        None => (line, &[]),
    }
}

/// Lines with their 1-based numbers; `\`-continued lines are joined (and numbered by their
/// first line); a trailing `\r` is dropped.
pub(super) struct Lines<'a> {
    data: &'a [u8],
    pos: usize,
    line: usize,
}

impl<'a> Lines<'a> {
    pub(super) fn new(data: &'a [u8]) -> Self {
        Lines {
            data,
            pos: 0,
            line: 0,
        }
    }
}

impl<'a> Iterator for Lines<'a> {
    type Item = (usize, Cow<'a, [u8]>);

    fn next(&mut self) -> Option<Self::Item> {
        if self.pos >= self.data.len() {
            return None;
        }
        let first_line = self.line + 1;
        let mut joined: Option<Vec<u8>> = None;
        loop {
            let rest = self.data.get(self.pos..).unwrap_or_default();
            let end = rest.iter().position(|&b| b == b'\n').unwrap_or(rest.len());
            let mut l = &rest[..end];
            self.pos = self.pos.saturating_add(end + 1).min(self.data.len());
            self.line += 1;
            if let Some(stripped) = l.strip_suffix(b"\r") {
                l = stripped;
            }
            if let Some(body) = l.strip_suffix(b"\\")
                && self.pos < self.data.len()
            {
                let j = joined.get_or_insert_with(Vec::new);
                j.extend_from_slice(body);
                j.push(b' ');
                continue;
            }
            return Some(match joined {
                Some(mut j) => {
                    j.extend_from_slice(l);
                    (first_line, Cow::Owned(j))
                }
                None => (first_line, Cow::Borrowed(l)),
            });
        }
    }
}
