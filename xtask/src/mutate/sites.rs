//! The mutants of one WGSL file, found textually: `cargo-mutants` does not read WGSL, and a
//! WGSL parser would have to keep every byte of the source to print a mutant back (naga's
//! does not), so the sites are found on the text, in code only (comments are skipped), and
//! naga judges afterwards which mutants are valid WGSL.
//!
//! The project's WGSL writes binary operators with a space on each side (`a < b`, never
//! `a<b`), which is what tells a comparison from a generic's angle bracket (`vec3<f32>`).

use std::ops::Range;

/// What a mutant changes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Kind {
    /// A comparison, arithmetic, logical, bit or compound-assignment operator swapped.
    Operator,
    /// A numeric literal plus or minus one.
    Constant,
    /// The two value arms of a `select` swapped.
    SelectArms,
    /// The condition of an `if` negated.
    NegatedCondition,
    /// One statement deleted.
    DeletedStatement,
}

impl Kind {
    /// The name the report uses.
    pub fn name(self) -> &'static str {
        match self {
            Kind::Operator => "operator",
            Kind::Constant => "constant",
            Kind::SelectArms => "select arms",
            Kind::NegatedCondition => "negated condition",
            Kind::DeletedStatement => "deleted statement",
        }
    }
}

/// One change to one file.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Mutant {
    /// 1-based line and column (in characters) of the changed text.
    pub line: usize,
    /// See `line`.
    pub col: usize,
    /// What kind of change.
    pub kind: Kind,
    /// The text replaced.
    pub from: String,
    /// The text put in its place.
    pub to: String,
    /// Byte range of `from` in the file.
    pub range: Range<usize>,
}

impl Mutant {
    /// The file with this change applied.
    pub fn apply(&self, src: &str) -> String {
        let mut out = String::with_capacity(src.len() + self.to.len());
        out.push_str(&src[..self.range.start]);
        out.push_str(&self.to);
        out.push_str(&src[self.range.end..]);
        out
    }

    /// One line for a report: `line:col kind: from -> to` (long texts shortened).
    pub fn describe(&self) -> String {
        let short = |s: &str| {
            let one: String = s.split_whitespace().collect::<Vec<_>>().join(" ");
            if one.chars().count() > 60 {
                format!("{}…", one.chars().take(59).collect::<String>())
            } else {
                one
            }
        };
        format!(
            "{}:{} {}: `{}` → `{}`",
            self.line,
            self.col,
            self.kind.name(),
            short(&self.from),
            short(&self.to)
        )
    }
}

/// Operators and what each becomes: the comparison at the other side of its boundary, the
/// inverse arithmetic, the other logic or bit operation.
const OPERATORS: &[(&str, &str)] = &[
    ("<", "<="),
    ("<=", "<"),
    (">", ">="),
    (">=", ">"),
    ("==", "!="),
    ("!=", "=="),
    ("+", "-"),
    ("-", "+"),
    ("*", "/"),
    ("/", "*"),
    ("%", "/"),
    ("&&", "||"),
    ("||", "&&"),
    ("&", "|"),
    ("|", "&"),
    ("^", "|"),
    ("<<", ">>"),
    (">>", "<<"),
    ("+=", "-="),
    ("-=", "+="),
    ("*=", "/="),
    ("/=", "*="),
    ("|=", "&="),
    ("&=", "|="),
];

/// Statement starts whose deletion cannot be valid WGSL or is not a statement.
const NOT_DELETABLE: &[&str] = &[
    "let ",
    "var ",
    "var<",
    "const ",
    "override ",
    "struct ",
    "fn ",
    "@",
    "alias ",
    "enable ",
    "for ",
    "for(",
    "if ",
    "while ",
    "loop",
    "}",
    "{",
];

/// Every mutant of `src`, in file order.
pub fn mutants(src: &str) -> Vec<Mutant> {
    let code = code_mask(src);
    let mut out = Vec::new();
    let mut line_start = 0;
    for (li, line) in src.split_inclusive('\n').enumerate() {
        let at = |off: usize| (li + 1, line[..off].chars().count() + 1);
        operator_sites(line, line_start, &code, &at, &mut out);
        constant_sites(line, line_start, &code, &at, &mut out);
        condition_site(line, line_start, &code, &at, &mut out);
        statement_site(line, line_start, &code, &at, &mut out);
        line_start += line.len();
    }
    select_sites(src, &code, &mut out);
    out.sort_by_key(|m| (m.range.start, m.kind, m.to.clone()));
    out
}

