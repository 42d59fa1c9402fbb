//! Fuzzes the asset cache reader: the bytes are written to a file and read back with the
//! source hash and level the header claims, so the reader gets past the header checks.
//! Under `cfg(fuzzing)` the reader skips checksum comparisons (a hostile file can carry
//! valid checksums), so the fuzzer reaches the structure checks: every result is `Ok` or a
//! `CacheError`, never a panic, an out-of-bounds read or an allocation larger than the file.
#![no_main]

use libfuzzer_sys::fuzz_target;
use ssbvb_voxel::asset::MAX_LEVEL;
use ssbvb_voxel::cache::read_cache;

fuzz_target!(|data: &[u8]| {
    let hash = data
        .get(16..32)
        .map_or(0, |b| u128::from_le_bytes(b.try_into().unwrap_or_default()));
    let level = data
        .get(32..36)
        .map_or(0, |b| u32::from_le_bytes(b.try_into().unwrap_or_default()))
        .min(MAX_LEVEL);
    let path = std::env::temp_dir().join(format!("ssbvb-fuzz-cache-{}.bin", std::process::id()));
    if std::fs::write(&path, data).is_ok() {
        let _ = read_cache(&path, hash, level);
    }
});
