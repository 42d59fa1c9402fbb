use std::collections::{BTreeMap, BTreeSet};

use super::*;

/// A LOD level holding `cells` (any order), coloured by `color(cell)`, normal +Y.
fn lod_of(level: u32, cells: &[[u32; 3]], color: impl Fn([u32; 3]) -> [f32; 4]) -> LodLevel {
    let mut cells: Vec<[u32; 3]> = cells.to_vec();
    cells.sort_by_key(|&c| morton_encode(c));
    cells.dedup();
    let voxels = cells
        .iter()
        .map(|&c| PackedVoxel::new(c, [0.0, 1.0, 0.0], color(c), [0.0; 2]))
        .collect();
    LodLevel {
        level,
        point_cloud: PointCloud { voxels },
        lookup: SparseLookup::from_cells(level, cells.iter().copied()),
        proxy: Default::default(),
    }
}

fn grey(_: [u32; 3]) -> [f32; 4] {
    [0.5, 0.5, 0.5, 1.0]
}

fn box_cells(lo: [u32; 3], hi: [u32; 3]) -> Vec<[u32; 3]> {
    let mut out = Vec::new();
    for z in lo[2]..hi[2] {
        for y in lo[1]..hi[1] {
            for x in lo[0]..hi[0] {
                out.push([x, y, z]);
            }
        }
    }
    out
}

/// Global cell → mask of a LOD `k` of the model.
fn cells_of(m: &SurfaceModel, k: usize) -> BTreeMap<[u32; 3], u32> {
    let lvl = &m.levels[k];
    let shift = m.chunk_log2 - k as u32;
    let mut out = BTreeMap::new();
    for (c, chunk) in m.chunks.iter().enumerate() {
        for i in lvl.chunk(c) {
            let p = lvl.voxels[i].pos();
            let cell = [0, 1, 2].map(|a| (chunk[a] << shift) + p[a]);
            assert!(
                out.insert(cell, lvl.voxels[i].mask()).is_none(),
                "{cell:?} twice"
            );
        }
    }
    out
}

#[test]
fn surface_voxels_pack_into_four_bytes() {
    assert_eq!(
        std::mem::size_of::<SurfaceVoxel>() as u64,
        SURFACE_VOXEL_BYTES
    );
    let v = SurfaceVoxel::new([255, 7, 128], 0b101101);
    assert_eq!(v.pos(), [255, 7, 128]);
    assert_eq!(v.mask(), 0b101101);
    assert_eq!(v.0 >> 30, 0, "padding stays zero");
    assert_eq!(
        SurfaceVoxel::new([1, 2, 3], 63).0,
        1 | 2 << 8 | 3 << 16 | 63 << 24
    );
    assert_eq!(face_bit(0, false), 1);
    assert_eq!(face_bit(2, false), 4);
    assert_eq!(face_bit(0, true), 8);
    assert_eq!(face_bit(2, true), 32);
}

#[test]
fn a_solid_box_keeps_its_boundary_with_outward_faces_only() {
    // A 4³ solid box in an 8³ grid: 64 − 2³ interior = 56 surface voxels, 6·16 faces.
    let lod = lod_of(3, &box_cells([2, 2, 2], [6, 6, 6]), grey);
    let m = SurfaceModel::extract(&lod).unwrap();
    assert_eq!((m.level, m.chunk_log2, m.chunks.len()), (3, 3, 1));
    assert_eq!(m.bounds, vec![[[2, 2, 2], [6, 6, 6]]]);
    let cells = cells_of(&m, 0);
    assert_eq!(cells.len(), 56);
    assert!(!cells.contains_key(&[3, 3, 3]) && !cells.contains_key(&[4, 4, 4]));
    let faces: u32 = cells.values().map(|m| m.count_ones()).sum();
    assert_eq!(faces, 96);
    assert_eq!(
        cells[&[2, 2, 2]],
        face_bit(0, false) | face_bit(1, false) | face_bit(2, false)
    );
    assert_eq!(
        cells[&[5, 5, 5]],
        face_bit(0, true) | face_bit(1, true) | face_bit(2, true)
    );
    assert_eq!(cells[&[3, 5, 2]], face_bit(1, true) | face_bit(2, false));
    assert_eq!(cells[&[2, 3, 4]], face_bit(0, false));
}

#[test]
fn the_grid_boundary_counts_as_empty() {
    let lod = lod_of(1, &box_cells([0; 3], [2; 3]), grey);
    let m = SurfaceModel::extract(&lod).unwrap();
    let cells = cells_of(&m, 0);
    assert_eq!(cells.len(), 8);
    assert!(cells.values().all(|m| m.count_ones() == 3));
    assert_eq!(
        cells[&[1, 0, 1]],
        face_bit(0, true) | face_bit(1, false) | face_bit(2, true)
    );
    // Level 1 has one level below it: the whole grid as one voxel with every face.
    assert_eq!(m.levels.len(), 2);
    assert_eq!(cells_of(&m, 1), BTreeMap::from([([0, 0, 0], 63)]));
}

