//! A Wavefront OBJ surface of the voxels: every exposed face (a side whose neighbour cell
//! is empty), coplanar faces of one colour merged into rectangles (greedy meshing, row by
//! row), two triangles each, counter-clockwise seen from outside. Positions are in the
//! model's own units (the inverse of the asset's object space), so the surface sits where
//! the source model did. Colours are per vertex (`v x y z r g b`, sRGB in [0, 1], the
//! extension Blender, MeshLab and most loaders read); every rectangle has its own four
//! vertices.

use std::collections::{HashMap, HashSet};
use std::path::Path;

use super::common::{ExportError, ExportVoxel};
use crate::model::ObjectSpace;

/// One merged rectangle: on the plane `axis = plane` (grid units), facing `+axis` when
/// `positive`, covering `[u0, u1] × [v0, v1]` of the two other axes (`(axis + 1) % 3`,
/// `(axis + 2) % 3`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Rect {
    /// The axis the rectangle faces along.
    pub axis: usize,
    /// Whether it faces `+axis`.
    pub positive: bool,
    /// Its plane, in grid units.
    pub plane: u32,
    /// Extent along `(axis + 1) % 3`.
    pub u: [u32; 2],
    /// Extent along `(axis + 2) % 3`.
    pub v: [u32; 2],
    /// sRGB-encoded RGBA.
    pub rgba: [u8; 4],
}

/// A plane of faces: `(axis, facing +axis, plane)`.
type PlaneKey = (usize, bool, u32);

/// The exposed unit faces of one plane, at `(u, v)`, with their colours.
type PlaneFaces = HashMap<(u32, u32), [u8; 4]>;

/// The exposed faces of `voxels`, merged into rectangles of one colour.
pub fn rectangles(voxels: &[ExportVoxel]) -> Vec<Rect> {
    let occupied: HashSet<[u32; 3]> = voxels.iter().map(|v| v.cell).collect();
    // Per (axis, side, plane): the exposed unit faces at (u, v) with their colours.
    let mut groups: HashMap<PlaneKey, PlaneFaces> = HashMap::new();
    for v in voxels {
        for axis in 0..3 {
            for positive in [false, true] {
                let mut n = v.cell.map(i64::from);
                n[axis] += if positive { 1 } else { -1 };
                let neighbour = n.map(|c| c as u32);
                if n[axis] >= 0 && occupied.contains(&neighbour) {
                    continue;
                }
                let plane = v.cell[axis] + u32::from(positive);
                let (ua, va) = ((axis + 1) % 3, (axis + 2) % 3);
                groups
                    .entry((axis, positive, plane))
                    .or_default()
                    .insert((v.cell[ua], v.cell[va]), v.rgba);
            }
        }
    }
    let mut keys: Vec<_> = groups.keys().copied().collect();
    keys.sort();
    let mut out = Vec::new();
    for key in keys {
        merge(key, &groups[&key], &mut out);
    }
    out
}

/// Greedy merge of one plane's faces: from the lowest unvisited face (by v, then u), as
/// wide as the row allows, then as tall as whole rows of that width allow.
fn merge((axis, positive, plane): PlaneKey, faces: &PlaneFaces, out: &mut Vec<Rect>) {
    let mut order: Vec<(u32, u32)> = faces.keys().copied().collect();
    order.sort_by_key(|&(u, v)| (v, u));
    let mut used: HashSet<(u32, u32)> = HashSet::new();
    let free = |used: &HashSet<(u32, u32)>, at: (u32, u32), rgba: [u8; 4]| {
        !used.contains(&at) && faces.get(&at) == Some(&rgba)
    };
    for (u0, v0) in order {
        if used.contains(&(u0, v0)) {
            continue;
        }
        let rgba = faces[&(u0, v0)];
        let mut u1 = u0 + 1;
        while free(&used, (u1, v0), rgba) {
            u1 += 1;
        }
        let mut v1 = v0 + 1;
        while (u0..u1).all(|u| free(&used, (u, v1), rgba)) {
            v1 += 1;
        }
        for v in v0..v1 {
            for u in u0..u1 {
                used.insert((u, v));
            }
        }
        out.push(Rect {
            axis,
            positive,
            plane,
            u: [u0, u1],
            v: [v0, v1],
            rgba,
        });
    }
}

/// Writes the surface of `voxels` (cells of an `edge`³ grid of `space`) as OBJ, streamed;
/// returns how many rectangles it has. A corner's coordinate on an axis is one of
/// `edge + 1` grid planes and a colour channel one of 256 values, so their text is made
/// once per value, and a line is copied from those pieces: formatting floats per vertex
/// was most of the time of a large export (`docs/bench/details.md`, "Export").
pub fn write(
    path: &Path,
    edge: u32,
    voxels: &[ExportVoxel],
    space: &ObjectSpace,
) -> Result<usize, ExportError> {
    let rects = rectangles(voxels);
    let cell = 2.0 / f64::from(edge);
    let planes: [Vec<String>; 3] = std::array::from_fn(|i| {
        (0..=edge)
            .map(|g| {
                let x = space.center[i] + (-1.0 + f64::from(g) * cell) / space.scale;
                format!("{x}")
            })
            .collect()
    });
    let channel: Vec<String> = (0..=255u32)
        .map(|c| format!("{:.4}", f64::from(c) / 255.0))
        .collect();
    crate::load::write_atomically_with(path, |w| {
        writeln!(
            w,
            "# ssbvb export: exposed voxel faces, vertex colours sRGB"
        )?;
        let mut n = 0usize;
        let mut line = Vec::with_capacity(256);
        let mut int = itoa::Buffer::new();
        for r in &rects {
            let (ua, va) = ((r.axis + 1) % 3, (r.axis + 2) % 3);
            let corner = |u: u32, v: u32| {
                let mut g = [0u32; 3];
                g[r.axis] = r.plane;
                g[ua] = u;
                g[va] = v;
                g
            };
            let mut quad = [
                corner(r.u[0], r.v[0]),
                corner(r.u[1], r.v[0]),
                corner(r.u[1], r.v[1]),
                corner(r.u[0], r.v[1]),
            ];
            if !r.positive {
                quad.reverse();
            }
            line.clear();
            for g in quad {
                line.push(b'v');
                for (i, p) in g.iter().enumerate() {
                    line.push(b' ');
                    line.extend_from_slice(planes[i][*p as usize].as_bytes());
                }
                for c in &r.rgba[..3] {
                    line.push(b' ');
                    line.extend_from_slice(channel[usize::from(*c)].as_bytes());
                }
                line.push(b'\n');
            }
            for tri in [[1, 2, 3], [1, 3, 4]] {
                line.push(b'f');
                for k in tri {
                    line.push(b' ');
                    line.extend_from_slice(int.format(n + k).as_bytes());
                }
                line.push(b'\n');
            }
            w.write_all(&line)?;
            n += 4;
        }
        Ok(())
    })?;
    Ok(rects.len())
}
