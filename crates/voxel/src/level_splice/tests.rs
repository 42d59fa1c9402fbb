//! The oracle is independent: the patched arrays must equal the arrays built from scratch
//! from the new voxel set ([`SparseLookup::from_codes`], [`stream_words`] per voxel).

use super::*;
use crate::lookup::SparseLookup;
use crate::svo::morton_encode;
use proptest::prelude::*;

/// A voxel set from distinct codes, attributes derived from the code and `salt`.
fn set(level: u32, mut codes: Vec<u64>, salt: u32) -> LevelVoxels {
    codes.sort_unstable();
    codes.dedup();
    let f = |c: u64, k: u32| {
        ((c as u32)
            .wrapping_mul(2654435761)
            .wrapping_add(salt * 97 + k)
            % 1000) as f32
            / 999.0
    };
    LevelVoxels {
        level,
        normals: codes
            .iter()
            .map(|&c| [f(c, 1) - 0.5, f(c, 2) - 0.5, 0.3])
            .collect(),
        colors: codes
            .iter()
            .map(|&c| [f(c, 3), f(c, 4), f(c, 5), 1.0])
            .collect(),
        uvs: codes.iter().map(|&c| [f(c, 6), f(c, 7)]).collect(),
        codes,
    }
}

fn words(v: &LevelVoxels) -> (Vec<u32>, Vec<u16>) {
    (0..v.len()).map(|i| stream_words(v, i)).unzip()
}

/// Splices `blocks` (aligned cubes: origin, side) of `old` with `new_in` (codes, filtered
/// to the blocks) and checks every array against a rebuild from the expected set.
fn check(level: u32, old_codes: Vec<u64>, blocks: &[([u32; 3], u32)], new_in: Vec<u64>) {
    let old = set(level, old_codes, 1);
    let mut ranges: Vec<(u64, u64)> = blocks
        .iter()
        .map(|&(o, side)| {
            let lo = morton_encode(o);
            (lo, lo + u64::from(side).pow(3))
        })
        .collect();
    ranges.sort_unstable();
    ranges.dedup();
    let inside = |c: u64| ranges.iter().any(|r| (r.0..r.1).contains(&c));
    let fresh = set(
        level,
        new_in.into_iter().filter(|&c| inside(c)).collect(),
        2,
    );
    let expected = {
        let mut codes: Vec<u64> = old.codes.iter().copied().filter(|&c| !inside(c)).collect();
        codes.extend(&fresh.codes);
        codes.sort_unstable();
        // Attributes: fresh inside the blocks, old outside.
        let mut e = LevelVoxels {
            level,
            ..Default::default()
        };
        for c in codes {
            let (src, i) = match fresh.codes.binary_search(&c) {
                Ok(i) => (&fresh, i),
                Err(_) => (&old, old.codes.binary_search(&c).unwrap()),
            };
            e.codes.push(c);
            e.normals.push(src.normals[i]);
            e.colors.push(src.colors[i]);
            e.uvs.push(src.uvs[i]);
        }
        e
    };
    let contents: Vec<((u64, u64), LevelVoxels)> =
        ranges.iter().map(|&r| (r, voxels_in(&fresh, r))).collect();
    let mut mirror = LevelMirror::new(old.clone());
    let patch = mirror.splice(&contents);

    let old_tree = SparseLookup::from_codes(level, &old.codes);
    let new_tree = SparseLookup::from_codes(level, &expected.codes);
    assert_eq!(patch.apply_nodes(&old_tree.nodes), new_tree.nodes, "nodes");
    let (old_c, old_n) = words(&old);
    let (new_c, new_n) = words(&expected);
    assert_eq!(patch.apply_colors(&old_c), new_c, "colours");
    assert_eq!(patch.apply_normals(&old_n), new_n, "normals");
    assert_eq!(
        (patch.old_voxels, patch.voxels, patch.old_nodes, patch.nodes),
        (
            old.len() as u32,
            expected.len() as u32,
            old_tree.node_count() as u32,
            new_tree.node_count() as u32
        )
    );
    // The plan holds no empty run (the GPU searches the runs for every element).
    let segments = patch.voxel_segments.iter().chain(&patch.node_segments);
    assert!(segments.clone().all(|s| s.len > 0), "{segments:?}");
    // Nothing before the first changed voxel differs, and it is where it says.
    let first = patch.first_changed_voxel() as usize;
    assert_eq!(
        old_c[..first.min(old_c.len())],
        new_c[..first.min(new_c.len())]
    );
    // It is the first block's start when that block's content goes in; an emptied or
    // empty first block may leave it later (nothing moves before the first change).
    let start = old.codes.partition_point(|&c| c < ranges[0].0);
    let fills_first = patch
        .voxel_segments
        .iter()
        .any(|s| matches!(s.source, Source::Patch { .. }) && s.start as usize == start);
    if fills_first {
        assert_eq!(first, start);
    } else {
        assert!(first >= start, "{first} < {start}");
    }
    // The mirror is what a fresh mirror of the new set would be.
    assert_eq!(mirror, LevelMirror::new(expected));
}

/// Every cell of a cube `side` at `o`.
fn cube(o: [u32; 3], side: u32) -> Vec<u64> {
    let mut v = Vec::new();
    for z in 0..side {
        for y in 0..side {
            for x in 0..side {
                v.push(morton_encode([o[0] + x, o[1] + y, o[2] + z]));
            }
        }
    }
    v
}

