//#include "common.inc.wgsl"
// Triangles: ordinary meshes drawn into the same G-buffer as the voxel billboards, with
// stencil = STENCIL_TRIANGLE (so smoothing never touches them). One draw per mesh; the mesh's
// uniform (group 1) holds its camera-relative model matrix, normal matrix and colour.
//
// Outputs: location 0 albedo (the mesh colour, alpha 1, packed RGBA8), 1 world-space unit
// shading normal (w = 1), 2 camera-relative world position (xyz) and linear view depth
// (w), 3 the triangle's plane normal towards the camera (octahedral).
// Lighting is two-sided: the shading normal is flipped to the side of the surface the camera
// sees (decided by the geometric normal, so any winding and mirrored transforms work). A
// zero-length or non-finite interpolated normal falls back to the geometric normal.

// Mirror of gpu_scene.rs `MeshUniform`.
struct Mesh {
    // Model -> camera-relative world.
    model: mat4x4<f32>,
    // Inverse transpose of the model's linear part.
    normal_matrix: mat4x4<f32>,
    // Linear RGBA albedo.
    color: vec4<f32>,
    pad: vec4<f32>,
}

@group(1) @binding(0) var<uniform> mesh: Mesh;

struct VsIn {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
}

struct VsOut {
    @builtin(position) clip: vec4<f32>,
    // Camera-relative world position.
    @location(0) world: vec3<f32>,
    // World-space normal (not normalized).
    @location(1) normal: vec3<f32>,
}

@vertex
fn vs_main(v: VsIn) -> VsOut {
    var out: VsOut;
    let world = (mesh.model * vec4(v.position, 1.0)).xyz;
    out.world = world;
    out.normal = (mesh.normal_matrix * vec4(v.normal, 0.0)).xyz;
    out.clip = frame.view_proj * vec4(world, 1.0);
    return out;
}

@fragment
fn fs_main(in: VsOut) -> GBuffer {
    // Geometric normal from screen derivatives (uniform control flow: computed first),
    // turned towards the camera (which sits at the camera-relative origin).
    var geo = safe_normalize(cross(dpdx(in.world), dpdy(in.world)), -frame.cam_forward.xyz);
    if dot(geo, in.world) > 0.0 {
        geo = -geo;
    }
    var n = safe_normalize(in.normal, geo);
    if dot(n, geo) < 0.0 {
        n = -n;
    }
    var out: GBuffer;
    out.albedo = pack4x8unorm(vec4(clamp(mesh.color.rgb, vec3(0.0), vec3(1.0)), 1.0));
    out.normal = vec4(n, 1.0);
    out.position = vec4(in.world, dot(in.world, frame.cam_forward.xyz));
    out.geometric_normal = oct_encode(geo);
    return out;
}
