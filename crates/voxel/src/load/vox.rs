//! MagicaVoxel `.vox` reader (format 150/200, with the scene-graph extension).
//!
//! Hand-written rather than `dot_vox` because `dot_vox` 5 recurses once per nested chunk
//! (a small crafted file overflows the stack, which no error handling can catch), drops
//! scene-graph node ids (it assumes they equal the chunk order), and reports no byte
//! offsets. The test suite cross-checks this reader against `dot_vox` on the test
//! models.
//!
//! # Placement (what MagicaVoxel does)
//!
//! A model of size `s` has its pivot at `floor(s / 2)`; voxel `v` is the cube
//! `[v − pivot, v − pivot + 1]` in model space, which the instance's accumulated `nTRN`
//! transforms (frame 0: rotation byte `_r`, translation `_t`) rotate and translate. A
//! rotated unit cube is again a unit cube; its minimum corner is `R·q + t`, minus 1 on every
//! axis whose row of `R` is negative. Hidden nodes and hidden layers are skipped; of a
//! shape's several models (animation keyframes) the frame-0 one is used. A file without
//! a scene graph (like the shared `T-Rex.vox`, whose 8 models are animation frames) has
//! every model at its own origin, unrotated and un-pivoted, overlapping.
//!
//! Then every cube is converted from MagicaVoxel's Z-up to Y-up with the rotation
//! `(x, y, z) ↦ (x, z, −y)`: minimum corner `p ↦ (p.x, p.z, −p.y − 1)`. Voxels that land
//! on the same cell (overlapping instances or frames) are merged, the later one winning.

use std::collections::HashMap;
use std::path::Path;

use super::common::{MAX_VOXELS, srgb_u8_table};
use super::error::LoadError;
use crate::model::VoxelModel;

/// Most voxels per axis of a model: `XYZI` coordinates are bytes.
const MAX_MODEL_SIZE: u32 = 256;

/// Parses a `.vox` file held in memory. `only_model`: load just that model, in its own
/// coordinates (converted to Y-up), ignoring the scene graph.
pub(super) fn parse(
    bytes: &[u8],
    path: &Path,
    only_model: Option<usize>,
    warnings: &mut Vec<String>,
) -> Result<VoxelModel, LoadError> {
    let file = read_chunks(bytes, path, warnings)?;
    let palette = file.palette();
    let instances: Vec<Instance> = match only_model {
        Some(k) => {
            if k >= file.models.len() {
                return Err(LoadError::parse(
                    path,
                    format!(
                        "model {k} does not exist (the file has {} models)",
                        file.models.len()
                    ),
                ));
            }
            vec![Instance {
                model: k,
                transform: Transform::raw(),
            }]
        }
        None if file.nodes.is_empty() => (0..file.models.len())
            .map(|model| Instance {
                model,
                transform: Transform::raw(),
            })
            .collect(),
        None => file.instances(path, warnings)?,
    };
    let total: u64 = instances
        .iter()
        .map(|i| file.models[i.model].count as u64)
        .sum();
    if total > MAX_VOXELS as u64 {
        return Err(LoadError::too_large(
            path,
            "voxels",
            total,
            MAX_VOXELS as u64,
        ));
    }
    let mut out = VoxelModel::default();
    // Reserve for the common case only: `total` may be large for a small file whose scene
    // graph instances one model many times, and memory should grow with actual output.
    let reserve = (total as usize).min(1 << 22);
    out.voxels.reserve(reserve);
    out.colors.reserve(reserve);
    // Several instances may cover the same cells: merge them (one model alone cannot
    // overlap itself in a valid file, so skip the map's cost then).
    let mut seen: Option<HashMap<[i32; 3], usize>> = (instances.len() > 1).then(HashMap::new);
    for inst in &instances {
        let model = &file.models[inst.model];
        for v in model.voxels.chunks_exact(4) {
            let color_index = v[3];
            if color_index == 0 {
                continue; // index 0 is "empty" in every palette
            }
            let local = [v[0], v[1], v[2]].map(i64::from);
            let p = inst.transform.place(local, model.size).ok_or_else(|| {
                LoadError::at_offset(
                    path,
                    model.offset,
                    "a voxel's transformed position overflows i32",
                )
            })?;
            // Z-up → Y-up (`p[1]` is far from overflow: translations are bounded by 2^40).
            let y_up = [p[0], p[2], -p[1] - 1];
            let mut cell = [0i32; 3];
            for (c, v) in cell.iter_mut().zip(y_up) {
                *c = i32::try_from(v).map_err(|_| {
                    LoadError::at_offset(path, model.offset, "a voxel's position overflows i32")
                })?;
            }
            let color = palette[color_index as usize];
            match seen.as_mut().map(|m| m.entry(cell)) {
                Some(std::collections::hash_map::Entry::Occupied(e)) => {
                    out.colors[*e.get()] = color
                }
                Some(std::collections::hash_map::Entry::Vacant(e)) => {
                    e.insert(out.voxels.len());
                    out.voxels.push(cell);
                    out.colors.push(color);
                }
                None => {
                    out.voxels.push(cell);
                    out.colors.push(color);
                }
            }
        }
    }
    Ok(out)
}

