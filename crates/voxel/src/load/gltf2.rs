//! glTF 2.0 reader (`.gltf` with external or data-URI buffers, and `.glb`).
//!
//! The `gltf` crate deserialises the JSON document (its validation pass can panic, see
//! `parse_document`); every index into it and everything that touches binary data is
//! checked here: the GLB container, buffer URIs
//! (base64 data URIs and relative files), accessors (any component type, normalised or
//! not, strided views, sparse storage) and embedded images. `gltf::import` is not used
//! because its binary paths can panic on malformed input (GLB header length underflow,
//! unchecked buffer-view slicing for images, `unwrap` on percent-decoded URIs).
//!
//! Loaded: the default scene (or, without one, every scene; without scenes, every root
//! node), every mesh instance with its node's world matrix applied (normals with the
//! inverse transpose, winding flipped under mirroring transforms), primitives in
//! `TRIANGLES`, `TRIANGLE_STRIP` and `TRIANGLE_FAN` modes (points and lines are skipped with
//! a warning), `POSITION`, `NORMAL`, `TEXCOORD_0`, `COLOR_0`, and each material's
//! `baseColorFactor` and base colour texture. Skins and morph targets are ignored (the bind
//! pose is loaded).

use std::collections::{HashMap, HashSet};
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};
use std::rc::Rc;

use glam::{Mat3, Mat4, Quat, Vec2, Vec3};
use gltf::json;
use gltf::json::accessor::{ComponentType, Type};
use gltf::json::mesh::{Mode, Semantic};
use gltf::json::validation::Checked;

use super::{LoadError, MAX_TRIANGLES, MAX_VERTICES, decode_texture, read_file};
use crate::model::{Material, Mesh, Texture};

const GLB_MAGIC: &[u8; 4] = b"glTF";
const CHUNK_JSON: u32 = 0x4E4F_534A;
const CHUNK_BIN: u32 = 0x004E_4942;

/// Parses a glTF or GLB file held in memory.
pub(super) fn parse(
    bytes: &[u8],
    path: &Path,
    base_dir: Option<&Path>,
    warnings: &mut Vec<String>,
) -> Result<Mesh, LoadError> {
    let is_glb = bytes.starts_with(GLB_MAGIC);
    let (json_bytes, json_offset, bin) = if is_glb {
        split_glb(bytes, path)?
    } else {
        (bytes, 0, None)
    };
    let root = parse_document(json_bytes, json_offset, is_glb, path)?;
    let buffers = load_buffers(&root, bin, path, base_dir)?;
    // Accessors without a buffer view are zero-filled and cost no bytes in the file: bound
    // them by the file size so that a tiny file cannot request gigabytes.
    let zero_fill_limit = (1u64 << 16).saturating_add((bytes.len() as u64).saturating_mul(16));
    let mut b = Builder {
        root: &root,
        buffers: &buffers,
        path,
        base_dir,
        zero_fill_limit,
        mesh: Mesh::default(),
        normals_missing: false,
        uvs_present: false,
        colors_present: false,
        materials: HashMap::new(),
        textures: HashMap::new(),
        accessor_cache: HashMap::new(),
        warnings,
    };
    b.load_scenes()?;
    b.finish()
}

/// A GLB container's parts: the JSON chunk, its file offset, and the BIN chunk if any.
type GlbParts<'a> = (&'a [u8], u64, Option<&'a [u8]>);

