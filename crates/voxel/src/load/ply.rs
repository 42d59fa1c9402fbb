//! PLY reader: ASCII, binary little-endian and binary big-endian.
//!
//! Hand-written (the header is simple) so that every error can name the line (ASCII) or
//! byte offset (binary), every declared count is checked against the bytes that follow the
//! header before anything is allocated, and `tristrips` elements (as in `igea.ply`) are
//! read, which generic PLY crates leave to the caller.
//!
//! Read: the `vertex` element (`x y z` as any numeric type; optional `nx ny nz`; optional
//! `red green blue [alpha]` or `r g b [a]`, integers normalised by their type's maximum,
//! floats taken as they are, both sRGB-decoded; optional `u v`, `s t`, `texture_u
//! texture_v` or `texture_s texture_t`), the `face` element (`vertex_indices` or
//! `vertex_index` list, polygons fan-triangulated) and the `tristrips` element
//! (`vertex_indices` list, `-1` restarts a strip). Every other element is skipped.

use std::path::Path;

use glam::{Vec2, Vec3};

use super::{LoadError, MAX_TRIANGLES, MAX_VERTICES, srgb_to_linear};
use crate::model::Mesh;

/// A header longer than this is not a PLY header.
const MAX_HEADER_BYTES: usize = 1 << 20;
/// Most instances of any one element.
const MAX_ELEMENT_COUNT: u64 = 1 << 28;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Scalar {
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

    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }

    fn is_int(self) -> bool {
        !matches!(self, Scalar::F32 | Scalar::F64)
    }

    /// The value that means "full intensity" for a colour channel of this type.
    fn unit(self) -> f64 {
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

    fn range(self) -> (f64, f64) {
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
enum Kind {
    Scalar(Scalar),
    List { count: Scalar, item: Scalar },
}

#[derive(Debug)]
struct Property {
    name: String,
    kind: Kind,
}

#[derive(Debug)]
struct Element {
    name: String,
    count: usize,
    props: Vec<Property>,
}

impl Element {
    fn prop(&self, names: &[&str]) -> Option<usize> {
        names
            .iter()
            .find_map(|n| self.props.iter().position(|p| p.name == *n))
    }

    /// Fewest bytes one instance can occupy in a binary body.
    fn min_binary_size(&self) -> u64 {
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
enum Encoding {
    Ascii,
    BinaryLe,
    BinaryBe,
}

struct Header {
    encoding: Encoding,
    elements: Vec<Element>,
    /// Byte offset of the body.
    body_start: usize,
    /// Line number of the body's first line (for ASCII bodies).
    body_line: usize,
}

/// Parses a PLY file held in memory.
pub(super) fn parse(
    bytes: &[u8],
    path: &Path,
    warnings: &mut Vec<String>,
) -> Result<Mesh, LoadError> {
    let header = parse_header(bytes, path)?;
    let body = bytes.get(header.body_start..).unwrap_or_default();
    check_counts(&header, body.len() as u64, path)?;
    match header.encoding {
        Encoding::Ascii => {
            let mut r = AsciiReader {
                data: body,
                pos: 0,
                line: header.body_line,
                path,
            };
            read_body(&mut r, &header, path, warnings)
        }
        Encoding::BinaryLe | Encoding::BinaryBe => {
            let mut r = BinaryReader {
                data: body,
                pos: 0,
                base: header.body_start as u64,
                big_endian: header.encoding == Encoding::BinaryBe,
                path,
            };
            read_body(&mut r, &header, path, warnings)
        }
    }
}

fn parse_header(bytes: &[u8], path: &Path) -> Result<Header, LoadError> {
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
fn check_counts(header: &Header, body_len: u64, path: &Path) -> Result<(), LoadError> {
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

/// Reads values from the body, in either encoding.
trait Reader {
    /// Reads one value of type `t`.
    fn value(&mut self, t: Scalar, what: &str) -> Result<f64, LoadError>;
    /// Whether `n` more items of type `t` can possibly be in the rest of the body.
    fn can_hold(&self, n: u64, t: Scalar) -> bool;
    /// Skips `n` instances of `size` bytes each when the encoding allows it (binary).
    fn skip_fixed(&mut self, n: usize, size: usize, what: &str) -> Result<bool, LoadError>;
    /// An error at the current position.
    fn error(&self, message: String) -> LoadError;
}

struct BinaryReader<'a> {
    data: &'a [u8],
    pos: usize,
    base: u64,
    big_endian: bool,
    path: &'a Path,
}

impl BinaryReader<'_> {
    fn take<const N: usize>(&mut self, what: &str) -> Result<[u8; N], LoadError> {
        let end = self.pos.checked_add(N);
        match end.and_then(|e| self.data.get(self.pos..e)) {
            Some(s) => {
                let mut a = [0u8; N];
                a.copy_from_slice(s);
                self.pos += N;
                Ok(a)
            }
            None => Err(self.error(format!("unexpected end of file while reading {what}"))),
        }
    }
}

impl Reader for BinaryReader<'_> {
    fn value(&mut self, t: Scalar, what: &str) -> Result<f64, LoadError> {
        let be = self.big_endian;
        Ok(match t {
            Scalar::I8 => self.take::<1>(what)?[0] as i8 as f64,
            Scalar::U8 => self.take::<1>(what)?[0] as f64,
            Scalar::I16 => {
                let b = self.take::<2>(what)?;
                (if be {
                    i16::from_be_bytes(b)
                } else {
                    i16::from_le_bytes(b)
                }) as f64
            }
            Scalar::U16 => {
                let b = self.take::<2>(what)?;
                (if be {
                    u16::from_be_bytes(b)
                } else {
                    u16::from_le_bytes(b)
                }) as f64
            }
            Scalar::I32 => {
                let b = self.take::<4>(what)?;
                (if be {
                    i32::from_be_bytes(b)
                } else {
                    i32::from_le_bytes(b)
                }) as f64
            }
            Scalar::U32 => {
                let b = self.take::<4>(what)?;
                (if be {
                    u32::from_be_bytes(b)
                } else {
                    u32::from_le_bytes(b)
                }) as f64
            }
            Scalar::F32 => {
                let b = self.take::<4>(what)?;
                (if be {
                    f32::from_be_bytes(b)
                } else {
                    f32::from_le_bytes(b)
                }) as f64
            }
            Scalar::F64 => {
                let b = self.take::<8>(what)?;
                if be {
                    f64::from_be_bytes(b)
                } else {
                    f64::from_le_bytes(b)
                }
            }
        })
    }

    fn can_hold(&self, n: u64, t: Scalar) -> bool {
        let remaining = (self.data.len() - self.pos.min(self.data.len())) as u64;
        n.checked_mul(t.size() as u64)
            .is_some_and(|bytes| bytes <= remaining)
    }

    fn skip_fixed(&mut self, n: usize, size: usize, what: &str) -> Result<bool, LoadError> {
        match n.checked_mul(size).and_then(|b| self.pos.checked_add(b)) {
            Some(end) if end <= self.data.len() => {
                self.pos = end;
                Ok(true)
            }
            _ => Err(self.error(format!("unexpected end of file while skipping {what}"))),
        }
    }

    fn error(&self, message: String) -> LoadError {
        LoadError::at_offset(self.path, self.base + self.pos as u64, message)
    }
}

struct AsciiReader<'a> {
    data: &'a [u8],
    pos: usize,
    line: usize,
    path: &'a Path,
}

impl<'a> AsciiReader<'a> {
    fn token(&mut self, what: &str) -> Result<&'a [u8], LoadError> {
        while let Some(&b) = self.data.get(self.pos) {
            if !b.is_ascii_whitespace() {
                break;
            }
            if b == b'\n' {
                self.line += 1;
            }
            self.pos += 1;
        }
        let start = self.pos;
        while self
            .data
            .get(self.pos)
            .is_some_and(|b| !b.is_ascii_whitespace())
        {
            self.pos += 1;
        }
        if start == self.pos {
            return Err(self.error(format!("unexpected end of file while reading {what}")));
        }
        Ok(&self.data[start..self.pos])
    }
}

impl Reader for AsciiReader<'_> {
    fn value(&mut self, t: Scalar, what: &str) -> Result<f64, LoadError> {
        let tok = self.token(what)?;
        let text = std::str::from_utf8(tok).unwrap_or("");
        let v = if t.is_int() {
            text.parse::<i64>().ok().map(|i| i as f64)
        } else {
            text.parse::<f64>().ok()
        };
        let (lo, hi) = t.range();
        match v {
            Some(v) if v >= lo && v <= hi || v.is_nan() && !t.is_int() => Ok(v),
            _ => Err(self.error(format!(
                "{what}: {:?} is not a valid {t:?} value",
                String::from_utf8_lossy(tok)
            ))),
        }
    }

    fn can_hold(&self, n: u64, _t: Scalar) -> bool {
        let remaining = (self.data.len() - self.pos.min(self.data.len())) as u64;
        n.saturating_mul(2) <= remaining.saturating_add(1)
    }

    fn skip_fixed(&mut self, _n: usize, _size: usize, _what: &str) -> Result<bool, LoadError> {
        Ok(false)
    }

    fn error(&self, message: String) -> LoadError {
        LoadError::at_line(self.path, self.line, message)
    }
}