/// Per byte of `src`: true in code, false in a `//` comment (to the end of the line) or a
/// `/* */` block comment.
fn code_mask(src: &str) -> Vec<bool> {
    let b = src.as_bytes();
    let mut mask = vec![true; b.len()];
    let mut i = 0;
    while i < b.len() {
        if b[i..].starts_with(b"//") {
            while i < b.len() && b[i] != b'\n' {
                mask[i] = false;
                i += 1;
            }
        } else if b[i..].starts_with(b"/*") {
            while i < b.len() && !b[i..].starts_with(b"*/") {
                mask[i] = false;
                i += 1;
            }
            for m in mask.iter_mut().skip(i).take(2) {
                *m = false;
            }
            i += 2;
        } else {
            i += 1;
        }
    }
    mask
}

fn is_code(code: &[bool], r: Range<usize>) -> bool {
    code.get(r).is_some_and(|s| s.iter().all(|&c| c))
}

fn operator_sites(
    line: &str,
    base: usize,
    code: &[bool],
    at: &dyn Fn(usize) -> (usize, usize),
    out: &mut Vec<Mutant>,
) {
    let bytes = line.as_bytes();
    for (i, _) in line.match_indices(' ') {
        let rest = &line[i + 1..];
        let Some(end) = rest.find([' ', '\n']) else {
            continue;
        };
        if bytes.get(i + 1 + end) != Some(&b' ') {
            continue;
        }
        let tok = &rest[..end];
        let Some((_, to)) = OPERATORS.iter().find(|(f, _)| *f == tok) else {
            continue;
        };
        let r = base + i + 1..base + i + 1 + end;
        if !is_code(code, r.clone()) {
            continue;
        }
        let (line, col) = at(i + 1);
        out.push(Mutant {
            line,
            col,
            kind: Kind::Operator,
            from: tok.to_string(),
            to: to.to_string(),
            range: r,
        });
    }
}

fn is_ident(c: u8) -> bool {
    c.is_ascii_alphanumeric() || c == b'_'
}

/// Literals inside an attribute (`@binding(3)`, `@workgroup_size(64)`) are left alone:
/// changing them breaks the binding layout, not the shader's arithmetic.
fn in_attribute(line: &str, off: usize) -> bool {
    line[..off]
        .rfind('@')
        .is_some_and(|a| !line[a..off].contains(')'))
}

fn constant_sites(
    line: &str,
    base: usize,
    code: &[bool],
    at: &dyn Fn(usize) -> (usize, usize),
    out: &mut Vec<Mutant>,
) {
    let b = line.as_bytes();
    let mut i = 0;
    while i < b.len() {
        let starts = b[i].is_ascii_digit() && (i == 0 || !(is_ident(b[i - 1]) || b[i - 1] == b'.'));
        if !starts {
            i += 1;
            continue;
        }
        let len = literal_len(&b[i..]);
        let text = &line[i..i + len];
        let r = base + i..base + i + len;
        if is_code(code, r.clone()) && !in_attribute(line, i) {
            for to in plus_minus_one(text) {
                let (line, col) = at(i);
                out.push(Mutant {
                    line,
                    col,
                    kind: Kind::Constant,
                    from: text.to_string(),
                    to,
                    range: r.clone(),
                });
            }
        }
        i += len;
    }
}

/// Length of the numeric literal at the start of `b` (digits, hex, fraction, exponent and
/// suffix).
fn literal_len(b: &[u8]) -> usize {
    let mut i = 0;
    if b.starts_with(b"0x") || b.starts_with(b"0X") {
        i = 2;
        while i < b.len() && b[i].is_ascii_hexdigit() {
            i += 1;
        }
    } else {
        while i < b.len() && (b[i].is_ascii_digit() || b[i] == b'.') {
            i += 1;
        }
        if i < b.len() && (b[i] == b'e' || b[i] == b'E') {
            i += 1;
            if i < b.len() && (b[i] == b'+' || b[i] == b'-') {
                i += 1;
            }
            while i < b.len() && b[i].is_ascii_digit() {
                i += 1;
            }
        }
    }
    if i < b.len() && matches!(b[i], b'u' | b'i' | b'f' | b'h') {
        i += 1;
    }
    i
}

