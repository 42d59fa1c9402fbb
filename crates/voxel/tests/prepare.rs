//! End-to-end preparation of the real models in `assets/models`: load → voxelize → LOD
//! chain → point clouds, lookups, proxies → cache round trip.

use std::path::PathBuf;

use ssbvb_voxel::asset::VoxelAsset;
use ssbvb_voxel::cache::{CacheStatus, load_or_prepare, read_cache, write_cache};
use ssbvb_voxel::load::load_model;
use ssbvb_voxel::model::{Model, cell_size};
use ssbvb_voxel::prepare::prepare_asset;
use ssbvb_voxel::progress::NoProgress;
use ssbvb_voxel::svo::{Svo, morton_encode};
use ssbvb_voxel::voxelize::{mesh_object_space, voxel_model_object_space};

const MODELS: [&str; 7] = [
    "bunny.obj",
    "teapot.obj",
    "cow.obj",
    "igea.ply",
    "chr_knight.vox",
    "T-Rex.vox",
    "monu1.vox",
];

/// The repository's test models (`assets/models`). Their absence is a failure: these tests
/// are the only ones that run the whole preparation on real data.
fn models_dir() -> PathBuf {
    let dir = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../assets/models"));
    assert!(
        dir.is_dir(),
        "test models folder missing: {}",
        dir.display()
    );
    dir
}

/// Structural checks every prepared asset must pass.
fn check_asset(name: &str, asset: &VoxelAsset, level: u32) {
    assert_eq!(asset.lods.len(), level as usize + 1, "{name}");
    for (l, lod) in asset.lods.iter().enumerate() {
        let cells: Vec<[u32; 3]> = lod.point_cloud.voxels.iter().map(|v| v.cell()).collect();
        assert!(!cells.is_empty(), "{name}: level {l} empty");
        assert!(
            cells
                .windows(2)
                .all(|w| morton_encode(w[0]) < morton_encode(w[1])),
            "{name}: level {l} not in Morton order"
        );
        for (id, c) in cells.iter().enumerate() {
            assert_eq!(
                lod.lookup.get(*c),
                Some(id as u32),
                "{name}: level {l} cell {c:?}"
            );
        }
        for v in &lod.point_cloud.voxels {
            assert!(
                v.normal().iter().all(|x| x.is_finite()),
                "{name}: NaN normal"
            );
        }
        // Each coarse level's cells are exactly the parents of the finer level's cells.
        if l + 1 < asset.lods.len() {
            let mut parents: Vec<u64> = asset.lods[l + 1]
                .point_cloud
                .voxels
                .iter()
                .map(|v| morton_encode(v.cell()) >> 3)
                .collect();
            parents.dedup();
            let codes: Vec<u64> = cells.iter().map(|&c| morton_encode(c)).collect();
            assert_eq!(
                parents,
                codes,
                "{name}: level {l} is not the parents of level {}",
                l + 1
            );
        }
        // Every level has a proxy; that it encloses the voxels is checked on the coarse
        // levels only (9 winding queries per voxel are slow in debug builds, and
        // crate::proxy tests the property itself).
        assert!(
            !lod.proxy.triangles.is_empty(),
            "{name}: level {l} has no proxy"
        );
        if l <= 4 {
            ssbvb_voxel::proxy::proxy_encloses(&lod.lookup, &lod.proxy)
                .unwrap_or_else(|e| panic!("{name}: level {l} proxy: {e}"));
        }
    }
    assert_eq!(asset.lods[0].point_cloud.voxels.len(), 1);
    let svo = Svo::from_asset(asset).unwrap();
    assert_eq!(
        svo.nodes.len(),
        asset
            .lods
            .iter()
            .map(|l| l.point_cloud.voxels.len())
            .sum::<usize>()
    );
}

