//! Vertex and face statements: corners resolved and de-indexed, polygons fan-triangulated,
//! and the finished mesh with its materials.

use std::path::Path;

use glam::{Vec2, Vec3};

use super::mtl::{TextureCache, load_libraries};
use super::text::{numbers, tokens};
use super::{MISSING, State};
use crate::load::common::{MAX_TRIANGLES, MAX_VERTICES, srgb_to_linear};
use crate::load::error::LoadError;
use crate::model::{Material, Mesh};

impl State {
    pub(super) fn vertex(
        &mut self,
        rest: &[u8],
        path: &Path,
        line: usize,
    ) -> Result<(), LoadError> {
        let (vals, n) = statement_numbers::<7>(rest, path, line, 3, |n| {
            format!("`v` needs 3 coordinates, found {n}")
        })?;
        check_room(self.positions.len(), "vertices", path)?;
        self.positions.push(Vec3::new(vals[0], vals[1], vals[2]));
        // 4 or 5 numbers: x y z w (rational weight, meaningless for us). 6+: x y z r g b [a].
        if n >= 6 {
            if self.position_colors.len() < self.positions.len() - 1 {
                self.position_colors
                    .resize(self.positions.len() - 1, [1.0; 4]);
            }
            let a = if n >= 7 { vals[6].clamp(0.0, 1.0) } else { 1.0 };
            self.position_colors.push([
                srgb_to_linear(vals[3]),
                srgb_to_linear(vals[4]),
                srgb_to_linear(vals[5]),
                a,
            ]);
        } else if !self.position_colors.is_empty() {
            self.position_colors.push([1.0; 4]);
        }
        Ok(())
    }

    pub(super) fn texcoord(
        &mut self,
        rest: &[u8],
        path: &Path,
        line: usize,
    ) -> Result<(), LoadError> {
        let (vals, _) = statement_numbers::<3>(rest, path, line, 1, |_| {
            "`vt` needs at least 1 coordinate".to_string()
        })?;
        check_room(self.texcoords.len(), "texture coordinates", path)?;
        self.texcoords.push(Vec2::new(vals[0], vals[1]));
        Ok(())
    }

    pub(super) fn normal(
        &mut self,
        rest: &[u8],
        path: &Path,
        line: usize,
    ) -> Result<(), LoadError> {
        let (vals, _) = statement_numbers::<3>(rest, path, line, 3, |n| {
            format!("`vn` needs 3 components, found {n}")
        })?;
        check_room(self.normals.len(), "normals", path)?;
        self.normals.push(Vec3::new(vals[0], vals[1], vals[2]));
        Ok(())
    }

    pub(super) fn face(&mut self, rest: &[u8], path: &Path, line: usize) -> Result<(), LoadError> {
        let mut face = std::mem::take(&mut self.face);
        face.clear();
        for tok in tokens(rest) {
            if tok[0] == b'#' {
                break;
            }
            face.push(self.corner(tok, path, line)?);
        }
        let result = self.emit_face(&face, path, line);
        self.face = face;
        result
    }

    fn emit_face(
        &mut self,
        face: &[(u32, u32, u32)],
        path: &Path,
        line: usize,
    ) -> Result<(), LoadError> {
        if face.len() < 3 {
            self.skipped_faces += 1;
            return Ok(());
        }
        let new_triangles = face.len() - 2;
        if self.triangles.len() + new_triangles > MAX_TRIANGLES {
            return Err(LoadError::too_large(
                path,
                "triangles",
                (self.triangles.len() + new_triangles) as u64,
                MAX_TRIANGLES as u64,
            ));
        }
        let first = self.output_vertex(face[0], path, line)?;
        let mut prev = self.output_vertex(face[1], path, line)?;
        for &corner in &face[2..] {
            let next = self.output_vertex(corner, path, line)?;
            self.triangles.push([first, prev, next]);
            self.triangle_materials.push(self.current_material);
            prev = next;
        }
        Ok(())
    }

    /// Parses one face corner `v[/[vt][/vn]]` into 0-based indices, validated against
    /// what the file has defined so far.
    fn corner(&self, tok: &[u8], path: &Path, line: usize) -> Result<(u32, u32, u32), LoadError> {
        let mut parts = tok.split(|&b| b == b'/');
        let v = parts.next().unwrap_or_default();
        let vt = parts.next().unwrap_or_default();
        let vn = parts.next().unwrap_or_default();
        if parts.next().is_some() {
            return Err(LoadError::at_line(
                path,
                line,
                format!("malformed face corner {:?}", String::from_utf8_lossy(tok)),
            ));
        }
        if v.is_empty() {
            return Err(LoadError::at_line(
                path,
                line,
                format!(
                    "face corner {:?} has no vertex index",
                    String::from_utf8_lossy(tok)
                ),
            ));
        }
        let v = resolve_index(v, self.positions.len(), "vertex", path, line)?;
        let vt = if vt.is_empty() {
            MISSING
        } else {
            resolve_index(vt, self.texcoords.len(), "texture coordinate", path, line)?
        };
        let vn = if vn.is_empty() {
            MISSING
        } else {
            resolve_index(vn, self.normals.len(), "normal", path, line)?
        };
        Ok((v, vt, vn))
    }

