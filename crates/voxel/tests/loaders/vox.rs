//! MagicaVoxel `.vox` fixtures (scene graph instancing) and errors.

use ssbvb_voxel::load::{Format, LoadError, srgb_to_linear};

use crate::{approx, mutate_and_parse, parse, parse_err, voxels_of};

fn chunk(id: &[u8; 4], content: &[u8], children: &[u8]) -> Vec<u8> {
    let mut out = id.to_vec();
    out.extend_from_slice(&(content.len() as u32).to_le_bytes());
    out.extend_from_slice(&(children.len() as u32).to_le_bytes());
    out.extend_from_slice(content);
    out.extend_from_slice(children);
    out
}

fn vox_string(s: &str) -> Vec<u8> {
    let mut out = (s.len() as i32).to_le_bytes().to_vec();
    out.extend_from_slice(s.as_bytes());
    out
}

fn vox_dict(pairs: &[(&str, &str)]) -> Vec<u8> {
    let mut out = (pairs.len() as i32).to_le_bytes().to_vec();
    for (k, v) in pairs {
        out.extend(vox_string(k));
        out.extend(vox_string(v));
    }
    out
}

fn ints(v: &[i32]) -> Vec<u8> {
    v.iter().flat_map(|i| i.to_le_bytes()).collect()
}

fn vox_file(children: &[Vec<u8>]) -> Vec<u8> {
    let mut out = b"VOX ".to_vec();
    out.extend_from_slice(&150u32.to_le_bytes());
    out.extend(chunk(b"MAIN", &[], &children.concat()));
    out
}

fn ntrn(id: i32, child: i32, layer: i32, frame: &[(&str, &str)]) -> Vec<u8> {
    let mut c = ints(&[id]);
    c.extend(vox_dict(&[]));
    c.extend(ints(&[child, -1, layer, 1]));
    c.extend(vox_dict(frame));
    chunk(b"nTRN", &c, &[])
}

/// Two models, a group with three instances: translated, rotated, and on a hidden layer.
pub(crate) fn scene_vox() -> Vec<u8> {
    let size = |x: i32, y: i32, z: i32| chunk(b"SIZE", &ints(&[x, y, z]), &[]);
    let xyzi = |vs: &[[u8; 4]]| {
        let mut c = ints(&[vs.len() as i32]);
        c.extend(vs.iter().flatten());
        chunk(b"XYZI", &c, &[])
    };
    let mut palette = Vec::new();
    for i in 0..256u32 {
        palette.extend_from_slice(&[i as u8, 0, 0, 255]);
    }
    let mut group = ints(&[1]);
    group.extend(vox_dict(&[]));
    group.extend(ints(&[3, 2, 4, 6]));
    let shape = |id: i32, model: i32| {
        let mut c = ints(&[id]);
        c.extend(vox_dict(&[]));
        c.extend(ints(&[1, model]));
        c.extend(vox_dict(&[]));
        chunk(b"nSHP", &c, &[])
    };
    let mut layer = ints(&[1]);
    layer.extend(vox_dict(&[("_hidden", "1")]));
    layer.extend(ints(&[-1]));
    vox_file(&[
        size(2, 2, 2),
        xyzi(&[[0, 0, 0, 1], [1, 0, 0, 2]]),
        size(1, 1, 1),
        xyzi(&[[0, 0, 0, 3]]),
        chunk(b"RGBA", &palette, &[]),
        ntrn(0, 1, -1, &[]),
        chunk(b"nGRP", &group, &[]),
        ntrn(2, 3, 0, &[("_t", "10 0 0")]),
        shape(3, 0),
        // 90° about +z: row 0 = (0, −1, 0), row 1 = (1, 0, 0), row 2 = (0, 0, 1).
        ntrn(4, 5, 0, &[("_r", "17"), ("_t", "0 20 0")]),
        shape(5, 0),
        ntrn(6, 7, 1, &[("_t", "0 0 30")]),
        shape(7, 1),
        chunk(b"LAYR", &layer, &[]),
    ])
}

