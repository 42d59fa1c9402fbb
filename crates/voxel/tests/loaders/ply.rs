//! PLY fixtures (ASCII, both binary byte orders, triangle strips) and errors.

use std::time::Instant;

use glam::Vec3;
use ssbvb_voxel::load::{Format, LoadError, srgb_to_linear};

use crate::{approx, assert_mesh_invariants, mesh_of, mutate_and_parse, parse, parse_err};

pub(crate) const ASCII_PLY: &str = "ply\n\
format ascii 1.0\n\
comment a quad and a triangle\n\
element vertex 5\n\
property float x\nproperty float y\nproperty float z\n\
property float nx\nproperty float ny\nproperty float nz\n\
property uchar red\nproperty uchar green\nproperty uchar blue\n\
property float u\nproperty float v\n\
element face 2\n\
property list uchar int vertex_indices\n\
end_header\n\
0 0 0 0 0 1 255 0 0 0 0\n\
1 0 0 0 0 1 0 255 0 1 0\n\
1 1 0 0 0 1 0 0 255 1 1\n\
0 1 0 0 0 1 128 128 128 0 1\n\
2 2 2 0 0 1 0 0 0 0.5 0.5\n\
4 0 1 2 3\n\
3 1 2 4\n";

#[test]
fn ascii_ply_with_attributes() {
    let m = mesh_of(parse(ASCII_PLY.as_bytes(), Format::Ply, "a.ply").unwrap());
    assert_mesh_invariants(&m);
    assert_eq!(m.positions.len(), 5);
    assert_eq!(m.triangles, vec![[0, 1, 2], [0, 2, 3], [1, 2, 4]]);
    assert_eq!(m.normals[0], Vec3::Z);
    assert_eq!(m.colors[0], [1.0, 0.0, 0.0, 1.0]);
    assert!(approx(m.colors[3][0], srgb_to_linear(128.0 / 255.0)));
    assert_eq!(m.uvs[4], glam::Vec2::new(0.5, 0.5));
}

pub(crate) fn binary_ply(big_endian: bool) -> Vec<u8> {
    let fmt = if big_endian {
        "binary_big_endian"
    } else {
        "binary_little_endian"
    };
    let mut out = format!(
        "ply\nformat {fmt} 1.0\nelement vertex 4\nproperty double x\nproperty double y\nproperty double z\n\
         property uchar red\nproperty uchar green\nproperty uchar blue\nproperty uchar alpha\n\
         element material 2\nproperty list uchar float stuff\n\
         element face 1\nproperty uchar flags\nproperty list uchar uint vertex_indices\nend_header\n"
    )
    .into_bytes();
    let f64b = |v: f64| {
        if big_endian {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        }
    };
    let u32b = |v: u32| {
        if big_endian {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        }
    };
    let f32b = |v: f32| {
        if big_endian {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        }
    };
    for (i, p) in [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [0.0, 1.0, 0.5],
    ]
    .iter()
    .enumerate()
    {
        for c in p {
            out.extend_from_slice(&f64b(*c));
        }
        out.extend_from_slice(&[255, 0, (i * 60) as u8, 128]);
    }
    out.push(1);
    out.extend_from_slice(&f32b(1.5));
    out.push(0);
    out.push(7); // flags
    out.push(4);
    for i in [0u32, 1, 2, 3] {
        out.extend_from_slice(&u32b(i));
    }
    out
}

#[test]
fn binary_ply_both_endiannesses() {
    for be in [false, true] {
        let bytes = binary_ply(be);
        let m = mesh_of(parse(&bytes, Format::Ply, "b.ply").unwrap());
        assert_mesh_invariants(&m);
        assert_eq!(m.triangles, vec![[0, 1, 2], [0, 2, 3]]);
        assert_eq!(m.positions[3], Vec3::new(0.0, 1.0, 0.5));
        assert_eq!(m.colors[0][0], 1.0);
        assert!(approx(m.colors[0][3], 128.0 / 255.0), "alpha is linear");
        // Truncations anywhere in the body give an offset-located error.
        let header_len = bytes
            .windows(11)
            .position(|w| w == b"end_header\n")
            .unwrap()
            + 11;
        for cut in header_len..bytes.len() {
            let e = parse_err(&bytes[..cut], Format::Ply, "b.ply");
            assert!(e.offset().is_some(), "{e}");
            assert!(e.to_string().starts_with("b.ply: byte "), "{e}");
        }
        mutate_and_parse(&bytes, Format::Ply, "b.ply", bytes.len(), 500);
    }
}