#[test]
fn every_shared_model_prepares_at_level_7() {
    let dir = models_dir();
    for name in MODELS {
        let path = dir.join(name);
        assert!(path.is_file(), "test model missing: {}", path.display());
        let model = load_model(&path).unwrap_or_else(|e| panic!("{e}"));
        let (asset, stats) =
            prepare_asset(&model, 7, &NoProgress).unwrap_or_else(|e| panic!("{name}: {e}"));
        check_asset(name, &asset, 7);
        // The object space is the documented convention, rebuilt from the model.
        let expected = match &model {
            Model::Mesh(m) => mesh_object_space(m),
            Model::Voxels(v) => voxel_model_object_space(v),
        };
        assert_eq!(Some(asset.object_space), expected, "{name}");
        assert_eq!(stats.levels.len(), 8);
        assert_eq!(
            stats.levels[7].voxels as usize,
            asset.lods[7].point_cloud.voxels.len()
        );
        assert!(stats.levels[7].lookup_percent_of_dense < 100.0, "{name}");
        let json = serde_json::to_string(&stats).unwrap();
        assert!(json.contains("\"resident_pages\""));
    }
}

#[test]
fn bunny_surface_is_where_the_mesh_is() {
    let path = models_dir().join("bunny.obj");
    let Model::Mesh(mesh) = load_model(&path).unwrap() else {
        panic!("bunny is a mesh")
    };
    let (asset, stats) = prepare_asset(&Model::Mesh(mesh.clone()), 8, &NoProgress).unwrap();
    check_asset("bunny", &asset, 8);
    // Every vertex of the mesh lies in a set cell (or on the border of one).
    let os = asset.object_space;
    let lod = &asset.lods[8];
    let s = cell_size(8);
    for p in mesh.positions.iter().step_by(7) {
        let o = os.to_object(p.as_dvec3());
        let c = o
            .to_array()
            .map(|x| (((x + 1.0) / s).floor() as i64).clamp(0, 255) as u32);
        let near = (0..27).any(|d| {
            let q = [0, 1, 2].map(|k| c[k] as i64 + (d / 3i64.pow(k as u32)) % 3 - 1);
            q.iter().all(|&x| (0..256).contains(&x))
                && lod.lookup.get(q.map(|x| x as u32)).is_some()
        });
        assert!(near, "vertex {p:?} has no voxel");
    }
    // Surface-sized, not volume-sized: ~4x per level.
    let ratio = stats.levels[8].voxels as f64 / stats.levels[7].voxels as f64;
    assert!((3.5..4.5).contains(&ratio), "{ratio}");
    assert_eq!(stats.voxelize.skipped_non_finite, 0);
}

#[test]
fn cache_round_trip_and_rebuild_on_real_models() {
    let dir = models_dir();
    let tmp = tempfile::tempdir().unwrap();
    for name in ["cow.obj", "chr_knight.vox"] {
        let path = dir.join(name);
        let (a, first) = load_or_prepare(&path, 6, Some(tmp.path()), &NoProgress).unwrap();
        assert!(
            matches!(first.status, CacheStatus::Rebuilt { .. }),
            "{first}"
        );
        assert!(first.cache_write_error.is_none(), "{first}");
        let (b, second) = load_or_prepare(&path, 6, Some(tmp.path()), &NoProgress).unwrap();
        assert_eq!(second.status, CacheStatus::Hit, "{second}");
        assert_eq!(a, b);
        // Explicit write/read elsewhere gives the same asset.
        let out = tmp.path().join(format!("{name}.ssbvbast"));
        write_cache(&out, &a, 123, 6).unwrap();
        assert_eq!(read_cache(&out, 123, 6).unwrap(), a);
        // Truncated cache: rebuilt, reason given.
        let bytes = std::fs::read(&second.cache_path).unwrap();
        std::fs::write(&second.cache_path, &bytes[..bytes.len() / 2]).unwrap();
        let (c, third) = load_or_prepare(&path, 6, Some(tmp.path()), &NoProgress).unwrap();
        match &third.status {
            CacheStatus::Rebuilt { reason } => assert!(reason.contains("truncated"), "{reason}"),
            s => panic!("{s:?}"),
        }
        assert_eq!(a, c);
    }
}

