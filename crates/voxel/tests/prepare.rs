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
