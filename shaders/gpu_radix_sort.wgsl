// One pass of a stable LSD radix sort of 64-bit keys (`key_lo`, `key_hi`) with one u32
// payload, on the 4-bit digit at bit `shift` (gpu_radix_sort.rs runs the passes and
// ping-pongs the buffers). Tiles of 1024 keys (256 threads × 4 rounds):
// - `radix_histogram` counts each tile's digits into `hist[digit * tiles + tile]`;
// - gpu_scan.wgsl turns `hist` into exclusive offsets (digit-major, so each digit's keys
//   land after all smaller digits and in tile order);
// - `radix_scatter` writes each key to its digit's offset plus its rank among the earlier
//   keys of the tile with the same digit. The rank comes from per-digit bit masks of the
//   256 threads (countOneBits of the lower threads' bits), which keeps the pass stable.

struct SortParams {
    n: u32,
    shift: u32,
    tiles: u32,
    _pad: u32,
}

@group(0) @binding(0) var<uniform> params: SortParams;
@group(0) @binding(1) var<storage, read> key_lo_in: array<u32>;
@group(0) @binding(2) var<storage, read> key_hi_in: array<u32>;
@group(0) @binding(3) var<storage, read> val_in: array<u32>;
@group(0) @binding(4) var<storage, read_write> key_lo_out: array<u32>;
@group(0) @binding(5) var<storage, read_write> key_hi_out: array<u32>;
@group(0) @binding(6) var<storage, read_write> val_out: array<u32>;
@group(0) @binding(7) var<storage, read_write> hist: array<u32>;

var<workgroup> counts: array<atomic<u32>, 16>;
var<workgroup> masks: array<atomic<u32>, 128>;
var<workgroup> running: array<u32, 16>;

fn digit(i: u32) -> u32 {
    if params.shift < 32u {
        return (key_lo_in[i] >> params.shift) & 15u;
    }
    return (key_hi_in[i] >> (params.shift - 32u)) & 15u;
}

@compute @workgroup_size(256)
fn radix_histogram(
    @builtin(local_invocation_index) li: u32,
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
) {
    let tile = wg.x + wg.y * nwg.x;
    if tile >= params.tiles {
        return;
    }
    if li < 16u {
        atomicStore(&counts[li], 0u);
    }
    workgroupBarrier();
    for (var r = 0u; r < 4u; r++) {
        let i = tile * 1024u + r * 256u + li;
        if i < params.n {
            atomicAdd(&counts[digit(i)], 1u);
        }
    }
    workgroupBarrier();
    if li < 16u {
        hist[li * params.tiles + tile] = atomicLoad(&counts[li]);
    }
}

@compute @workgroup_size(256)
fn radix_scatter(
    @builtin(local_invocation_index) li: u32,
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
) {
    let tile = wg.x + wg.y * nwg.x;
    if tile >= params.tiles {
        return;
    }
    if li < 16u {
        running[li] = hist[li * params.tiles + tile];
    }
    let word = li / 32u;
    let below = (1u << (li % 32u)) - 1u;
    for (var r = 0u; r < 4u; r++) {
        if li < 128u {
            atomicStore(&masks[li], 0u);
        }
        workgroupBarrier();
        let i = tile * 1024u + r * 256u + li;
        let valid = i < params.n;
        var d = 0u;
        if valid {
            d = digit(i);
            atomicOr(&masks[d * 8u + word], 1u << (li % 32u));
        }
        workgroupBarrier();
        if valid {
            var rank = countOneBits(atomicLoad(&masks[d * 8u + word]) & below);
            for (var w = 0u; w < word; w++) {
                rank += countOneBits(atomicLoad(&masks[d * 8u + w]));
            }
            let dst = running[d] + rank;
            key_lo_out[dst] = key_lo_in[i];
            key_hi_out[dst] = key_hi_in[i];
            val_out[dst] = val_in[i];
        }
        workgroupBarrier();
        if li < 16u {
            var total = 0u;
            for (var w = 0u; w < 8u; w++) {
                total += countOneBits(atomicLoad(&masks[li * 8u + w]));
            }
            running[li] += total;
        }
        workgroupBarrier();
    }
}