/// The cache follows every file a model reads: editing an MTL library, a texture or a
/// glTF buffer, or adding a library that was missing, rebuilds the asset with a reason that
/// names the file; an untouched model is a hit.
#[test]
fn the_cache_rebuilds_when_a_file_the_model_reads_changes() {
    use std::path::Path;

    let dir = tempfile::tempdir().unwrap();
    let cache = dir.path().join("cache");
    let d = dir.path();
    let run = |model: &Path| load_or_prepare(model, 3, Some(&cache), &NoProgress).unwrap();
    let rebuilt_naming = |model: &Path, file: &str| -> VoxelAsset {
        let (asset, outcome) = run(model);
        match &outcome.status {
            CacheStatus::Rebuilt { reason } => {
                assert!(reason.contains(file), "{file}: {reason}")
            }
            other => panic!("{file} changed but the cache was not rebuilt: {other:?}"),
        }
        assert!(outcome.cache_write_error.is_none(), "{outcome}");
        asset
    };
    let hit = |model: &Path| assert_eq!(run(model).1.status, CacheStatus::Hit);
    // Mean colour of the finest level, linear RGB.
    let mean_color = |a: &VoxelAsset| {
        let v = &a.lods.last().unwrap().point_cloud.voxels;
        let mut m = [0.0f32; 3];
        for x in v {
            let c = x.color();
            for i in 0..3 {
                m[i] += c[i] / v.len() as f32;
            }
        }
        m
    };

    // OBJ + MTL: the stale-material report (red, then blue).
    let obj = d.join("tri.obj");
    std::fs::write(
        &obj,
        "mtllib tri.mtl\nv -1 -1 -1\nv 1 -1 0\nv 0 1 1\nvt 0 0\nvt 1 0\nvt 0 1\nusemtl m\nf 1/1 2/2 3/3\n",
    )
    .unwrap();
    std::fs::write(d.join("tri.mtl"), "newmtl m\nKd 1 0 0\n").unwrap();
    let red = mean_color(&run(&obj).0);
    assert!(red[0] > 0.9 && red[2] < 0.1, "{red:?}");
    hit(&obj);
    std::fs::write(d.join("tri.mtl"), "newmtl m\nKd 0 0 1\n").unwrap();
    let blue = mean_color(&rebuilt_naming(&obj, "tri.mtl"));
    assert!(blue[2] > 0.9 && blue[0] < 0.1, "{blue:?}");
    hit(&obj);

    // A texture named by the MTL library.
    let png = |rgb: [u8; 3]| {
        let img = image::RgbImage::from_pixel(2, 2, image::Rgb(rgb));
        img.save(d.join("tex.png")).unwrap();
    };
    png([255, 0, 0]);
    std::fs::write(d.join("tri.mtl"), "newmtl m\nmap_Kd tex.png\n").unwrap();
    let textured = mean_color(&rebuilt_naming(&obj, "tri.mtl"));
    assert!(textured[0] > 0.9 && textured[1] < 0.1, "{textured:?}");
    png([0, 255, 0]);
    let green = mean_color(&rebuilt_naming(&obj, "tex.png"));
    assert!(green[1] > 0.9 && green[0] < 0.1, "{green:?}");

    // A library that did not exist when the asset was built.
    let lonely = d.join("lonely.obj");
    std::fs::write(
        &lonely,
        "mtllib later.mtl\nv -1 -1 -1\nv 1 -1 0\nv 0 1 1\nusemtl m\nf 1 2 3\n",
    )
    .unwrap();
    run(&lonely);
    hit(&lonely);
    std::fs::write(d.join("later.mtl"), "newmtl m\nKd 0 1 0\n").unwrap();
    let later = mean_color(&rebuilt_naming(&lonely, "later.mtl"));
    assert!(later[1] > 0.9, "{later:?}");

    // glTF with an external buffer: moving a vertex changes the voxels.
    let write_bin = |z: f32| {
        let v: [f32; 9] = [-1.0, -1.0, -1.0, 1.0, -1.0, 0.0, 0.0, 1.0, z];
        let bytes: Vec<u8> = v.iter().flat_map(|f| f.to_le_bytes()).collect();
        std::fs::write(d.join("tri.bin"), bytes).unwrap();
    };
    write_bin(1.0);
    let gltf = d.join("tri.gltf");
    std::fs::write(
        &gltf,
        r#"{"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0}],
"meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}],
"buffers":[{"uri":"tri.bin","byteLength":36}],
"bufferViews":[{"buffer":0,"byteOffset":0,"byteLength":36}],
"accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[-1,-1,-1],"max":[1,1,1]}]}"#,
    )
    .unwrap();
    let before = run(&gltf).0;
    hit(&gltf);
    write_bin(-1.0);
    let after = rebuilt_naming(&gltf, "tri.bin");
    assert_ne!(
        before.lods.last().unwrap().point_cloud.voxels,
        after.lods.last().unwrap().point_cloud.voxels,
        "the moved vertex must change the voxels"
    );
}

