//#include "common.inc.wgsl"

// empty_space: the empty-space prepass (docs/architecture.md, "A frame", step 1).
//
// Rasterizes the proxy mesh of every visible instance (vertex buffer: object-space
// `vec4<f32>` positions; `instance_index` = index into `instances`) into
//
// - `entry` (Rgba32Float colour attachment): xyz = object-space point where the pixel-centre
//   ray enters the nearest proxy, w = instance index + 1 (0 = no proxy under the pixel);
// - `prepass_depth` (Depth32Float, reversed Z: cleared to 0, test `Greater`).
//
// Three draws, all depth-tested against each other so the nearest proxy surface wins:
//
// 1. front faces (`vs_main` + `fs_main`): the interpolated object-space position;
// 2. back faces (`vs_main` + `fs_back`): a back face is nearest only where the ray starts
//    inside a proxy (or the front face was clipped by the near plane): the entry is the
//    camera itself (`t = 0`). Drawn only for the instances where that can happen;
// 3. for instances whose proxy holds the camera, a full-screen triangle at the farthest
//    depth (`vs_fill` + `fs_back`, test `GreaterEqual`, no depth write): it fills the pixels
//    where the proxy's own back faces were clipped by the near or far plane.

struct VsOut {
    @builtin(position) clip: vec4<f32>,
    // Object-space position on the proxy (perspective-correct interpolation).
    @location(0) object_pos: vec3<f32>,
    @location(1) @interpolate(flat) instance: u32,
}

@vertex
fn vs_main(@location(0) position: vec4<f32>, @builtin(instance_index) instance: u32) -> VsOut {
    let inst = instances[instance];
    var out: VsOut;
    // Object -> view (composed in f64 on the CPU) -> clip keeps f32 precision for objects
    // far from the origin and from the camera.
    out.clip = frame.proj * (inst.object_to_view * vec4(position.xyz, 1.0));
    out.object_pos = position.xyz;
    out.instance = instance;
    return out;
}

@fragment
fn fs_main(in: VsOut) -> @location(0) vec4<f32> {
    return vec4(in.object_pos, f32(in.instance + 1u));
}

@fragment
fn fs_back(in: VsOut) -> @location(0) vec4<f32> {
    return vec4(instances[in.instance].camera_object.xyz, f32(in.instance + 1u));
}

// One triangle covering the screen at NDC depth 0 (the far end under reversed Z).
@vertex
fn vs_fill(@builtin(vertex_index) vertex: u32, @builtin(instance_index) instance: u32) -> VsOut {
    let uv = vec2(f32((vertex << 1u) & 2u), f32(vertex & 2u));
    var out: VsOut;
    out.clip = vec4(uv * 2.0 - 1.0, 0.0, 1.0);
    out.object_pos = instances[instance].camera_object.xyz;
    out.instance = instance;
    return out;
}