/// Splits a GLB container into its JSON chunk (with its file offset) and BIN chunk.
fn split_glb<'a>(bytes: &'a [u8], path: &Path) -> Result<GlbParts<'a>, LoadError> {
    let u32_at = |at: usize| -> Option<u32> {
        let b = bytes.get(at..at.checked_add(4)?)?;
        Some(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    };
    let version = u32_at(4).ok_or_else(|| LoadError::at_offset(path, 4, "truncated GLB header"))?;
    if version != 2 {
        return Err(LoadError::at_offset(
            path,
            4,
            format!("GLB version {version} is not supported (only 2)"),
        ));
    }
    let length =
        u32_at(8).ok_or_else(|| LoadError::at_offset(path, 8, "truncated GLB header"))? as usize;
    if length < 12 || length > bytes.len() {
        return Err(LoadError::at_offset(
            path,
            8,
            format!(
                "GLB header declares {length} bytes but the file has {}",
                bytes.len()
            ),
        ));
    }
    let data = &bytes[..length];
    let mut json = None;
    let mut bin = None;
    let mut at = 12usize;
    while at < data.len() {
        let (Some(len), Some(kind)) = (u32_at(at), u32_at(at + 4)) else {
            return Err(LoadError::at_offset(
                path,
                at as u64,
                "truncated GLB chunk header",
            ));
        };
        let start = at + 8;
        let end = start
            .checked_add(len as usize)
            .filter(|&e| e <= data.len())
            .ok_or_else(|| {
                LoadError::at_offset(
                    path,
                    at as u64,
                    format!("GLB chunk of {len} bytes runs past the end of the file"),
                )
            })?;
        let chunk = &data[start..end];
        match kind {
            CHUNK_JSON if json.is_none() && at == 12 => json = Some((chunk, start as u64)),
            CHUNK_BIN if json.is_some() && bin.is_none() => bin = Some(chunk),
            CHUNK_JSON | CHUNK_BIN => {
                return Err(LoadError::at_offset(
                    path,
                    at as u64,
                    "unexpected or repeated GLB chunk",
                ));
            }
            _ => {} // unknown chunk types must be ignored
        }
        // Chunks are 4-byte aligned; `end` is at most `u32::MAX + 20`, so no overflow.
        at = end.next_multiple_of(4);
    }
    let (json, offset) =
        json.ok_or_else(|| LoadError::at_offset(path, 12, "GLB file has no JSON chunk first"))?;
    Ok((json, offset, bin))
}

/// Deserialises the JSON document (without the `gltf` crate's validation pass).
fn parse_document(
    json_bytes: &[u8],
    json_offset: u64,
    is_glb: bool,
    path: &Path,
) -> Result<json::Root, LoadError> {
    // The `gltf` crate has had panics on malformed input in the past; a panic here must
    // become an error, never take the caller down. This is a last line of defence only:
    // all binary data is handled by our own checked code below.
    let result = catch_unwind(AssertUnwindSafe(|| -> Result<json::Root, LoadError> {
        let root: json::Root = json::deserialize::from_slice(json_bytes).map_err(|e| {
            if is_glb {
                LoadError::at_offset(
                    path,
                    json_offset,
                    format!(
                        "invalid glTF JSON chunk (line {}, column {}): {e}",
                        e.line(),
                        e.column()
                    ),
                )
            } else {
                LoadError::at_line(path, e.line().max(1), format!("invalid glTF JSON: {e}"))
            }
        })?;
        // The crate's validation pass is deliberately not run: gltf-json 1.4.1 indexes
        // `accessors[...]` unchecked in its primitive hook and panics on an out-of-range
        // POSITION index (found by fuzzing). Every index this module follows is checked
        // where it is used instead, with `get`.
        Ok(root)
    }));
    result.unwrap_or_else(|_| {
        Err(LoadError::parse(
            path,
            "the glTF JSON parser panicked on this file",
        ))
    })
}

/// Loads every buffer: the GLB BIN chunk, a base64 data URI, or a file beside the model.
fn load_buffers(
    root: &json::Root,
    mut bin: Option<&[u8]>,
    path: &Path,
    base_dir: Option<&Path>,
) -> Result<Vec<Vec<u8>>, LoadError> {
    let mut out = Vec::with_capacity(root.buffers.len().min(1024));
    for (i, buffer) in root.buffers.iter().enumerate() {
        let declared = buffer.byte_length.0;
        let mut data = match &buffer.uri {
            None => bin
                .take()
                .ok_or_else(|| {
                    LoadError::parse(
                        path,
                        format!("buffer {i} has no uri and there is no GLB BIN chunk"),
                    )
                })?
                .to_vec(),
            Some(uri) => read_uri(uri, path, base_dir)
                .map_err(|e| e.in_context(path, &format!("buffer {i}")))?,
        };
        if (data.len() as u64) < declared {
            return Err(LoadError::parse(
                path,
                format!(
                    "buffer {i} declares {declared} bytes but holds only {}",
                    data.len()
                ),
            ));
        }
        data.truncate(declared as usize);
        out.push(data);
    }
    Ok(out)
}

/// Why a URI could not be read.
enum UriError {
    Load(LoadError),
    Message(String),
}

