//! Which cells of a grid a surface of cells encloses (a cheap solid fill that tolerates
//! holes). Used by the cone tracer's scene volume and by RGBA volumes made from meshes.

fn index(dims: [u32; 3], c: [u32; 3]) -> usize {
    c[0] as usize + dims[0] as usize * (c[1] as usize + dims[1] as usize * c[2] as usize)
}

/// The surface and the cells it encloses: an empty cell is inside when the surface lies
/// on all six of its axis directions. Unlike a flood fill from outside, this fills most of
/// a shell with a hole (the Stanford bunny's open base): a hollow shell's coarse mip levels
/// are far more transparent than the solid it bounds (filled, the AO error of the plane
/// under the bunny drops: docs/architecture.md). Measured on the bunny on its plane (AO
/// mean absolute error against Monte Carlo): five of six directions over-fills concave
/// parts (voxel receivers +0.004, lit PSNR −2.8 dB).
pub fn enclosed(surface: &[bool], dims: [u32; 3]) -> Vec<bool> {
    // Per cell, how many of the six directions meet the surface.
    let mut seen = vec![0u8; surface.len()];
    for axis in 0..3 {
        let (a, b) = ((axis + 1) % 3, (axis + 2) % 3);
        for u in 0..dims[a] {
            for v in 0..dims[b] {
                let cell = |t: u32| {
                    let mut c = [0u32; 3];
                    c[axis] = t;
                    c[a] = u;
                    c[b] = v;
                    index(dims, c)
                };
                let mut hit = false;
                for t in 0..dims[axis] {
                    let i = cell(t);
                    seen[i] += u8::from(hit);
                    hit |= surface[i];
                }
                hit = false;
                for t in (0..dims[axis]).rev() {
                    let i = cell(t);
                    seen[i] += u8::from(hit);
                    hit |= surface[i];
                }
            }
        }
    }
    surface
        .iter()
        .zip(&seen)
        .map(|(&s, &n)| s || n == 6)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A hollow box of surface cells from 2 to 7 in a 10³ grid, optionally with one cell of
    /// its top face missing.
    fn shell(hole: bool) -> (Vec<bool>, [u32; 3]) {
        let dims = [10; 3];
        let mut s = vec![false; 1000];
        for z in 2..=7u32 {
            for y in 2..=7u32 {
                for x in 2..=7u32 {
                    let on_face = [x, y, z].iter().any(|&c| c == 2 || c == 7);
                    let is_hole = hole && y == 7 && x == 4 && z == 4;
                    s[index(dims, [x, y, z])] = on_face && !is_hole;
                }
            }
        }
        (s, dims)
    }

    #[test]
    fn a_closed_shell_is_filled_and_nothing_outside_it() {
        let (s, dims) = shell(false);
        let solid = enclosed(&s, dims);
        for z in 0..10u32 {
            for y in 0..10u32 {
                for x in 0..10u32 {
                    let inside = [x, y, z].iter().all(|&c| (2..=7).contains(&c));
                    assert_eq!(solid[index(dims, [x, y, z])], inside, "{x} {y} {z}");
                }
            }
        }
    }

    #[test]
    fn a_hole_leaves_only_the_cells_in_line_with_it_hollow() {
        let (s, dims) = shell(true);
        let solid = enclosed(&s, dims);
        for y in 3..=6u32 {
            // Straight below the hole: open upwards.
            assert!(!solid[index(dims, [4, y, 4])], "{y}");
            // Beside it: enclosed on all six sides.
            assert!(
                solid[index(dims, [5, y, 4])] && solid[index(dims, [4, y, 5])],
                "{y}"
            );
        }
    }
}
