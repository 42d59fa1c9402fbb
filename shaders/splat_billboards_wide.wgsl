//#include "common.inc.wgsl"
//#include "billboard_quad.inc.wgsl"
//#include "splat_billboards.inc.wgsl"

// splat_billboards_wide: the compute splat in one step, for adapters with 64-bit atomics
// (`SHADER_INT64_ATOMIC_ALL_OPS`; splat_billboards.inc.wgsl has the steps). Each pixel's
// word holds its nearest depth's bits above the winning entry, inverted: one `atomicMax`
// keeps the nearest depth and, at equal depths, the lowest entry (what the two steps of
// splat_billboards.wgsl decide), so each quad is walked once.

// Per pixel p = y * width + x: word p (depth bits << 32) | inverted entry; after the
// pixels, per entry e: word `pixels + e` its quad plane's view depth in the low half
// (bits; `NEAR_FIELD_WORD` for a near-field quad); after the entries, per resolve tile a
// word, 1 where a quad touched the tile.
@group(1) @binding(2) var<storage, read_write> splat_pixels: array<atomic<u64>>;

// The word of entry `e`'s quad depth, after the per-pixel words.
fn entry_word(e: u32) -> u32 {
    return u32(frame.screen.x) * u32(frame.screen.y) + e;
}

fn mark_tile(t: u32) {
    let w = u32(frame.screen.x) * u32(frame.screen.y) + arrayLength(&ssbvb) + t;
    // Most quads share their tile with others: a load before the store spares the write.
    if atomicLoad(&splat_pixels[w]) == u64(0u) {
        atomicStore(&splat_pixels[w], u64(1u));
    }
}

fn store_plane(e: u32, bits: u32) {
    atomicStore(&splat_pixels[entry_word(e)], u64(bits));
}

fn plane_bits(e: u32) -> u32 {
    return u32(atomicLoad(&splat_pixels[entry_word(e)]));
}

// The one step: the nearest depth, then the lowest entry, in one word.
fn splat_pixel(p: u32, depth_bits: u32, e: u32, splat_step: u32) {
    atomicMax(&splat_pixels[p], (u64(depth_bits) << 32u) | u64(~e));
}

// x: the winning entry, inverted (0: none); y: its depth's bits.
fn pixel_winner(p: u32) -> vec2<u32> {
    let word = atomicLoad(&splat_pixels[p]);
    return vec2(u32(word), u32(word >> 32u));
}
