//! PLY reader: ASCII, binary little-endian and binary big-endian.
//!
//! Hand-written (the header is simple) so that every error can name the line (ASCII) or
//! byte offset (binary), every declared count is checked against the bytes that follow the
//! header before anything is allocated, and `tristrips` elements (as in `igea.ply`) are
//! read, which generic PLY crates leave to the caller.
//!
//! Read: the `vertex` element (`x y z` as any numeric type; optional `nx ny nz`; optional
//! `red green blue [alpha]` or `r g b [a]`, integers normalised by their type's maximum,
//! floats taken as they are, both sRGB-decoded; optional `u v`, `s t`, `texture_u
//! texture_v` or `texture_s texture_t`), the `face` element (`vertex_indices` or
//! `vertex_index` list, polygons fan-triangulated) and the `tristrips` element
//! (`vertex_indices` list, `-1` restarts a strip). Every other element is skipped.
//!
//! Layout: the header (`header`), value readers for the ASCII and binary encodings
//! (`reader`) and the elements of the body (`body`).

mod body;
mod header;
mod reader;

use std::path::Path;

use super::error::LoadError;
use crate::model::Mesh;
use body::read_body;
use header::{Encoding, check_counts, parse_header};
use reader::{AsciiReader, BinaryReader};

/// Parses a PLY file held in memory.
pub(super) fn parse(
    bytes: &[u8],
    path: &Path,
    warnings: &mut Vec<String>,
) -> Result<Mesh, LoadError> {
    let header = parse_header(bytes, path)?;
    let body = bytes.get(header.body_start..).unwrap_or_default();
    check_counts(&header, body.len() as u64, path)?;
    match header.encoding {
        Encoding::Ascii => {
            let mut r = AsciiReader {
                data: body,
                pos: 0,
                line: header.body_line,
                path,
            };
            read_body(&mut r, &header, path, warnings)
        }
        Encoding::BinaryLe | Encoding::BinaryBe => {
            let mut r = BinaryReader {
                data: body,
                pos: 0,
                base: header.body_start as u64,
                big_endian: header.encoding == Encoding::BinaryBe,
                path,
            };
            read_body(&mut r, &header, path, warnings)
        }
    }
}
