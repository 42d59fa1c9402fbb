//! The PLY header: format line, elements and their typed properties, and the check of the
//! declared counts against the body size.

use std::path::Path;

use crate::load::common::{MAX_TRIANGLES, MAX_VERTICES};
use crate::load::error::LoadError;

/// A header longer than this is not a PLY header.
const MAX_HEADER_BYTES: usize = 1 << 20;
/// Most instances of any one element.
const MAX_ELEMENT_COUNT: u64 = 1 << 28;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn from_name(name: &str) -> Option<Self> {
        Some(match name {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }

    pub(super) fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }

    pub(super) fn is_int(self) -> bool {
        !matches!(self, Scalar::F32 | Scalar::F64)
    }

    /// The value that means "full intensity" for a colour channel of this type.
    pub(super) fn unit(self) -> f64 {
        match self {
            Scalar::I8 => i8::MAX as f64,
            Scalar::U8 => u8::MAX as f64,
            Scalar::I16 => i16::MAX as f64,
            Scalar::U16 => u16::MAX as f64,
            Scalar::I32 => i32::MAX as f64,
            Scalar::U32 => u32::MAX as f64,
            Scalar::F32 | Scalar::F64 => 1.0,
        }
    }

    pub(super) fn range(self) -> (f64, f64) {
        match self {
            Scalar::I8 => (i8::MIN as f64, i8::MAX as f64),
            Scalar::U8 => (0.0, u8::MAX as f64),
            Scalar::I16 => (i16::MIN as f64, i16::MAX as f64),
            Scalar::U16 => (0.0, u16::MAX as f64),
            Scalar::I32 => (i32::MIN as f64, i32::MAX as f64),
            Scalar::U32 => (0.0, u32::MAX as f64),
            Scalar::F32 | Scalar::F64 => (f64::NEG_INFINITY, f64::INFINITY),
        }
    }
}

#[derive(Debug, Clone, Copy)]
pub(super) enum Kind {
    Scalar(Scalar),
    List { count: Scalar, item: Scalar },
}

#[derive(Debug)]
pub(super) struct Property {
    pub(super) name: String,
    pub(super) kind: Kind,
}

#[derive(Debug)]
pub(super) struct Element {
    pub(super) name: String,
    pub(super) count: usize,
    pub(super) props: Vec<Property>,
}

impl Element {
    pub(super) fn prop(&self, names: &[&str]) -> Option<usize> {
        names
            .iter()
            .find_map(|n| self.props.iter().position(|p| p.name == *n))
    }