/// The literal plus and minus one, as WGSL text of the same type (negative values in
/// parentheses). Floats at or above 2^24 are left alone: ±1 does not change them in f32.
fn plus_minus_one(text: &str) -> Vec<String> {
    let (body, suffix) = match text.chars().last() {
        Some(c @ ('u' | 'i' | 'f' | 'h')) if !text.starts_with("0x") || c != 'f' => {
            (&text[..text.len() - 1], c.to_string())
        }
        _ => (text, String::new()),
    };
    let is_float = suffix == "f"
        || suffix == "h"
        || (!body.starts_with("0x") && (body.contains('.') || body.contains(['e', 'E'])));
    let wrap = |s: String| {
        if s.starts_with('-') {
            format!("({s})")
        } else {
            s
        }
    };
    if is_float {
        let Ok(v) = body.parse::<f64>() else {
            return Vec::new();
        };
        if v.abs() >= 16_777_216.0 {
            return Vec::new();
        }
        [v + 1.0, v - 1.0]
            .iter()
            .map(|x| {
                let mut s = format!("{x}");
                if !s.contains(['.', 'e', 'E']) {
                    s.push_str(".0");
                }
                wrap(format!("{s}{suffix}"))
            })
            .collect()
    } else {
        let v = match body.strip_prefix("0x") {
            Some(h) => i64::from_str_radix(h, 16),
            None => body.parse::<i64>(),
        };
        let Ok(v) = v else {
            return Vec::new();
        };
        let mut outs = vec![v + 1];
        if v > 0 || suffix != "u" {
            outs.push(v - 1);
        }
        outs.into_iter()
            .map(|x| {
                if body.starts_with("0x") && x >= 0 {
                    format!("0x{x:x}{suffix}")
                } else {
                    wrap(format!("{x}{suffix}"))
                }
            })
            .collect()
    }
}

/// `if COND {` (also `} else if COND {`) becomes `if !(COND) {`.
fn condition_site(
    line: &str,
    base: usize,
    code: &[bool],
    at: &dyn Fn(usize) -> (usize, usize),
    out: &mut Vec<Mutant>,
) {
    let trimmed = line.trim_start();
    let lead = line.len() - trimmed.len();
    let start = if trimmed.starts_with("if ") {
        lead + 3
    } else if let Some(p) = trimmed.find("} else if ").filter(|&p| p == 0) {
        lead + p + "} else if ".len()
    } else {
        return;
    };
    let Some(brace) = line.trim_end().strip_suffix('{').map(|s| s.len()) else {
        return;
    };
    if brace <= start {
        return;
    }
    let cond = line[start..brace].trim_end();
    let r = base + start..base + start + cond.len();
    if cond.is_empty() || !is_code(code, r.clone()) {
        return;
    }
    let (line, col) = at(start);
    out.push(Mutant {
        line,
        col,
        kind: Kind::NegatedCondition,
        from: cond.to_string(),
        to: format!("!({cond})"),
        range: r,
    });
}

/// A one-line statement (`x += 1u;`, `atomicAdd(...);`, `return y;`, `break;`) deleted.
fn statement_site(
    line: &str,
    base: usize,
    code: &[bool],
    at: &dyn Fn(usize) -> (usize, usize),
    out: &mut Vec<Mutant>,
) {
    let trimmed = line.trim();
    if !trimmed.ends_with(';') || NOT_DELETABLE.iter().any(|p| trimmed.starts_with(p)) {
        return;
    }
    let depth = trimmed.matches('(').count() as i64 - trimmed.matches(')').count() as i64;
    if depth != 0 {
        return;
    }
    let start = line.find(trimmed).unwrap_or(0);
    let r = base + start..base + start + trimmed.len();
    if !is_code(code, r.clone()) {
        return;
    }
    let (line, col) = at(start);
    out.push(Mutant {
        line,
        col,
        kind: Kind::DeletedStatement,
        from: trimmed.to_string(),
        to: String::new(),
        range: r,
    });
}

