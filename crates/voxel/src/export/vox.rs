//! MagicaVoxel `.vox` (format 150), written with `dot_vox`'s writer: one model of the
//! level's grid (`edge`³, at most 256³, the format's limit per model), its voxels coloured
//! by a palette of the closest 255 colours ([`super::palette`]). MagicaVoxel is Z-up: cell
//! `(x, y, z)` of the renderer's Y-up grid is voxel `(x, edge − 1 − z, y)`, the inverse of
//! the reader's rotation, so that `ssbvb` loads it back as it was.
//!
//! Levels finer than 8 would need several 256³ models placed by the format's scene-graph
//! extension; that is not written yet, and such an export is refused with what avoids it.

use std::path::Path;

use super::common::{ExportError, ExportFormat, ExportVoxel, check_size};
use super::palette;

/// Writes the voxels of an `edge`³ grid as one VOX model.
pub fn write(path: &Path, edge: u32, voxels: &[ExportVoxel]) -> Result<(), ExportError> {
    check_size(ExportFormat::Vox, edge)?;
    let colors: Vec<[u8; 4]> = voxels.iter().map(|v| v.rgba).collect();
    let (entries, index) = palette::quantize(&colors, 255);
    let mut palette: Vec<dot_vox::Color> = entries
        .iter()
        .map(|c| dot_vox::Color {
            r: c[0],
            g: c[1],
            b: c[2],
            a: c[3],
        })
        .collect();
    palette.resize(
        256,
        dot_vox::Color {
            r: 0,
            g: 0,
            b: 0,
            a: 255,
        },
    );
    let model = dot_vox::Model {
        size: dot_vox::Size {
            x: edge,
            y: edge,
            z: edge,
        },
        voxels: voxels
            .iter()
            .map(|v| {
                let [x, y, z] = v.cell;
                dot_vox::Voxel {
                    x: x as u8,
                    y: (edge - 1 - z) as u8,
                    z: y as u8,
                    i: index[&v.rgba],
                }
            })
            .collect(),
    };
    let data = dot_vox::DotVoxData {
        version: 150,
        index_map: Vec::new(),
        models: vec![model],
        palette,
        materials: Vec::new(),
        scenes: Vec::new(),
        layers: Vec::new(),
    };
    let mut bytes = Vec::new();
    data.write_vox(&mut bytes)
        .map_err(|e| crate::load::LoadError::io(path, e))?;
    crate::load::write_atomically(path, &[&bytes])?;
    Ok(())
}