    /// Fewest bytes one instance can occupy in a binary body.
    pub(super) fn min_binary_size(&self) -> u64 {
        self.props
            .iter()
            .map(|p| match p.kind {
                Kind::Scalar(s) => s.size() as u64,
                Kind::List { count, .. } => count.size() as u64,
            })
            .sum()
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Encoding {
    Ascii,
    BinaryLe,
    BinaryBe,
}

pub(super) struct Header {
    pub(super) encoding: Encoding,
    pub(super) elements: Vec<Element>,
    /// Byte offset of the body.
    pub(super) body_start: usize,
    /// Line number of the body's first line (for ASCII bodies).
    pub(super) body_line: usize,
}

pub(super) fn parse_header(bytes: &[u8], path: &Path) -> Result<Header, LoadError> {
    let mut pos = 0usize;
    let mut line_no = 0usize;
    let mut encoding = None;
    let mut elements: Vec<Element> = Vec::new();
    loop {
        if pos >= bytes.len() {
            return Err(LoadError::at_line(
                path,
                line_no.max(1),
                "end of file inside the header (no `end_header`)",
            ));
        }
        if pos > MAX_HEADER_BYTES {
            return Err(LoadError::at_line(
                path,
                line_no,
                "header longer than 1 MiB (no `end_header`?)",
            ));
        }
        let rest = &bytes[pos..];
        let end = rest.iter().position(|&b| b == b'\n').unwrap_or(rest.len());
        let raw_line = &rest[..end];
        pos = pos.saturating_add(end + 1).min(bytes.len());
        line_no += 1;
        let line =
            String::from_utf8_lossy(raw_line.strip_suffix(b"\r").unwrap_or(raw_line)).into_owned();
        let mut words = line.split_ascii_whitespace();
        let keyword = words.next().unwrap_or("");
        if line_no == 1 {
            if line.trim() != "ply" {
                return Err(LoadError::at_line(
                    path,
                    1,
                    "not a PLY file (first line is not `ply`)",
                ));
            }
            continue;
        }
        let err = |msg: String| LoadError::at_line(path, line_no, msg);
        match keyword {
            "" | "comment" | "obj_info" => {}
            "format" => {
                encoding = Some(match words.next() {
                    Some("ascii") => Encoding::Ascii,
                    Some("binary_little_endian") => Encoding::BinaryLe,
                    Some("binary_big_endian") => Encoding::BinaryBe,
                    other => return Err(err(format!("unknown PLY format {other:?}"))),
                });
            }
            "element" => {
                let (Some(name), Some(count)) = (words.next(), words.next()) else {
                    return Err(err("`element` needs a name and a count".into()));
                };
                let count: u64 = count
                    .parse()
                    .map_err(|_| err(format!("element count {count:?} is not a number")))?;
                let limit = match name {
                    "vertex" => MAX_VERTICES as u64,
                    "face" => MAX_TRIANGLES as u64,
                    _ => MAX_ELEMENT_COUNT,
                };
                if count > limit {
                    return Err(LoadError::too_large(
                        path,
                        &format!("`{name}` elements"),
                        count,
                        limit,
                    ));
                }
                if elements.iter().any(|e| e.name == name) {
                    return Err(err(format!("element `{name}` is declared twice")));
                }
                elements.push(Element {
                    name: name.to_string(),
                    count: count as usize,
                    props: Vec::new(),
                });
            }
            "property" => {
                let Some(element) = elements.last_mut() else {
                    return Err(err("`property` before any `element`".into()));
                };
                let first = words.next().unwrap_or("");
                let kind = if first == "list" {
                    let (Some(c), Some(i)) = (words.next(), words.next()) else {
                        return Err(err(
                            "`property list` needs a count type and an item type".into()
                        ));
                    };
                    let count =
                        Scalar::from_name(c).ok_or_else(|| err(format!("unknown type {c:?}")))?;
                    let item =
                        Scalar::from_name(i).ok_or_else(|| err(format!("unknown type {i:?}")))?;
                    if !count.is_int() {
                        return Err(err(format!("list count type {c:?} is not an integer type")));
                    }
                    Kind::List { count, item }
                } else {
                    Kind::Scalar(
                        Scalar::from_name(first)
                            .ok_or_else(|| err(format!("unknown type {first:?}")))?,
                    )
                };
                let Some(name) = words.next() else {
                    return Err(err("`property` needs a name".into()));
                };
                element.props.push(Property {
                    name: name.to_string(),
                    kind,
                });
            }
            "end_header" => break,
            other => return Err(err(format!("unknown header keyword {other:?}"))),
        }
    }
    let encoding =
        encoding.ok_or_else(|| LoadError::at_line(path, 2, "header has no `format` line"))?;
    Ok(Header {
        encoding,
        elements,
        body_start: pos,
        body_line: line_no + 1,
    })
}

/// Refuses headers whose declared counts cannot fit in the bytes that follow, before
/// anything is allocated from them.
pub(super) fn check_counts(header: &Header, body_len: u64, path: &Path) -> Result<(), LoadError> {
    let mut needed: u64 = 0;
    for e in &header.elements {
        let per_instance = match header.encoding {
            // Each ASCII value takes at least one character and one separator.
            Encoding::Ascii => 2 * e.props.len() as u64,
            _ => e.min_binary_size(),
        };
        needed = needed.saturating_add((e.count as u64).saturating_mul(per_instance));
        // The last ASCII value may end the file without a separator, hence the `+ 1`.
        if needed > body_len.saturating_add(1) {
            return Err(LoadError::at_offset(
                path,
                header.body_start as u64,
                format!(
                    "the header declares {} `{}` elements, which need at least {needed} bytes, \
                     but only {body_len} bytes follow the header",
                    e.count, e.name
                ),
            ));
        }
    }
    Ok(())
}
