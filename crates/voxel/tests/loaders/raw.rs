//! The project's raw dense grids: round trip and errors.

use ssbvb_voxel::load::{Format, LoadError, load_model, srgb_to_linear, write_raw};

use crate::{approx, mutate_and_parse, parse, parse_err, voxels_of};

#[test]
fn raw_round_trip_and_errors() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("g.raw");
    let (nx, ny, nz) = (3u32, 2u32, 2u32);
    let mut cells = vec![0u8; 12];
    cells[1] = 255; // (1, 0, 0)
    cells[3 + 2] = 128; // (2, 1, 0)
    cells[6] = 1; // (0, 0, 1)
    write_raw(&path, nx, ny, nz, &cells).unwrap();
    let names: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(names.len(), 1, "no temporary file left behind: {names:?}");
    let v = voxels_of(load_model(&path).unwrap());
    assert_eq!(v.voxels, vec![[1, 0, 0], [2, 1, 0], [0, 0, 1]]);
    assert_eq!(v.colors[0], [1.0, 1.0, 1.0, 1.0]);
    assert!(approx(v.colors[1][0], srgb_to_linear(128.0 / 255.0)));
    // In memory gives the same.
    let bytes = std::fs::read(&path).unwrap();
    assert_eq!(
        voxels_of(parse(&bytes, Format::Raw, "g.raw").unwrap()).voxels,
        v.voxels
    );
    // Errors.
    assert!(write_raw(&path, 3, 2, 2, &cells[..11]).is_err());
    assert!(write_raw(&path, 5000, 1, 1, &[]).is_err());
    let e = parse_err(&bytes[..bytes.len() - 1], Format::Raw, "g.raw");
    assert!(
        e.offset().is_some() && e.to_string().contains("12 cells"),
        "{e}"
    );
    let e = parse_err(b"SSBVBRAW 4096 4096 4097\n", Format::Raw, "h.raw");
    assert!(matches!(e, LoadError::TooLarge { .. }), "{e}");
    let e = parse_err(b"SSBVBRAW 4096 4096 4096\n\x01", Format::Raw, "h.raw");
    assert!(e.to_string().contains("68719476736 cells"), "{e}");
    assert_eq!(
        parse_err(b"SSBVBRAW 1 x 1\n\x01", Format::Raw, "x.raw").line(),
        Some(1)
    );
    std::fs::write(&path, b"SSBVBRAW 2 2 2\n\0\0\0\0\0\0\0").unwrap();
    assert!(
        load_model(&path)
            .unwrap_err()
            .to_string()
            .contains("7 bytes follow")
    );
    mutate_and_parse(&bytes, Format::Raw, "g.raw", bytes.len(), 300);
}
