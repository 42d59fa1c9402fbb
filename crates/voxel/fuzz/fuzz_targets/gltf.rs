//! Fuzzes the glTF loader with arbitrary bytes, both as JSON `.gltf` and as `.glb` (the
//! loader picks GLB when the bytes start with the `glTF` magic, whatever the format says).
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use ssbvb_voxel::load::{Format, LoadOptions, load_from_bytes};

fuzz_target!(|data: &[u8]| {
    let _ = load_from_bytes(
        data,
        Format::Gltf,
        Path::new("fuzz.gltf"),
        None,
        &LoadOptions::default(),
    );
});
