use super::*;
use ssbvb_voxel::progress::NoProgress;

fn err(arrays: VoxelArrays<'_>, p: Placement) -> String {
    match prepare(&arrays, p, &NoProgress) {
        Ok(_) => panic!("expected an error"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn wrong_types_shapes_and_placements_are_named() {
    let p = Placement::default();
    let five = [0f64; 2 * 2 * 2 * 5];
    let e = err(
        VoxelArrays::Dense(Array::new(vec![2, 2, 2, 5], ArrayData::F64(&five))),
        p,
    );
    assert!(
        e.contains("must have shape (X, Y, Z, 4) or (X, Y, Z, 3), got [2, 2, 2, 5]"),
        "{e}"
    );
    let flat = [0u8; 16];
    let e = err(
        VoxelArrays::Dense(Array::new(vec![4, 4], ArrayData::U8(&flat))),
        p,
    );
    assert!(e.contains("got [4, 4]"), "{e}");
    let ints = [0i32; 8 * 4];
    let e = err(
        VoxelArrays::Dense(Array::new(vec![2, 2, 2, 4], ArrayData::I32(&ints))),
        p,
    );
    assert!(
        e.contains("dense colour grid must be uint8, or float32"),
        "{e}"
    );
    let f = [0f32; 8];
    let e = err(
        VoxelArrays::Occupancy {
            occupied: Array::new(vec![2, 2, 2], ArrayData::F32(&f)),
            color: [255; 4],
        },
        p,
    );
    assert!(
        e.contains("must be bool or an integer type, got float32"),
        "{e}"
    );
    let short = [true; 7];
    let e = err(
        VoxelArrays::Occupancy {
            occupied: Array::new(vec![2, 2, 2], ArrayData::Bool(&short)),
            color: [255; 4],
        },
        p,
    );
    assert!(e.contains("holds 8 elements, got 7"), "{e}");
    let one = [true];
    let occ = || VoxelArrays::Occupancy {
        occupied: Array::new(vec![1, 1, 1], ArrayData::Bool(&one)),
        color: [255; 4],
    };
    for bad in [0.0, f64::NAN, -1.0, f64::INFINITY] {
        let e = err(
            occ(),
            Placement {
                voxel_size: bad,
                ..p
            },
        );
        assert!(
            e.contains("voxel_size must be a positive finite number"),
            "{e}"
        );
    }
    let e = err(
        occ(),
        Placement {
            origin: [0.0, f64::NAN, 0.0],
            ..p
        },
    );
    assert!(e.contains("origin must be finite"), "{e}");
    // Finite inputs whose grid does not fit f64 world coordinates (a 3-cell row needs
    // the 4-cell grid: twice 1e308 across).
    let row = [true; 3];
    let e = err(
        VoxelArrays::Occupancy {
            occupied: Array::new(vec![3, 1, 1], ArrayData::Bool(&row)),
            color: [255; 4],
        },
        Placement {
            voxel_size: 1e308,
            ..p
        },
    );
    assert!(e.contains("outside finite world coordinates"), "{e}");
}

/// A grid past level 13 is refused from its shape alone: the 8193³ array is never
/// looked at (its data is empty, which a length check after allocation would report).
#[test]
fn a_grid_past_the_finest_level_is_refused_before_anything_is_allocated() {
    let e = err(
        VoxelArrays::Occupancy {
            occupied: Array::new(vec![8193, 1, 1], ArrayData::Bool(&vec![false; 8193])),
            color: [255; 4],
        },
        Placement::default(),
    );
    assert!(e.contains("8193 cells along axis 0"), "{e}");
    // Two sparse voxels at x = `a` and x = `b`.
    let two = |a: i64, b: i64| {
        let coords = [a, 0, 0, b, 0, 0];
        let rgba = [255u8; 8];
        err(
            VoxelArrays::Sparse {
                coords: Array::new(vec![2, 3], ArrayData::I64(&coords)),
                colors: SparseColors::Each(Array::new(vec![2, 4], ArrayData::U8(&rgba))),
            },
            Placement::default(),
        )
    };
    let e = two(0, 9000);
    assert!(e.contains("9001 cells along axis 0"), "{e}");
    // Coordinates at both ends of i64: refused, not overflowed.
    let e = two(i64::MIN, i64::MAX);
    assert!(e.contains("cells along axis 0"), "{e}");
}

#[test]
fn an_empty_grid_is_a_warning_not_an_error() {
    let none = [false; 8];
    let p = prepare(
        &VoxelArrays::Occupancy {
            occupied: Array::new(vec![2, 2, 2], ArrayData::Bool(&none)),
            color: [255; 4],
        },
        Placement::default(),
        &NoProgress,
    )
    .unwrap();
    assert!(p.asset.is_none());
    assert_eq!(p.warnings.len(), 1);
}

/// Dense and sparse forms of the same voxels give the same cells, placed where the
/// origin and voxel size say: each voxel's world box, from the asset's finest level and
/// the instance, is the box the arrays describe.
#[test]
fn dense_and_sparse_agree_and_cells_land_in_their_world_boxes() {
    let (nx, ny, nz) = (3usize, 5usize, 2usize);
    let mut rgba = vec![0u8; nx * ny * nz * 4];
    let set = [[0, 0, 0], [2, 4, 1], [1, 3, 0]];
    let mut coords = Vec::new();
    let mut colors = Vec::new();
    for (n, c) in set.iter().enumerate() {
        let i = ((c[0] * ny + c[1]) * nz + c[2]) * 4;
        let px = [10 * n as u8, 200, 30, 255];
        rgba[i..i + 4].copy_from_slice(&px);
        // Sparse coordinates shifted by (-5, 7, 0), the origin moved back to match.
        coords.extend([c[0] as i32 - 5, c[1] as i32 + 7, c[2] as i32]);
        colors.extend(px);
    }
    let placement = Placement {
        origin: [1.0, -2.0, 0.5],
        voxel_size: 0.25,
    };
    let dense = prepare(
        &VoxelArrays::Dense(Array::new(vec![nx, ny, nz, 4], ArrayData::U8(&rgba))),
        placement,
        &NoProgress,
    )
    .unwrap();
    let shifted = Placement {
        origin: [1.0 + 5.0 * 0.25, -2.0 - 7.0 * 0.25, 0.5],
        ..placement
    };
    let sparse = prepare(
        &VoxelArrays::Sparse {
            coords: Array::new(vec![3, 3], ArrayData::I32(&coords)),
            colors: SparseColors::Each(Array::new(vec![3, 4], ArrayData::U8(&colors))),
        },
        shifted,
        &NoProgress,
    )
    .unwrap();
    let boxes = |p: &PreparedArrays| {
        let (asset, xf, level) = p.asset.as_ref().unwrap();
        assert_eq!(*level, 3, "5 cells need the 8-cell grid");
        let lod = &asset.lods[*level as usize].point_cloud;
        let cell = 2.0 / 8.0;
        let mut out: Vec<[i64; 3]> = lod
            .voxels
            .iter()
            .map(|v| {
                let c = v.cell();
                let lo = DVec3::new(c[0] as f64, c[1] as f64, c[2] as f64) * cell - 1.0;
                let w = xf.transform_point3(lo);
                // World min corner back to the dense grid's cell index.
                let idx = (w - DVec3::from(placement.origin)) / placement.voxel_size;
                assert!((idx - idx.round()).abs().max_element() < 1e-9, "{idx}");
                [idx.x, idx.y, idx.z].map(|x| x.round() as i64)
            })
            .collect();
        out.sort();
        out
    };
    let want: Vec<[i64; 3]> = {
        let mut w: Vec<[i64; 3]> = set.iter().map(|c| c.map(|x| x as i64)).collect();
        w.sort();
        w
    };
    assert_eq!(boxes(&dense), want);
    assert_eq!(boxes(&sparse), want);
}

/// Prepares `arrays`, returning each voxel's cell (in the arrays' coordinates) and its
/// sRGB colour, sorted.
fn voxels_of(arrays: VoxelArrays<'_>) -> Vec<([i64; 3], [u8; 4])> {
    let p = prepare(&arrays, Placement::default(), &NoProgress).unwrap();
    let (asset, _, level) = p.asset.as_ref().unwrap();
    let (_, voxels) = ssbvb_voxel::export::level_voxels(asset, *level).unwrap();
    let mut out: Vec<_> = voxels
        .iter()
        .map(|v| {
            let c = v.cell.map(i64::from);
            ([0, 1, 2].map(|k| c[k] + p.min_cell[k]), v.rgba)
        })
        .collect();
    out.sort();
    out
}

/// The same three voxels as RGBA bytes in C order, as float RGB in Fortran order (read
/// through strides), as labels with a palette, as a z-y-x view, and as K3D's sparse
/// `[x, y, z, label]` rows: the same cells and colours every time.
#[test]
fn every_form_and_memory_order_gives_the_same_voxels() {
    let (nx, ny, nz) = (3usize, 2usize, 4usize);
    let set: [([usize; 3], [u8; 4]); 3] = [
        ([0, 0, 0], [255, 0, 0, 255]),
        ([2, 1, 3], [0, 128, 255, 255]),
        ([1, 0, 2], [10, 20, 30, 255]),
    ];
    let want: Vec<([i64; 3], [u8; 4])> = {
        let mut w: Vec<_> = set
            .iter()
            .map(|(c, px)| (c.map(|x| x as i64), *px))
            .collect();
        w.sort();
        w
    };
    let mut rgba = vec![0u8; nx * ny * nz * 4];
    // Fortran order: x fastest, then y, z, channel.
    let mut rgb_f = vec![0f32; nx * ny * nz * 3];
    let mut labels = vec![0i64; nx * ny * nz];
    // The same labels stored z-major: `zyx[z][y][x]`.
    let mut zyx = vec![0u16; nx * ny * nz];
    let mut palette = vec![0u8; 4 * 4];
    let mut k3d = Vec::new();
    for (n, ([x, y, z], px)) in set.iter().enumerate() {
        let c = (x * ny + y) * nz + z;
        rgba[c * 4..c * 4 + 4].copy_from_slice(px);
        for ch in 0..3 {
            rgb_f[x + nx * (y + ny * (z + nz * ch))] = f32::from(px[ch]) / 255.0;
        }
        labels[c] = n as i64 + 1;
        zyx[(z * ny + y) * nx + x] = n as u16 + 1;
        palette[(n + 1) * 4..(n + 2) * 4].copy_from_slice(px);
        k3d.extend([*x as i32, *y as i32, *z as i32, n as i32 + 1]);
    }
    // An unlabelled row is skipped.
    k3d.extend([7, 7, 7, 0]);
    let pal = || Array::new(vec![4, 4], ArrayData::U8(&palette));
    // Colours are stored linear in 8 bits, so a dark sRGB byte comes back near, not equal
    // (10 → 13): the cells are the set's, and every form gives the first form's colours.
    let first = voxels_of(VoxelArrays::Dense(Array::new(
        vec![nx, ny, nz, 4],
        ArrayData::U8(&rgba),
    )));
    let cells = |v: &[([i64; 3], [u8; 4])]| v.iter().map(|(c, _)| *c).collect::<Vec<_>>();
    assert_eq!(cells(&first), cells(&want));
    for ((_, got), (_, px)) in first.iter().zip(&want) {
        assert!(
            got.iter().zip(px).all(|(a, b)| a.abs_diff(*b) <= 4),
            "{got:?} {px:?}"
        );
    }
    let want = first;
    let f_strides = vec![1, nx, nx * ny, nx * ny * nz];
    assert_eq!(
        voxels_of(VoxelArrays::Dense(Array::strided(
            vec![nx, ny, nz, 3],
            f_strides,
            ArrayData::F32(&rgb_f)
        ))),
        want
    );
    assert_eq!(
        voxels_of(VoxelArrays::Labels {
            labels: Array::new(vec![nx, ny, nz], ArrayData::I64(&labels)),
            palette: pal(),
        }),
        want
    );
    // `order="zyx"`: axis x of the view steps 1 element, y steps nx, z steps nx·ny.
    assert_eq!(
        voxels_of(VoxelArrays::Labels {
            labels: Array::strided(vec![nx, ny, nz], vec![1, nx, nx * ny], ArrayData::U16(&zyx)),
            palette: pal(),
        }),
        want
    );
    assert_eq!(
        voxels_of(VoxelArrays::Sparse {
            coords: Array::new(vec![4, 4], ArrayData::I32(&k3d)),
            colors: SparseColors::Palette(pal()),
        }),
        want
    );
}

/// Values no voxel can take are named with their element: a float colour outside [0, 1], a
/// label past the palette, a negative label, strides that reach past the data.
#[test]
fn refused_values_name_their_element() {
    let p = Placement::default();
    let mut f = vec![0f64; 2 * 4];
    f[4 + 3] = 1.0;
    f[4 + 1] = f64::NAN;
    let e = err(
        VoxelArrays::Dense(Array::new(vec![1, 1, 2, 4], ArrayData::F64(&f))),
        p,
    );
    assert!(e.contains("element [0, 0, 1, 1] is NaN"), "{e}");
    let palette = [255u8; 2 * 3];
    let grid = |l: &'static [i32]| VoxelArrays::Labels {
        labels: Array::new(vec![2, 2, 1], ArrayData::I32(l)),
        palette: Array::new(vec![2, 3], ArrayData::U8(&palette)),
    };
    let e = err(grid(&[0, 1, 2, 0]), p);
    assert!(e.contains("label 2 at [1, 0, 0] has no palette row"), "{e}");
    let e = err(grid(&[0, -1, 1, 0]), p);
    assert!(e.contains("label -1 at [0, 1, 0]"), "{e}");
    let floats = [1.0f32; 4];
    let e = err(
        VoxelArrays::Labels {
            labels: Array::new(vec![2, 2, 1], ArrayData::F32(&floats)),
            palette: Array::new(vec![2, 3], ArrayData::U8(&palette)),
        },
        p,
    );
    assert!(
        e.contains("label grid must be an integer type, got float32"),
        "{e}"
    );
    let coords = [0.5f32; 3];
    let e = err(
        VoxelArrays::Sparse {
            coords: Array::new(vec![1, 3], ArrayData::F32(&coords)),
            colors: SparseColors::One([255; 4]),
        },
        p,
    );
    assert!(
        e.contains("sparse coordinates must be an integer type"),
        "{e}"
    );
    let few = [true; 4];
    let e = err(
        VoxelArrays::Occupancy {
            occupied: Array::strided(vec![2, 2, 2], vec![2, 1, 4], ArrayData::Bool(&few)),
            color: [255; 4],
        },
        p,
    );
    assert!(e.contains("holds 8 elements, got 4"), "{e}");
}