/// A sphere shell of radius `r` cells around the grid centre.
fn shell(level: u32, r: f64) -> Vec<u64> {
    let n = 1u32 << level;
    let c = f64::from(n) / 2.0;
    let mut v = Vec::new();
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                let d = [x, y, z].map(|a| f64::from(a) + 0.5 - c);
                let d = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                if (d - r).abs() < 0.9 {
                    v.push(morton_encode([x, y, z]));
                }
            }
        }
    }
    v
}

#[test]
fn carving_and_filling_a_shell_matches_a_rebuild() {
    let old = shell(6, 20.0);
    // Remove a block on the shell, fill another, both 8³, and one in empty space.
    check(6, old.clone(), &[([40, 32, 32], 8)], vec![]);
    check(6, old.clone(), &[([48, 24, 24], 8)], cube([48, 24, 24], 8));
    check(6, old.clone(), &[([0, 0, 0], 4)], cube([0, 0, 0], 4));
    // Several blocks at once, on both sides of the grid's centre (different subtrees).
    check(
        6,
        old.clone(),
        &[([24, 24, 24], 8), ([32, 32, 32], 8), ([32, 24, 24], 8)],
        cube([24, 24, 24], 16),
    );
    // Blocks of one cell and of the whole grid.
    check(
        6,
        old.clone(),
        &[([13, 50, 7], 1)],
        vec![morton_encode([13, 50, 7])],
    );
    check(6, old.clone(), &[([0, 0, 0], 64)], shell(6, 9.0));
}

#[test]
fn emptying_and_filling_the_whole_level_matches_a_rebuild() {
    for level in [0, 1, 2, 3, 5] {
        let n = 1u32 << level;
        let all = cube([0, 0, 0], n);
        check(level, all.clone(), &[([0, 0, 0], n)], vec![]);
        check(level, vec![], &[([0, 0, 0], n)], all.clone());
        check(level, vec![], &[([0, 0, 0], 1)], vec![0]);
    }
}

#[test]
fn repeated_splices_keep_the_mirror_exact() {
    let level = 5;
    let mut expected = set(level, shell(level, 10.0), 1);
    let mut mirror = LevelMirror::new(expected.clone());
    let mut nodes = SparseLookup::from_codes(level, &expected.codes).nodes;
    let (mut colors, mut normals) = words(&expected);
    for (i, o) in [[16u32, 16, 16], [8, 8, 24], [24, 0, 8], [16, 16, 16]]
        .into_iter()
        .enumerate()
    {
        let range = (morton_encode(o), morton_encode(o) + 8 * 8 * 8);
        // Alternately fill and empty the block.
        let content = if i % 2 == 0 {
            set(level, cube(o, 8), 3 + i as u32)
        } else {
            LevelVoxels {
                level,
                ..Default::default()
            }
        };
        let patch = mirror.splice(&[(range, content.clone())]);
        nodes = patch.apply_nodes(&nodes);
        colors = patch.apply_colors(&colors);
        normals = patch.apply_normals(&normals);
        let mut next = voxels_in(&expected, (0, range.0));
        for part in [content, voxels_in(&expected, (range.1, u64::MAX))] {
            next.codes.extend(part.codes);
            next.normals.extend(part.normals);
            next.colors.extend(part.colors);
            next.uvs.extend(part.uvs);
        }
        expected = next;
        assert_eq!(
            nodes,
            SparseLookup::from_codes(level, &expected.codes).nodes
        );
        assert_eq!((colors.clone(), normals.clone()), words(&expected));
        assert_eq!(mirror.voxels, expected);
    }
}

#[test]
fn segments_cover_the_new_arrays_in_order() {
    let mut mirror = LevelMirror::new(set(6, shell(6, 20.0), 1));
    let o = [40, 32, 32];
    let range = (morton_encode(o), morton_encode(o) + 512);
    let patch = mirror.splice(&[(range, set(6, cube(o, 8), 5))]);
    for (segs, total) in [
        (&patch.voxel_segments, patch.voxels),
        (&patch.node_segments, patch.nodes),
    ] {
        let mut at = 0;
        for s in segs {
            assert_eq!(s.start, at);
            assert!(s.len > 0);
            at += s.len;
        }
        assert_eq!(at, total);
    }
    // The GPU's view of a segment.
    let s = Segment {
        start: 7,
        len: 3,
        source: Source::Old {
            from: 2,
            base_delta: -5,
        },
    };
    assert_eq!(s.words(), [7, 2, 0, (-5i32) as u32]);
    let p = Segment {
        start: 1,
        len: 3,
        source: Source::Patch { from: 9 },
    };
    assert_eq!(p.words(), [1, 9, 1, 0]);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    #[test]
    fn random_splices_match_a_rebuild(
        level in 1u32..=6,
        density in 1u32..=60,
        side_log in 0u32..=3,
        picks in proptest::collection::vec((0u32..64, 0u32..64, 0u32..64), 1..5),
        seed in 0u64..1000,
    ) {
        let n = 1u32 << level;
        let side = (1u32 << side_log).min(n);
        let mut h = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
        let mut rand = || { h ^= h << 13; h ^= h >> 7; h ^= h << 17; (h % 100) as u32 };
        let all = cube([0, 0, 0], n);
        let old: Vec<u64> = all.iter().copied().filter(|_| rand() < density).collect();
        let new: Vec<u64> = all.iter().copied().filter(|_| rand() < density).collect();
        let blocks: Vec<([u32; 3], u32)> = picks
            .iter()
            .map(|&(x, y, z)| ([x, y, z].map(|a| (a % n) / side * side), side))
            .collect();
        check(level, old, &blocks, new);
    }
}
