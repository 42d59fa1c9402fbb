//! Fuzzes the MagicaVoxel loader: the whole scene, and a single model picked by the first
//! byte (so that the `vox_model` path is covered too).
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use ssbvb_voxel::load::{Format, LoadOptions, load_from_bytes};

fuzz_target!(|data: &[u8]| {
    let name = Path::new("fuzz.vox");
    let _ = load_from_bytes(data, Format::Vox, name, None, &LoadOptions::default());
    if let Some(&k) = data.get(8) {
        let options = LoadOptions {
            vox_model: Some(usize::from(k % 4)),
            ..LoadOptions::default()
        };
        let _ = load_from_bytes(data, Format::Vox, name, None, &options);
    }
});
