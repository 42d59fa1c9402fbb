//! Round trips: each export read back by an independent reader (the project's own loaders
//! for VOX, raw and OBJ; the `npyz` crate for `.npy`) gives the voxels, or for OBJ the
//! exposed faces, that were written.

use std::collections::{HashMap, HashSet};
use std::path::Path;

use super::*;
use crate::load::{Format, LoadOptions, load_model};
use crate::model::Model;

fn asset(model: &str, level: u32) -> VoxelAsset {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../assets/models")
        .join(model);
    let m = load_model(&path).unwrap();
    crate::prepare::prepare_asset(&m, level, &crate::progress::NoProgress)
        .unwrap()
        .0
}

/// Cells shifted so that the smallest of each axis is 0.
fn normalized(cells: impl IntoIterator<Item = [i64; 3]>) -> HashSet<[i64; 3]> {
    let cells: Vec<[i64; 3]> = cells.into_iter().collect();
    let min: [i64; 3] = std::array::from_fn(|i| cells.iter().map(|c| c[i]).min().unwrap_or(0));
    cells
        .into_iter()
        .map(|c| std::array::from_fn(|i| c[i] - min[i]))
        .collect()
}

fn voxel_model(path: &Path) -> crate::model::VoxelModel {
    match load_model(path).unwrap() {
        Model::Voxels(v) => v,
        Model::Mesh(_) => panic!("{} loaded as a mesh", path.display()),
    }
}

#[test]
fn vox_and_raw_load_back_as_the_same_voxels() {
    let dir = tempfile::tempdir().unwrap();
    for (model, level) in [("chr_knight.vox", 5), ("teapot.obj", 6)] {
        let a = asset(model, level);
        let (edge, voxels) = level_voxels(&a, level).unwrap();
        let cells = normalized(voxels.iter().map(|v| v.cell.map(i64::from)));
        let vox = dir.path().join("out.vox");
        vox::write(&vox, edge, &voxels).unwrap();
        let back = voxel_model(&vox);
        assert_eq!(
            normalized(back.voxels.iter().map(|c| c.map(i64::from))),
            cells,
            "{model}"
        );
        // Colours: sRGB of the palette entry; the knight has fewer than 256 colours, so
        // each comes back as it was (up to the 8-bit sRGB round trip).
        if model.ends_with(".vox") {
            let want: HashMap<[i64; 3], [u8; 4]> = voxels
                .iter()
                .map(|v| (v.cell.map(i64::from), v.rgba))
                .collect();
            let min: [i64; 3] =
                std::array::from_fn(|i| back.voxels.iter().map(|c| i64::from(c[i])).min().unwrap());
            let vmin: [i64; 3] = std::array::from_fn(|i| want.keys().map(|c| c[i]).min().unwrap());
            for (c, col) in back.voxels.iter().zip(&back.colors) {
                let key: [i64; 3] = std::array::from_fn(|i| i64::from(c[i]) - min[i] + vmin[i]);
                let got = col.map(crate::shading::linear_to_srgb8);
                let w = want[&key];
                for i in 0..3 {
                    assert!(
                        got[i].abs_diff(w[i]) <= 1,
                        "{model} {key:?}: {got:?} vs {w:?}"
                    );
                }
            }
        }
        let raw = dir.path().join("out.raw");
        write_raw(&raw, edge, &voxels).unwrap();
        let back = voxel_model(&raw);
        assert_eq!(
            normalized(back.voxels.iter().map(|c| c.map(i64::from))),
            cells,
            "{model}"
        );
    }
    // Past 16³ models of 256³, VOX is refused before anything is written.
    let a = asset("chr_knight.vox", 2);
    let (_, voxels) = level_voxels(&a, 2).unwrap();
    let path = dir.path().join("big.vox");
    let e = vox::write(&path, 8192, &voxels).unwrap_err().to_string();
    assert!(e.contains("4096³ cells") && e.contains("--level 12"), "{e}");
    assert!(!path.exists());
}

