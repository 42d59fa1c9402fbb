//! Fuzzes the ply loader with arbitrary bytes: it must return `Ok` or `Err`, never panic,
//! and never allocate beyond what the input justifies.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use ssbvb_voxel::load::{Format, LoadOptions, load_from_bytes};

fuzz_target!(|data: &[u8]| {
    let _ = load_from_bytes(
        data,
        Format::Ply,
        Path::new("fuzz.ply"),
        None,
        &LoadOptions::default(),
    );
});