    /// The output vertex of a corner, created on first use.
    fn output_vertex(
        &mut self,
        (v, vt, vn): (u32, u32, u32),
        path: &Path,
        line: usize,
    ) -> Result<u32, LoadError> {
        if vt == MISSING {
            self.corners_without_uv += 1;
        } else {
            self.corners_with_uv += 1;
        }
        if vn == MISSING {
            self.corners_without_normal += 1;
        }
        let existing = if vt == MISSING && vn == MISSING {
            self.by_position
                .get(v as usize)
                .copied()
                .filter(|&i| i != MISSING)
        } else {
            self.by_corner.get(&(v, vt, vn)).copied()
        };
        if let Some(i) = existing {
            return Ok(i);
        }
        let index = self.out_positions.len();
        check_room(index, "vertices", path)?;
        // All three lookups were validated by `corner`; `get` keeps this panic-free anyway.
        let position = self
            .positions
            .get(v as usize)
            .copied()
            .ok_or_else(|| LoadError::at_line(path, line, "vertex index out of range"))?;
        self.out_positions.push(position);
        self.out_uvs.push(
            self.texcoords
                .get(vt as usize)
                .copied()
                .unwrap_or(Vec2::ZERO),
        );
        self.out_normals
            .push(self.normals.get(vn as usize).copied().unwrap_or(Vec3::ZERO));
        self.out_source.push(v);
        let index = index as u32;
        if vt == MISSING && vn == MISSING {
            if self.by_position.len() <= v as usize {
                self.by_position.resize(self.positions.len(), MISSING);
            }
            if let Some(slot) = self.by_position.get_mut(v as usize) {
                *slot = index;
            }
        } else {
            self.by_corner.insert((v, vt, vn), index);
        }
        Ok(index)
    }

    pub(super) fn finish(
        mut self,
        path: &Path,
        base_dir: Option<&Path>,
        warnings: &mut Vec<String>,
    ) -> Result<Mesh, LoadError> {
        let mut mesh = Mesh {
            positions: std::mem::take(&mut self.out_positions),
            triangles: std::mem::take(&mut self.triangles),
            ..Mesh::default()
        };
        if self.corners_with_uv > 0 {
            // Corners without `vt` keep (0, 0): there is nothing better to give them.
            mesh.uvs = std::mem::take(&mut self.out_uvs);
        }
        if self.corners_without_normal == 0 {
            mesh.normals = std::mem::take(&mut self.out_normals);
        } else if !self.normals.is_empty() {
            warnings.push(format!(
                "{}: some face corners have no normal; ignoring all normals (face normals are used)",
                path.display()
            ));
        }
        if !self.position_colors.is_empty() {
            self.position_colors.resize(self.positions.len(), [1.0; 4]);
            mesh.colors = self
                .out_source
                .iter()
                .map(|&v| {
                    self.position_colors
                        .get(v as usize)
                        .copied()
                        .unwrap_or([1.0; 4])
                })
                .collect();
        }
        if !self.material_names.is_empty() {
            let library = load_libraries(&self.mtllibs, path, base_dir, warnings)?;
            let mut textures = TextureCache::default();
            for name in &self.material_names {
                let material = match library.get(name) {
                    Some(m) => m.to_material(&mut textures, warnings),
                    None => {
                        warnings.push(format!(
                            "{}: material {name:?} is not defined in any MTL library; using a default",
                            path.display()
                        ));
                        Material::default()
                    }
                };
                mesh.materials.push(material);
            }
            // Faces before the first `usemtl` get a default material of their own.
            let default_index = mesh.materials.len() as u32;
            let mut needs_default = false;
            for m in &mut self.triangle_materials {
                if *m == MISSING {
                    *m = default_index;
                    needs_default = true;
                }
            }
            if needs_default {
                mesh.materials.push(Material::default());
            }
            mesh.triangle_materials = self.triangle_materials;
        }
        Ok(mesh)
    }
}

/// The numbers of a `v`, `vt` or `vn` statement and how many were given; fewer than `min`
/// is an error with the message `too_few(count)`.
fn statement_numbers<const N: usize>(
    rest: &[u8],
    path: &Path,
    line: usize,
    min: usize,
    too_few: impl FnOnce(usize) -> String,
) -> Result<([f32; N], usize), LoadError> {
    let mut vals = [0f32; N];
    let n = numbers(rest, &mut vals, path, line)?;
    if n < min {
        return Err(LoadError::at_line(path, line, too_few(n)));
    }
    Ok((vals, n))
}

/// Fails when `len` elements of `what` (a vertex-sized kind) already fill `MAX_VERTICES`.
fn check_room(len: usize, what: &str, path: &Path) -> Result<(), LoadError> {
    if len >= MAX_VERTICES {
        return Err(LoadError::too_large(
            path,
            what,
            len as u64 + 1,
            MAX_VERTICES as u64,
        ));
    }
    Ok(())
}

/// Resolves a 1-based (or negative, relative) OBJ index against `count` defined elements.
fn resolve_index(
    tok: &[u8],
    count: usize,
    what: &str,
    path: &Path,
    line: usize,
) -> Result<u32, LoadError> {
    let text = String::from_utf8_lossy(tok);
    let i: i64 = text.parse().map_err(|_| {
        LoadError::at_line(
            path,
            line,
            format!("{what} index {text:?} is not an integer"),
        )
    })?;
    let resolved = if i > 0 {
        i - 1
    } else if i < 0 {
        // `count` is at most 2^28, so this cannot overflow.
        count as i64 + i
    } else {
        return Err(LoadError::at_line(
            path,
            line,
            format!("{what} index 0 is invalid (OBJ indices start at 1)"),
        ));
    };
    if resolved < 0 || resolved >= count as i64 {
        return Err(LoadError::at_line(
            path,
            line,
            format!("{what} index {i} is out of range: {count} defined so far"),
        ));
    }
    Ok(resolved as u32)
}