/// The held models (MagicaVoxel's samples among them) prepared at a level, exported as
/// VOX, loaded again and prepared at the same level (keeping every loaded cell) give the
/// same cells and colours: the export is a fixed point of loading. At level 9 the grid is 512³, written as 256³
/// models placed by the scene graph, and `dot_vox`'s parser (an independent reader) finds
/// the same models and nodes.
#[test]
fn held_models_export_to_vox_and_load_back_unchanged() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        ("chr_knight.vox", 6),
        ("monu1.vox", 6),
        ("T-Rex.vox", 6),
        ("bunny.obj", 6),
        ("cow.obj", 6),
        ("igea.ply", 6),
        ("teapot.obj", 6),
        ("chr_knight.vox", 9),
    ];
    for (model, level) in cases {
        let a = asset(model, level);
        let (edge, voxels) = level_voxels(&a, level).unwrap();
        let out = dir.path().join(format!("{model}.{level}.vox"));
        vox::write(&out, edge, &voxels).unwrap();
        // Every cell loaded is kept (a mesh's surface cells can have six occupied
        // neighbours, which the default shell fill of voxel models would drop).
        let options = crate::prepare::PrepareOptions {
            voxel_fill: crate::voxelize::VoxelFill::Solid,
            ..Default::default()
        };
        let again = crate::prepare::prepare_asset_with(
            &Model::Voxels(voxel_model(&out)),
            level,
            &options,
            &crate::progress::NoProgress,
        )
        .unwrap()
        .0;
        let (_, back) = level_voxels(&again, level).unwrap();
        let cells = |v: &[ExportVoxel]| -> Vec<([u32; 3], [u8; 4])> {
            let mut c: Vec<_> = v.iter().map(|v| (v.cell, v.rgba)).collect();
            c.sort_unstable();
            c
        };
        assert_eq!(back.len(), voxels.len(), "{model} at level {level}");
        assert_eq!(cells(&back), cells(&voxels), "{model} at level {level}");
        if level > 8 {
            let parsed = dot_vox::load(out.to_str().unwrap()).unwrap();
            let models = parsed.models.len();
            assert!(models > 1 && models <= 8, "{models} models");
            assert!(parsed.models.iter().all(|m| m.size.x == 256));
            let voxel_total: usize = parsed.models.iter().map(|m| m.voxels.len()).sum();
            assert_eq!(voxel_total, voxels.len());
            assert_eq!(parsed.scenes.len(), 2 + 2 * models);
        }
    }
}

#[test]
fn npy_reads_back_with_npyz_dense_and_sparse() {
    let dir = tempfile::tempdir().unwrap();
    let a = asset("chr_knight.vox", 5);
    let (edge, voxels) = level_voxels(&a, 5).unwrap();
    let dense = dir.path().join("d.npy");
    npy::write_dense(&dense, edge, &voxels).unwrap();
    let bytes = std::fs::read(&dense).unwrap();
    let file = npyz::NpyFile::new(bytes.as_slice()).unwrap();
    let e = u64::from(edge);
    assert_eq!(file.shape(), &[e, e, e, 4]);
    let data: Vec<u8> = file.into_vec().unwrap();
    let occupied: HashSet<[u32; 3]> = (0..edge)
        .flat_map(|x| (0..edge).flat_map(move |y| (0..edge).map(move |z| [x, y, z])))
        .filter(|&[x, y, z]| data[(((x * edge + y) * edge + z) * 4 + 3) as usize] > 0)
        .collect();
    let want: HashSet<[u32; 3]> = voxels.iter().map(|v| v.cell).collect();
    assert_eq!(occupied, want);
    for v in &voxels {
        let [x, y, z] = v.cell;
        let i = (((x * edge + y) * edge + z) * 4) as usize;
        assert_eq!(data[i..i + 3], v.rgba[..3]);
    }
    let sparse = dir.path().join("s.npy");
    npy::write_sparse(&sparse, &voxels).unwrap();
    let bytes = std::fs::read(&sparse).unwrap();
    let file = npyz::NpyFile::new(bytes.as_slice()).unwrap();
    assert_eq!(file.shape(), &[voxels.len() as u64]);
    let npyz::DType::Record(fields) = file.dtype() else {
        panic!("not a record dtype: {:?}", file.dtype());
    };
    let names: Vec<&str> = fields.iter().map(|f| f.name.as_str()).collect();
    assert_eq!(names, ["x", "y", "z", "r", "g", "b", "a", "nx", "ny", "nz"]);
    let body = &bytes[bytes.len() - voxels.len() * 22..];
    for (rec, v) in body.chunks_exact(22).zip(&voxels) {
        let u = |i: usize| u32::from(u16::from_le_bytes([rec[i], rec[i + 1]]));
        assert_eq!([u(0), u(2), u(4)], v.cell);
        assert_eq!(rec[6..10], v.rgba);
        let nz = f32::from_le_bytes(rec[18..22].try_into().unwrap());
        assert_eq!(nz, v.normal[2]);
    }
    // A level-10 dense grid (4 GiB) is refused before anything is written.
    let big = dir.path().join("big.npy");
    let e = npy::write_dense(&big, 1024, &voxels)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("--sparse") && e.contains("coarser --level"),
        "{e}"
    );
    assert!(!big.exists());
}

