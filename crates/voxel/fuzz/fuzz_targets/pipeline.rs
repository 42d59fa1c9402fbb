//! Fuzzes RON pipeline resolution (`ssbvb pipeline check` on arbitrary text): every result is
//! a resolved pipeline or errors naming the file, never a panic.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    // Included files are not read: the fuzzer's text may name any path.
    let no_files = |_: &str| Err("the fuzz target reads no file".to_string());
    if let Err(e) = ssbvb_graph::resolve_str_with(&text, "fuzz.ron", &no_files) {
        assert!(!e.errors.is_empty());
        for err in &e.errors {
            assert!(err.to_string().starts_with("fuzz.ron"), "{err}");
        }
    }
});