/// A cache folder that cannot be created (its parent is a file): the asset is still
/// prepared and returned, the outcome says why nothing was cached, and the next call
/// rebuilds again instead of failing.
#[test]
fn an_unwritable_cache_is_reported_not_fatal() {
    let dir = tempfile::tempdir().unwrap();
    let obj = dir.path().join("tri.obj");
    std::fs::write(&obj, "v -1 -1 -1\nv 1 -1 0\nv 0 1 1\nf 1 2 3\n").unwrap();
    let blocker = dir.path().join("not-a-folder");
    std::fs::write(&blocker, "x").unwrap();
    let cache = blocker.join("cache");
    for _ in 0..2 {
        let (asset, outcome) = load_or_prepare(&obj, 3, Some(&cache), &NoProgress).unwrap();
        assert!(!asset.lods.last().unwrap().point_cloud.voxels.is_empty());
        assert!(
            matches!(outcome.status, CacheStatus::Rebuilt { .. }),
            "{outcome}"
        );
        let why = outcome
            .cache_write_error
            .as_deref()
            .expect("the write failed");
        assert!(why.contains("not-a-folder"), "{why}");
        assert!(
            outcome.to_string().contains("cache not written"),
            "{outcome}"
        );
    }
}

#[test]
fn region_by_region_preparation_equals_the_whole_grid() {
    // Regions of 32³ cells (the smallest: one brick) at level 8 are 512 regions, so every
    // level from 8 down to 3 is built inside regions and levels 3..0 from their roots.
    for name in ["bunny.obj", "cow.obj"] {
        let Model::Mesh(mesh) = load_model(&models_dir().join(name)).unwrap() else {
            panic!("{name} is a mesh");
        };
        let level = 8;
        let set = ssbvb_voxel::voxelize::voxelize_mesh(&mesh, level, &NoProgress).unwrap();
        let report = set.report.clone();
        let (whole, _) = ssbvb_voxel::prepare::prepare_voxel_set(set, &NoProgress);
        let (regions, stats) =
            ssbvb_voxel::prepare::prepare_mesh_in_regions(&mesh, level, 5, &NoProgress).unwrap();
        assert_eq!(stats.voxelize, report, "{name}");
        assert_eq!(whole.object_space, regions.object_space, "{name}");
        for (a, b) in whole.lods.iter().zip(&regions.lods) {
            assert!(a == b, "{name}: LOD {} differs", a.level);
        }
        assert_eq!(whole.lods.len(), regions.lods.len());
    }
}