/// The OBJ's triangles cover exactly the exposed unit faces: every exposed face's centre
/// lies in a triangle of its plane and facing, and the triangles' area per facing is the
/// count of exposed faces (no overlap, nothing extra).
#[test]
fn obj_is_the_exposed_faces() {
    let dir = tempfile::tempdir().unwrap();
    let a = asset("teapot.obj", 5);
    let (edge, voxels) = level_voxels(&a, 5).unwrap();
    let path = dir.path().join("s.obj");
    let rects = obj::write(&path, edge, &voxels, &a.object_space).unwrap();
    let occupied: HashSet<[i64; 3]> = voxels.iter().map(|v| v.cell.map(i64::from)).collect();
    let mut exposed: Vec<([f64; 3], usize, bool)> = Vec::new();
    for c in &occupied {
        for axis in 0..3 {
            for positive in [false, true] {
                let mut n = *c;
                n[axis] += if positive { 1 } else { -1 };
                if occupied.contains(&n) {
                    continue;
                }
                let mut centre = c.map(|x| x as f64 + 0.5);
                centre[axis] = (c[axis] + i64::from(positive)) as f64;
                exposed.push((centre, axis, positive));
            }
        }
    }
    assert!(
        rects < exposed.len() / 2,
        "{rects} rectangles for {} faces",
        exposed.len()
    );
    let bytes = std::fs::read(&path).unwrap();
    let loaded =
        crate::load::load_from_bytes(&bytes, Format::Obj, &path, None, &LoadOptions::default())
            .unwrap();
    let Model::Mesh(mesh) = loaded.model else {
        panic!("not a mesh")
    };
    // Back to grid units.
    let s = &a.object_space;
    let grid = |p: [f32; 3]| -> [f64; 3] {
        std::array::from_fn(|i| {
            ((f64::from(p[i]) - s.center[i]) * s.scale + 1.0) * f64::from(edge) / 2.0
        })
    };
    let mut area = HashMap::new();
    type Triangle = [[f64; 3]; 3];
    let mut tris: HashMap<(usize, bool, i64), Vec<Triangle>> = HashMap::new();
    for t in &mesh.triangles {
        let p = t.map(|i| grid(mesh.positions[i as usize].to_array()));
        let e1: [f64; 3] = std::array::from_fn(|i| p[1][i] - p[0][i]);
        let e2: [f64; 3] = std::array::from_fn(|i| p[2][i] - p[0][i]);
        let n = [
            e1[1] * e2[2] - e1[2] * e2[1],
            e1[2] * e2[0] - e1[0] * e2[2],
            e1[0] * e2[1] - e1[1] * e2[0],
        ];
        let axis = (0..3)
            .max_by(|&a, &b| n[a].abs().total_cmp(&n[b].abs()))
            .unwrap();
        let positive = n[axis] > 0.0;
        *area.entry((axis, positive)).or_insert(0.0) += n[axis].abs() / 2.0;
        tris.entry((axis, positive, p[0][axis].round() as i64))
            .or_default()
            .push(p);
    }
    let inside = |t: &[[f64; 3]; 3], q: [f64; 3], axis: usize| {
        let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
        let d = |a: [f64; 3], b: [f64; 3]| {
            (b[u] - a[u]) * (q[v] - a[v]) - (b[v] - a[v]) * (q[u] - a[u])
        };
        let s = [d(t[0], t[1]), d(t[1], t[2]), d(t[2], t[0])];
        s.iter().all(|&x| x >= -1e-6) || s.iter().all(|&x| x <= 1e-6)
    };
    for (centre, axis, positive) in &exposed {
        let plane = centre[*axis].round() as i64;
        let found = tris
            .get(&(*axis, *positive, plane))
            .is_some_and(|ts| ts.iter().any(|t| inside(t, *centre, *axis)));
        assert!(
            found,
            "exposed face at {centre:?} ({axis}, {positive}) not covered"
        );
    }
    // Vertex colours come back as the voxels' (up to the 8-bit sRGB round trip).
    let colours: HashSet<[u8; 3]> = voxels
        .iter()
        .map(|v| [v.rgba[0], v.rgba[1], v.rgba[2]])
        .collect();
    assert_eq!(mesh.colors.len(), mesh.positions.len());
    for c in &mesh.colors {
        let srgb = [0, 1, 2].map(|i| crate::shading::linear_to_srgb8(c[i]));
        assert!(
            colours
                .iter()
                .any(|k| (0..3).all(|i| k[i].abs_diff(srgb[i]) <= 1)),
            "{srgb:?}"
        );
    }
    for axis in 0..3 {
        for positive in [false, true] {
            let want = exposed
                .iter()
                .filter(|e| e.1 == axis && e.2 == positive)
                .count() as f64;
            let got = area.get(&(axis, positive)).copied().unwrap_or(0.0);
            assert!(
                (got - want).abs() < 1e-3 * want.max(1.0),
                "{axis} {positive}: {got} vs {want}"
            );
        }
    }
}