impl UriError {
    fn in_context(self, path: &Path, what: &str) -> LoadError {
        match self {
            UriError::Load(e) => e,
            UriError::Message(m) => LoadError::parse(path, format!("{what}: {m}")),
        }
    }

    fn describe(self) -> String {
        match self {
            UriError::Load(e) => e.to_string(),
            UriError::Message(m) => m,
        }
    }
}

/// The bytes a glTF URI points at.
fn read_uri(uri: &str, path: &Path, base_dir: Option<&Path>) -> Result<Vec<u8>, UriError> {
    if let Some(rest) = uri.strip_prefix("data:") {
        let Some((_, payload)) = rest.split_once(";base64,") else {
            return Err(UriError::Message(
                "only base64 data URIs are supported".into(),
            ));
        };
        return base64_decode(payload).map_err(|at| {
            UriError::Message(format!("invalid base64 at character {at} of the data URI"))
        });
    }
    if uri.contains("://") {
        return Err(UriError::Message(format!(
            "URI scheme of {uri:?} is not supported (only relative files)"
        )));
    }
    let Some(dir) = base_dir else {
        return Err(UriError::Message(format!(
            "external file {uri:?} cannot be opened (no base folder given for {})",
            path.display()
        )));
    };
    let relative =
        percent_decode(uri).ok_or_else(|| UriError::Message(format!("malformed URI {uri:?}")))?;
    let file: PathBuf = dir.join(relative);
    read_file(&file).map_err(UriError::Load)
}

/// Decodes `%XX` escapes (URIs in glTF are URI-encoded); `None` if malformed or not UTF-8.
fn percent_decode(s: &str) -> Option<String> {
    let bytes = s.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' {
            let hex = std::str::from_utf8(bytes.get(i + 1..i + 3)?).ok()?;
            out.push(u8::from_str_radix(hex, 16).ok()?);
            i += 3;
        } else {
            out.push(bytes[i]);
            i += 1;
        }
    }
    String::from_utf8(out).ok()
}

/// Standard base64 (padding optional); on error, the index of the offending character.
fn base64_decode(s: &str) -> Result<Vec<u8>, usize> {
    fn sextet(c: u8) -> Option<u32> {
        Some(match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' | b'-' => 62,
            b'/' | b'_' => 63,
            _ => return None,
        } as u32)
    }
    let bytes = s.trim_end().as_bytes();
    let unpadded = bytes
        .strip_suffix(b"==")
        .or_else(|| bytes.strip_suffix(b"="))
        .unwrap_or(bytes);
    if unpadded.len() % 4 == 1 {
        return Err(unpadded.len().saturating_sub(1));
    }
    let mut out = Vec::with_capacity(unpadded.len() / 4 * 3 + 2);
    for (chunk_index, chunk) in unpadded.chunks(4).enumerate() {
        let mut acc = 0u32;
        for (k, &c) in chunk.iter().enumerate() {
            acc = (acc << 6) | sextet(c).ok_or(chunk_index * 4 + k)?;
        }
        match chunk.len() {
            4 => out.extend_from_slice(&[(acc >> 16) as u8, (acc >> 8) as u8, acc as u8]),
            3 => out.extend_from_slice(&[(acc >> 10) as u8, (acc >> 2) as u8]),
            2 => out.push((acc >> 4) as u8),
            _ => {}
        }
    }
    Ok(out)
}

/// Accessor values widened to `f64` (which holds every glTF component type exactly).
struct Values {
    data: Vec<f64>,
    components: usize,
    count: usize,
}

impl Values {
    fn get(&self, i: usize, c: usize) -> f64 {
        self.data
            .get(i * self.components + c)
            .copied()
            .unwrap_or(0.0)
    }
}

struct Builder<'a> {
    root: &'a json::Root,
    buffers: &'a [Vec<u8>],
    path: &'a Path,
    base_dir: Option<&'a Path>,
    zero_fill_limit: u64,
    mesh: Mesh,
    /// Some primitive had no normals: all normals are dropped at the end.
    normals_missing: bool,
    uvs_present: bool,
    colors_present: bool,
    /// glTF material index (`None`: the default material) → index in `mesh.materials`.
    materials: HashMap<Option<usize>, u32>,
    /// Decoded accessors by index.
    accessor_cache: HashMap<usize, Rc<Values>>,
    /// Decoded base colour textures per glTF image index (`None`: failed, warned once).
    textures: HashMap<usize, Option<Texture>>,
    warnings: &'a mut Vec<String>,
}

