//! Round trips and damaged files of the asset cache.
use super::format::{SECTION_HEADER_BYTES, kind_name};
use super::*;
use crate::prepare::prepare_asset;
use crate::prepare::tests::tetra;
use crate::progress::NoProgress;

fn asset() -> VoxelAsset {
    let (mut asset, _) = prepare_asset(&tetra(), 5, &NoProgress).unwrap();
    // A proxy in every level, so the proxy sections are exercised too.
    for lod in &mut asset.lods {
        lod.proxy = ProxyMesh {
            positions: vec![[-1.0, -1.0, -1.0], [1.0, -1.0, -1.0], [0.0, 1.0, 0.5]],
            triangles: vec![[0, 1, 2]],
        };
    }
    asset
}

/// A temporary folder with [`asset`] written in it as the level-5 cache file `name` of
/// source hash `source`: the folder (kept alive), the file's path and the asset.
fn cached_asset(name: &str, source: u128) -> (tempfile::TempDir, PathBuf, VoxelAsset) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join(name);
    let a = asset();
    write_cache(&path, &a, source, 5).unwrap();
    (dir, path, a)
}

/// A temporary folder with a small OBJ model `tri.obj` in it: the folder and the model's path.
fn tri_model() -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let model = dir.path().join("tri.obj");
    std::fs::write(
        &model,
        "v 0 0 0\nv 1 0 0\nv 0 1 0.5\nv 0.3 0.2 1\nf 1 2 3\nf 1 2 4\n",
    )
    .unwrap();
    (dir, model)
}

#[test]
fn round_trip_is_exact() {
    let (_dir, path, a) = cached_asset("sub/dir/a.ssbvbast", 0xdead_beef_u128 << 64 | 42);
    let b = read_cache(&path, 0xdead_beef_u128 << 64 | 42, 5).unwrap();
    assert_eq!(a, b);
    // Only the cache file is left in the folder (the temporary file was renamed).
    assert_eq!(
        std::fs::read_dir(path.parent().unwrap()).unwrap().count(),
        1
    );
    assert!(matches!(
        read_cache(&path, 7, 5),
        Err(CacheError::SourceMismatch { .. })
    ));
    assert!(matches!(
        read_cache(&path, 0xdead_beef_u128 << 64 | 42, 4),
        Err(CacheError::LevelMismatch {
            found: 5,
            expected: 4,
            ..
        })
    ));
    assert!(write_cache(&path, &a, 1, 4).is_err());
}

#[test]
fn damaged_files_are_errors() {
    let (dir, path, _) = cached_asset("a.ssbvbast", 99);
    let good = std::fs::read(&path).unwrap();
    let bad = dir.path().join("bad.ssbvbast");
    // Truncation at many offsets, including inside every section.
    let step = (good.len() / 300).max(1);
    for cut in (0..good.len())
        .step_by(step)
        .chain([good.len() - 1, HEADER_BYTES, 87, 89])
    {
        std::fs::write(&bad, &good[..cut]).unwrap();
        let e = read_cache(&bad, 99, 5).unwrap_err();
        assert!(e.to_string().contains("bad.ssbvbast"), "{e}");
    }
    // A flipped byte anywhere is caught.
    for pos in (0..good.len()).step_by(step) {
        let mut b = good.clone();
        b[pos] ^= 0x40;
        std::fs::write(&bad, &b).unwrap();
        assert!(read_cache(&bad, 99, 5).is_err(), "flip at {pos} accepted");
    }
    // A flip in the point-cloud payload of level 5 is a checksum error naming it.
    let mut b = good.clone();
    let last_pc = good.len() - 200;
    b[last_pc] ^= 1;
    std::fs::write(&bad, &b).unwrap();
    let e = read_cache(&bad, 99, 5).unwrap_err();
    assert!(matches!(e, CacheError::Checksum { .. }), "{e}");
    // Magic and version.
    let mut b = good.clone();
    b[0] = b'X';
    std::fs::write(&bad, &b).unwrap();
    assert!(matches!(
        read_cache(&bad, 99, 5),
        Err(CacheError::BadMagic { .. })
    ));
    let mut b = good.clone();
    b[8..12].copy_from_slice(&0u32.to_le_bytes());
    std::fs::write(&bad, &b).unwrap();
    assert!(matches!(
        read_cache(&bad, 99, 5),
        Err(CacheError::UnsupportedVersion { found: 0, .. })
    ));
    // An absurd section length is refused before allocating.
    let mut b = good.clone();
    b[HEADER_BYTES + 8..HEADER_BYTES + 16].copy_from_slice(&(u64::MAX - 15).to_le_bytes());
    std::fs::write(&bad, &b).unwrap();
    assert!(matches!(
        read_cache(&bad, 99, 5),
        Err(CacheError::Truncated { .. })
    ));
    // Trailing garbage.
    let mut b = good.clone();
    b.extend_from_slice(b"junk");
    std::fs::write(&bad, &b).unwrap();
    assert!(matches!(
        read_cache(&bad, 99, 5),
        Err(CacheError::Corrupt { .. })
    ));
    assert!(matches!(
        read_cache(&dir.path().join("none"), 99, 5),
        Err(CacheError::Io { .. })
    ));
}