struct ModelData<'a> {
    size: [u32; 3],
    /// `count` × (x, y, z, colour index).
    voxels: &'a [u8],
    count: usize,
    /// File offset of the `XYZI` chunk (for messages).
    offset: u64,
}

enum Node {
    Transform {
        child: i32,
        hidden: bool,
        layer: i32,
        transform: Transform,
    },
    Group {
        children: Vec<i32>,
    },
    Shape {
        model: i32,
    },
}

struct VoxFile<'a> {
    models: Vec<ModelData<'a>>,
    rgba: Option<&'a [u8]>,
    nodes: HashMap<i32, (Node, u64)>,
    hidden_layers: Vec<i32>,
}

impl VoxFile<'_> {
    /// Linear RGBA of every colour index.
    fn palette(&self) -> [[f32; 4]; 256] {
        let lin = srgb_u8_table();
        let mut out = [[0.0; 4]; 256];
        for (i, slot) in out.iter_mut().enumerate() {
            let rgba: [u8; 4] = match self.rgba {
                // The RGBA chunk's entry k is colour index k + 1.
                Some(chunk) if i > 0 => {
                    let k = (i - 1) * 4;
                    chunk
                        .get(k..k + 4)
                        .map_or([0; 4], |s| [s[0], s[1], s[2], s[3]])
                }
                Some(_) => [0; 4],
                None => DEFAULT_PALETTE[i].to_le_bytes(),
            };
            *slot = [
                lin[rgba[0] as usize],
                lin[rgba[1] as usize],
                lin[rgba[2] as usize],
                rgba[3] as f32 / 255.0,
            ];
        }
        out
    }

    /// Walks the scene graph from node 0 and lists every visible model instance.
    fn instances(
        &self,
        path: &Path,
        warnings: &mut Vec<String>,
    ) -> Result<Vec<Instance>, LoadError> {
        let mut out = Vec::new();
        if !self.nodes.contains_key(&0) {
            return Err(LoadError::parse(path, "scene graph has no root node 0"));
        }
        // Each node is expanded once: this ends cycles and bounds the work by the file size.
        let mut expanded = std::collections::HashSet::new();
        let mut stack = vec![(0i32, Transform::identity())];
        let mut revisits = 0usize;
        while let Some((id, parent)) = stack.pop() {
            let Some((node, offset)) = self.nodes.get(&id) else {
                return Err(LoadError::parse(
                    path,
                    format!("scene graph references missing node {id}"),
                ));
            };
            if !expanded.insert(id) {
                revisits += 1;
                continue;
            }
            match node {
                Node::Transform {
                    child,
                    hidden,
                    layer,
                    transform,
                } => {
                    if *hidden || self.hidden_layers.contains(layer) {
                        continue;
                    }
                    let world = parent.then(transform).ok_or_else(|| {
                        LoadError::at_offset(path, *offset, "accumulated translation overflows")
                    })?;
                    stack.push((*child, world));
                }
                Node::Group { children } => {
                    stack.extend(children.iter().rev().map(|&c| (c, parent)));
                }
                Node::Shape { model } => {
                    let index = usize::try_from(*model)
                        .ok()
                        .filter(|&m| m < self.models.len())
                        .ok_or_else(|| {
                            LoadError::at_offset(
                                path,
                                *offset,
                                format!(
                                    "shape node {id} references model {model}, but the file has {}",
                                    self.models.len()
                                ),
                            )
                        })?;
                    out.push(Instance {
                        model: index,
                        transform: parent,
                    });
                }
            }
        }
        if revisits > 0 {
            warnings.push(format!(
                "{}: {revisits} scene-graph reference(s) to an already expanded node were ignored",
                path.display()
            ));
        }
        Ok(out)
    }
}

