//! The scene walk: nodes and their transforms, meshes, primitives and their attributes.

use std::collections::HashSet;

use glam::{Mat3, Mat4, Quat, Vec2, Vec3};
use gltf::json;
use gltf::json::accessor::Type;
use gltf::json::mesh::{Mode, Semantic};
use gltf::json::validation::Checked;

use super::Builder;
use super::values::Values;
use crate::load::common::{MAX_TRIANGLES, MAX_VERTICES};
use crate::load::error::LoadError;
use crate::model::Mesh;

impl Builder<'_> {
    pub(super) fn load_scenes(&mut self) -> Result<(), LoadError> {
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

    /// Appends one primitive's vertices, attributes and triangles, placed by `world`.
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
        let triangles = self.primitive_triangles(prim, mode, n, world)?;

        self.push_positions(&positions, world)?;
        self.push_normals(normal, n, base, world)?;
        self.push_uvs(uv, n, base)?;
        self.push_colors(color, n, base)?;

        let material = self.material(prim.material.map(|m| m.value()))?;
        let offset = base as u32;
        for t in triangles {
            self.mesh.triangles.push(t.map(|i| i + offset));
            self.mesh.triangle_materials.push(material);
        }
        Ok(())
    }

    /// The triangles of a primitive of `n` vertices in `mode`, as indices into its own
    /// vertices, wound for the placement `world`.
    fn primitive_triangles(
        &mut self,
        prim: &json::mesh::Primitive,
        mode: Mode,
        n: usize,
        world: Mat4,
    ) -> Result<Vec<[u32; 3]>, LoadError> {
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
        Ok(triangles)
    }

    /// Appends the `POSITION` values placed by `world`; refuses a non-finite one.
    fn push_positions(&mut self, positions: &Values, world: Mat4) -> Result<(), LoadError> {
        for i in 0..positions.count {
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
        Ok(())
    }

    /// Appends the `NORMAL` values (accessor `normal`) of `n` vertices turned by `world`,
    /// or zeros (and notes the gap) without them; `base`: the primitive's first vertex.
    fn push_normals(
        &mut self,
        normal: Option<usize>,
        n: usize,
        base: usize,
        world: Mat4,
    ) -> Result<(), LoadError> {
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
        Ok(())
    }

    /// Appends the `TEXCOORD_0` values (accessor `uv`) of `n` vertices, or zeros without
    /// them; `base`: the primitive's first vertex.
    fn push_uvs(&mut self, uv: Option<usize>, n: usize, base: usize) -> Result<(), LoadError> {
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
        Ok(())
    }

    /// Appends the `COLOR_0` values (accessor `color`) of `n` vertices, or white without
    /// them; `base`: the primitive's first vertex.
    fn push_colors(
        &mut self,
        color: Option<usize>,
        n: usize,
        base: usize,
    ) -> Result<(), LoadError> {
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
        Ok(())
    }

    pub(super) fn finish(mut self) -> Result<Mesh, LoadError> {
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