#[test]
fn load_or_prepare_reports_what_it_did() {
    let (dir, model) = tri_model();
    let cache = dir.path().join("cache");
    let (a, first) = load_or_prepare(&model, 4, Some(&cache), &NoProgress).unwrap();
    assert_eq!(
        first.status,
        CacheStatus::Rebuilt {
            reason: "cache missing".into()
        }
    );
    assert!(first.stats.is_some() && first.cache_write_error.is_none());
    let (b, second) = load_or_prepare(&model, 4, Some(&cache), &NoProgress).unwrap();
    assert_eq!(second.status, CacheStatus::Hit);
    assert_eq!(a, b);
    // Corrupt the cache: rebuilt, with the reason.
    let mut bytes = std::fs::read(&second.cache_path).unwrap();
    let n = bytes.len();
    bytes[n - 49] ^= 0xff; // last byte of the level-4 point cloud (two empty proxy sections follow)
    std::fs::write(&second.cache_path, &bytes).unwrap();
    let (c, third) = load_or_prepare(&model, 4, Some(&cache), &NoProgress).unwrap();
    match &third.status {
        CacheStatus::Rebuilt { reason } => {
            assert!(
                reason.starts_with("cache corrupt (checksum mismatch in section"),
                "{reason}"
            )
        }
        s => panic!("{s:?}"),
    }
    assert!(third.to_string().contains("rebuilt"));
    assert_eq!(a, c);
    assert_eq!(
        load_or_prepare(&model, 4, Some(&cache), &NoProgress)
            .unwrap()
            .1
            .status,
        CacheStatus::Hit
    );
    // A missing model is a load error naming it.
    let e =
        load_or_prepare(&dir.path().join("nope.obj"), 4, Some(&cache), &NoProgress).unwrap_err();
    assert!(e.to_string().contains("nope.obj"), "{e}");
}

/// Byte offset of a level's point cloud in the bytes of a cache file.
fn offset_of(file: &[u8], voxels: &[PackedVoxel]) -> usize {
    let needle: &[u8] = bytemuck::cast_slice(voxels);
    file.windows(needle.len())
        .position(|w| w == needle)
        .expect("the point cloud in the file")
}

