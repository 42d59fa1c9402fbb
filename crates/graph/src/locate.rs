//! Finds where names appear in a RON pipeline file, so semantic errors (which serde does
//! not see) can still point at a line and column.
//!
//! A small tokenizer (strings, identifiers, punctuation; comments skipped) is enough: the
//! questions are "where is pass `x` declared", "where does pass `x` mention resource `y`".

use std::fmt;

/// A 1-based line and column in a pipeline file.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, PartialOrd, Ord)]
pub struct Position {
    /// 1-based line.
    pub line: usize,
    /// 1-based column (in characters).
    pub col: usize,
}

impl fmt::Display for Position {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}", self.line, self.col)
    }
}

#[derive(Debug, Clone, PartialEq)]
enum Tok {
    Str(String),
    Ident(String),
    Punct(char),
}

/// Token positions of one file.
#[derive(Debug, Clone, Default)]
pub struct Locator {
    toks: Vec<(Tok, Position)>,
}

impl Locator {
    /// Tokenizes `src`; never fails (unknown characters become punctuation).
    pub fn new(src: &str) -> Self {
        let mut toks = Vec::new();
        let mut it = src.chars().peekable();
        let (mut line, mut col) = (1usize, 1usize);
        macro_rules! bump {
            ($c:expr) => {
                if $c == '\n' {
                    line += 1;
                    col = 1;
                } else {
                    col += 1;
                }
            };
        }
        while let Some(&c) = it.peek() {
            let pos = Position { line, col };
            if c.is_whitespace() {
                it.next();
                bump!(c);
            } else if c == '/' {
                it.next();
                bump!(c);
                match it.peek() {
                    Some('/') => {
                        while let Some(&d) = it.peek() {
                            if d == '\n' {
                                break;
                            }
                            it.next();
                            bump!(d);
                        }
                    }
                    Some('*') => {
                        let mut prev = ' ';
                        for d in it.by_ref() {
                            bump!(d);
                            if prev == '*' && d == '/' {
                                break;
                            }
                            prev = d;
                        }
                    }
                    _ => toks.push((Tok::Punct('/'), pos)),
                }
            } else if c == '"' {
                it.next();
                bump!(c);
                let mut s = String::new();
                while let Some(d) = it.next() {
                    bump!(d);
                    match d {
                        '"' => break,
                        '\\' => {
                            if let Some(e) = it.next() {
                                bump!(e);
                                s.push(e);
                            }
                        }
                        _ => s.push(d),
                    }
                }
                toks.push((Tok::Str(s), pos));
            } else if c.is_alphanumeric() || c == '_' {
                let mut s = String::new();
                loop {
                    while let Some(&d) = it.peek() {
                        if d.is_alphanumeric() || d == '_' || d == '.' {
                            s.push(d);
                            it.next();
                            bump!(d);
                        } else {
                            break;
                        }
                    }
                    // A raw identifier (`r#Composite`) names `Composite`, as serde reads it.
                    let mut ahead = it.clone();
                    let raw = s == "r"
                        && ahead.next() == Some('#')
                        && ahead.next().is_some_and(|d| d.is_alphabetic() || d == '_');
                    if !raw {
                        break;
                    }
                    it.next();
                    bump!('#');
                    s.clear();
                }
                toks.push((Tok::Ident(s), pos));
            } else {
                it.next();
                bump!(c);
                toks.push((Tok::Punct(c), pos));
            }
        }
        Self { toks }
    }

    fn is_key(&self, i: usize, key: &str) -> bool {
        matches!(&self.toks.get(i), Some((Tok::Ident(k), _)) if k == key)
            && matches!(self.toks.get(i + 1), Some((Tok::Punct(':'), _)))
    }

    /// Token index of the string `"name"` that follows `name:` for the given pass.
    fn pass_token(&self, pass: &str) -> Option<usize> {
        (0..self.toks.len()).find_map(|i| {
            if self.is_key(i, "name") {
                match self.toks.get(i + 2) {
                    Some((Tok::Str(s), _)) if s == pass => Some(i + 2),
                    _ => None,
                }
            } else {
                None
            }
        })
    }