#[test]
fn or_merging_grows_a_thin_line_and_averages_colours() {
    // A one-voxel line along x at y = 1, z = 2 (level 3), red and blue alternating.
    let line: Vec<[u32; 3]> = (0..8).map(|x| [x, 1, 2]).collect();
    let color = |c: [u32; 3]| {
        if c[0].is_multiple_of(2) {
            [1.0, 0.0, 0.0, 1.0]
        } else {
            [0.0, 0.0, 1.0, 1.0]
        }
    };
    let m = SurfaceModel::extract(&lod_of(3, &line, color)).unwrap();
    assert_eq!(m.levels.len(), 4);
    let l1 = cells_of(&m, 1);
    // The line survives at every level: each parent holds a child.
    assert_eq!(
        l1.keys().copied().collect::<Vec<_>>(),
        (0..4).map(|x| [x, 0, 1]).collect::<Vec<_>>()
    );
    // Interior x faces were absent in every child except at the ends; y and z faces all set.
    assert_eq!(l1[&[0, 0, 1]], 0b110111, "−X end");
    assert_eq!(l1[&[1, 0, 1]], 0b110110);
    assert_eq!(l1[&[3, 0, 1]], 0b111110, "+X end");
    assert_eq!(cells_of(&m, 3), BTreeMap::from([([0, 0, 0], 63)]));
    // Red (255, 0, 0) and blue (0, 0, 255) average to (128, 0, 128) with rounding.
    let c = m.levels[1].colors[0];
    assert_eq!(
        [c & 0xff, (c >> 8) & 0xff, (c >> 16) & 0xff, c >> 24],
        [128, 0, 128, 255]
    );
    // A normal shared by every child survives the averaging.
    let n = m.levels[3].normals[0];
    let d = decode_octahedral(n & 0xff, (n >> 8) & 0xff);
    assert!((d[1] - 1.0).abs() < 1e-3, "{d:?}");
}

/// Pseudo-random cells of a blob (deterministic).
fn blob(level: u32, seed: u64, count: usize) -> Vec<[u32; 3]> {
    let n = 1u64 << level;
    let mut s = seed;
    let mut next = || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        s
    };
    (0..count)
        .map(|_| {
            let r = next();
            // Clustered around the centre so neighbours exist.
            let c = |k: u32| {
                ((n / 2) as i64 + ((r >> (k * 16)) % 23) as i64 - 11).clamp(0, n as i64 - 1) as u32
            };
            [c(0), c(1), c(2)]
        })
        .collect()
}

#[test]
fn every_lod_is_the_or_merge_of_the_one_below_across_chunks() {
    // Level 9: chunks of 256³; the blob straddles the chunk boundary at 256 on every axis.
    let cells = blob(9, 0x9e37_79b9_7f4a_7c15, 3000);
    let lod = lod_of(9, &cells, |c| [c[0] as f32 / 511.0, 0.2, 0.9, 1.0]);
    let m = SurfaceModel::extract(&lod).unwrap();
    assert_eq!(m.chunk_log2, 8);
    assert_eq!(m.chunks.len(), 8, "the blob touches all 8 chunks");
    assert_eq!(m.levels.len(), 9);
    let codes: Vec<u64> = m.chunks.iter().map(|&c| morton_encode(c)).collect();
    assert!(
        codes.windows(2).all(|w| w[0] < w[1]),
        "chunks in Morton order"
    );
    // Finest: exactly the solid cells with an empty neighbour, with those faces.
    let solid: BTreeSet<[u32; 3]> = cells.iter().copied().collect();
    let expect: BTreeMap<[u32; 3], u32> = solid
        .iter()
        .filter_map(|&c| {
            let mut mask = 0;
            for a in 0..3 {
                for (pos, bit) in [(false, face_bit(a, false)), (true, face_bit(a, true))] {
                    let mut nb = c.map(i64::from);
                    nb[a] += if pos { 1 } else { -1 };
                    let inside = nb.iter().all(|&x| (0..512).contains(&x));
                    if !inside || !solid.contains(&nb.map(|x| x as u32)) {
                        mask |= bit;
                    }
                }
            }
            (mask != 0).then_some((c, mask))
        })
        .collect();
    assert!(expect.len() < solid.len(), "the blob has interior voxels");
    assert_eq!(cells_of(&m, 0), expect);
    for k in 1..m.levels.len() {
        let mut parents: BTreeMap<[u32; 3], u32> = BTreeMap::new();
        for (c, mask) in cells_of(&m, k - 1) {
            *parents.entry(c.map(|x| x >> 1)).or_default() |= mask;
        }
        assert_eq!(cells_of(&m, k), parents, "LOD {k}");
        let lvl = &m.levels[k];
        assert_eq!(lvl.ranges.len(), m.chunks.len());
        assert_eq!(
            lvl.ranges.iter().map(|r| r[1] as usize).sum::<usize>(),
            lvl.voxels.len()
        );
        for c in 0..m.chunks.len() {
            let r = lvl.chunk(c);
            let local: Vec<u64> = lvl.voxels[r]
                .iter()
                .map(|v| morton_encode(v.pos()))
                .collect();
            assert!(
                local.windows(2).all(|w| w[0] < w[1]),
                "LOD {k} chunk {c} in Morton order"
            );
            assert!(
                lvl.voxels[lvl.chunk(c)]
                    .iter()
                    .all(|v| v.pos().iter().all(|&p| p < 256 >> k))
            );
        }
    }
    // One voxel per chunk at the end.
    assert!(m.levels[8].ranges.iter().all(|r| r[1] == 1));
    // Chunk bounds hold their voxels and are tight.
    let finest = cells_of(&m, 0);
    for (c, b) in m.bounds.iter().enumerate() {
        let mine: Vec<&[u32; 3]> = finest
            .keys()
            .filter(|p| p.map(|x| x >> 8) == m.chunks[c])
            .collect();
        for a in 0..3 {
            assert_eq!(b[0][a], mine.iter().map(|p| p[a]).min().unwrap());
            assert_eq!(b[1][a], mine.iter().map(|p| p[a]).max().unwrap() + 1);
        }
    }
    // Bytes: 4 per finest voxel plus 8 of attributes, 12 per coarser voxel.
    let b = m.bytes();
    assert_eq!(b.base_voxels, 4 * expect.len() as u64);
    assert_eq!(b.base_attributes, 8 * expect.len() as u64);
    let coarse: usize = m.levels[1..].iter().map(|l| l.voxels.len()).sum();
    assert_eq!(b.lod, 12 * coarse as u64);
    assert_eq!(
        b.total(),
        b.base_voxels + b.base_attributes + b.lod + b.chunk_tables
    );
}