struct Instance {
    model: usize,
    transform: Transform,
}

/// A MagicaVoxel rigid transform: a signed permutation matrix and an integer translation.
/// `pivot`: whether the model pivot `floor(size / 2)` is subtracted first (scene-graph
/// instances) or not (raw models at their own origin).
#[derive(Clone, Copy)]
struct Transform {
    /// Row i has its non-zero entry in column `col[i]`, with sign `sign[i]`.
    col: [usize; 3],
    sign: [i64; 3],
    t: [i64; 3],
    pivot: bool,
}

impl Transform {
    fn identity() -> Self {
        Transform {
            col: [0, 1, 2],
            sign: [1; 3],
            t: [0; 3],
            pivot: true,
        }
    }

    fn raw() -> Self {
        Transform {
            pivot: false,
            ..Transform::identity()
        }
    }

    /// `self ∘ local`: apply `local` first.
    fn then(&self, local: &Transform) -> Option<Transform> {
        let mut out = *self;
        for i in 0..3 {
            let j = self.col[i];
            out.col[i] = local.col[j];
            out.sign[i] = self.sign[i] * local.sign[j];
            out.t[i] = self.sign[i]
                .checked_mul(local.t[j])?
                .checked_add(self.t[i])?;
            // Keep translations where sums of them and of voxel offsets stay far from
            // overflow (MagicaVoxel scenes are a few thousand voxels wide).
            if out.t[i].abs() > 1 << 40 {
                return None;
            }
        }
        Some(out)
    }

    /// Minimum corner of the placed unit cube of local voxel `v` (model of `size`).
    fn place(&self, v: [i64; 3], size: [u32; 3]) -> Option<[i64; 3]> {
        let q = if self.pivot {
            [0, 1, 2].map(|k| v[k] - i64::from(size[k] / 2))
        } else {
            v
        };
        let mut p = [0i64; 3];
        for i in 0..3 {
            let rotated = self.sign[i] * q[self.col[i]];
            // A negated axis maps [q, q + 1] to [−q − 1, −q].
            let corner = if self.sign[i] < 0 {
                rotated - 1
            } else {
                rotated
            };
            p[i] = corner.checked_add(self.t[i])?;
        }
        Some(p)
    }

    /// Decodes the `_r` rotation byte (row-major signed permutation).
    fn from_rotation_byte(r: u8) -> Option<Transform> {
        let c0 = (r & 3) as usize;
        let c1 = ((r >> 2) & 3) as usize;
        if c0 > 2 || c1 > 2 || c0 == c1 {
            return None;
        }
        let c2 = 3 - c0 - c1;
        let sign = |bit: u8| if r & (1 << bit) != 0 { -1 } else { 1 };
        Some(Transform {
            col: [c0, c1, c2],
            sign: [sign(4), sign(5), sign(6)],
            t: [0; 3],
            pivot: true,
        })
    }
}