impl Builder<'_> {
    fn err(&self, message: String) -> LoadError {
        LoadError::parse(self.path, message)
    }

    fn warn(&mut self, message: String) {
        self.warnings
            .push(format!("{}: {message}", self.path.display()));
    }

    fn load_scenes(&mut self) -> Result<(), LoadError> {
        let root = self.root;
        let roots: Vec<usize> = match root.scene {
            Some(s) => root
                .scenes
                .get(s.value())
                .ok_or_else(|| self.err(format!("default scene {} does not exist", s.value())))?
                .nodes
                .iter()
                .map(|n| n.value())
                .collect(),
            None if !root.scenes.is_empty() => root
                .scenes
                .iter()
                .flat_map(|s| s.nodes.iter().map(|n| n.value()))
                .collect(),
            None => {
                let children: HashSet<usize> = root
                    .nodes
                    .iter()
                    .flat_map(|n| n.children.iter().flatten().map(|c| c.value()))
                    .collect();
                (0..root.nodes.len())
                    .filter(|i| !children.contains(i))
                    .collect()
            }
        };
        // Each node is visited once: this ends cycles and refuses nodes with two parents
        // (which the specification forbids) without exponential blow-up.
        let mut visited = vec![false; root.nodes.len()];
        let mut stack: Vec<(usize, Mat4)> = roots
            .into_iter()
            .rev()
            .map(|n| (n, Mat4::IDENTITY))
            .collect();
        let mut revisits = 0usize;
        while let Some((index, parent)) = stack.pop() {
            let node = root
                .nodes
                .get(index)
                .ok_or_else(|| self.err(format!("node {index} does not exist")))?;
            match visited.get_mut(index) {
                Some(v) if *v => {
                    revisits += 1;
                    continue;
                }
                Some(v) => *v = true,
                None => continue,
            }
            let world = parent * node_matrix(node);
            if let Some(mesh) = node.mesh {
                self.add_mesh(mesh.value(), world)?;
            }
            for child in node.children.iter().flatten().rev() {
                stack.push((child.value(), world));
            }
        }
        if revisits > 0 {
            self.warn(format!("{revisits} node reference(s) to an already placed node were ignored (cycle or shared node)"));
        }
        Ok(())
    }

    fn add_mesh(&mut self, mesh_index: usize, world: Mat4) -> Result<(), LoadError> {
        let root = self.root;
        let mesh = root
            .meshes
            .get(mesh_index)
            .ok_or_else(|| self.err(format!("mesh {mesh_index} does not exist")))?;
        for (p, prim) in mesh.primitives.iter().enumerate() {
            self.add_primitive(prim, world).map_err(|e| match e {
                LoadError::Parse {
                    path,
                    line,
                    offset,
                    message,
                } => LoadError::Parse {
                    path,
                    line,
                    offset,
                    message: format!("mesh {mesh_index} primitive {p}: {message}"),
                },
                other => other,
            })?;
        }
        Ok(())
    }

    fn add_primitive(
        &mut self,
        prim: &json::mesh::Primitive,
        world: Mat4,
    ) -> Result<(), LoadError> {
        let mode = match prim.mode {
            Checked::Valid(m @ (Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan)) => m,
            Checked::Valid(other) => {
                self.warn(format!(
                    "skipped a primitive in {other:?} mode (only triangles are voxelized)"
                ));
                return Ok(());
            }
            Checked::Invalid => return Err(self.err("invalid primitive mode".into())),
        };
        let (mut position, mut normal, mut uv, mut color) = (None, None, None, None);
        for (semantic, accessor) in &prim.attributes {
            match semantic {
                Checked::Valid(Semantic::Positions) => position = Some(accessor.value()),
                Checked::Valid(Semantic::Normals) => normal = Some(accessor.value()),
                Checked::Valid(Semantic::TexCoords(0)) => uv = Some(accessor.value()),
                Checked::Valid(Semantic::Colors(0)) => color = Some(accessor.value()),
                _ => {}
            }
        }
        let Some(position) = position else {
            self.warn("skipped a primitive without POSITION".into());
            return Ok(());
        };
        let positions = self.accessor(position, "POSITION", &[Type::Vec3])?;
        let n = positions.count;
        let base = self.mesh.positions.len();
        if base + n > MAX_VERTICES {
            return Err(LoadError::too_large(
                self.path,
                "vertices",
                (base + n) as u64,
                MAX_VERTICES as u64,
            ));
        }
        let indices: Vec<u32> = match prim.indices {
            Some(a) => {
                let v = self.accessor(a.value(), "indices", &[Type::Scalar])?;
                let mut out = Vec::with_capacity(v.count);
                for &i in &v.data {
                    if i < 0.0 || i >= n as f64 || i.fract() != 0.0 {
                        return Err(self.err(format!("index {i} is out of range ({n} vertices)")));
                    }
                    out.push(i as u32);
                }
                out
            }
            None => (0..n as u32).collect(),
        };
        let mut triangles = assemble(mode, &indices);
        if self.mesh.triangles.len() + triangles.len() > MAX_TRIANGLES {
            return Err(LoadError::too_large(
                self.path,
                "triangles",
                (self.mesh.triangles.len() + triangles.len()) as u64,
                MAX_TRIANGLES as u64,
            ));
        }
        // A mirroring transform turns the winding inside out: flip it back.
        if world.determinant() < 0.0 {
            for t in &mut triangles {
                t.swap(1, 2);
            }
        }

        for i in 0..n {
            let p = world.transform_point3(Vec3::new(
                positions.get(i, 0) as f32,
                positions.get(i, 1) as f32,
                positions.get(i, 2) as f32,
            ));
            if !p.is_finite() {
                return Err(self.err(format!("vertex {i} has a non-finite position")));
            }
            self.mesh.positions.push(p);
        }
        match normal {
            Some(a) => {
                let normals = self.accessor(a, "NORMAL", &[Type::Vec3])?;
                if normals.count != n {
                    return Err(self.err(format!(
                        "NORMAL has {} entries, POSITION {n}",
                        normals.count
                    )));
                }
                let m = Mat3::from_mat4(world).inverse().transpose();
                for i in 0..n {
                    let v = Vec3::new(
                        normals.get(i, 0) as f32,
                        normals.get(i, 1) as f32,
                        normals.get(i, 2) as f32,
                    );
                    let t = (m * v).normalize_or_zero();
                    self.mesh
                        .normals
                        .push(if t.is_finite() { t } else { Vec3::ZERO });
                }
            }
            None => {
                self.normals_missing = true;
                self.mesh.normals.resize(base + n, Vec3::ZERO);
            }
        }
        match uv {
            Some(a) => {
                let uvs = self.accessor(a, "TEXCOORD_0", &[Type::Vec2])?;
                if uvs.count != n {
                    return Err(self.err(format!(
                        "TEXCOORD_0 has {} entries, POSITION {n}",
                        uvs.count
                    )));
                }
                self.uvs_present = true;
                for i in 0..n {
                    let t = Vec2::new(uvs.get(i, 0) as f32, uvs.get(i, 1) as f32);
                    self.mesh
                        .uvs
                        .push(if t.is_finite() { t } else { Vec2::ZERO });
                }
            }
            None => self.mesh.uvs.resize(base + n, Vec2::ZERO),
        }
        match color {
            Some(a) => {
                let colors = self.accessor(a, "COLOR_0", &[Type::Vec3, Type::Vec4])?;
                if colors.count != n {
                    return Err(self.err(format!(
                        "COLOR_0 has {} entries, POSITION {n}",
                        colors.count
                    )));
                }
                self.colors_present = true;
                for i in 0..n {
                    let c = |k: usize| (colors.get(i, k) as f32).clamp(0.0, 1.0);
                    let a = if colors.components == 4 { c(3) } else { 1.0 };
                    self.mesh.colors.push([c(0), c(1), c(2), a]);
                }
            }
            // White is the identity of the colour product (see the module docs of `load`).
            None => self.mesh.colors.resize(base + n, [1.0; 4]),
        }

        let material = self.material(prim.material.map(|m| m.value()))?;
        let offset = base as u32;
        for t in triangles {
            self.mesh.triangles.push(t.map(|i| i + offset));
            self.mesh.triangle_materials.push(material);
        }
        Ok(())
    }

    /// The `mesh.materials` index of a glTF material, converting it on first use.
    fn material(&mut self, index: Option<usize>) -> Result<u32, LoadError> {
        if let Some(&m) = self.materials.get(&index) {
            return Ok(m);
        }
        let material = match index {
            // The glTF default material is white (not the project's grey default).
            None => Material {
                base_color: [1.0; 4],
                base_color_texture: None,
            },
            Some(i) => {
                let root = self.root;
                let m = root
                    .materials
                    .get(i)
                    .ok_or_else(|| self.err(format!("material {i} does not exist")))?;
                let pbr = &m.pbr_metallic_roughness;
                let texture = match &pbr.base_color_texture {
                    Some(info) => {
                        if info.tex_coord != 0 {
                            self.warn(format!(
                                "material {i}: base colour texture uses TEXCOORD_{}; only TEXCOORD_0 is read",
                                info.tex_coord
                            ));
                        }
                        self.texture(info.index.value())
                    }
                    None => None,
                };
                Material {
                    base_color: pbr.base_color_factor.0.map(|c| {
                        if c.is_finite() {
                            c.clamp(0.0, 1.0)
                        } else {
                            1.0
                        }
                    }),
                    base_color_texture: texture,
                }
            }
        };
        let slot = self.mesh.materials.len() as u32;
        self.mesh.materials.push(material);
        self.materials.insert(index, slot);
        Ok(slot)
    }

    /// Decodes the image of glTF texture `texture_index`; failures are warnings.
    fn texture(&mut self, texture_index: usize) -> Option<Texture> {
        let root = self.root;
        let Some(image_index) = root.textures.get(texture_index).map(|t| t.source.value()) else {
            self.warn(format!("texture {texture_index} does not exist"));
            return None;
        };
        if let Some(t) = self.textures.get(&image_index) {
            return t.clone();
        }
        let result = self
            .image_bytes(image_index)
            .and_then(|bytes| decode_texture(&bytes));
        let texture = match result {
            Ok(t) => Some(t),
            Err(e) => {
                self.warn(format!("image {image_index} not loaded: {e}"));
                None
            }
        };
        self.textures.insert(image_index, texture.clone());
        texture
    }

    fn image_bytes(&self, image_index: usize) -> Result<Vec<u8>, String> {
        let image = self
            .root
            .images
            .get(image_index)
            .ok_or("the image does not exist")?;
        if let Some(view) = image.buffer_view {
            return self
                .view_bytes(view.value())
                .map(<[u8]>::to_vec)
                .map_err(|e| e.to_string());
        }
        match &image.uri {
            Some(uri) => read_uri(uri, self.path, self.base_dir).map_err(UriError::describe),
            None => Err("the image has neither a uri nor a bufferView".into()),
        }
    }

    /// The bytes of a buffer view, range-checked.
    fn view_bytes(&self, view_index: usize) -> Result<&[u8], LoadError> {
        let view = self
            .root
            .buffer_views
            .get(view_index)
            .ok_or_else(|| self.err(format!("buffer view {view_index} does not exist")))?;
        let buffer = self
            .buffers
            .get(view.buffer.value())
            .ok_or_else(|| self.err(format!("buffer {} does not exist", view.buffer.value())))?;
        let start = view.byte_offset.map_or(0, |o| o.0);
        let end = start.checked_add(view.byte_length.0);
        match end.filter(|&e| e <= buffer.len() as u64) {
            Some(end) => Ok(&buffer[start as usize..end as usize]),
            None => Err(self.err(format!(
                "buffer view {view_index} (bytes {start}..+{}) lies outside buffer {} ({} bytes)",
                view.byte_length.0,
                view.buffer.value(),
                buffer.len()
            ))),
        }
    }

    /// An accessor's values, decoded once however many primitives or instances use it.
    fn accessor(
        &mut self,
        index: usize,
        what: &str,
        types: &[Type],
    ) -> Result<Rc<Values>, LoadError> {
        if let Some(v) = self.accessor_cache.get(&index) {
            // The same accessor may serve several semantics: re-check the type for this one.
            let ok = self
                .root
                .accessors
                .get(index)
                .is_some_and(|a| matches!(a.type_, Checked::Valid(t) if types.contains(&t)));
            if ok {
                return Ok(Rc::clone(v));
            }
        }
        let values = Rc::new(self.read_accessor(index, what, types)?);
        self.accessor_cache.insert(index, Rc::clone(&values));
        Ok(values)
    }

    /// Reads an accessor (dense and/or sparse) after checking every byte range it covers.
    fn read_accessor(&self, index: usize, what: &str, types: &[Type]) -> Result<Values, LoadError> {
        let acc = self
            .root
            .accessors
            .get(index)
            .ok_or_else(|| self.err(format!("{what}: accessor {index} does not exist")))?;
        let err = |m: String| self.err(format!("{what} (accessor {index}): {m}"));
        let component = match &acc.component_type {
            Checked::Valid(c) => c.0,
            Checked::Invalid => return Err(err("invalid component type".into())),
        };
        let ty = match acc.type_ {
            Checked::Valid(t) if types.contains(&t) => t,
            Checked::Valid(t) => {
                return Err(err(format!(
                    "type {t:?} is not allowed here (expected {types:?})"
                )));
            }
            Checked::Invalid => return Err(err("invalid accessor type".into())),
        };
        let components = ty.multiplicity();
        let count = acc.count.0;
        let elem = component.size() * components;
        let normalized = acc.normalized;
        let mut data: Vec<f64>;
        match acc.buffer_view {
            Some(view_index) => {
                let bytes = self.view_bytes(view_index.value())?;
                let stride = self
                    .root
                    .buffer_views
                    .get(view_index.value())
                    .and_then(|v| v.byte_stride)
                    .map_or(elem, |s| s.0);
                if stride < elem {
                    return Err(err(format!(
                        "byte stride {stride} is smaller than the element size {elem}"
                    )));
                }
                let offset = acc.byte_offset.map_or(0, |o| o.0);
                let span = if count == 0 {
                    Some(0)
                } else {
                    (count - 1)
                        .checked_mul(stride as u64)
                        .and_then(|s| s.checked_add(elem as u64))
                        .and_then(|s| s.checked_add(offset))
                };
                if span.is_none_or(|s| s > bytes.len() as u64) {
                    return Err(err(format!(
                        "{count} elements of {elem} bytes (stride {stride}, offset {offset}) overrun the {}-byte buffer view",
                        bytes.len()
                    )));
                }
                // `count` is now bounded by the buffer's size, so these allocations are too.
                let (count, offset) = (count as usize, offset as usize);
                data = Vec::with_capacity(count * components);
                for i in 0..count {
                    let at = offset + i * stride;
                    for c in 0..components {
                        data.push(decode_component(
                            bytes,
                            at + c * component.size(),
                            component,
                            normalized,
                        ));
                    }
                }
            }
            None => {
                if count > self.zero_fill_limit {
                    return Err(LoadError::too_large(
                        self.path,
                        "zero-filled accessor elements",
                        count,
                        self.zero_fill_limit,
                    ));
                }
                data = vec![0.0; count as usize * components];
            }
        }
        if let Some(sparse) = &acc.sparse {
            let n = sparse.count.0;
            if n > count {
                return Err(err(format!("{n} sparse entries for {count} elements")));
            }
            let index_type = match &sparse.indices.component_type {
                Checked::Valid(c) => c.0,
                Checked::Invalid => return Err(err("invalid sparse index type".into())),
            };
            let idx_bytes = self.view_bytes(sparse.indices.buffer_view.value())?;
            let idx_off = sparse.indices.byte_offset.0;
            let val_bytes = self.view_bytes(sparse.values.buffer_view.value())?;
            let val_off = sparse.values.byte_offset.0;
            let fits = |off: u64, size: usize, len: usize| {
                n.checked_mul(size as u64)
                    .and_then(|s| s.checked_add(off))
                    .is_some_and(|end| end <= len as u64)
            };
            if !fits(idx_off, index_type.size(), idx_bytes.len())
                || !fits(val_off, elem, val_bytes.len())
            {
                return Err(err(
                    "sparse indices or values overrun their buffer views".into()
                ));
            }
            for k in 0..n as usize {
                let target = decode_component(
                    idx_bytes,
                    idx_off as usize + k * index_type.size(),
                    index_type,
                    false,
                );
                if target < 0.0 || target >= count as f64 {
                    return Err(err(format!("sparse index {target} is out of range")));
                }
                for c in 0..components {
                    let v = decode_component(
                        val_bytes,
                        val_off as usize + k * elem + c * component.size(),
                        component,
                        normalized,
                    );
                    if let Some(slot) = data.get_mut(target as usize * components + c) {
                        *slot = v;
                    }
                }
            }
        }
        Ok(Values {
            data,
            components,
            count: count as usize,
        })
    }

    fn finish(mut self) -> Result<Mesh, LoadError> {
        if self.normals_missing {
            if self.mesh.normals.iter().any(|n| *n != Vec3::ZERO) {
                self.warn(
                    "some primitives have no NORMAL; all normals dropped (face normals are used)"
                        .into(),
                );
            }
            self.mesh.normals.clear();
        }
        if !self.uvs_present {
            self.mesh.uvs.clear();
        }
        if !self.colors_present {
            self.mesh.colors.clear();
        }
        Ok(self.mesh)
    }
}

