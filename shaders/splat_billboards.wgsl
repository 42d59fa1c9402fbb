//#include "common.inc.wgsl"
//#include "billboard_quad.inc.wgsl"
//#include "splat_billboards.inc.wgsl"

// splat_billboards: the compute splat with 32-bit atomics, for every adapter with compute
// shaders (splat_billboards.inc.wgsl has the steps). The splat takes two steps over the
// same pixels: step 0 takes each pixel's nearest depth (`atomicMax` on its bits), step 1,
// where that depth is the entry's own, the lowest entry (`atomicMax` of the inverted
// index). Where the adapter has 64-bit atomics, splat_billboards_wide.wgsl does both in
// one step.

// Per pixel p = y * width + x: word 2p the nearest depth's bits, word 2p + 1 the winning
// entry, inverted; after the pixels, per entry e: word `entry_word(e)` its quad plane's
// view depth (bits; `NEAR_FIELD_WORD` for a near-field quad), written by step 0 so that the
// resolve need not rebuild the winner's quad at every pixel; after the entries, per
// resolve tile a pair of words, the first 1 where a quad touched the tile. One buffer:
// WebGPU allows 8 storage buffers per stage.
@group(1) @binding(2) var<storage, read_write> splat_pixels: array<atomic<u32>>;

// The word of entry `e`'s quad depth, after the per-pixel words.
fn entry_word(e: u32) -> u32 {
    return 2u * u32(frame.screen.x) * u32(frame.screen.y) + e;
}

// The first word of tile `t`'s pair, after the entry words.
fn tile_word(t: u32) -> u32 {
    return 2u * u32(frame.screen.x) * u32(frame.screen.y) + arrayLength(&ssbvb) + 2u * t;
}

fn mark_tile(t: u32) {
    // Most quads share their tile with others: a load before the store spares the write.
    if atomicLoad(&splat_pixels[tile_word(t)]) == 0u {
        atomicStore(&splat_pixels[tile_word(t)], 1u);
    }
}

fn store_plane(e: u32, bits: u32) {
    atomicStore(&splat_pixels[entry_word(e)], bits);
}

fn plane_bits(e: u32) -> u32 {
    return atomicLoad(&splat_pixels[entry_word(e)]);
}

// Step 0: the nearest depth; step 1: the lowest entry at that depth.
fn splat_pixel(p: u32, depth_bits: u32, e: u32, splat_step: u32) {
    if splat_step == 0u {
        atomicMax(&splat_pixels[2u * p], depth_bits);
    } else if atomicLoad(&splat_pixels[2u * p]) == depth_bits {
        atomicMax(&splat_pixels[2u * p + 1u], ~e);
    }
}

// x: the winning entry, inverted (0: none); y: its depth's bits.
fn pixel_winner(p: u32) -> vec2<u32> {
    return vec2(atomicLoad(&splat_pixels[2u * p + 1u]), atomicLoad(&splat_pixels[2u * p]));
}