/// A bounds-checked little-endian cursor over one chunk's content.
struct Cursor<'a, 'p> {
    data: &'a [u8],
    pos: usize,
    base: u64,
    path: &'p Path,
}

impl<'a> Cursor<'a, '_> {
    fn err(&self, message: impl Into<String>) -> LoadError {
        LoadError::at_offset(self.path, self.base + self.pos as u64, message)
    }

    fn bytes(&mut self, n: usize, what: &str) -> Result<&'a [u8], LoadError> {
        let end = self.pos.checked_add(n).filter(|&e| e <= self.data.len());
        match end {
            Some(end) => {
                let s = &self.data[self.pos..end];
                self.pos = end;
                Ok(s)
            }
            None => Err(self.err(format!("chunk ends inside {what}"))),
        }
    }

    fn i32(&mut self, what: &str) -> Result<i32, LoadError> {
        let b = self.bytes(4, what)?;
        Ok(i32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    }

    /// A count of items of at least `min_item_bytes` each, checked against what is left.
    fn count(&mut self, min_item_bytes: usize, what: &str) -> Result<usize, LoadError> {
        let at = self.pos;
        let n = self.i32(what)?;
        let left = self.data.len() - self.pos;
        match usize::try_from(n) {
            Ok(n) if n.checked_mul(min_item_bytes).is_some_and(|b| b <= left) => Ok(n),
            _ => Err(LoadError::at_offset(
                self.path,
                self.base + at as u64,
                format!("{what} {n} does not fit in the {left} bytes left in the chunk"),
            )),
        }
    }

    fn string(&mut self, what: &str) -> Result<String, LoadError> {
        let n = self.count(1, what)?;
        Ok(String::from_utf8_lossy(self.bytes(n, what)?).into_owned())
    }

    fn dict(&mut self) -> Result<Vec<(String, String)>, LoadError> {
        let n = self.count(8, "dictionary size")?;
        let mut out = Vec::with_capacity(n);
        for _ in 0..n {
            let key = self.string("dictionary key")?;
            let value = self.string("dictionary value")?;
            out.push((key, value));
        }
        Ok(out)
    }
}

fn lookup<'d>(dict: &'d [(String, String)], key: &str) -> Option<&'d str> {
    dict.iter().find(|(k, _)| k == key).map(|(_, v)| v.as_str())
}

/// Reads the chunk list of the `MAIN` chunk (iteratively: no recursion on nesting).
fn read_chunks<'a>(
    bytes: &'a [u8],
    path: &Path,
    warnings: &mut Vec<String>,
) -> Result<VoxFile<'a>, LoadError> {
    let (mut at, end) = main_children(bytes, path, warnings)?;
    let mut file = VoxFile {
        models: Vec::new(),
        rgba: None,
        nodes: HashMap::new(),
        hidden_layers: Vec::new(),
    };
    let mut pending_size: Option<[u32; 3]> = None;
    while at < end {
        let chunk = chunk_header(bytes, at, end, path)?;
        let mut c = Cursor {
            data: &bytes[chunk.content_start..chunk.content_end],
            pos: 0,
            base: chunk.content_start as u64,
            path,
        };
        read_chunk(&mut file, &mut pending_size, &chunk.id, &mut c, at)?;
        at = chunk.chunk_end;
    }
    if pending_size.is_some() {
        warnings.push(format!(
            "{}: a SIZE chunk has no XYZI chunk",
            path.display()
        ));
    }
    Ok(file)
}