#[test]
fn one_page_reads_alone_and_is_checked_alone() {
    let (_dir, path, a) = cached_asset("p.ssbvbast", 5);
    let mut pages = 0;
    for lod in &a.lods {
        let index = page_index(&lod.point_cloud.voxels);
        // Level 5 (32³ cells) has up to 8 pages; every voxel lies in exactly one of them.
        let mut seen = 0;
        for e in &index {
            let p = crate::svo::morton_decode(e.page);
            let got = read_page(&path, 5, 5, lod.level, p).unwrap();
            let start = e.first_voxel as usize;
            assert_eq!(got, lod.point_cloud.voxels[start..start + got.len()]);
            assert!(got.iter().all(|v| v.cell().map(|c| c / 16) == p));
            seen += got.len();
            pages += 1;
        }
        assert_eq!(seen, lod.point_cloud.voxels.len(), "level {}", lod.level);
        // An unoccupied page is empty, not an error.
        let occupied: Vec<[u32; 3]> = index
            .iter()
            .map(|e| crate::svo::morton_decode(e.page))
            .collect();
        if let Some(free) = [[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 1], [7, 7, 7]]
            .into_iter()
            .find(|p| !occupied.contains(p))
        {
            assert!(read_page(&path, 5, 5, lod.level, free).unwrap().is_empty());
        }
    }
    assert!(pages > 8);
    assert!(read_page(&path, 5, 5, 6, [0; 3]).is_err());
    assert!(matches!(
        read_page(&path, 6, 5, 5, [0; 3]),
        Err(CacheError::SourceMismatch { .. })
    ));

    // Flip a byte inside one page of level 5: that page fails on its own checksum, naming
    // it; the other pages still read; the whole file is refused.
    let finest = &a.lods[5];
    let index = page_index(&finest.point_cloud.voxels);
    assert!(index.len() >= 2);
    let good = std::fs::read(&path).unwrap();
    let pc = offset_of(&good, &finest.point_cloud.voxels);
    let victim = index[1];
    let mut bad = good.clone();
    bad[pc + victim.first_voxel as usize * 16 + 5] ^= 0x10;
    std::fs::write(&path, &bad).unwrap();
    let p = crate::svo::morton_decode(victim.page);
    let e = read_page(&path, 5, 5, 5, p).unwrap_err();
    assert!(
        matches!(&e, CacheError::Checksum { section, .. } if section.contains("page")),
        "{e}"
    );
    let other = crate::svo::morton_decode(index[0].page);
    assert!(!read_page(&path, 5, 5, 5, other).unwrap().is_empty());
    assert!(read_cache(&path, 5, 5).is_err());
    // Truncated inside the page: an error, never a short page.
    std::fs::write(&path, &good[..pc + victim.first_voxel as usize * 16 + 8]).unwrap();
    assert!(matches!(
        read_page(&path, 5, 5, 5, p),
        Err(CacheError::Truncated { .. })
    ));
}

#[test]
fn a_page_index_that_disagrees_with_its_point_cloud_is_refused() {
    let a = asset();
    let voxels = &a.lods[5].point_cloud.voxels;
    let codes: Vec<u64> = voxels
        .iter()
        .map(|v| crate::svo::morton_encode(v.cell()))
        .collect();
    let path = Path::new("x.ssbvbast");
    let index = page_index(voxels);
    assert!(pages::check_index(path, 5, &index, voxels, &codes).is_ok());
    let mut shifted = index.clone();
    shifted[1].first_voxel += 1;
    assert!(pages::check_index(path, 5, &shifted, voxels, &codes).is_err());
    let mut short = index.clone();
    short.pop();
    assert!(pages::check_index(path, 5, &short, voxels, &codes).is_err());
    let mut long = index.clone();
    long.push(*index.last().unwrap());
    assert!(pages::check_index(path, 5, &long, voxels, &codes).is_err());
    let mut sum = index.clone();
    sum[0].checksum ^= 1;
    assert!(matches!(
        pages::check_index(path, 5, &sum, voxels, &codes),
        Err(CacheError::Checksum { .. })
    ));
}

