//! NumPy `.npy` files (format version 1.0), written here rather than through a crate
//! because the format is a short text header before the raw array, and the structured
//! dtype of the sparse form is one line of it; the tests read the files back with the
//! `npyz` crate. `numpy.load(path)` reads both forms with `allow_pickle=False`.
//!
//! - **Dense** (default): `uint8`, shape `(X, Y, Z, 4)`, C order, index `[x, y, z, c]`:
//!   sRGB-encoded RGBA, alpha 0 where a cell is empty (alpha 255 × the voxel's where it
//!   is occupied, never 0).
//! - **Sparse** (`--sparse`): one record per voxel, dtype
//!   `[('x','<u2'),('y','<u2'),('z','<u2'),('r','u1'),('g','u1'),('b','u1'),('a','u1'),
//!   ('nx','<f4'),('ny','<f4'),('nz','<f4')]`.

use std::path::Path;

use super::common::{ExportError, ExportFormat, ExportVoxel, check_size};

/// The sparse form's record dtype, as the header writes it.
pub const SPARSE_DTYPE: &str = "[('x', '<u2'), ('y', '<u2'), ('z', '<u2'), ('r', '|u1'), \
('g', '|u1'), ('b', '|u1'), ('a', '|u1'), ('nx', '<f4'), ('ny', '<f4'), ('nz', '<f4')]";

/// The `.npy` header for `descr` and `shape`, padded so the data starts on 64 bytes.
fn header(descr: &str, shape: &[u64]) -> Vec<u8> {
    let dims: Vec<String> = shape.iter().map(u64::to_string).collect();
    let shape = if dims.len() == 1 {
        format!("({},)", dims[0])
    } else {
        format!("({})", dims.join(", "))
    };
    let dict = format!("{{'descr': {descr}, 'fortran_order': False, 'shape': {shape}, }}");
    let mut out = b"\x93NUMPY\x01\x00".to_vec();
    let unpadded = out.len() + 2 + dict.len() + 1;
    let len = unpadded.div_ceil(64) * 64 - out.len() - 2;
    out.extend_from_slice(&(len as u16).to_le_bytes());
    out.extend_from_slice(dict.as_bytes());
    out.resize(out.len() + len - dict.len() - 1, b' ');
    out.push(b'\n');
    out
}

/// The dense RGBA grid of `shape` (C order, index `[x, y, z, c]`) holding `voxels` (cell,
/// sRGB RGBA): alpha 0 where a cell is empty, at least 1 where it is occupied. Every cell
/// must lie inside `shape`.
pub fn dense_grid(
    shape: [usize; 3],
    voxels: impl IntoIterator<Item = ([usize; 3], [u8; 4])>,
) -> Vec<u8> {
    let mut grid = vec![0u8; shape.iter().product::<usize>() * 4];
    for ([x, y, z], mut rgba) in voxels {
        let i = ((x * shape[1] + y) * shape[2] + z) * 4;
        rgba[3] = rgba[3].max(1);
        grid[i..i + 4].copy_from_slice(&rgba);
    }
    grid
}

/// Writes the dense RGBA grid of `edge`³ cells.
pub fn write_dense(path: &Path, edge: u32, voxels: &[ExportVoxel]) -> Result<(), ExportError> {
    check_size(ExportFormat::Npy { sparse: false }, edge)?;
    let e = edge as usize;
    let grid = dense_grid(
        [e; 3],
        voxels.iter().map(|v| (v.cell.map(|c| c as usize), v.rgba)),
    );
    let e = u64::from(edge);
    let head = header("'|u1'", &[e, e, e, 4]);
    crate::load::write_atomically(path, &[&head, &grid])?;
    Ok(())
}

/// Writes the sparse voxel list (streamed: no copy of the records is held).
pub fn write_sparse(path: &Path, voxels: &[ExportVoxel]) -> Result<(), ExportError> {
    let head = header(SPARSE_DTYPE, &[voxels.len() as u64]);
    crate::load::write_atomically_with(path, |w| {
        w.write_all(&head)?;
        for v in voxels {
            let mut record = [0u8; 22];
            for (i, c) in v.cell.iter().enumerate() {
                record[2 * i..2 * i + 2].copy_from_slice(&(*c as u16).to_le_bytes());
            }
            record[6..10].copy_from_slice(&v.rgba);
            for (i, n) in v.normal.iter().enumerate() {
                record[10 + 4 * i..14 + 4 * i].copy_from_slice(&n.to_le_bytes());
            }
            w.write_all(&record)?;
        }
        Ok(())
    })?;
    Ok(())
}
