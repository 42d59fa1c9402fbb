//! Fuzzes scene files (`ssbvb render SCENE`, before any model is loaded): every result is a
//! scene whose fields all pass their checks, or an error naming the file, never a panic.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    match ssbvb_scene_file::parse(&text, "fuzz.ron") {
        Ok(scene) => assert!(scene.problems().is_empty()),
        Err(e) => assert!(e.to_string().starts_with("fuzz.ron"), "{e}"),
    }
});