    /// The token range of a pass: from its `name:` to the next pass's `name:`.
    fn pass_range(&self, pass: &str) -> Option<(usize, usize)> {
        let start = self.pass_token(pass)?;
        let end = (start + 1..self.toks.len())
            .find(|&i| self.is_key(i, "name"))
            .unwrap_or(self.toks.len());
        // The pass's fields may come before `name:` inside its parentheses: start at the
        // opening parenthesis of the pass.
        let mut depth = 0i32;
        let mut open = start;
        for i in (0..start).rev() {
            match self.toks[i].0 {
                Tok::Punct(')') | Tok::Punct(']') | Tok::Punct('}') => depth += 1,
                Tok::Punct('(') | Tok::Punct('[') | Tok::Punct('{') => {
                    if depth == 0 {
                        open = i;
                        break;
                    }
                    depth -= 1;
                }
                _ => {}
            }
        }
        Some((open, end))
    }

    /// Every place pass `pass` is declared (more than one for a duplicate).
    pub fn pass_declarations(&self, pass: &str) -> Vec<Position> {
        (0..self.toks.len())
            .filter(|&i| {
                self.is_key(i, "name")
                    && matches!(self.toks.get(i + 2), Some((Tok::Str(s), _)) if s == pass)
            })
            .map(|i| self.toks[i + 2].1)
            .collect()
    }

    /// Every place resource `name` is declared (more than one for a duplicate).
    pub fn resource_declarations(&self, name: &str) -> Vec<Position> {
        let passes = (0..self.toks.len())
            .find(|&i| self.is_key(i, "passes"))
            .unwrap_or(self.toks.len());
        (0..passes)
            .filter_map(|i| match (&self.toks[i], self.toks.get(i + 1)) {
                ((Tok::Str(s), p), Some((Tok::Punct(':'), _))) if s == name => Some(*p),
                _ => None,
            })
            .collect()
    }

    /// Where pass `pass` is declared (its name string).
    pub fn pass(&self, pass: &str) -> Option<Position> {
        self.pass_token(pass).map(|i| self.toks[i].1)
    }

    /// Where resource `name` is declared (a string key followed by `:` before `passes`).
    pub fn resource(&self, name: &str) -> Option<Position> {
        let passes = (0..self.toks.len())
            .find(|&i| self.is_key(i, "passes"))
            .unwrap_or(self.toks.len());
        (0..passes).find_map(|i| match (&self.toks[i], self.toks.get(i + 1)) {
            ((Tok::Str(s), p), Some((Tok::Punct(':'), _))) if s == name => Some(*p),
            _ => None,
        })
    }

    /// Where pass `pass` mentions the string `name` (a binding or `after` entry), else the
    /// pass itself.
    pub fn in_pass(&self, pass: &str, name: &str) -> Option<Position> {
        let (a, b) = self.pass_range(pass)?;
        (a..b)
            .find_map(|i| match &self.toks[i] {
                (Tok::Str(s), p)
                    if s == name && i != self.pass_token(pass).unwrap_or(usize::MAX) =>
                {
                    Some(*p)
                }
                _ => None,
            })
            .or_else(|| self.pass(pass))
    }

    /// Where the field `field:` of pass `pass` is (e.g. `kind`), else the pass itself.
    pub fn pass_field(&self, pass: &str, field: &str) -> Option<Position> {
        let (a, b) = self.pass_range(pass)?;
        (a..b)
            .find(|&i| self.is_key(i, field))
            .map(|i| self.toks[i].1)
            .or_else(|| self.pass(pass))
    }

    /// Where `name` is written in the `include:` list.
    pub fn include_entry(&self, name: &str) -> Option<Position> {
        let start = (0..self.toks.len()).find(|&i| self.is_key(i, "include"))?;
        self.toks[start..].iter().find_map(|(t, p)| match t {
            Tok::Str(s) if s == name => Some(*p),
            _ => None,
        })
    }

    /// Where the top-level `output:` field is.
    pub fn output(&self) -> Option<Position> {
        (0..self.toks.len())
            .rev()
            .find(|&i| self.is_key(i, "output"))
            .map(|i| self.toks[i].1)
    }

    /// Every `kind: Ident` in the file: (identifier, its position, enclosing pass name).
    pub fn kinds(&self) -> Vec<(String, Position, Option<String>)> {
        let mut out = Vec::new();
        for i in 0..self.toks.len() {
            if self.is_key(i, "kind") {
                if let Some((Tok::Ident(k), p)) = self.toks.get(i + 2) {
                    let pass = self.pass_of_token(i);
                    out.push((k.clone(), *p, pass));
                }
            }
        }
        out
    }