/// Where the vertex attributes sit among the vertex element's properties.
struct VertexLayout {
    pos: [usize; 3],
    normal: Option<[usize; 3]>,
    color: Option<([usize; 3], Option<usize>)>,
    uv: Option<[usize; 2]>,
}

impl VertexLayout {
    fn new(e: &Element, path: &Path) -> Result<Self, LoadError> {
        let scalar = |names: &[&str]| {
            e.prop(names)
                .filter(|&i| matches!(e.props[i].kind, Kind::Scalar(_)))
        };
        let (Some(x), Some(y), Some(z)) = (scalar(&["x"]), scalar(&["y"]), scalar(&["z"])) else {
            return Err(LoadError::parse(
                path,
                "the `vertex` element has no scalar x, y and z properties",
            ));
        };
        let normal = match (scalar(&["nx"]), scalar(&["ny"]), scalar(&["nz"])) {
            (Some(a), Some(b), Some(c)) => Some([a, b, c]),
            _ => None,
        };
        let color = match (
            scalar(&["red", "r", "diffuse_red"]),
            scalar(&["green", "g", "diffuse_green"]),
            scalar(&["blue", "b", "diffuse_blue"]),
        ) {
            (Some(r), Some(g), Some(b)) => {
                Some(([r, g, b], scalar(&["alpha", "a", "diffuse_alpha"])))
            }
            _ => None,
        };
        let uv = [
            ("u", "v"),
            ("s", "t"),
            ("texture_u", "texture_v"),
            ("texture_s", "texture_t"),
        ]
        .iter()
        .find_map(|(u, v)| Some([scalar(&[u])?, scalar(&[v])?]));
        Ok(VertexLayout {
            pos: [x, y, z],
            normal,
            color,
            uv,
        })
    }
}

