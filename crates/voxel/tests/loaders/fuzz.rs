//! Property-based: arbitrary and mutated bytes never panic, errors always name the file.

use proptest::prelude::*;
use ssbvb_voxel::load::Format;

use crate::gltf::{textured_glb, triangle_buffer, triangle_gltf_json};
use crate::ply::{ASCII_PLY, binary_ply};
use crate::vox::scene_vox;
use crate::{base64, parse};

fn small_inputs() -> Vec<(Vec<u8>, Format)> {
    let uri = format!(
        "data:application/octet-stream;base64,{}",
        base64(&triangle_buffer())
    );
    vec![
        (ASCII_PLY.as_bytes().to_vec(), Format::Ply),
        (binary_ply(true), Format::Ply),
        (b"mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\nusemtl a\nf 1/1/1 2/1/1 -1/1/1\n".to_vec(), Format::Obj),
        (triangle_gltf_json(Some(&uri), "", 4).into_bytes(), Format::Gltf),
        (textured_glb(), Format::Glb),
        (scene_vox(), Format::Vox),
        (b"SSBVBRAW 2 1 1\n\x01\x00".to_vec(), Format::Raw),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, .. ProptestConfig::default() })]

    #[test]
    fn arbitrary_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..512), f in 0usize..6) {
        let format = [Format::Obj, Format::Ply, Format::Gltf, Format::Glb, Format::Vox, Format::Raw][f];
        match parse(&bytes, format, "p.bin") {
            Ok(m) => crate::assert_usable(&m, "p.bin", "arbitrary bytes"),
            Err(e) => prop_assert!(e.to_string().starts_with("p.bin")),
        }
    }

    #[test]
    fn mutated_fixtures_never_panic(
        which in 0usize..7,
        edits in proptest::collection::vec((any::<prop::sample::Index>(), any::<u8>()), 1..8),
        cut in any::<prop::sample::Index>(),
    ) {
        let (mut bytes, format) = small_inputs().swap_remove(which);
        for (at, value) in edits {
            let i = at.index(bytes.len());
            bytes[i] = value;
        }
        let keep = cut.index(bytes.len() + 1).max(bytes.len() / 2);
        bytes.truncate(keep);
        match parse(&bytes, format, "m.bin") {
            Ok(m) => crate::assert_usable(&m, "m.bin", "mutated fixture"),
            Err(e) => prop_assert!(e.to_string().starts_with("m.bin")),
        }
    }
}

/// The seeds of `cargo xtask fuzz` (`crates/voxel/fuzz/seeds`) are valid inputs: a seed
/// that no longer parses would start the fuzzer from nothing.
#[test]
fn fuzz_seeds_parse() {
    let seeds = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz/seeds");
    let mut checked = 0;
    for (dir, format) in [
        ("obj", Format::Obj),
        ("ply", Format::Ply),
        ("gltf", Format::Gltf),
        ("raw", Format::Raw),
    ] {
        for entry in std::fs::read_dir(seeds.join(dir)).expect("seed folder") {
            let path = entry.unwrap().path();
            let bytes = std::fs::read(&path).unwrap();
            let name = path.file_name().unwrap().to_string_lossy().into_owned();
            let m = parse(&bytes, format, &name).unwrap_or_else(|e| panic!("{e}"));
            crate::assert_usable(&m, &name, "fuzz seed");
            checked += 1;
        }
    }
    assert_eq!(checked, 6, "seed files");
}
