//! Declarations read as source text: the doc comments, fields, types and
//! `#[serde(default …)]` attributes of a Rust struct or enum, for references generated
//! from the code (`docs/scenes.md`, the parameter meanings of `docs/pipelines.md`). A small
//! line parser of rustfmt-formatted source, embedded at build time: rustdoc has the same
//! text, but not as data. Its users' tests hold what it finds to what serde reads.

/// Where shared default functions live (`one`, used across the scene format).
const EXTRA_DEFAULTS: &str = include_str!("../../scene-file/src/instance.rs");

/// One field of a struct or of an enum variant.
#[derive(Debug, Clone, PartialEq)]
pub struct Field {
    /// Field name.
    pub name: String,
    /// Type, without module paths.
    pub ty: String,
    /// Default as the reference shows it (`required` when there is none).
    pub default: String,
    /// Doc comment, as one paragraph.
    pub doc: String,
}

/// One enum variant.
#[derive(Debug, Clone, PartialEq)]
pub struct Variant {
    /// Variant name.
    pub name: String,
    /// `Some(type)` for a tuple variant (`Fixed(u32)`).
    pub tuple: Option<String>,
    /// Fields of a struct variant.
    pub fields: Vec<Field>,
    /// Doc comment, as one paragraph.
    pub doc: String,
}

/// A declaration: a struct's fields or an enum's variants.
#[derive(Debug, Clone, PartialEq)]
pub enum Decl {
    /// A struct's fields.
    Struct(Vec<Field>),
    /// An enum's variants.
    Enum(Vec<Variant>),
}

/// The doc comment and declaration of `name` in `source` (`None` when it is not there);
/// `default = "f"` functions are looked up in `source`.
pub fn parse(source: &str, name: &str) -> Option<(String, Decl)> {
    let lines: Vec<&str> = source.lines().collect();
    let start = lines.iter().position(|l| {
        *l == format!("pub struct {name} {{") || *l == format!("pub enum {name} {{")
    })?;
    let doc = docs_above(&lines, start);
    let body: Vec<&str> = lines[start + 1..]
        .iter()
        .take_while(|l| **l != "}")
        .copied()
        .collect();
    let decl = if lines[start].starts_with("pub struct") {
        Decl::Struct(fields(source, &body, "    "))
    } else {
        Decl::Enum(variants(source, &body))
    };
    Some((doc, decl))
}

/// The `///` lines right above line `at` (attributes between them skipped), as one
/// paragraph.
fn docs_above(lines: &[&str], at: usize) -> String {
    let mut doc = Vec::new();
    for l in lines[..at].iter().rev() {
        let t = l.trim();
        if let Some(d) = t.strip_prefix("///") {
            doc.push(d.trim());
        } else if !t.starts_with("#[") {
            break;
        }
    }
    doc.reverse();
    doc.join(" ")
}

/// The fields declared in `body` at `indent` (`pub name: Type,` or `name: Type,`).
fn fields(source: &str, body: &[&str], indent: &str) -> Vec<Field> {
    let mut out = Vec::new();
    let (mut doc, mut default) = (Vec::new(), String::from("required"));
    for l in body {
        let Some(t) = l.strip_prefix(indent) else {
            continue;
        };
        if t.starts_with(' ') {
            continue;
        }
        if let Some(d) = t.strip_prefix("///") {
            doc.push(d.trim().to_string());
        } else if let Some(attr) = t.strip_prefix("#[serde(default") {
            default = match attr.strip_prefix(" = \"") {
                Some(rest) => default_fn(source, rest.split('"').next().unwrap_or_default()),
                None => String::from("the type's default"),
            };
        } else if let Some((name, ty)) = t
            .trim_start_matches("pub ")
            .trim_end_matches(',')
            .split_once(": ")
        {
            let shown = match (default.as_str(), ty) {
                ("the type's default", t) if t.starts_with("Option<") => "none".into(),
                ("the type's default", t) if t.starts_with("Vec<") => "`[]`".into(),
                ("the type's default", "bool") => "`false`".into(),
                ("the type's default", t) if t.starts_with('(') => {
                    format!("`({})`", vec!["0.0"; t.matches(',').count() + 1].join(", "))
                }
                ("the type's default", t) if t.starts_with(['u', 'i', 'f']) => "`0`".into(),
                ("the type's default", _) => "its defaults (below)".into(),
                (d, _) => d.to_string(),
            };
            // `ssbvb_voxel::edit::Edit` is `Edit` here, as the reference's headings name it.
            let ty = strip_paths(ty);
            out.push(Field {
                name: name.to_string(),
                ty,
                default: shown,
                doc: doc.join(" "),
            });
            doc.clear();
            default = String::from("required");
        }
    }
    out
}

/// `ty` without module paths (`Option<ssbvb_voxel::edit::Edit>` → `Option<Edit>`).
fn strip_paths(ty: &str) -> String {
    let mut out = String::new();
    let mut word = String::new();
    for c in ty.chars().chain(std::iter::once(' ')) {
        if c.is_alphanumeric() || c == '_' || c == ':' {
            word.push(c);
        } else {
            out.push_str(word.rsplit("::").next().unwrap_or_default());
            word.clear();
            out.push(c);
        }
    }
    out.pop();
    out
}

/// The value a `fn name() -> T { value }` default function returns, as written.
fn default_fn(source: &str, name: &str) -> String {
    for s in [source, EXTRA_DEFAULTS] {
        let lines: Vec<&str> = s.lines().collect();
        let head = format!("fn {name}() -> ");
        if let Some(i) = lines.iter().position(|l| l.contains(&head)) {
            if let Some(value) = lines.get(i + 1) {
                return format!("`{}`", value.trim());
            }
        }
    }
    format!("`{name}()`")
}

/// The variants declared in an enum's `body`.
fn variants(source: &str, body: &[&str]) -> Vec<Variant> {
    let mut out = Vec::new();
    let mut doc = Vec::new();
    let mut i = 0;
    while i < body.len() {
        let l = body[i];
        let Some(t) = l.strip_prefix("    ").filter(|t| !t.starts_with(' ')) else {
            i += 1;
            continue;
        };
        if let Some(d) = t.strip_prefix("///") {
            doc.push(d.trim().to_string());
        } else if !t.starts_with("#[") {
            let name: String = t.chars().take_while(|c| c.is_alphanumeric()).collect();
            let rest = &t[name.len()..];
            let mut v = Variant {
                name,
                tuple: None,
                fields: Vec::new(),
                doc: doc.join(" "),
            };
            if let Some(inner) = rest.strip_prefix('(') {
                v.tuple = Some(inner.trim_end_matches("),").to_string());
            } else if rest.trim() == "{" {
                let end = body[i..].iter().position(|l| *l == "    },").unwrap_or(0) + i;
                v.fields = fields(source, &body[i + 1..end], "        ");
                i = end;
            }
            out.push(v);
            doc.clear();
        }
        i += 1;
    }
    out
}