fn read_body<R: Reader>(
    r: &mut R,
    header: &Header,
    path: &Path,
    warnings: &mut Vec<String>,
) -> Result<Mesh, LoadError> {
    let vertex_count = header
        .elements
        .iter()
        .find(|e| e.name == "vertex")
        .map(|e| e.count)
        .ok_or_else(|| LoadError::parse(path, "no `vertex` element in the header"))?;
    let mut mesh = Mesh::default();
    let mut skipped_faces = 0usize;
    let mut dropped_strip_triangles = 0usize;
    for e in &header.elements {
        match e.name.as_str() {
            "vertex" => read_vertices(r, e, &mut mesh, path)?,
            "face" | "tristrips" => {
                let list = e
                    .prop(&["vertex_indices", "vertex_index"])
                    .or_else(|| {
                        e.props
                            .iter()
                            .position(|p| matches!(p.kind, Kind::List { .. }))
                    })
                    .filter(|&i| matches!(e.props[i].kind, Kind::List { .. }))
                    .ok_or_else(|| {
                        LoadError::parse(
                            path,
                            format!("the `{}` element has no index list", e.name),
                        )
                    })?;
                let strips = e.name == "tristrips";
                if let Kind::List { item, .. } = e.props[list].kind
                    && !item.is_int()
                {
                    return Err(LoadError::parse(
                        path,
                        format!("`{}` indices are not integers", e.name),
                    ));
                }
                let mut indices: Vec<i64> = Vec::new();
                for _ in 0..e.count {
                    for (j, p) in e.props.iter().enumerate() {
                        if j == list {
                            read_index_list(r, p, &mut indices, vertex_count, strips)?;
                        } else {
                            skip_property(r, p)?;
                        }
                    }
                    if strips {
                        dropped_strip_triangles += strip_triangles(&indices, &mut mesh.triangles);
                    } else if indices.len() < 3 {
                        skipped_faces += 1;
                    } else {
                        let first = indices[0] as u32;
                        for w in indices[1..].windows(2) {
                            mesh.triangles.push([first, w[0] as u32, w[1] as u32]);
                        }
                    }
                    if mesh.triangles.len() > MAX_TRIANGLES {
                        return Err(LoadError::too_large(
                            path,
                            "triangles",
                            mesh.triangles.len() as u64,
                            MAX_TRIANGLES as u64,
                        ));
                    }
                }
            }
            _ => skip_element(r, e)?,
        }
    }
    if skipped_faces > 0 {
        warnings.push(format!(
            "{}: skipped {skipped_faces} face(s) with fewer than 3 vertices",
            path.display()
        ));
    }
    if dropped_strip_triangles > 0 {
        log::debug!(
            "{}: dropped {dropped_strip_triangles} strip-stitching triangles with repeated indices",
            path.display()
        );
    }
    Ok(mesh)
}

