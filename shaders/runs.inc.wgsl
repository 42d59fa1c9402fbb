// Runs of equal keys in a sorted array, found by a flag per element, a prefix scan of the
// flags, then a scatter of each run's first element. The including shader defines
// `params.n` (elements), `flags` (read-write `array<u32>`), `starts_run(i)` (whether
// element `i` begins a run) and `store_run_start(run, i)` (where a run's first element
// goes), and includes `voxel_codes.inc.wgsl` (`thread_id`).

@compute @workgroup_size(256)
fn run_flags(
    @builtin(local_invocation_index) li: u32,
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
) {
    let i = thread_id(li, wg, nwg);
    if i < params.n {
        flags[i] = select(0u, 1u, starts_run(i));
    }
}

// After the scan, `flags[i]` is the run index of a run's first element.
@compute @workgroup_size(256)
fn run_starts(
    @builtin(local_invocation_index) li: u32,
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
) {
    let i = thread_id(li, wg, nwg);
    if i < params.n && starts_run(i) {
        store_run_start(flags[i], i);
    }
}