#[test]
fn preparing_into_the_cache_writes_what_load_or_prepare_reads() {
    let (dir, model) = tri_model();
    let cache = dir.path().join("cache");
    // A miss streams the mesh into the cache file: no asset, statistics of every level.
    let (none, first) = prepare_into_cache(&model, 6, Some(&cache), &NoProgress).unwrap();
    assert!(none.is_none());
    assert!(matches!(first.status, CacheStatus::Rebuilt { .. }));
    let stats = first.stats.clone().unwrap();
    assert_eq!(stats.levels.len(), 7);
    // The file it wrote is a hit for load_or_prepare, with the asset a fresh preparation
    // gives.
    let (asset, second) = load_or_prepare(&model, 6, Some(&cache), &NoProgress).unwrap();
    assert_eq!(second.status, CacheStatus::Hit);
    assert_eq!(second.cache_path, first.cache_path);
    let loaded = crate::load::load_model(&model).unwrap();
    let (fresh, fresh_stats) = prepare_asset(&loaded, 6, &NoProgress).unwrap();
    assert_eq!(asset, fresh);
    for (a, b) in stats.levels.iter().zip(&fresh_stats.levels) {
        assert_eq!(
            (
                a.voxels,
                a.lookup_bytes,
                a.resident_pages,
                a.proxy_triangles
            ),
            (
                b.voxels,
                b.lookup_bytes,
                b.resident_pages,
                b.proxy_triangles
            )
        );
    }
    // A hit returns the asset.
    let (hit, third) = prepare_into_cache(&model, 6, Some(&cache), &NoProgress).unwrap();
    assert_eq!(third.status, CacheStatus::Hit);
    assert_eq!(hit.as_ref(), Some(&fresh));
    // Levels above the maximum are refused, as by prepare_asset.
    let e = prepare_into_cache(&model, 14, Some(&cache), &NoProgress).unwrap_err();
    assert!(e.to_string().contains("maximum level 13"), "{e}");
}

#[test]
fn a_page_file_reads_every_page_and_refuses_a_damaged_one_alone() {
    let (_dir, path, a) = cached_asset("p.ssbvbast", 5);
    let file = PageFile::open(&path, 5, 5).unwrap();
    for lod in &a.lods {
        let index = page_index(&lod.point_cloud.voxels);
        assert_eq!(file.pages(lod.level), &index[..]);
        assert_eq!(file.voxels(lod.level), lod.point_cloud.voxels.len() as u64);
        let mut joined = Vec::new();
        for k in 0..index.len() {
            let got = file.read_page(lod.level, k).unwrap();
            assert_eq!(got.len() as u64, file.page_voxels(lod.level, k));
            joined.extend(got);
        }
        assert_eq!(joined, lod.point_cloud.voxels, "level {}", lod.level);
    }
    assert!(file.read_page(5, 10_000).is_err());
    assert!(file.read_page(6, 0).is_err());
    assert!(matches!(
        PageFile::open(&path, 6, 5),
        Err(CacheError::SourceMismatch { .. })
    ));
    // A page damaged after opening: that page is refused by its checksum, naming it; its
    // neighbours still read.
    let finest = &a.lods[5];
    let good = std::fs::read(&path).unwrap();
    let pc = offset_of(&good, &finest.point_cloud.voxels);
    let index = file.pages(5).to_vec();
    let mut bad = good.clone();
    bad[pc + index[1].first_voxel as usize * 16 + 3] ^= 0x01;
    std::fs::write(&path, &bad).unwrap();
    let file = PageFile::open(&path, 5, 5).unwrap();
    let e = file.read_page(5, 1).unwrap_err();
    assert!(
        matches!(&e, CacheError::Checksum { section, .. } if section.starts_with("page [")),
        "{e}"
    );
    assert!(file.read_page(5, 0).is_ok() && file.read_page(5, 2).is_ok());
    // A damaged index is refused when the file is opened.
    let ix: &[u8] = bytemuck::cast_slice(&index);
    let at = good.windows(ix.len()).position(|w| w == ix).unwrap();
    let mut bad = good.clone();
    bad[at + 24 + 8] ^= 0x40;
    std::fs::write(&path, &bad).unwrap();
    assert!(PageFile::open(&path, 5, 5).is_err());
}