/// Checks the file header (magic, version, `MAIN`) and returns the byte range
/// `[start, end)` of `MAIN`'s child chunks.
fn main_children(
    bytes: &[u8],
    path: &Path,
    warnings: &mut Vec<String>,
) -> Result<(usize, usize), LoadError> {
    if !bytes.starts_with(b"VOX ") {
        return Err(LoadError::at_offset(
            path,
            0,
            "not a MagicaVoxel file (no `VOX ` magic)",
        ));
    }
    let u32_at = |at: usize| -> Option<u32> {
        let b = bytes.get(at..at.checked_add(4)?)?;
        Some(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    };
    let version = u32_at(4).ok_or_else(|| LoadError::at_offset(path, 4, "truncated header"))?;
    if version != 150 && version != 200 {
        warnings.push(format!(
            "{}: unknown .vox version {version}; reading it as 150",
            path.display()
        ));
    }
    if bytes.get(8..12) != Some(b"MAIN") {
        return Err(LoadError::at_offset(path, 8, "expected the MAIN chunk"));
    }
    let (Some(content), Some(children)) = (u32_at(12), u32_at(16)) else {
        return Err(LoadError::at_offset(
            path,
            12,
            "truncated MAIN chunk header",
        ));
    };
    let start = 20usize
        .checked_add(content as usize)
        .filter(|&s| s <= bytes.len());
    let end = start
        .and_then(|s| s.checked_add(children as usize))
        .filter(|&e| e <= bytes.len());
    let (Some(start), Some(end)) = (start, end) else {
        return Err(LoadError::at_offset(
            path,
            12,
            format!(
                "MAIN chunk declares {content} + {children} bytes but the file has {}",
                bytes.len()
            ),
        ));
    };
    Ok((start, end))
}

/// A child chunk's header: its id and the byte offsets of its content and end.
struct ChunkHeader {
    id: [u8; 4],
    content_start: usize,
    content_end: usize,
    /// End of the chunk including its own children.
    chunk_end: usize,
}

/// Reads the header of the chunk at `at`, which with its content must end by `end`.
fn chunk_header(
    bytes: &[u8],
    at: usize,
    end: usize,
    path: &Path,
) -> Result<ChunkHeader, LoadError> {
    let header = bytes.get(at..at + 12).filter(|_| at + 12 <= end);
    let Some(header) = header else {
        return Err(LoadError::at_offset(
            path,
            at as u64,
            "truncated chunk header",
        ));
    };
    let id = [header[0], header[1], header[2], header[3]];
    let n = u32::from_le_bytes([header[4], header[5], header[6], header[7]]) as usize;
    let m = u32::from_le_bytes([header[8], header[9], header[10], header[11]]) as usize;
    let content_start = at + 12;
    let content_end = content_start.checked_add(n).filter(|&e| e <= end);
    let chunk_end = content_end
        .and_then(|e| e.checked_add(m))
        .filter(|&e| e <= end);
    let (Some(content_end), Some(chunk_end)) = (content_end, chunk_end) else {
        return Err(LoadError::at_offset(
            path,
            at as u64,
            format!(
                "chunk {:?} of {n} + {m} bytes runs past the end of MAIN",
                String::from_utf8_lossy(&id)
            ),
        ));
    };
    Ok(ChunkHeader {
        id,
        content_start,
        content_end,
        chunk_end,
    })
}

/// Reads the content of one chunk with id `id` at file offset `at` into `file`.
fn read_chunk<'a>(
    file: &mut VoxFile<'a>,
    pending_size: &mut Option<[u32; 3]>,
    id: &[u8; 4],
    c: &mut Cursor<'a, '_>,
    at: usize,
) -> Result<(), LoadError> {
    match id {
        b"SIZE" => *pending_size = Some(read_size(c)?),
        b"XYZI" => {
            let size = pending_size
                .take()
                .ok_or_else(|| c.err("XYZI chunk without a preceding SIZE chunk"))?;
            let count = c.count(4, "voxel count")?;
            let voxels = c.bytes(count * 4, "voxels")?;
            file.models.push(ModelData {
                size,
                voxels,
                count,
                offset: at as u64,
            });
        }
        b"RGBA" => file.rgba = Some(c.bytes(256 * 4, "the palette")?),
        b"nTRN" => read_transform_node(file, c, at)?,
        b"nGRP" => {
            let id = c.i32("node id")?;
            let _attrs = c.dict()?;
            let n = c.count(4, "child count")?;
            let mut children = Vec::with_capacity(n);
            for _ in 0..n {
                children.push(c.i32("child id")?);
            }
            insert_node(file, id, Node::Group { children }, at, c.path)?;
        }
        b"nSHP" => read_shape_node(file, c, at)?,
        b"LAYR" => {
            let id = c.i32("layer id")?;
            let attrs = c.dict()?;
            if lookup(&attrs, "_hidden") == Some("1") {
                file.hidden_layers.push(id);
            }
        }
        _ => {} // PACK, MATL, MATT, IMAP, rOBJ, rCAM, NOTE, ...: not needed
    }
    Ok(())
}