#[test]
fn binary_ply_tristrips_alternate_winding() {
    let mut bytes = b"ply\nformat binary_little_endian 1.0\nelement vertex 5\nproperty float x\nproperty float y\nproperty float z\nelement tristrips 1\nproperty list int int vertex_indices\nend_header\n".to_vec();
    for p in [
        [0f32, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [1.0, 1.0, 0.0],
        [2.0, 0.0, 0.0],
    ] {
        for c in p {
            bytes.extend_from_slice(&c.to_le_bytes());
        }
    }
    let strip: [i32; 10] = [0, 1, 2, 3, -1, 1, 4, 3, 3, 3];
    bytes.extend_from_slice(&(strip.len() as i32).to_le_bytes());
    for i in strip {
        bytes.extend_from_slice(&i.to_le_bytes());
    }
    let m = mesh_of(parse(&bytes, Format::Ply, "s.ply").unwrap());
    // (0 1 2), (2 1 3) [odd: swapped], restart, (1 4 3); (4 3 3), (3 3 3) are stitching.
    assert_eq!(m.triangles, vec![[0, 1, 2], [2, 1, 3], [1, 4, 3]]);
    // All three face +z (consistent winding).
    for t in &m.triangles {
        let [a, b, c] = t.map(|i| m.positions[i as usize]);
        assert!((b - a).cross(c - a).z > 0.0, "{t:?}");
    }
    mutate_and_parse(&bytes, Format::Ply, "s.ply", bytes.len(), 500);
}

#[test]
fn ply_errors_are_located_and_huge_counts_fail_fast() {
    // ASCII: bad value on line 21 (the body starts at line 19 in ASCII_PLY).
    let bad = ASCII_PLY.replace("1 1 0 0 0 1 0 0 255 1 1", "1 1 0 0 0 1 0 0 256 1 1");
    let e = parse_err(bad.as_bytes(), Format::Ply, "a.ply");
    assert_eq!(e.line(), Some(21), "{e}");
    let bad = ASCII_PLY.replace("3 1 2 4\n", "3 1 2 5\n");
    let e = parse_err(bad.as_bytes(), Format::Ply, "a.ply");
    assert!(
        e.line() == Some(25) && e.to_string().contains("out of range"),
        "{e}"
    );
    let bad = ASCII_PLY.replace("property float u\n", "property flaot u\n");
    assert_eq!(
        parse_err(bad.as_bytes(), Format::Ply, "a.ply").line(),
        Some(14)
    );
    let e = parse_err(
        b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n",
        Format::Ply,
        "t.ply",
    );
    assert!(e.to_string().contains("end_header"), "{e}");

    // Absurd declared counts: refused from the header, before any allocation.
    let t = Instant::now();
    let huge = b"ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\nproperty float x\nproperty float y\nproperty float z\nend_header\n";
    assert!(matches!(
        parse_err(huge, Format::Ply, "h.ply"),
        LoadError::TooLarge { .. }
    ));
    let big = b"ply\nformat binary_little_endian 1.0\nelement vertex 200000000\nproperty float x\nproperty float y\nproperty float z\nend_header\n\0\0\0\0";
    let e = parse_err(big, Format::Ply, "h.ply");
    assert!(e.to_string().contains("only 4 bytes follow"), "{e}");
    let mut list = b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uint int vertex_indices\nend_header\n".to_vec();
    list.extend_from_slice(&[0u8; 36]);
    list.extend_from_slice(&u32::MAX.to_le_bytes());
    let e = parse_err(&list, Format::Ply, "h.ply");
    assert!(e.to_string().contains("runs past the end"), "{e}");
    assert!(t.elapsed().as_millis() < 500, "huge counts must fail fast");
}
