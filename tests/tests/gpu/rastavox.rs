//! RastaVox (seed 001): the GPU surface build against the CPU build.

use ssbvb_passes::surface_build::SurfaceBuilder;
use ssbvb_voxel::asset::{LodLevel, PackedVoxel, PointCloud, SparseLookup};
use ssbvb_voxel::surface::SurfaceModel;
use ssbvb_voxel::svo::morton_encode;

/// A spherical shell of radius `r` cells around `centre` at `level`, coloured by position.
fn shell(level: u32, centre: [f64; 3], r: f64) -> LodLevel {
    let mut cells = Vec::new();
    let lo = |a: usize| (centre[a] - r - 2.0).max(0.0) as u32;
    let hi = |a: usize| ((centre[a] + r + 2.0) as u32).min((1 << level) - 1);
    for z in lo(2)..=hi(2) {
        for y in lo(1)..=hi(1) {
            for x in lo(0)..=hi(0) {
                let p = [x, y, z].map(|c| c as f64 + 0.5);
                let d = ((p[0] - centre[0]).powi(2)
                    + (p[1] - centre[1]).powi(2)
                    + (p[2] - centre[2]).powi(2))
                .sqrt();
                if (r - 1.5..=r).contains(&d) {
                    cells.push([x, y, z]);
                }
            }
        }
    }
    cells.sort_by_key(|&c| morton_encode(c));
    let voxels = cells
        .iter()
        .map(|&c| {
            let n = [0, 1, 2].map(|a| (c[a] as f64 + 0.5 - centre[a]) as f32);
            let col = [
                c[0] as f32 / 511.0,
                c[1] as f32 / 511.0,
                c[2] as f32 / 511.0,
                1.0,
            ];
            PackedVoxel::new(c, n, col, [0.0; 2])
        })
        .collect();
    LodLevel {
        level,
        point_cloud: PointCloud { voxels },
        lookup: SparseLookup::from_cells(level, cells.iter().copied()),
        proxy: Default::default(),
    }
}

fn assert_same_model(gpu: &SurfaceModel, cpu: &SurfaceModel, what: &str) {
    assert_eq!(
        (gpu.level, gpu.chunk_log2),
        (cpu.level, cpu.chunk_log2),
        "{what}"
    );
    assert_eq!(gpu.chunks, cpu.chunks, "{what}: chunks");
    assert_eq!(gpu.bounds, cpu.bounds, "{what}: bounds");
    assert_eq!(gpu.levels.len(), cpu.levels.len(), "{what}: levels");
    for (k, (g, c)) in gpu.levels.iter().zip(&cpu.levels).enumerate() {
        assert_eq!(g.ranges, c.ranges, "{what} LOD {k}: ranges");
        assert_eq!(g.voxels.len(), c.voxels.len(), "{what} LOD {k}: voxels");
        let wrong = g
            .voxels
            .iter()
            .zip(&c.voxels)
            .filter(|(a, b)| a != b)
            .count();
        assert_eq!(wrong, 0, "{what} LOD {k}: {wrong} voxels differ");
        let wrong = g
            .colors
            .iter()
            .zip(&c.colors)
            .filter(|(a, b)| a != b)
            .count();
        assert_eq!(wrong, 0, "{what} LOD {k}: {wrong} colours differ");
        // Normals: one octahedral step at most (GPU sqrt and division round differently).
        let far = g
            .normals
            .iter()
            .zip(&c.normals)
            .filter(|&(&a, &b)| {
                let d = |s: u32| ((a >> s) & 0xff).abs_diff((b >> s) & 0xff);
                d(0) > 1 || d(8) > 1 || a >> 16 != 0
            })
            .count();
        assert_eq!(
            far, 0,
            "{what} LOD {k}: {far} normals differ by more than one step"
        );
    }
}

#[test]
fn the_gpu_surface_build_equals_the_cpu_build() {
    let ctx = ssbvb_tests::ctx();
    let builder = SurfaceBuilder::new(ctx).unwrap();
    let bunny = ssbvb_tests::model_asset("bunny.obj", 7);
    let knight = ssbvb_tests::model_asset("chr_knight.vox", 6);
    let cases: Vec<(String, LodLevel)> = vec![
        ("bunny level 7".into(), bunny.lods[7].clone()),
        ("bunny level 4".into(), bunny.lods[4].clone()),
        ("knight level 6".into(), knight.lods[6].clone()),
        // Level 9: chunks of 256³, the shell crosses the chunk planes at 256 on every axis.
        (
            "shell level 9".into(),
            shell(9, [250.0, 262.0, 255.0], 40.0),
        ),
    ];
    for (what, lod) in &cases {
        let cpu = SurfaceModel::extract(lod).unwrap();
        let gpu = builder.build(ctx, lod).unwrap();
        assert!(ctx.take_uncaptured_errors().is_empty(), "{what}");
        let back = gpu.read_back(ctx).unwrap();
        eprintln!(
            "{what}: {} points, {} surface voxels, {} chunks, LOD counts {:?}, build {:.3} + {:.3} s",
            lod.point_cloud.voxels.len(),
            cpu.surface_voxels(),
            cpu.chunks.len(),
            cpu.levels
                .iter()
                .map(|l| l.voxels.len())
                .collect::<Vec<_>>(),
            gpu.times.base_seconds,
            gpu.times.lod_seconds,
        );
        assert!(cpu.surface_voxels() > 0, "{what}");
        assert_same_model(&back, &cpu, what);
        assert_eq!(
            gpu.bytes(),
            cpu.bytes().base_voxels + cpu.bytes().base_attributes + cpu.bytes().lod,
            "{what}"
        );
    }
    assert_eq!(SurfaceModel::extract(&cases[3].1).unwrap().chunks.len(), 8);
}
