//! MagicaVoxel `.vox` (format 150), written with `dot_vox`'s writer, its voxels coloured
//! by a palette of the closest 255 colours ([`super::palette`]). MagicaVoxel is Z-up: cell
//! `(x, y, z)` of the renderer's Y-up grid is voxel `(x, edge − 1 − z, y)`, the inverse of
//! the reader's rotation, so that `ssbvb` loads it back as it was.
//!
//! A grid of at most 256³ (level 8) is one model without a scene graph. A larger one is
//! split into 256³ models, the non-empty ones written, each placed by the scene-graph
//! extension (MagicaVoxel's `vox-extension` notes): a root `nTRN`
//! over one `nGRP`, and per model an `nTRN` whose `_t` puts it in place over an `nSHP`.
//! MagicaVoxel centres a model of size `s` on its pivot `floor(s / 2)`, so the translation
//! of the model at MagicaVoxel offset `o` is `o + 128 − edge / 2`: the whole grid centred
//! on the origin.

use std::collections::BTreeMap;
use std::path::Path;

use super::common::{ExportError, ExportFormat, ExportVoxel, MAX_VOX_EDGE, check_size};
use super::palette;

/// Writes the voxels of an `edge`³ grid as VOX: one model, or 256³ models in a scene
/// graph when `edge` is larger.
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
    // MagicaVoxel coordinates, by 256³ model.
    let side = edge.min(MAX_VOX_EDGE);
    let mut models: BTreeMap<[u32; 3], Vec<dot_vox::Voxel>> = BTreeMap::new();
    for v in voxels {
        let [x, y, z] = v.cell;
        let m = [x, edge - 1 - z, y];
        models
            .entry(m.map(|c| c / side))
            .or_default()
            .push(dot_vox::Voxel {
                x: (m[0] % side) as u8,
                y: (m[1] % side) as u8,
                z: (m[2] % side) as u8,
                i: index[&v.rgba],
            });
    }
    if models.is_empty() {
        models.insert([0, 0, 0], Vec::new());
    }
    let size = dot_vox::Size {
        x: side,
        y: side,
        z: side,
    };
    let scenes = if edge > MAX_VOX_EDGE {
        scene_graph(models.keys(), edge, side)
    } else {
        Vec::new()
    };
    let data = dot_vox::DotVoxData {
        version: 150,
        index_map: Vec::new(),
        models: models
            .into_values()
            .map(|voxels| dot_vox::Model { size, voxels })
            .collect(),
        palette,
        materials: Vec::new(),
        scenes,
        layers: vec![dot_vox::Layer {
            attributes: dot_vox::Dict::new(),
        }],
    };
    let mut bytes = Vec::new();
    data.write_vox(&mut bytes)
        .map_err(|e| crate::load::LoadError::io(path, e))?;
    crate::load::write_atomically(path, &[&bytes])?;
    Ok(())
}

/// The scene graph placing the models at `offsets` (in units of `side`, the models'
/// order) in an `edge`³ grid centred on the origin: node 0 the root transform, node 1 the
/// group, then a transform and a shape per model.
fn scene_graph<'a>(
    offsets: impl Iterator<Item = &'a [u32; 3]>,
    edge: u32,
    side: u32,
) -> Vec<dot_vox::SceneNode> {
    let offsets: Vec<[u32; 3]> = offsets.copied().collect();
    let mut nodes = vec![
        dot_vox::SceneNode::Transform {
            attributes: dot_vox::Dict::new(),
            frames: vec![dot_vox::Frame::new(dot_vox::Dict::new())],
            child: 1,
            layer_id: u32::MAX,
        },
        dot_vox::SceneNode::Group {
            attributes: dot_vox::Dict::new(),
            children: (0..offsets.len() as u32).map(|k| 2 + 2 * k).collect(),
        },
    ];
    let half = i64::from(edge / 2);
    let pivot = i64::from(side / 2);
    for (k, o) in offsets.iter().enumerate() {
        let t = o.map(|c| i64::from(c) * i64::from(side) + pivot - half);
        let mut frame = dot_vox::Dict::new();
        frame.insert("_t".into(), format!("{} {} {}", t[0], t[1], t[2]));
        nodes.push(dot_vox::SceneNode::Transform {
            attributes: dot_vox::Dict::new(),
            frames: vec![dot_vox::Frame::new(frame)],
            child: 3 + 2 * k as u32,
            layer_id: 0,
        });
        nodes.push(dot_vox::SceneNode::Shape {
            attributes: dot_vox::Dict::new(),
            models: vec![dot_vox::ShapeModel {
                model_id: k as u32,
                attributes: dot_vox::Dict::new(),
            }],
        });
    }
    nodes
}