/// Reads a `SIZE` chunk: a model's voxels per axis, each at most [`MAX_MODEL_SIZE`].
fn read_size(c: &mut Cursor<'_, '_>) -> Result<[u32; 3], LoadError> {
    let size = [c.i32("SIZE")?, c.i32("SIZE")?, c.i32("SIZE")?];
    let mut dims = [0u32; 3];
    for (d, s) in dims.iter_mut().zip(size) {
        *d = u32::try_from(s).map_err(|_| c.err(format!("negative model size {s}")))?;
        if *d > MAX_MODEL_SIZE {
            return Err(LoadError::too_large(
                c.path,
                "voxels along a model axis (SIZE)",
                u64::from(*d),
                u64::from(MAX_MODEL_SIZE),
            ));
        }
    }
    Ok(dims)
}

/// Reads an `nTRN` chunk (at file offset `at`) into a transform node of frame 0.
fn read_transform_node(
    file: &mut VoxFile<'_>,
    c: &mut Cursor<'_, '_>,
    at: usize,
) -> Result<(), LoadError> {
    let id = c.i32("node id")?;
    let attrs = c.dict()?;
    let child = c.i32("child id")?;
    let _reserved = c.i32("reserved id")?;
    let layer = c.i32("layer id")?;
    let frames = c.count(4, "frame count")?;
    let mut transform = Transform::identity();
    for f in 0..frames {
        let dict = c.dict()?;
        let frame_index = lookup(&dict, "_f")
            .and_then(|s| s.trim().parse::<u32>().ok())
            .unwrap_or(0);
        // Frame 0 (the static pose): the first frame, or the one marked `_f 0`.
        if f > 0 && frame_index != 0 {
            continue;
        }
        transform = frame_transform(&dict)
            .ok_or_else(|| c.err("malformed _r or _t in a transform frame"))?;
        if frame_index == 0 {
            break;
        }
    }
    let hidden = lookup(&attrs, "_hidden") == Some("1");
    insert_node(
        file,
        id,
        Node::Transform {
            child,
            hidden,
            layer,
            transform,
        },
        at,
        c.path,
    )
}

/// Reads an `nSHP` chunk (at file offset `at`) into a shape node of its frame-0 model.
fn read_shape_node(
    file: &mut VoxFile<'_>,
    c: &mut Cursor<'_, '_>,
    at: usize,
) -> Result<(), LoadError> {
    let id = c.i32("node id")?;
    let _attrs = c.dict()?;
    let n = c.count(8, "model count")?;
    let mut chosen = None;
    for k in 0..n {
        let model = c.i32("model id")?;
        let dict = c.dict()?;
        let frame = lookup(&dict, "_f")
            .and_then(|s| s.trim().parse::<u32>().ok())
            .unwrap_or(0);
        if k == 0 || frame == 0 && chosen.is_none_or(|(f, _)| f != 0) {
            chosen = Some((frame, model));
        }
    }
    let (_, model) = chosen.ok_or_else(|| c.err("shape node with no model"))?;
    insert_node(file, id, Node::Shape { model }, at, c.path)
}