/// `select(A, B, C)` becomes `select(B, A, C)` (the call may span lines).
fn select_sites(src: &str, code: &[bool], out: &mut Vec<Mutant>) {
    let b = src.as_bytes();
    for (i, _) in src.match_indices("select(") {
        if i > 0 && is_ident(b[i - 1]) || !code[i] {
            continue;
        }
        let open = i + "select".len();
        let mut depth = 0i32;
        let mut commas = Vec::new();
        let mut close = None;
        for (j, &c) in b.iter().enumerate().skip(open) {
            if !code[j] {
                continue;
            }
            match c {
                b'(' => depth += 1,
                b')' => {
                    depth -= 1;
                    if depth == 0 {
                        close = Some(j);
                        break;
                    }
                }
                b',' if depth == 1 => commas.push(j),
                _ => {}
            }
        }
        let (Some(close), [c1, c2]) = (close, commas.as_slice()) else {
            continue;
        };
        let a = src[open + 1..*c1].trim();
        let bb = src[c1 + 1..*c2].trim();
        let c = src[c2 + 1..close].trim();
        if a == bb {
            continue;
        }
        let line = src[..i].matches('\n').count() + 1;
        let col = src[..i]
            .rsplit('\n')
            .next()
            .map_or(0, |l| l.chars().count())
            + 1;
        out.push(Mutant {
            line,
            col,
            kind: Kind::SelectArms,
            from: src[i..=close].to_string(),
            to: format!("select({bb}, {a}, {c})"),
            range: i..close + 1,
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn changes(src: &str) -> Vec<(Kind, String, String)> {
        mutants(src)
            .into_iter()
            .map(|m| (m.kind, m.from, m.to))
            .collect()
    }

    #[test]
    fn operators_in_code_are_swapped_and_generics_and_comments_are_not() {
        let src = "var<private> a: vec3<f32>; // x < y\nfn f() -> u32 { let b = c < d; }\n";
        let ops: Vec<_> = changes(src)
            .into_iter()
            .filter(|c| c.0 == Kind::Operator)
            .collect();
        assert_eq!(ops, vec![(Kind::Operator, "<".into(), "<=".into())]);
        let m = &mutants(src)
            .into_iter()
            .find(|m| m.kind == Kind::Operator)
            .unwrap();
        assert_eq!((m.line, m.col), (2, 27));
        assert!(m.apply(src).contains("let b = c <= d;"));
    }

    #[test]
    fn constants_move_by_one_and_keep_their_type() {
        assert_eq!(plus_minus_one("3u"), vec!["4u", "2u"]);
        assert_eq!(plus_minus_one("0u"), vec!["1u"]);
        assert_eq!(plus_minus_one("0"), vec!["1", "(-1)"]);
        assert_eq!(plus_minus_one("0.5"), vec!["1.5", "(-0.5)"]);
        assert_eq!(plus_minus_one("2.0"), vec!["3.0", "1.0"]);
        assert_eq!(
            plus_minus_one("1e-12"),
            vec!["1.000000000001", "(-0.999999999999)"]
        );
        assert_eq!(plus_minus_one("0xffu"), vec!["0x100u", "0xfeu"]);
        assert!(plus_minus_one("3.0e38").is_empty());
        // Attributes and identifiers are not literals to change.
        let src = "@group(0) @binding(12) var x: u32;\nlet vec3 = a2 + 7u;\n";
        let consts: Vec<_> = changes(src)
            .into_iter()
            .filter(|c| c.0 == Kind::Constant)
            .map(|c| c.2)
            .collect();
        assert_eq!(consts, vec!["6u", "8u"]);
    }

    #[test]
    fn selects_conditions_and_statements() {
        let src = "    if a < b && (c || d) {\n        x = select(p, f(q, r),\n            s);\n        y += 1u;\n        let z = 2;\n    }\n";
        let all = changes(src);
        assert!(all.contains(&(
            Kind::NegatedCondition,
            "a < b && (c || d)".into(),
            "!(a < b && (c || d))".into()
        )));
        assert!(all.contains(&(
            Kind::SelectArms,
            "select(p, f(q, r),\n            s)".into(),
            "select(f(q, r), p, s)".into()
        )));
        assert!(all.contains(&(Kind::DeletedStatement, "y += 1u;".into(), String::new())));
        // `let` is never deleted (the name would be undefined), a split statement neither.
        assert!(!all.iter().any(|c| c.1.starts_with("let ")));
        assert!(
            !all.iter()
                .any(|c| c.0 == Kind::DeletedStatement && c.1.contains("s);"))
        );
        // Each mutant changes its own range and leaves the rest.
        for m in mutants(src) {
            let out = m.apply(src);
            assert_ne!(out, src, "{m:?}");
            assert_eq!(out.len(), src.len() - m.from.len() + m.to.len());
        }
    }
}
