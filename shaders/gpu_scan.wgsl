// Exclusive prefix sum of `data[0..n]` in place (Blelloch-style three phases over blocks
// of 1024 = 256 threads × 4): `scan_reduce` writes each block's total to `sums`,
// `scan_sums` (one workgroup) scans the totals and stores the grand total at
// `sums[blocks]`, `scan_apply` scans each block and adds its offset. Used by the radix
// sort (digit offsets) and the surface build (run starts); gpu_scan.rs.

struct ScanParams {
    n: u32,
    blocks: u32,
}

@group(0) @binding(0) var<uniform> params: ScanParams;
@group(0) @binding(1) var<storage, read_write> data: array<u32>;
@group(0) @binding(2) var<storage, read_write> sums: array<u32>;

var<workgroup> tmp: array<u32, 256>;

// Inclusive scan of `v` across the workgroup (Hillis–Steele); every thread must call it.
fn workgroup_inclusive(li: u32, v: u32) -> u32 {
    tmp[li] = v;
    workgroupBarrier();
    for (var off = 1u; off < 256u; off = off << 1u) {
        var add = 0u;
        if li >= off {
            add = tmp[li - off];
        }
        workgroupBarrier();
        tmp[li] = tmp[li] + add;
        workgroupBarrier();
    }
    let out = tmp[li];
    workgroupBarrier();
    return out;
}

fn block_of(wg: vec3<u32>, nwg: vec3<u32>) -> u32 {
    return wg.x + wg.y * nwg.x;
}

@compute @workgroup_size(256)
fn scan_reduce(
    @builtin(local_invocation_index) li: u32,
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
) {
    let block = block_of(wg, nwg);
    if block >= params.blocks {
        return;
    }
    var s = 0u;
    for (var j = 0u; j < 4u; j++) {
        let i = block * 1024u + li * 4u + j;
        if i < params.n {
            s += data[i];
        }
    }
    let total = workgroup_inclusive(li, s);
    if li == 255u {
        sums[block] = total;
    }
}

@compute @workgroup_size(256)
fn scan_sums(@builtin(local_invocation_index) li: u32) {
    var carry = 0u;
    let rounds = (params.blocks + 255u) / 256u;
    for (var r = 0u; r < rounds; r++) {
        let i = r * 256u + li;
        var v = 0u;
        if i < params.blocks {
            v = sums[i];
        }
        let inc = workgroup_inclusive(li, v);
        if i < params.blocks {
            sums[i] = carry + inc - v;
        }
        // Every thread reads the round's total before the next round overwrites `tmp`.
        let total = tmp[255];
        workgroupBarrier();
        carry += total;
    }
    if li == 0u {
        sums[params.blocks] = carry;
    }
}

@compute @workgroup_size(256)
fn scan_apply(
    @builtin(local_invocation_index) li: u32,
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
) {
    let block = block_of(wg, nwg);
    if block >= params.blocks {
        return;
    }
    var v: array<u32, 4>;
    var s = 0u;
    for (var j = 0u; j < 4u; j++) {
        let i = block * 1024u + li * 4u + j;
        v[j] = 0u;
        if i < params.n {
            v[j] = data[i];
        }
        s += v[j];
    }
    var run = sums[block] + workgroup_inclusive(li, s) - s;
    for (var j = 0u; j < 4u; j++) {
        let i = block * 1024u + li * 4u + j;
        if i < params.n {
            data[i] = run;
        }
        run += v[j];
    }
}