/// The local matrix of a node: `matrix`, or translation × rotation × scale.
fn node_matrix(node: &json::Node) -> Mat4 {
    if let Some(m) = node.matrix {
        return Mat4::from_cols_array(&m);
    }
    let t = node.translation.map_or(Vec3::ZERO, Vec3::from);
    let r = node
        .rotation
        .map_or(Quat::IDENTITY, |q| Quat::from_array(q.0).normalize());
    let s = node.scale.map_or(Vec3::ONE, Vec3::from);
    let r = if r.is_finite() { r } else { Quat::IDENTITY };
    Mat4::from_scale_rotation_translation(s, r, t)
}

/// Triangles of a primitive from its (validated) index list.
fn assemble(mode: Mode, idx: &[u32]) -> Vec<[u32; 3]> {
    match mode {
        Mode::TriangleStrip => idx
            .windows(3)
            .enumerate()
            .filter(|(_, w)| w[0] != w[1] && w[1] != w[2] && w[0] != w[2])
            .map(|(k, w)| {
                if k % 2 == 0 {
                    [w[0], w[1], w[2]]
                } else {
                    [w[1], w[0], w[2]]
                }
            })
            .collect(),
        Mode::TriangleFan => match idx.split_first() {
            Some((&first, rest)) => rest.windows(2).map(|w| [first, w[0], w[1]]).collect(),
            None => Vec::new(),
        },
        _ => idx.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
    }
}