#[test]
fn face_lods_hold_the_chunk_cells_in_the_objects_grid() {
    let cells = blob(9, 7, 2000);
    let m = SurfaceModel::extract(&lod_of(9, &cells, grey)).unwrap();
    for k in [0, 3] {
        let all = m.face_lod_all(k);
        assert_eq!(all.lod.level, 9 - k as u32);
        let got: BTreeMap<[u32; 3], u32> = all
            .lod
            .point_cloud
            .voxels
            .iter()
            .zip(&all.faces)
            .map(|(v, &f)| (v.cell(), u32::from(f)))
            .collect();
        assert_eq!(got, cells_of(&m, k));
        for (id, v) in all.lod.point_cloud.voxels.iter().enumerate() {
            assert_eq!(all.lod.lookup.get(v.cell()), Some(id as u32));
        }
        let per_chunk: usize = (0..m.chunks.len())
            .map(|c| m.face_lod(c, k).faces.len())
            .sum();
        assert_eq!(per_chunk, all.faces.len());
    }
}

#[test]
fn empty_and_interior_only_models_have_no_chunks() {
    let m = SurfaceModel::extract(&lod_of(4, &[], grey)).unwrap();
    assert!(m.is_empty() && m.surface_voxels() == 0);
    assert_eq!(m.bytes().total(), 0);
    let too_fine = LodLevel {
        level: MAX_LEVEL + 1,
        ..Default::default()
    };
    assert_eq!(
        SurfaceModel::extract(&too_fine),
        Err(SurfaceError::LevelTooHigh {
            level: MAX_LEVEL + 1
        })
    );
}

#[test]
fn pixel_error_picks_the_coarsest_lod_within_the_error() {
    // A cell of 0.01 at distance 10 with 500 px per unit: 3^¼·0.01·2^k·50 px.
    let px = |k: u32| 3f64.powf(0.25) * 0.01 * f64::from(1u32 << k) * 500.0 / 10.0;
    assert!(px(0) < 1.0 && px(1) > 1.0 && px(1) < 2.0 && px(2) > 2.0);
    assert_eq!(pixel_error_lod(0.01, 10.0, 500.0, 0.0, 8), 0);
    assert_eq!(pixel_error_lod(0.01, 10.0, 500.0, 1.0, 8), 0);
    assert_eq!(pixel_error_lod(0.01, 10.0, 500.0, 2.0, 8), 1);
    assert_eq!(pixel_error_lod(0.01, 10.0, 500.0, 4.0, 8), 2);
    assert_eq!(pixel_error_lod(0.01, 10.0, 500.0, 4.0, 1), 1, "capped");
    assert_eq!(
        pixel_error_lod(0.01, 1e9, 500.0, 1.0, 5),
        5,
        "far: coarsest"
    );
    assert_eq!(
        pixel_error_lod(0.01, 0.0, 500.0, 4.0, 5),
        0,
        "inside the chunk"
    );
    assert_eq!(pixel_error_lod(0.01, f64::NAN, 500.0, 4.0, 5), 0);
    // Twice the distance allows one level coarser.
    assert_eq!(pixel_error_lod(0.01, 20.0, 500.0, 1.0, 8), 1);
    assert_eq!(pixel_error_lod(0.01, 20.0, 500.0, 2.0, 8), 2);
}
