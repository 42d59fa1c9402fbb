//! Per-voxel attributes: colour (material × texture × vertex colour) sampled on a
//! triangle, and the occupancy-gradient normal used where no surface normal exists.

use glam::DVec3;

use crate::model::{Material, Texture};

/// Per-triangle attribute sources, resolved once per (brick, triangle).
pub(super) struct TriAttrs<'a> {
    pub(super) material: &'a Material,
    pub(super) uv: Option<[glam::Vec2; 3]>,
    pub(super) color: Option<[[f32; 4]; 3]>,
}

/// Minus the occupancy-weighted sum of the 26 neighbour offsets (each divided by its
/// length): points from the occupied side of a cell towards the empty side.
pub(crate) fn gradient_26(mut occupied: impl FnMut([i64; 3]) -> bool) -> [f64; 3] {
    let mut g = [0.0f64; 3];
    for dz in -1i64..=1 {
        for dy in -1i64..=1 {
            for dx in -1i64..=1 {
                if (dx, dy, dz) == (0, 0, 0) || !occupied([dx, dy, dz]) {
                    continue;
                }
                let inv = 1.0 / ((dx * dx + dy * dy + dz * dz) as f64).sqrt();
                g[0] -= dx as f64 * inv;
                g[1] -= dy as f64 * inv;
                g[2] -= dz as f64 * inv;
            }
        }
    }
    g
}

/// Colour and uv of a triangle at point `p` (grid units) on it.
pub(super) fn sample(v: &[DVec3; 3], a: &TriAttrs<'_>, p: DVec3) -> ([f32; 4], [f64; 2]) {
    let w = barycentric(v, p);
    let mut color = a.material.base_color;
    let mut uv = [0.0f64; 2];
    if let Some(uvs) = a.uv {
        for k in 0..3 {
            uv[0] += w[k] * f64::from(uvs[k].x);
            uv[1] += w[k] * f64::from(uvs[k].y);
        }
        if !(uv[0].is_finite() && uv[1].is_finite()) {
            uv = [0.0; 2];
        }
        if let Some(tex) = &a.material.base_color_texture {
            let t = sample_texture(tex, uv);
            for k in 0..4 {
                color[k] *= t[k];
            }
        }
    }
    if let Some(cols) = a.color {
        for k in 0..4 {
            let c = (0..3).map(|i| w[i] * f64::from(cols[i][k])).sum::<f64>();
            color[k] *= c as f32;
        }
    }
    (sanitize(color), uv)
}

/// A colour clamped into [0, 1], non-finite components as 0.
pub(super) fn sanitize(color: [f32; 4]) -> [f32; 4] {
    color.map(|c| {
        if c.is_finite() {
            c.clamp(0.0, 1.0)
        } else {
            0.0
        }
    })
}

/// Barycentric weights of `p` (projected onto the triangle, clamped into it). For a
/// degenerate triangle: all weight on the vertex nearest to `p`.
fn barycentric(t: &[DVec3; 3], p: DVec3) -> [f64; 3] {
    let e0 = t[1] - t[0];
    let e1 = t[2] - t[0];
    let ep = p - t[0];
    let d00 = e0.dot(e0);
    let d01 = e0.dot(e1);
    let d11 = e1.dot(e1);
    let d20 = ep.dot(e0);
    let d21 = ep.dot(e1);
    let denom = d00 * d11 - d01 * d01;
    if denom > 1e-12 * d00 * d11 && denom.is_finite() {
        let v = ((d11 * d20 - d01 * d21) / denom).clamp(0.0, 1.0);
        let w = ((d00 * d21 - d01 * d20) / denom).clamp(0.0, 1.0);
        let s = v + w;
        let (v, w) = if s > 1.0 { (v / s, w / s) } else { (v, w) };
        [1.0 - v - w, v, w]
    } else {
        let d = t.map(|q| q.distance_squared(p));
        let i = if d[0] <= d[1] && d[0] <= d[2] {
            0
        } else if d[1] <= d[2] {
            1
        } else {
            2
        };
        let mut w = [0.0; 3];
        w[i] = 1.0;
        w
    }
}

/// Bilinear, wrap-around sample of an RGBA8 texture; `uv` (0, 0) is the top-left corner
/// of texel row 0 (the glTF convention the loaders convert to). A malformed texture
/// (zero size, too few texels) samples as white.
fn sample_texture(tex: &Texture, uv: [f64; 2]) -> [f32; 4] {
    let (w, h) = (tex.width as i64, tex.height as i64);
    if w == 0 || h == 0 || (tex.texels.len() as i64) < w * h {
        return [1.0; 4];
    }
    let x = uv[0] * w as f64 - 0.5;
    let y = uv[1] * h as f64 - 0.5;
    let (x0, y0) = (x.floor(), y.floor());
    let (fx, fy) = ((x - x0) as f32, (y - y0) as f32);
    let texel = |xi: i64, yi: i64| {
        let t = tex.texels[(yi.rem_euclid(h) * w + xi.rem_euclid(w)) as usize];
        t.map(|c| f32::from(c) / 255.0)
    };
    let (x0, y0) = (x0 as i64, y0 as i64);
    let (a, b, c, d) = (
        texel(x0, y0),
        texel(x0 + 1, y0),
        texel(x0, y0 + 1),
        texel(x0 + 1, y0 + 1),
    );
    let mut out = [0.0f32; 4];
    for k in 0..4 {
        let top = a[k] + (b[k] - a[k]) * fx;
        let bottom = c[k] + (d[k] - c[k]) * fx;
        out[k] = top + (bottom - top) * fy;
    }
    out
}

#[cfg(test)]
#[path = "sampling_tests.rs"]
mod tests;
