//! The real test models (`assets/models`): exact counts, agreement with `tobj` and
//! `dot_vox`, and truncated or flipped copies that must never panic.

use std::collections::HashMap;
use std::time::Instant;

use ssbvb_voxel::load::{
    Format, LoadOptions, load_mesh, load_model, load_model_with, load_vox_model, srgb_to_linear,
};
use ssbvb_voxel::model::VoxelModel;

use crate::{
    approx, assert_mesh_invariants, bounds, mesh_of, model, models_dir, mutate_and_parse, parse,
    voxels_of,
};

#[test]
fn bunny_obj_loads_with_exact_counts() {
    let t = Instant::now();
    let m = load_mesh(&model("bunny.obj")).unwrap();
    eprintln!("bunny: {:?}", t.elapsed());
    assert_eq!(m.triangles.len(), 69_451);
    // The file has 35,947 vertices, 1,113 of which no face uses; de-indexing keeps the
    // 34,834 referenced ones (unreferenced vertices would only distort the bounds).
    assert_eq!(m.positions.len(), 34_834);
    assert_mesh_invariants(&m);
    let (lo, hi) = bounds(m.positions.iter().copied());
    let extent = hi - lo;
    assert!(
        extent.min_element() > 0.01 && extent.max_element() < 10.0,
        "bunny bounds {lo} {hi}"
    );
    assert!(m.materials.is_empty() && m.triangle_materials.is_empty());
}

#[test]
fn teapot_and_cow_obj_load() {
    for (name, faces) in [("teapot.obj", 6_320), ("cow.obj", 5_804)] {
        let m = mesh_of(load_model(&model(name)).unwrap());
        assert_mesh_invariants(&m);
        assert!(
            m.triangles.len() >= faces,
            "{name}: {} triangles for {faces} faces",
            m.triangles.len()
        );
    }
}

/// Differential test: our OBJ reader against `tobj` on the test models (same triangles,
/// same corner positions).
#[test]
fn obj_reader_agrees_with_tobj() {
    for name in ["bunny.obj", "teapot.obj", "cow.obj"] {
        let path = model(name);
        let ours = load_mesh(&path).unwrap();
        let options = tobj::LoadOptions {
            triangulate: true,
            single_index: true,
            ..Default::default()
        };
        let (models, _) = tobj::load_obj(&path, &options).unwrap();
        let mut theirs: Vec<[f32; 9]> = Vec::new();
        for model in &models {
            let mesh = &model.mesh;
            for tri in mesh.indices.chunks_exact(3) {
                let mut corners = [0f32; 9];
                for (k, &i) in tri.iter().enumerate() {
                    corners[k * 3..k * 3 + 3]
                        .copy_from_slice(&mesh.positions[i as usize * 3..i as usize * 3 + 3]);
                }
                theirs.push(corners);
            }
        }
        assert_eq!(ours.triangles.len(), theirs.len(), "{name}: triangle count");
        for (t, expected) in ours.triangles.iter().zip(&theirs) {
            for k in 0..3 {
                let p = ours.positions[t[k] as usize];
                assert_eq!(
                    [p.x, p.y, p.z],
                    expected[k * 3..k * 3 + 3],
                    "{name}: corner differs"
                );
            }
        }
    }
}

#[test]
fn igea_ply_tristrips_load() {
    let t = Instant::now();
    let m = load_mesh(&model("igea.ply")).unwrap();
    eprintln!("igea: {:?}, {} triangles", t.elapsed(), m.triangles.len());
    assert_eq!(m.positions.len(), 134_345);
    assert_mesh_invariants(&m);
    // igea is a closed genus-0 surface: Euler's formula gives T = 2V − 4 exactly, which
    // only holds if strips, restarts and stitching triangles are all decoded right.
    assert_eq!(m.triangles.len(), 2 * 134_345 - 4);
    assert!(
        m.triangles
            .iter()
            .all(|t| t[0] != t[1] && t[1] != t[2] && t[0] != t[2])
    );
    // Strips alternate winding: on a consistently wound closed surface every directed edge
    // appears exactly once, and its reverse once.
    let mut directed: HashMap<(u32, u32), u32> = HashMap::new();
    for t in &m.triangles {
        for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
            *directed.entry((a, b)).or_default() += 1;
        }
    }
    assert!(
        directed.values().all(|&c| c == 1),
        "igea: a directed edge repeats: inconsistent winding"
    );
    assert!(
        directed
            .keys()
            .all(|&(a, b)| directed.contains_key(&(b, a))),
        "igea: not closed"
    );
}

