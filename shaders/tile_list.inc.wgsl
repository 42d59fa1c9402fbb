// The list of a compute pass's screen tiles that hold work (TILE × TILE pixels, the pass's
// workgroup), so that its main dispatch launches those only: a software adapter runs every
// branch of a shader under a lane mask (llvmpipe jumps over none that no lane takes), so a
// workgroup without work cost it nearly what one with work costs (docs/benchmarks.md, "The
// filter over tiles with a proxy"). A GPU skips such branches; the list costs it a
// dispatch of one workgroup.
//
// The includer flags tiles (row-major index), then calls `list_screen_tiles` from one
// workgroup of LIST_GROUP invocations, and dispatches its main entry point indirectly on
// the grid that stores; a workgroup finds its tile with `listed_index` and `tile_origin`.
// It defines `fn tile_flagged(tile: u32) -> bool`, `fn store_listed(i: u32, packed: u32)`
// and `fn store_listing(count: u32, grid: vec3<u32>)`.

// Pixels per side of a tile (the includer's main workgroup is TILE × TILE).
const TILE: u32 = 16u;
// Invocations of the listing workgroup: the tiles it takes at a time.
const LIST_GROUP: u32 = 256u;
// Most workgroups per dimension of a dispatch (the pass sets the device's limit, at least
// 65535 unless a device asks for fewer): longer lists take more rows.
override MAX_GRID: u32 = 65535u;

// Per invocation of the listing workgroup: how many of the tiles it takes at a time up to
// its own are flagged (a prefix sum).
var<workgroup> flagged_before: array<u32, LIST_GROUP>;

// Lists the flagged tiles among `n` (`per_row` a row) in raster order: `store_listed(i,
// x | y << 16)` for the i-th (packed: no division to undo per pixel, which llvmpipe does
// not vectorize). Returns the count. Called by every invocation of one workgroup of
// LIST_GROUP (`li`: its local index) with the same `n` and `per_row`; the order is the
// screen's, whatever the order in which tiles were flagged.
fn list_flagged_tiles(li: u32, n: u32, per_row: u32) -> u32 {
    var listed = 0u;
    for (var first = 0u; first < n; first += LIST_GROUP) {
        let tile = first + li;
        let flagged = tile < n && tile_flagged(tile);
        flagged_before[li] = u32(flagged);
        workgroupBarrier();
        // Inclusive prefix sum (Hillis–Steele).
        for (var o = 1u; o < LIST_GROUP; o <<= 1u) {
            let v = select(0u, flagged_before[max(li, o) - o], li >= o);
            workgroupBarrier();
            flagged_before[li] += v;
            workgroupBarrier();
        }
        if flagged {
            store_listed(listed + flagged_before[li] - 1u, (tile % per_row) | ((tile / per_row) << 16u));
        }
        listed += flagged_before[LIST_GROUP - 1u];
        workgroupBarrier();
    }
    return listed;
}

// Lists the flagged tiles of a `size` screen, then stores their count and the main
// dispatch's grid (`store_listing`, from the first invocation). Called by every invocation
// of one workgroup of LIST_GROUP (`li`: its local index).
fn list_screen_tiles(li: u32, size: vec2<u32>) {
    let listed = list_flagged_tiles(li, tile_total(size), tiles_per_row(size));
    if li == 0u {
        store_listing(listed, tile_grid(listed));
    }
}

// The main dispatch's grid for `n` listed tiles: one workgroup each, in rows of MAX_GRID.
fn tile_grid(n: u32) -> vec3<u32> {
    return vec3(min(n, MAX_GRID), (n + MAX_GRID - 1u) / MAX_GRID, 1u);
}

// The list index of workgroup `wg` of `tile_grid`'s grid (at or past the count in the
// last row's tail).
fn listed_index(wg: vec3<u32>) -> u32 {
    return wg.y * MAX_GRID + wg.x;
}

// The first pixel of a listed tile.
fn tile_origin(packed: u32) -> vec2<u32> {
    return vec2(packed & 0xffffu, packed >> 16u) * TILE;
}

// Tiles per row, and in all, of a `size` screen.
fn tiles_per_row(size: vec2<u32>) -> u32 {
    return (size.x + TILE - 1u) / TILE;
}

fn tile_total(size: vec2<u32>) -> u32 {
    return tiles_per_row(size) * ((size.y + TILE - 1u) / TILE);
}