fn read_vertices<R: Reader>(
    r: &mut R,
    e: &Element,
    mesh: &mut Mesh,
    path: &Path,
) -> Result<(), LoadError> {
    let layout = VertexLayout::new(e, path)?;
    // `check_counts` has bounded `e.count` by the body size, so reserving is safe.
    mesh.positions.reserve_exact(e.count);
    if layout.normal.is_some() {
        mesh.normals.reserve_exact(e.count);
    }
    if layout.color.is_some() {
        mesh.colors.reserve_exact(e.count);
    }
    if layout.uv.is_some() {
        mesh.uvs.reserve_exact(e.count);
    }
    let srgb = super::srgb_u8_table();
    let mut vals = vec![0f64; e.props.len()];
    for i in 0..e.count {
        for (j, p) in e.props.iter().enumerate() {
            match p.kind {
                Kind::Scalar(t) => vals[j] = r.value(t, "a vertex property")?,
                Kind::List { .. } => skip_property(r, p)?,
            }
        }
        let [x, y, z] = layout.pos.map(|k| vals[k] as f32);
        if !(x.is_finite() && y.is_finite() && z.is_finite()) {
            return Err(r.error(format!("vertex {i} has a non-finite coordinate")));
        }
        mesh.positions.push(Vec3::new(x, y, z));
        if let Some(n) = layout.normal {
            let n = Vec3::from(n.map(|k| vals[k] as f32));
            mesh.normals
                .push(if n.is_finite() { n } else { Vec3::ZERO });
        }
        if let Some((rgb, alpha)) = layout.color {
            let channel = |k: usize| -> f32 {
                let t = match e.props[k].kind {
                    Kind::Scalar(t) => t,
                    Kind::List { item, .. } => item,
                };
                let v = (vals[k] / t.unit()).clamp(0.0, 1.0);
                if v.is_nan() { 0.0 } else { v as f32 }
            };
            let lin = |k: usize| -> f32 {
                // Exact table lookup for the usual uchar channels.
                if matches!(e.props[k].kind, Kind::Scalar(Scalar::U8)) {
                    srgb[vals[k] as u8 as usize]
                } else {
                    srgb_to_linear(channel(k))
                }
            };
            let a = alpha.map_or(1.0, channel);
            mesh.colors.push([lin(rgb[0]), lin(rgb[1]), lin(rgb[2]), a]);
        }
        if let Some([u, v]) = layout.uv {
            let uv = Vec2::new(vals[u] as f32, vals[v] as f32);
            mesh.uvs.push(if uv.is_finite() { uv } else { Vec2::ZERO });
        }
    }
    Ok(())
}

