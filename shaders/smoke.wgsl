// GPU smoke test: a compute kernel and a render pipeline with depth and stencil, whose
// results the tests know exactly (crates/gpu/tests/smoke.rs).

@group(0) @binding(0) var<storage, read_write> values: array<u32>;

// values[i] = i * i + 7, for every i in the buffer.
@compute @workgroup_size(64)
fn fill(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x < arrayLength(&values) {
        values[id.x] = id.x * id.x + 7u;
    }
}

struct Quad {
    // Clip-space x range [x0, x1], depth z and colour.
    x0: f32,
    x1: f32,
    z: f32,
    _pad: f32,
    color: vec4<f32>,
}

@group(0) @binding(0) var<uniform> quad: Quad;

// Two triangles covering x in [x0, x1], all of y, at depth z.
@vertex
fn vs_main(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let corners = array<vec2<f32>, 6>(
        vec2(0.0, 0.0), vec2(1.0, 0.0), vec2(0.0, 1.0),
        vec2(0.0, 1.0), vec2(1.0, 0.0), vec2(1.0, 1.0),
    );
    let c = corners[i];
    return vec4(mix(quad.x0, quad.x1, c.x), mix(-1.0, 1.0, c.y), quad.z, 1.0);
}

@fragment
fn fs_main() -> @location(0) vec4<f32> {
    return quad.color;
}