#[test]
fn vox_scene_graph_places_instances() {
    let bytes = scene_vox();
    let v = voxels_of(parse(&bytes, Format::Vox, "s.vox").unwrap());
    // Pivot (1, 1, 1). Instance 1: q = (−1,−1,−1), (0,−1,−1) + (10, 0, 0) → (9,−1,−1),
    // (10,−1,−1). Instance 2: rotated cubes' minimum corners (0,−1,−1), (0, 0,−1) + (0, 20,
    // 0) → (0, 19,−1), (0, 20,−1). Then Z-up → Y-up: (x, y, z) ↦ (x, z, −y − 1).
    let expected = [[9, -1, 0], [10, -1, 0], [0, -1, -20], [0, -1, -21]];
    assert_eq!(v.voxels, expected, "hidden layer must be skipped");
    // Palette entry k is colour index k + 1: index 1 → red byte 0, index 2 → red byte 1.
    assert_eq!(v.colors[0][0], 0.0);
    assert!(approx(v.colors[1][0], srgb_to_linear(1.0 / 255.0)));
    // dot_vox reads our fixture too (sanity of the writer).
    assert_eq!(dot_vox::load_bytes(&bytes).unwrap().models.len(), 2);
    mutate_and_parse(&bytes, Format::Vox, "s.vox", bytes.len(), 2000);
}

#[test]
fn vox_errors_and_limits() {
    let size = |x: i32, y: i32, z: i32| chunk(b"SIZE", &ints(&[x, y, z]), &[]);
    let e = parse_err(&vox_file(&[size(1 << 30, 1, 1)]), Format::Vox, "h.vox");
    assert!(matches!(e, LoadError::TooLarge { .. }), "{e}");
    let mut xyzi = ints(&[i32::MAX]);
    xyzi.extend([0, 0, 0, 1]);
    let e = parse_err(
        &vox_file(&[size(1, 1, 1), chunk(b"XYZI", &xyzi, &[])]),
        Format::Vox,
        "c.vox",
    );
    assert!(
        e.offset().is_some() && e.to_string().contains("does not fit"),
        "{e}"
    );
    let e = parse_err(
        b"VOX \x96\0\0\0MAIN\0\0\0\0\xff\xff\0\0",
        Format::Vox,
        "m.vox",
    );
    assert_eq!(e.offset(), Some(12), "{e}");
    assert!(matches!(
        parse_err(&vox_file(&[]), Format::Vox, "e.vox"),
        LoadError::Empty { .. }
    ));
    // Deeply nested chunks (a stack overflow for recursive readers) are just skipped.
    let levels = 100_000u32;
    let mut nested = Vec::with_capacity(12 * (levels as usize + 1));
    for k in 0..levels {
        nested.extend_from_slice(b"NEST");
        nested.extend_from_slice(&0u32.to_le_bytes());
        nested.extend_from_slice(&((levels - k) * 12).to_le_bytes());
    }
    nested.extend_from_slice(&chunk(b"XXXX", &[], &[]));
    let mut file = vec![
        size(1, 1, 1),
        chunk(b"XYZI", &[1, 0, 0, 0, 0, 0, 0, 1], &[]),
    ];
    file.push(nested);
    assert_eq!(
        voxels_of(parse(&vox_file(&file), Format::Vox, "n.vox").unwrap())
            .voxels
            .len(),
        1
    );
    // A scene-graph cycle terminates.
    let cyclic = vox_file(&[
        size(1, 1, 1),
        chunk(b"XYZI", &[1, 0, 0, 0, 0, 0, 0, 1], &[]),
        ntrn(0, 0, -1, &[]),
    ]);
    assert!(
        parse(&cyclic, Format::Vox, "y.vox").is_err(),
        "no instance: empty"
    );
    // Bad rotation byte: located.
    let bad = vox_file(&[
        size(1, 1, 1),
        chunk(b"XYZI", &[1, 0, 0, 0, 0, 0, 0, 1], &[]),
        ntrn(0, 1, -1, &[("_r", "3")]),
    ]);
    assert!(parse_err(&bad, Format::Vox, "r.vox").offset().is_some());
}