/// Reads one index list into `out`, validating every index against `vertex_count`
/// (`-1` is kept for strips, as their restart marker).
fn read_index_list<R: Reader>(
    r: &mut R,
    p: &Property,
    out: &mut Vec<i64>,
    vertex_count: usize,
    strips: bool,
) -> Result<(), LoadError> {
    let Kind::List { count, item } = p.kind else {
        return Err(r.error(format!("`{}` is not a list", p.name)));
    };
    let n = r.value(count, "a list length")?;
    if n < 0.0 || n.fract() != 0.0 {
        return Err(r.error(format!("invalid list length {n}")));
    }
    let n = n as u64;
    if !r.can_hold(n, item) {
        return Err(r.error(format!(
            "a list of {n} indices runs past the end of the file"
        )));
    }
    out.clear();
    for _ in 0..n {
        let v = r.value(item, "a vertex index")?;
        let valid =
            v.fract() == 0.0 && ((v >= 0.0 && v < vertex_count as f64) || (strips && v == -1.0));
        if !valid {
            return Err(r.error(format!(
                "vertex index {v} is out of range (the file has {vertex_count} vertices)"
            )));
        }
        out.push(v as i64);
    }
    Ok(())
}

/// Appends the triangles of a strip list (with `-1` restarts), alternating the winding so
/// that every triangle keeps the orientation of the first. Returns how many triangles were
/// dropped for repeating an index (strip stitching).
fn strip_triangles(indices: &[i64], out: &mut Vec<[u32; 3]>) -> usize {
    let mut dropped = 0;
    for strip in indices.split(|&i| i < 0) {
        for (k, w) in strip.windows(3).enumerate() {
            let (a, b, c) = (w[0] as u32, w[1] as u32, w[2] as u32);
            if a == b || b == c || a == c {
                dropped += 1;
                continue;
            }
            out.push(if k % 2 == 0 { [a, b, c] } else { [b, a, c] });
        }
    }
    dropped
}

fn skip_property<R: Reader>(r: &mut R, p: &Property) -> Result<(), LoadError> {
    match p.kind {
        Kind::Scalar(t) => {
            r.value(t, &p.name)?;
        }
        Kind::List { count, item } => {
            let n = r.value(count, "a list length")?;
            if n < 0.0 || n.fract() != 0.0 {
                return Err(r.error(format!("invalid list length {n} in `{}`", p.name)));
            }
            let n = n as u64;
            if !r.can_hold(n, item) {
                return Err(r.error(format!("a list of {n} items runs past the end of the file")));
            }
            if !r.skip_fixed(n as usize, item.size(), &p.name)? {
                for _ in 0..n {
                    r.value(item, &p.name)?;
                }
            }
        }
    }
    Ok(())
}

fn skip_element<R: Reader>(r: &mut R, e: &Element) -> Result<(), LoadError> {
    if e.props.is_empty() {
        return Ok(()); // nothing to read, however many instances are declared
    }
    if e.props.iter().all(|p| matches!(p.kind, Kind::Scalar(_)))
        && r.skip_fixed(e.count, e.min_binary_size() as usize, &e.name)?
    {
        return Ok(());
    }
    for _ in 0..e.count {
        for p in &e.props {
            skip_property(r, p)?;
        }
    }
    Ok(())
}
