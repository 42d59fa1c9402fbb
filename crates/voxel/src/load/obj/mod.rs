//! Wavefront OBJ and MTL reader.
//!
//! A hand-written reader rather than `tobj`, for three reasons found while evaluating
//! `tobj` 4: its errors carry no line number (a second validating pass would have to
//! re-implement the parser anyway), it panics on some malformed inputs (an MTL `Kd` with
//! fewer than three numbers hits an `unwrap`; `f 1/0/1` overflows `vt * 2 + 1` in debug
//! builds), and de-indexing needs the corner triples it does not expose. The test suite
//! cross-checks this reader against `tobj` on the test models.
//!
//! Supported: `v x y z [w]` and the common `v x y z r g b [a]` vertex-colour extension,
//! `vt`, `vn`, `f`/`fo` with `v`, `v/vt`, `v//vn`, `v/vt/vn` corners and negative
//! (relative) indices, polygons (fan-triangulated), `usemtl`, `mtllib`, `\` line
//! continuations. Points, lines, groups, smoothing groups and free-form geometry are
//! ignored. Face indices must refer to elements already defined (as the format says).
//!
//! Layout: the statement loop and the parse state here, vertices, faces and de-indexing
//! in `mesh`, MTL libraries and textures in `mtl`, line and number lexing in `text`.

mod mesh;
mod mtl;
mod text;

use std::collections::HashMap;
use std::path::Path;

use glam::{Vec2, Vec3};

use super::error::LoadError;
use crate::model::Mesh;
use text::{Lines, split_keyword, tokens, trim};

/// Marks an absent `vt` / `vn` in a face corner, and "no `usemtl` yet".
const MISSING: u32 = u32::MAX;

/// Whether the first statement of `text` is an OBJ keyword (content sniffing).
pub(super) fn looks_like_obj(text: &[u8]) -> bool {
    for line in text.split(|&b| b == b'\n') {
        let line = trim(line);
        if line.is_empty() || line[0] == b'#' {
            continue;
        }
        let keyword = tokens(line).next().unwrap_or_default();
        return matches!(
            keyword,
            b"v" | b"vn" | b"vt" | b"f" | b"o" | b"g" | b"s" | b"mtllib" | b"usemtl" | b"l" | b"p"
        );
    }
    false
}

/// Parses an OBJ file held in memory; MTL libraries and textures are looked up in
/// `base_dir` (none are opened when it is `None`).
pub(super) fn parse(
    bytes: &[u8],
    path: &Path,
    base_dir: Option<&Path>,
    warnings: &mut Vec<String>,
) -> Result<Mesh, LoadError> {
    let mut st = State::default();
    for (line_no, line) in Lines::new(bytes) {
        let line = trim(&line);
        if line.is_empty() || line[0] == b'#' {
            continue;
        }
        let (keyword, rest) = split_keyword(line);
        match keyword {
            b"v" => st.vertex(rest, path, line_no)?,
            b"vt" => st.texcoord(rest, path, line_no)?,
            b"vn" => st.normal(rest, path, line_no)?,
            b"f" | b"fo" => st.face(rest, path, line_no)?,
            b"usemtl" => {
                let name = String::from_utf8_lossy(trim(rest)).into_owned();
                let next = st.material_names.len() as u32;
                let index = *st.material_index.entry(name.clone()).or_insert_with(|| {
                    st.material_names.push(name);
                    next
                });
                st.current_material = index;
            }
            b"mtllib" => st
                .mtllibs
                .push((line_no, String::from_utf8_lossy(trim(rest)).into_owned())),
            _ => {} // o, g, s, l, p, curves, ...: nothing the voxelizer needs.
        }
    }
    if st.skipped_faces > 0 {
        warnings.push(format!(
            "{}: skipped {} face(s) with fewer than 3 vertices",
            path.display(),
            st.skipped_faces
        ));
    }
    st.finish(path, base_dir, warnings)
}

/// What the file has defined so far and the de-indexed mesh being built.
struct State {
    // What the file defines, indexed by OBJ index - 1.
    positions: Vec<Vec3>,
    /// Per-position colours, empty until the first coloured `v` line.
    position_colors: Vec<[f32; 4]>,
    texcoords: Vec<Vec2>,
    normals: Vec<Vec3>,
    // The de-indexed output: one vertex per distinct (v, vt, vn) corner.
    out_positions: Vec<Vec3>,
    out_uvs: Vec<Vec2>,
    out_normals: Vec<Vec3>,
    /// Source position of each output vertex (for colours, which may appear late).
    out_source: Vec<u32>,
    corners_with_uv: usize,
    corners_without_uv: usize,
    corners_without_normal: usize,
    /// Output vertex of a corner that has only a position (the common, fast case).
    by_position: Vec<u32>,
    /// Output vertex of any other corner.
    by_corner: HashMap<(u32, u32, u32), u32>,
    triangles: Vec<[u32; 3]>,
    triangle_materials: Vec<u32>,
    current_material: u32,
    material_names: Vec<String>,
    material_index: HashMap<String, u32>,
    mtllibs: Vec<(usize, String)>,
    skipped_faces: usize,
    /// Scratch buffer for the corners of the face being parsed.
    face: Vec<(u32, u32, u32)>,
}

impl Default for State {
    fn default() -> Self {
        State {
            positions: Vec::new(),
            position_colors: Vec::new(),
            texcoords: Vec::new(),
            normals: Vec::new(),
            out_positions: Vec::new(),
            out_uvs: Vec::new(),
            out_normals: Vec::new(),
            out_source: Vec::new(),
            corners_with_uv: 0,
            corners_without_uv: 0,
            corners_without_normal: 0,
            by_position: Vec::new(),
            by_corner: HashMap::new(),
            triangles: Vec::new(),
            triangle_materials: Vec::new(),
            current_material: MISSING,
            material_names: Vec::new(),
            material_index: HashMap::new(),
            mtllibs: Vec::new(),
            skipped_faces: 0,
            face: Vec::new(),
        }
    }
}