#[test]
fn a_page_index_wrong_under_a_valid_checksum_is_refused_by_the_single_page_read() {
    // The index of level 5 rewritten so that page 0 ends where it starts, and its
    // section's checksum recomputed: only `read_page`'s own entry check can see it.
    let (_dir, path, a) = cached_asset("p.ssbvbast", 5);
    let mut index = page_index(&a.lods[5].point_cloud.voxels);
    assert!(index.len() >= 2 && index[1].first_voxel > 0);
    let good = std::fs::read(&path).unwrap();
    let ix: &[u8] = bytemuck::cast_slice(&index);
    let at = good.windows(ix.len()).position(|w| w == ix).unwrap();
    index[1].first_voxel = index[0].first_voxel;
    let payload: &[u8] = bytemuck::cast_slice(&index);
    let mut bad = good.clone();
    bad[at..at + payload.len()].copy_from_slice(payload);
    let sum = section_checksum(KIND_PAGE_INDEX, 5, payload);
    bad[at - 8..at].copy_from_slice(&sum.to_le_bytes());
    std::fs::write(&path, &bad).unwrap();
    let p = crate::svo::morton_decode(index[0].page);
    let e = read_page(&path, 5, 5, 5, p).unwrap_err();
    assert!(
        matches!(&e, CacheError::Corrupt { reason, .. } if reason.ends_with("bad index entry")),
        "{e}"
    );
    // The untouched levels still read; the whole file is refused.
    assert!(!read_page(&path, 5, 5, 4, [0; 3]).unwrap().is_empty());
    assert!(PageFile::open(&path, 5, 5).is_err());
}

#[test]
fn a_page_file_cut_short_after_opening_reports_the_page_as_truncated() {
    let (_dir, path, a) = cached_asset("p.ssbvbast", 5);
    let file = PageFile::open(&path, 5, 5).unwrap();
    let last = file.pages(5).len() - 1;
    let good = std::fs::read(&path).unwrap();
    let pc = offset_of(&good, &a.lods[5].point_cloud.voxels);
    // Cut inside the last page, half a voxel into it.
    let cut = pc as u64 + file.pages(5)[last].first_voxel * 16 + 8;
    std::fs::OpenOptions::new()
        .write(true)
        .open(&path)
        .unwrap()
        .set_len(cut)
        .unwrap();
    let e = file.read_page(5, last).unwrap_err();
    assert!(
        matches!(&e, CacheError::Truncated { what, .. } if what.starts_with("page [")),
        "{e}"
    );
    assert!(file.read_page(5, 0).is_ok());
}

#[test]
fn the_source_hash_is_xxh3_128_of_the_whole_file() {
    let dir = tempfile::tempdir().unwrap();
    // Empty, short, and longer than the 1 MiB read buffer (several reads).
    let mut long = Vec::with_capacity(3 << 20);
    let mut x = 0x9E37_79B9u32;
    while long.len() < (3 << 20) + 17 {
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        long.push(x as u8);
    }
    let mut hashes = Vec::new();
    // The empty file last: a reader that never stops at the end hangs on it.
    for (i, bytes) in [&b"abc"[..], b"abd", &long, b""].into_iter().enumerate() {
        let path = dir.path().join(format!("{i}.obj"));
        std::fs::write(&path, bytes).unwrap();
        let h = hash_source(&path).unwrap();
        assert_eq!(h, xxhash_rust::xxh3::xxh3_128(bytes), "file {i}");
        hashes.push(h);
    }
    hashes.dedup();
    assert_eq!(hashes.len(), 4, "different files must hash apart");
    assert!(matches!(
        hash_source(&dir.path().join("none.obj")),
        Err(CacheError::Io { .. })
    ));
}