    /// Name of the pass whose parentheses enclose token `i`, if any.
    fn pass_of_token(&self, i: usize) -> Option<String> {
        // Find the enclosing '(' then look for `name: "x"` at depth 0 inside it.
        let mut depth = 0i32;
        let mut open = None;
        for j in (0..i).rev() {
            match self.toks[j].0 {
                Tok::Punct(')') | Tok::Punct(']') | Tok::Punct('}') => depth += 1,
                Tok::Punct('(') | Tok::Punct('[') | Tok::Punct('{') => {
                    if depth == 0 {
                        open = Some(j);
                        break;
                    }
                    depth -= 1;
                }
                _ => {}
            }
        }
        let open = open?;
        let mut depth = 0i32;
        for j in open + 1..self.toks.len() {
            match self.toks[j].0 {
                Tok::Punct('(') | Tok::Punct('[') | Tok::Punct('{') => depth += 1,
                Tok::Punct(')') | Tok::Punct(']') | Tok::Punct('}') => {
                    if depth == 0 {
                        return None;
                    }
                    depth -= 1;
                }
                _ => {}
            }
            if depth == 0 && self.is_key(j, "name") {
                if let Some((Tok::Str(s), _)) = self.toks.get(j + 2) {
                    return Some(s.clone());
                }
            }
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const SRC: &str = r#"Pipeline(
  // a comment with "entry": inside
  resources: {
    "entry": Texture(format: Rgba32Float, size: Screen),
  },
  passes: [
    (name: "a", kind: Foo, writes: ["entry"]),
    (
      kind: Bar(x: 1),
      name: "b",
      reads: ["entry"],
    ),
  ],
  output: "entry",
)"#;

    #[test]
    fn finds_declarations_and_mentions() {
        let l = Locator::new(SRC);
        assert_eq!(l.resource("entry"), Some(Position { line: 4, col: 5 }));
        assert_eq!(l.pass("a"), Some(Position { line: 7, col: 12 }));
        assert_eq!(
            l.in_pass("b", "entry"),
            Some(Position { line: 11, col: 15 })
        );
        assert_eq!(l.in_pass("a", "entry"), Some(Position { line: 7, col: 37 }));
        assert_eq!(
            l.pass_field("b", "kind"),
            Some(Position { line: 9, col: 7 })
        );
        assert_eq!(l.output(), Some(Position { line: 14, col: 3 }));
        let kinds = l.kinds();
        assert_eq!(kinds.len(), 2);
        assert_eq!(kinds[0].0, "Foo");
        assert_eq!(kinds[0].2.as_deref(), Some("a"));
        assert_eq!(
            kinds[1],
            (
                "Bar".to_string(),
                Position { line: 9, col: 13 },
                Some("b".to_string())
            )
        );
    }

    /// Duplicates, a binding list with another name first, and a pass whose `kind` follows
    /// a closed list and precedes `name` (the enclosing pass is found across brackets).
    const SRC2: &str = r#"Pipeline(
  resources: {
    "entry": Texture(format: Rgba8Unorm, size: Screen),
    "entry": Texture(format: Rgba8Unorm, size: Screen),
  },
  passes: [
    (name: "a", reads: ["y", "entry"], kind: Foo),
    (reads: ["x"], kind: Baz, name: "c"),
  ],
  output: "entry",
)"#;

    #[test]
    fn duplicates_lists_and_names_after_kinds() {
        let l = Locator::new(SRC2);
        let at = |line, col| Position { line, col };
        assert_eq!(l.resource_declarations("entry"), vec![at(3, 5), at(4, 5)]);
        assert_eq!(l.resource_declarations("a"), vec![]);
        assert_eq!(l.in_pass("a", "entry"), Some(at(7, 30)));
        assert_eq!(l.pass("c"), Some(at(8, 37)));
        assert_eq!(l.pass_declarations("c"), vec![at(8, 37)]);
        assert_eq!(
            l.kinds(),
            vec![
                ("Foo".to_string(), at(7, 46), Some("a".to_string())),
                ("Baz".to_string(), at(8, 26), Some("c".to_string())),
            ]
        );
    }
}