/// Decodes one component (little-endian) at byte `at`; out-of-range reads give 0 (they
/// cannot happen: every range is checked before decoding).
fn decode_component(bytes: &[u8], at: usize, component: ComponentType, normalized: bool) -> f64 {
    fn get<const N: usize>(bytes: &[u8], at: usize) -> [u8; N] {
        let mut a = [0u8; N];
        if let Some(s) = at.checked_add(N).and_then(|end| bytes.get(at..end)) {
            a.copy_from_slice(s);
        }
        a
    }
    match component {
        ComponentType::F32 => f32::from_le_bytes(get(bytes, at)) as f64,
        ComponentType::U8 => {
            let v = get::<1>(bytes, at)[0] as f64;
            if normalized { v / 255.0 } else { v }
        }
        ComponentType::I8 => {
            let v = get::<1>(bytes, at)[0] as i8 as f64;
            if normalized { (v / 127.0).max(-1.0) } else { v }
        }
        ComponentType::U16 => {
            let v = u16::from_le_bytes(get(bytes, at)) as f64;
            if normalized { v / 65535.0 } else { v }
        }
        ComponentType::I16 => {
            let v = i16::from_le_bytes(get(bytes, at)) as f64;
            if normalized {
                (v / 32767.0).max(-1.0)
            } else {
                v
            }
        }
        ComponentType::U32 => {
            let v = u32::from_le_bytes(get(bytes, at)) as f64;
            if normalized { v / u32::MAX as f64 } else { v }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_round_trips_known_vectors() {
        assert_eq!(base64_decode("").unwrap(), b"");
        assert_eq!(base64_decode("Zg==").unwrap(), b"f");
        assert_eq!(base64_decode("Zm8=").unwrap(), b"fo");
        assert_eq!(base64_decode("Zm9v").unwrap(), b"foo");
        assert_eq!(base64_decode("Zm9vYg").unwrap(), b"foob");
        assert!(base64_decode("Zm9v!").is_err());
        assert!(base64_decode("Z").is_err());
    }

    #[test]
    fn percent_decoding() {
        assert_eq!(percent_decode("a%20b.bin").as_deref(), Some("a b.bin"));
        assert_eq!(percent_decode("%FF"), None);
        assert_eq!(percent_decode("%2"), None);
    }
}