#[test]
fn cache_names_and_the_default_folder() {
    assert_eq!(
        cache_file_name(0xab, 7),
        "000000000000000000000000000000ab-L7.ssbvbast"
    );
    assert_eq!(
        cache_file_name(u128::MAX, 12),
        format!("{}-L12.ssbvbast", "f".repeat(32))
    );
    let env = |pairs: &'static [(&'static str, &'static str)]| {
        move |k: &str| {
            pairs
                .iter()
                .find(|(n, _)| *n == k)
                .map(|(_, v)| std::ffi::OsString::from(v))
        }
    };
    const ALL: [(&str, &str); 3] = [
        ("SSBVB_CACHE_DIR", "/a"),
        ("XDG_CACHE_HOME", "/x"),
        ("HOME", "/h"),
    ];
    assert_eq!(cache_dir_from(env(&ALL)), PathBuf::from("/a"));
    assert_eq!(cache_dir_from(env(&ALL[1..])), PathBuf::from("/x/ssbvb"));
    assert_eq!(
        cache_dir_from(env(&ALL[2..])),
        PathBuf::from("/h/.cache/ssbvb")
    );
    // Empty values count as unset.
    const EMPTY: [(&str, &str); 3] = [
        ("SSBVB_CACHE_DIR", ""),
        ("XDG_CACHE_HOME", ""),
        ("HOME", "/h"),
    ];
    assert_eq!(
        cache_dir_from(env(&EMPTY)),
        PathBuf::from("/h/.cache/ssbvb")
    );
    assert_eq!(
        cache_dir_from(env(&[])),
        std::env::temp_dir().join("ssbvb-cache")
    );
    // The real environment gives some folder, whichever variable is set here.
    assert!(!default_cache_dir().as_os_str().is_empty());
}

/// The header of `good` with the bytes at `offset` replaced by `value` and the header
/// checksum recomputed, so only the field's meaning is wrong.
fn with_header_bytes(good: &[u8], offset: usize, value: &[u8]) -> Vec<u8> {
    let mut b = good.to_vec();
    b[offset..offset + value.len()].copy_from_slice(value);
    let sum = xxhash_rust::xxh3::xxh3_64(&b[..80]);
    b[80..88].copy_from_slice(&sum.to_le_bytes());
    b
}

/// [`with_header_bytes`] for a u32 field.
fn with_header_field(good: &[u8], offset: usize, value: u32) -> Vec<u8> {
    with_header_bytes(good, offset, &value.to_le_bytes())
}

#[test]
fn damaged_headers_and_sections_are_named() {
    let (dir, path, _) = cached_asset("a.ssbvbast", 99);
    let good = std::fs::read(&path).unwrap();
    let bad = dir.path().join("bad.ssbvbast");
    let read = |bytes: &[u8], level: u32| {
        std::fs::write(&bad, bytes).unwrap();
        read_cache(&bad, 99, level).unwrap_err()
    };
    // Shorter than the magic: not a cache file; the magic alone: a truncated one.
    assert!(matches!(read(&good[..3], 5), CacheError::BadMagic { .. }));
    assert!(matches!(read(&good[..8], 5), CacheError::Truncated { .. }));
    // Section counts that disagree with the level, under a valid checksum.
    for (offset, value) in [(36, 7), (72, 25), (72, 0)] {
        let e = read(&with_header_field(&good, offset, value), 5);
        assert!(
            e.to_string()
                .contains("inconsistent level / section counts"),
            "{offset}: {e}"
        );
    }
    // Level 16 is the most there is: its header passes (the file then ends); 17 does not.
    let mut top = with_header_field(&good, 32, 16);
    top = with_header_field(&top, 36, 17);
    top = with_header_field(&top, 72, 68);
    let e = read(&top[..HEADER_BYTES], 16);
    assert!(matches!(e, CacheError::Truncated { .. }), "{e}");
    let mut over = with_header_field(&good, 32, 17);
    over = with_header_field(&over, 36, 18);
    over = with_header_field(&over, 72, 72);
    let e = read(&over[..HEADER_BYTES], 17);
    assert!(
        e.to_string()
            .contains("inconsistent level / section counts"),
        "{e}"
    );
    // An object space that is not one, under a valid checksum: a scale of zero, below
    // zero or infinite, a centre not finite (centre at bytes 40..64, scale at 64..72).
    for (offset, value) in [
        (64, 0.0),
        (64, -1.0),
        (64, f64::INFINITY),
        (40, f64::NAN),
        (56, f64::NEG_INFINITY),
    ] {
        let e = read(&with_header_bytes(&good, offset, &value.to_le_bytes()), 5);
        assert!(
            e.to_string().contains("non-finite object space"),
            "{offset} = {value}: {e}"
        );
    }
    // A section of the right kind for another level, or of another kind for this one.
    let mut b = good.clone();
    b[HEADER_BYTES + 4..HEADER_BYTES + 8].copy_from_slice(&1u32.to_le_bytes());
    let e = read(&b, 5);
    assert!(
        e.to_string()
            .contains("expected section page_index of level 0, found page_index of level 1"),
        "{e}"
    );
    let mut b = good.clone();
    b[HEADER_BYTES..HEADER_BYTES + 4].copy_from_slice(&1u32.to_le_bytes());
    let e = read(&b, 5);
    assert!(
        e.to_string()
            .contains("expected section page_index of level 0, found point_cloud of level 0"),
        "{e}"
    );
    // A flipped payload byte is a checksum error naming its section, for every kind.
    let mut at = HEADER_BYTES;
    let mut named = std::collections::BTreeSet::new();
    while at + SECTION_HEADER_BYTES <= good.len() {
        let u32_at = |o: usize| u32::from_le_bytes(good[o..o + 4].try_into().unwrap());
        let (kind, lod) = (u32_at(at), u32_at(at + 4));
        let len = u64::from_le_bytes(good[at + 8..at + 16].try_into().unwrap()) as usize;
        if len > 0 && named.insert(kind) {
            let mut b = good.clone();
            b[at + SECTION_HEADER_BYTES] ^= 0x10;
            let e = read(&b, 5);
            let want = format!("{} of level {lod}", kind_name(kind));
            match &e {
                CacheError::Checksum { section, .. } => assert_eq!(section, &want),
                other => panic!("{want}: {other}"),
            }
        }
        at += SECTION_HEADER_BYTES + len;
    }
    let names: Vec<&str> = named.iter().map(|&k| kind_name(k)).collect();
    assert_eq!(
        names,
        [
            "point_cloud",
            "proxy_positions",
            "proxy_triangles",
            "page_index"
        ]
    );
}

