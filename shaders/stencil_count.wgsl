//#include "fullscreen.inc.wgsl"
// Counting the pixels of a stencil value where a stencil cannot be copied to a buffer (GL):
// a fullscreen triangle stencil-tested for the value writes 1 into an R32Uint target, which
// is read back (gbuffer.rs, `count_stencil`).

@fragment
fn fs_main() -> @location(0) u32 {
    return 1u;
}
