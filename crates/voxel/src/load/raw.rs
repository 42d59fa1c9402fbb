//! The project's raw dense grid: `SSBVBRAW <nx> <ny> <nz>\n` then `nx·ny·nz` bytes, x
//! fastest, then y, then z; 0 = empty, otherwise an sRGB grey level (see
//! [`write_raw`](super::write_raw)).

use std::fs::File;
use std::io::{self, Read};
use std::path::Path;

use super::common::{MAX_RAW_DIM, MAX_VOXELS, srgb_u8_table};
use super::error::LoadError;
use crate::model::VoxelModel;

/// The first bytes of every raw grid file.
pub(super) const MAGIC: &[u8] = b"SSBVBRAW";
/// The header line is never longer than this (`SSBVBRAW 4096 4096 4096\n` is 24 bytes).
const MAX_HEADER: usize = 64;

/// Checks grid dimensions and returns the cell count.
pub(super) fn checked_cells(path: &Path, nx: u32, ny: u32, nz: u32) -> Result<u64, LoadError> {
    for d in [nx, ny, nz] {
        if d == 0 {
            return Err(LoadError::parse(
                path,
                "raw grid dimensions must be at least 1",
            ));
        }
        if d > MAX_RAW_DIM {
            return Err(LoadError::too_large(
                path,
                "cells along a raw grid axis",
                d.into(),
                MAX_RAW_DIM.into(),
            ));
        }
    }
    // At most 4096³ = 2^36: no overflow in u64.
    Ok(u64::from(nx) * u64::from(ny) * u64::from(nz))
}

/// Parses the header line at the start of `head`: the dimensions and the header length.
fn parse_header(head: &[u8], path: &Path) -> Result<([u32; 3], usize), LoadError> {
    if !head.starts_with(MAGIC) {
        return Err(LoadError::at_offset(
            path,
            0,
            "not a raw grid (no `SSBVBRAW` magic)",
        ));
    }
    let limit = head.len().min(MAX_HEADER);
    let newline = head[..limit]
        .iter()
        .position(|&b| b == b'\n')
        .ok_or_else(|| {
            LoadError::at_line(path, 1, "header line is not terminated within 64 bytes")
        })?;
    let line = std::str::from_utf8(&head[..newline])
        .map_err(|_| LoadError::at_line(path, 1, "header line is not ASCII"))?;
    let words: Vec<&str> = line.split_ascii_whitespace().collect();
    let ["SSBVBRAW", x, y, z] = words[..] else {
        return Err(LoadError::at_line(
            path,
            1,
            "expected `SSBVBRAW <nx> <ny> <nz>`",
        ));
    };
    let dim = |s: &str| {
        s.parse::<u32>()
            .map_err(|_| LoadError::at_line(path, 1, format!("dimension {s:?} is not a number")))
    };
    Ok(([dim(x)?, dim(y)?, dim(z)?], newline + 1))
}

/// Collects the occupied cells of a grid fed in order, in pieces of any size.
struct Scanner {
    dims: [u32; 3],
    cell: [u32; 3],
    grey: [f32; 256],
    out: VoxelModel,
}

impl Scanner {
    fn new(dims: [u32; 3]) -> Self {
        Scanner {
            dims,
            cell: [0; 3],
            grey: srgb_u8_table(),
            out: VoxelModel::default(),
        }
    }

    fn feed(&mut self, bytes: &[u8], path: &Path) -> Result<(), LoadError> {
        for &b in bytes {
            if b != 0 {
                if self.out.voxels.len() >= MAX_VOXELS {
                    return Err(LoadError::too_large(
                        path,
                        "occupied cells",
                        MAX_VOXELS as u64 + 1,
                        MAX_VOXELS as u64,
                    ));
                }
                // Dimensions are at most 4096: the cast to i32 is exact.
                self.out.voxels.push(self.cell.map(|c| c as i32));
                let g = self.grey[b as usize];
                self.out.colors.push([g, g, g, 1.0]);
            }
            self.cell[0] += 1;
            if self.cell[0] == self.dims[0] {
                self.cell[0] = 0;
                self.cell[1] += 1;
                if self.cell[1] == self.dims[1] {
                    self.cell[1] = 0;
                    self.cell[2] += 1;
                }
            }
        }
        Ok(())
    }
}

fn length_error(
    path: &Path,
    header_len: usize,
    dims: [u32; 3],
    cells: u64,
    body: u64,
) -> LoadError {
    LoadError::at_offset(
        path,
        header_len as u64,
        format!(
            "header declares {}×{}×{} = {cells} cells, but {body} bytes follow the header",
            dims[0], dims[1], dims[2]
        ),
    )
}

/// Parses a raw grid held in memory.
pub(super) fn parse_bytes(bytes: &[u8], path: &Path) -> Result<VoxelModel, LoadError> {
    let (dims, header_len) = parse_header(bytes, path)?;
    let cells = checked_cells(path, dims[0], dims[1], dims[2])?;
    let body = bytes.get(header_len..).unwrap_or_default();
    if body.len() as u64 != cells {
        return Err(length_error(
            path,
            header_len,
            dims,
            cells,
            body.len() as u64,
        ));
    }
    let mut s = Scanner::new(dims);
    s.feed(body, path)?;
    Ok(s.out)
}

/// Streams a raw grid from disk (it may be far larger than memory would like), after
/// checking that the file length matches the header exactly.
pub(super) fn load_path(path: &Path) -> Result<VoxelModel, LoadError> {
    let io_err = |e: io::Error| LoadError::io(path, e);
    let mut file = File::open(path).map_err(io_err)?;
    let len = file.metadata().map_err(io_err)?.len();
    let mut head = [0u8; MAX_HEADER];
    let mut n = 0;
    while n < head.len() {
        match file.read(&mut head[n..]) {
            Ok(0) => break,
            Ok(k) => n += k,
            Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
            Err(e) => return Err(io_err(e)),
        }
    }
    let (dims, header_len) = parse_header(&head[..n], path)?;
    let cells = checked_cells(path, dims[0], dims[1], dims[2])?;
    let body_len = len.saturating_sub(header_len as u64);
    if body_len != cells {
        return Err(length_error(path, header_len, dims, cells, body_len));
    }
    let mut s = Scanner::new(dims);
    s.feed(&head[header_len..n], path)?;
    let mut remaining = cells - (n - header_len) as u64;
    let mut buf = vec![0u8; 1 << 20];
    while remaining > 0 {
        let want = buf
            .len()
            .min(usize::try_from(remaining).unwrap_or(usize::MAX));
        let got = match file.read(&mut buf[..want]) {
            Ok(0) => {
                return Err(LoadError::at_offset(
                    path,
                    len - remaining,
                    "file shrank while being read",
                ));
            }
            Ok(k) => k,
            Err(e) if e.kind() == io::ErrorKind::Interrupted => continue,
            Err(e) => return Err(io_err(e)),
        };
        s.feed(&buf[..got], path)?;
        remaining -= got as u64;
    }
    Ok(s.out)
}