/// A missing MTL library and a missing texture are warnings of the load, said on the
/// rebuild and again on a cache hit; a fixed model (the files put back) says none.
#[test]
fn load_warnings_name_missing_materials_and_survive_a_cache_hit() {
    let dir = tempfile::tempdir().unwrap();
    let obj = dir.path().join("m.obj");
    std::fs::write(
        &obj,
        "mtllib gone.mtl\nmtllib here.mtl\nusemtl red\nv -1 -1 -1\nv 1 -1 0\nv 0 1 1\nf 1 2 3\n",
    )
    .unwrap();
    std::fs::write(
        dir.path().join("here.mtl"),
        "newmtl red\nKd 1 0 0\nmap_Kd missing.png\n",
    )
    .unwrap();
    let cache = dir.path().join("cache");
    let (_, first) = load_or_prepare(&obj, 3, Some(&cache), &NoProgress).unwrap();
    assert!(matches!(first.status, CacheStatus::Rebuilt { .. }));
    let said = |o: &PrepareOutcome, what: &str| o.warnings.iter().any(|w| w.contains(what));
    assert!(said(&first, "gone.mtl"), "{:?}", first.warnings);
    assert!(said(&first, "missing.png"), "{:?}", first.warnings);
    let (_, hit) = load_or_prepare(&obj, 3, Some(&cache), &NoProgress).unwrap();
    assert_eq!(hit.status, CacheStatus::Hit);
    assert_eq!(hit.warnings, first.warnings);
    // The library and the texture put in place: another cache key, and no warning.
    std::fs::write(dir.path().join("gone.mtl"), "newmtl blue\nKd 0 0 1\n").unwrap();
    image::RgbaImage::new(1, 1)
        .save(dir.path().join("missing.png"))
        .unwrap();
    let (_, fixed) = load_or_prepare(&obj, 3, Some(&cache), &NoProgress).unwrap();
    assert!(matches!(fixed.status, CacheStatus::Rebuilt { .. }));
    assert!(fixed.warnings.is_empty(), "{:?}", fixed.warnings);
}
