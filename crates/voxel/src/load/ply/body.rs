//! The body: vertices with their attributes, faces and triangle strips, skipped elements.

use std::path::Path;

use glam::{Vec2, Vec3};

use super::header::{Element, Header, Kind, Property, Scalar};
use super::reader::Reader;
use crate::load::common::{MAX_TRIANGLES, srgb_to_linear, srgb_u8_table};
use crate::load::error::LoadError;
use crate::model::Mesh;

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

pub(super) fn read_body<R: Reader>(
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
    let srgb = srgb_u8_table();
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