fn insert_node(
    file: &mut VoxFile<'_>,
    id: i32,
    node: Node,
    at: usize,
    path: &Path,
) -> Result<(), LoadError> {
    if file.nodes.insert(id, (node, at as u64)).is_some() {
        return Err(LoadError::at_offset(
            path,
            at as u64,
            format!("duplicate scene-graph node id {id}"),
        ));
    }
    Ok(())
}

/// The transform of one `nTRN` frame dictionary (`_r` rotation byte, `_t` "x y z").
fn frame_transform(dict: &[(String, String)]) -> Option<Transform> {
    let mut t = match lookup(dict, "_r") {
        Some(r) => Transform::from_rotation_byte(r.trim().parse::<u8>().ok()?)?,
        None => Transform::identity(),
    };
    if let Some(s) = lookup(dict, "_t") {
        let mut it = s.split_ascii_whitespace().map(|v| v.parse::<i32>());
        for slot in &mut t.t {
            *slot = i64::from(it.next()?.ok()?);
        }
    }
    Some(t)
}

/// The default palette of the `.vox` specification, `0xAABBGGRR`, indexed by colour index
/// (index 0 is unused). Used when a file has no `RGBA` chunk.
#[rustfmt::skip]
const DEFAULT_PALETTE: [u32; 256] = [
    0x00000000, 0xFFFFFFFF, 0xFFCCFFFF, 0xFF99FFFF, 0xFF66FFFF, 0xFF33FFFF, 0xFF00FFFF, 0xFFFFCCFF,
    0xFFCCCCFF, 0xFF99CCFF, 0xFF66CCFF, 0xFF33CCFF, 0xFF00CCFF, 0xFFFF99FF, 0xFFCC99FF, 0xFF9999FF,
    0xFF6699FF, 0xFF3399FF, 0xFF0099FF, 0xFFFF66FF, 0xFFCC66FF, 0xFF9966FF, 0xFF6666FF, 0xFF3366FF,
    0xFF0066FF, 0xFFFF33FF, 0xFFCC33FF, 0xFF9933FF, 0xFF6633FF, 0xFF3333FF, 0xFF0033FF, 0xFFFF00FF,
    0xFFCC00FF, 0xFF9900FF, 0xFF6600FF, 0xFF3300FF, 0xFF0000FF, 0xFFFFFFCC, 0xFFCCFFCC, 0xFF99FFCC,
    0xFF66FFCC, 0xFF33FFCC, 0xFF00FFCC, 0xFFFFCCCC, 0xFFCCCCCC, 0xFF99CCCC, 0xFF66CCCC, 0xFF33CCCC,
    0xFF00CCCC, 0xFFFF99CC, 0xFFCC99CC, 0xFF9999CC, 0xFF6699CC, 0xFF3399CC, 0xFF0099CC, 0xFFFF66CC,
    0xFFCC66CC, 0xFF9966CC, 0xFF6666CC, 0xFF3366CC, 0xFF0066CC, 0xFFFF33CC, 0xFFCC33CC, 0xFF9933CC,
    0xFF6633CC, 0xFF3333CC, 0xFF0033CC, 0xFFFF00CC, 0xFFCC00CC, 0xFF9900CC, 0xFF6600CC, 0xFF3300CC,
    0xFF0000CC, 0xFFFFFF99, 0xFFCCFF99, 0xFF99FF99, 0xFF66FF99, 0xFF33FF99, 0xFF00FF99, 0xFFFFCC99,
    0xFFCCCC99, 0xFF99CC99, 0xFF66CC99, 0xFF33CC99, 0xFF00CC99, 0xFFFF9999, 0xFFCC9999, 0xFF999999,
    0xFF669999, 0xFF339999, 0xFF009999, 0xFFFF6699, 0xFFCC6699, 0xFF996699, 0xFF666699, 0xFF336699,
    0xFF006699, 0xFFFF3399, 0xFFCC3399, 0xFF993399, 0xFF663399, 0xFF333399, 0xFF003399, 0xFFFF0099,
    0xFFCC0099, 0xFF990099, 0xFF660099, 0xFF330099, 0xFF000099, 0xFFFFFF66, 0xFFCCFF66, 0xFF99FF66,
    0xFF66FF66, 0xFF33FF66, 0xFF00FF66, 0xFFFFCC66, 0xFFCCCC66, 0xFF99CC66, 0xFF66CC66, 0xFF33CC66,
    0xFF00CC66, 0xFFFF9966, 0xFFCC9966, 0xFF999966, 0xFF669966, 0xFF339966, 0xFF009966, 0xFFFF6666,
    0xFFCC6666, 0xFF996666, 0xFF666666, 0xFF336666, 0xFF006666, 0xFFFF3366, 0xFFCC3366, 0xFF993366,
    0xFF663366, 0xFF333366, 0xFF003366, 0xFFFF0066, 0xFFCC0066, 0xFF990066, 0xFF660066, 0xFF330066,
    0xFF000066, 0xFFFFFF33, 0xFFCCFF33, 0xFF99FF33, 0xFF66FF33, 0xFF33FF33, 0xFF00FF33, 0xFFFFCC33,
    0xFFCCCC33, 0xFF99CC33, 0xFF66CC33, 0xFF33CC33, 0xFF00CC33, 0xFFFF9933, 0xFFCC9933, 0xFF999933,
    0xFF669933, 0xFF339933, 0xFF009933, 0xFFFF6633, 0xFFCC6633, 0xFF996633, 0xFF666633, 0xFF336633,
    0xFF006633, 0xFFFF3333, 0xFFCC3333, 0xFF993333, 0xFF663333, 0xFF333333, 0xFF003333, 0xFFFF0033,
    0xFFCC0033, 0xFF990033, 0xFF660033, 0xFF330033, 0xFF000033, 0xFFFFFF00, 0xFFCCFF00, 0xFF99FF00,
    0xFF66FF00, 0xFF33FF00, 0xFF00FF00, 0xFFFFCC00, 0xFFCCCC00, 0xFF99CC00, 0xFF66CC00, 0xFF33CC00,
    0xFF00CC00, 0xFFFF9900, 0xFFCC9900, 0xFF999900, 0xFF669900, 0xFF339900, 0xFF009900, 0xFFFF6600,
    0xFFCC6600, 0xFF996600, 0xFF666600, 0xFF336600, 0xFF006600, 0xFFFF3300, 0xFFCC3300, 0xFF993300,
    0xFF663300, 0xFF333300, 0xFF003300, 0xFFFF0000, 0xFFCC0000, 0xFF990000, 0xFF660000, 0xFF330000,
    0xFF0000EE, 0xFF0000DD, 0xFF0000BB, 0xFF0000AA, 0xFF000088, 0xFF000077, 0xFF000055, 0xFF000044,
    0xFF000022, 0xFF000011, 0xFF00EE00, 0xFF00DD00, 0xFF00BB00, 0xFF00AA00, 0xFF008800, 0xFF007700,
    0xFF005500, 0xFF004400, 0xFF002200, 0xFF001100, 0xFFEE0000, 0xFFDD0000, 0xFFBB0000, 0xFFAA0000,
    0xFF880000, 0xFF770000, 0xFF550000, 0xFF440000, 0xFF220000, 0xFF110000, 0xFFEEEEEE, 0xFFDDDDDD,
    0xFFBBBBBB, 0xFFAAAAAA, 0xFF888888, 0xFF777777, 0xFF555555, 0xFF444444, 0xFF222222, 0xFF111111,
];
