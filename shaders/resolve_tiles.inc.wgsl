// A resolve drawn over screen tiles instead of one fullscreen triangle (the compute splat's
// and the ray casters' compute form): each tile of `tile_px` × `tile_px` pixels is an
// instance of six vertices (two triangles), and a tile whose word its compute pass left 0
// (no quad, no hit) collapses to a point off screen, so the resolve shades only where
// there is something to write. Tile `t` is column t % across, row t / across.

// Vertex `v` (0..6) of tile `t` in clip space; `seen` the tile's word.
fn tile_vertex(v: u32, t: u32, seen: u32, tile_px: u32) -> vec4<f32> {
    if seen == 0u {
        return vec4(2.0, 2.0, 0.0, 1.0);
    }
    let corner = vec2(
        select(0u, 1u, v == 1u || v == 4u || v == 5u),
        select(0u, 1u, v == 2u || v == 3u || v == 5u),
    );
    let across = (u32(frame.screen.x) + tile_px - 1u) / tile_px;
    let px = vec2<f32>((vec2(t % across, t / across) + corner) * tile_px);
    return vec4(px.x * frame.screen.z * 2.0 - 1.0, 1.0 - px.y * frame.screen.w * 2.0, 0.0, 1.0);
}