/// Differential test against `dot_vox`: same voxels (converted) and colours.
#[test]
fn vox_reader_agrees_with_dot_vox() {
    for name in ["chr_knight.vox", "T-Rex.vox", "monu1.vox"] {
        let path = model(name);
        let data = dot_vox::load(path.to_str().unwrap()).unwrap();
        for (k, model) in data.models.iter().enumerate() {
            let ours = load_vox_model(&path, k).unwrap();
            assert_eq!(
                ours.voxels.len(),
                model.voxels.len(),
                "{name} model {k}: voxel count"
            );
            for (v, (p, c)) in model
                .voxels
                .iter()
                .zip(ours.voxels.iter().zip(&ours.colors))
            {
                // Z-up → Y-up: (x, y, z) ↦ (x, z, −y − 1) for the cube's minimum corner.
                assert_eq!(
                    *p,
                    [v.x as i32, v.z as i32, -(v.y as i32) - 1],
                    "{name}: position"
                );
                let col = data.palette[v.i as usize];
                let expected = [
                    srgb_to_linear(col.r as f32 / 255.0),
                    srgb_to_linear(col.g as f32 / 255.0),
                ];
                assert!(
                    approx(c[0], expected[0]) && approx(c[1], expected[1]),
                    "{name}: colour"
                );
                assert!(approx(c[3], col.a as f32 / 255.0));
            }
        }
        assert!(load_vox_model(&path, data.models.len()).is_err());
    }
}

#[test]
fn vox_shared_models_load_whole() {
    // T-Rex: 8 animation frames, no scene graph: all frames at their own origin.
    let trex = voxels_of(load_model(&model("T-Rex.vox")).unwrap());
    let frame0 = load_vox_model(&model("T-Rex.vox"), 0).unwrap();
    assert!(trex.voxels.len() >= frame0.voxels.len());
    let (lo, hi) = voxel_bounds(&trex);
    assert!(
        lo.iter().zip(hi).all(|(l, h)| h - l < 26 && *l >= -26),
        "T-Rex bounds {lo:?} {hi:?}"
    );

    for name in ["chr_knight.vox", "monu1.vox"] {
        let v = voxels_of(load_model(&model(name)).unwrap());
        assert_eq!(v.voxels.len(), v.colors.len());
        let (lo, hi) = voxel_bounds(&v);
        assert!(
            lo.iter().zip(hi).all(|(l, h)| h - l < 256),
            "{name} bounds {lo:?} {hi:?}"
        );
        // Y-up: the Z extent of MagicaVoxel becomes the Y extent.
        let data = dot_vox::load(model(name).to_str().unwrap()).unwrap();
        let size = data.models[0].size;
        assert!(hi[1] - lo[1] < size.z as i32 && hi[2] - lo[2] < size.y as i32);
        let mut unique = v.voxels.clone();
        unique.sort();
        unique.dedup();
        assert_eq!(unique.len(), v.voxels.len(), "{name}: duplicate voxels");
    }
}

fn voxel_bounds(v: &VoxelModel) -> ([i32; 3], [i32; 3]) {
    let mut lo = [i32::MAX; 3];
    let mut hi = [i32::MIN; 3];
    for p in &v.voxels {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    (lo, hi)
}

#[test]
fn every_shared_model_loads_through_load_model() {
    for entry in std::fs::read_dir(models_dir()).unwrap() {
        let path = entry.unwrap().path();
        if Format::from_path(&path).is_some() {
            let loaded = load_model_with(&path, &LoadOptions::default()).unwrap();
            assert!(
                loaded.warnings.is_empty(),
                "{}: {:?}",
                path.display(),
                loaded.warnings
            );
        }
    }
}

#[test]
fn truncated_and_flipped_real_models_never_panic() {
    for (name, format, truncations, flips) in [
        ("chr_knight.vox", Format::Vox, 400, 400),
        ("T-Rex.vox", Format::Vox, 150, 150),
        ("cow.obj", Format::Obj, 60, 60),
        ("igea.ply", Format::Ply, 12, 12),
    ] {
        let bytes = std::fs::read(model(name)).unwrap();
        mutate_and_parse(&bytes, format, name, truncations, flips);
    }
    // The PLY header and the first vertices, cut and flipped densely.
    let igea = std::fs::read(model("igea.ply")).unwrap();
    let mut head = igea[..4096].to_vec();
    // Keep it consistent: declare as many vertices as the 4096 bytes can hold, no strips.
    let text = String::from_utf8_lossy(&head[..200]).into_owned();
    let end = text.find("end_header\n").unwrap() + "end_header\n".len();
    let body = &igea[end..4096];
    let n = body.len() / 12;
    let header = format!(
        "ply\nformat binary_little_endian 1.0\nelement vertex {n}\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
    );
    head = header.into_bytes();
    head.extend_from_slice(&body[..n * 12]);
    head.extend_from_slice(&[3, 0, 0, 0, 0, 1, 0, 0, 0, 2, 0, 0, 0]);
    assert_eq!(
        mesh_of(parse(&head, Format::Ply, "head.ply").unwrap())
            .triangles
            .len(),
        1
    );
    mutate_and_parse(&head, Format::Ply, "head.ply", 300, 600);
}
