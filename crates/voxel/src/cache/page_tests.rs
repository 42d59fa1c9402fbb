//! The page-index rules of the cache one by one (from the mutation run: the damaged-file
//! sweeps rarely produce an index that is wrong in exactly one way under valid checksums).
use super::page_file::check_entries;
use super::pages::{PageEntry, check_index, check_page, page_coords, page_index};
use super::*;
use crate::svo::morton_encode;

fn path() -> &'static Path {
    Path::new("t.ssbvbast")
}

fn entry(page: u64, first_voxel: u64) -> PageEntry {
    PageEntry {
        page,
        first_voxel,
        checksum: 0,
    }
}

#[test]
fn page_file_entries_follow_every_rule() {
    // Level 6: 64 pages of 16³ cells.
    let ok = |e: &[PageEntry], voxels: u64| check_entries(path(), 6, e, voxels).is_ok();
    assert!(ok(&[], 0));
    assert!(!ok(&[], 5), "voxels without pages");
    assert!(!ok(&[entry(0, 0)], 0), "a page without voxels");
    assert!(ok(&[entry(0, 0), entry(3, 10)], 20));
    assert!(
        !ok(&[entry(0, 1), entry(3, 10)], 20),
        "first page not at voxel 0"
    );
    assert!(ok(&[entry(63, 0)], 5));
    assert!(!ok(&[entry(64, 0)], 5), "a page beyond the level");
    assert!(!ok(&[entry(0, 0), entry(3, 0)], 20), "an empty page");
    assert!(!ok(&[entry(0, 0), entry(3, 10)], 10), "an empty last page");
    assert!(ok(&[entry(0, 0)], 4096), "a full page");
    assert!(
        !ok(&[entry(0, 0)], 4097),
        "more voxels than a page has cells"
    );
    assert!(ok(&[entry(0, 0), entry(3, 3000)], 6000));
    assert!(!ok(&[entry(3, 0), entry(3, 10)], 20), "one page twice");
    assert!(!ok(&[entry(3, 0), entry(2, 10)], 20), "pages out of order");
}

/// Voxels at `cells` (level 6), in the given order.
fn voxels(cells: &[[u32; 3]]) -> (Vec<PackedVoxel>, Vec<u64>) {
    let v: Vec<PackedVoxel> = cells
        .iter()
        .map(|&c| PackedVoxel::new(c, [0.0, 0.0, 1.0], [0.5; 4], [0.0; 2]))
        .collect();
    let codes = cells.iter().map(|&c| morton_encode(c)).collect();
    (v, codes)
}

#[test]
fn a_level_index_must_be_the_one_page_index_writes() {
    // Two voxels in page 0, two in page (1, 0, 0) (code 1).
    let (v, codes) = voxels(&[[0, 0, 0], [1, 0, 0], [16, 0, 0], [17, 0, 0]]);
    let good = page_index(&v);
    assert_eq!(
        good.iter()
            .map(|e| (e.page, e.first_voxel))
            .collect::<Vec<_>>(),
        [(0, 0), (1, 2)]
    );
    let check = |index: &[PageEntry]| check_index(path(), 6, index, &v, &codes);
    assert!(check(&good).is_ok());
    let mut wrong_first = good.clone();
    wrong_first[1].first_voxel = 3;
    assert!(
        check(&wrong_first).is_err(),
        "page right, first voxel wrong"
    );
    let mut wrong_page = good.clone();
    wrong_page[1].page = 2;
    assert!(check(&wrong_page).is_err(), "first voxel right, page wrong");
    assert!(check(&good[..1]).is_err(), "a page missing");
    let mut extra = good.clone();
    extra.push(entry(5, 4));
    assert!(check(&extra).is_err(), "an entry too many");
    let mut sum = good.clone();
    sum[0].checksum ^= 1;
    let e = check(&sum).unwrap_err();
    assert!(matches!(e, CacheError::Checksum { .. }), "{e}");
}

#[test]
fn a_page_holds_its_own_cells_in_order() {
    let page = morton_encode([1, 2, 3]);
    assert_eq!(page_coords(page), [1, 2, 3]);
    let base = [16, 32, 48];
    let at = |d: [u32; 3]| [base[0] + d[0], base[1] + d[1], base[2] + d[2]];
    let check = |cells: &[[u32; 3]], lod: u32| {
        let (mut v, _) = voxels(cells);
        let e = PageEntry {
            page,
            first_voxel: 0,
            checksum: xxhash_rust::xxh3::xxh3_64(bytemuck::cast_slice(&v)),
        };
        check_page(path(), lod, &e, &mut v)
    };
    assert!(check(&[at([0, 0, 0]), at([1, 0, 0]), at([15, 15, 15])], 6).is_ok());
    let e = check(&[at([1, 0, 0]), at([0, 0, 0])], 6).unwrap_err();
    assert!(e.to_string().contains("page [1, 2, 3] of level 6"), "{e}");
    assert!(
        check(&[at([0, 0, 0]), at([0, 0, 0])], 6).is_err(),
        "a cell twice"
    );
    assert!(check(&[[0, 0, 0]], 6).is_err(), "a cell of another page");
    // The page lies outside a level-5 grid (32 cells: z = 48 is beyond).
    assert!(
        check(&[at([0, 0, 0])], 5).is_err(),
        "a cell outside the grid"
    );
    // A wrong checksum names the page.
    let (mut v, _) = voxels(&[at([0, 0, 0])]);
    let e = PageEntry {
        page,
        first_voxel: 0,
        checksum: 7,
    };
    match check_page(path(), 6, &e, &mut v) {
        Err(CacheError::Checksum { section, .. }) => {
            assert_eq!(section, "page [1, 2, 3] of level 6")
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn point_clouds_are_checked_cell_by_cell() {
    let ok = |cells: &[[u32; 3]], level: u32| validated_codes(path(), level, &voxels(cells).0);
    assert_eq!(
        ok(&[[0, 0, 0], [1, 0, 0], [3, 3, 3]], 2).unwrap(),
        [0, 1, morton_encode([3, 3, 3])]
    );
    assert!(ok(&[[4, 0, 0]], 2).is_err(), "outside a 4³ grid");
    assert!(ok(&[[1, 0, 0], [0, 0, 0]], 2).is_err(), "out of order");
    assert!(ok(&[[1, 0, 0], [1, 0, 0]], 2).is_err(), "a cell twice");
    // At most 8^level voxels: 8 at level 1 (the full grid) but not 9.
    let full: Vec<[u32; 3]> = (0..8).map(|i| [i & 1, (i >> 1) & 1, i >> 2]).collect();
    assert!(ok(&full, 1).is_ok());
    let mut nine = full.clone();
    nine.push([1, 1, 1]);
    let e = ok(&nine, 1).unwrap_err();
    assert!(e.to_string().contains("too many voxels for level 1"), "{e}");
}
