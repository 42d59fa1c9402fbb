// What the face rasterizers share (cube_raster.wgsl, rastavox.wgsl): the G-buffer outputs
// (common.inc.wgsl's `GBuffer`), the corners of a face quad, and the fragment's exact hit. The pixel's ray (the same
// `pixel_ray` and object-space ray as the ray casters, so depth and cell agree with the CPU
// reference up to f32 rounding) meets the face's plane at t; the G-buffer gets the face's
// shading normal (the voxel's stored one), the face's geometric normal, the
// camera-relative hit and its linear depth. Depth is the rasterized face
// depth (no frag_depth, so early depth testing stays on).

// Corners (u, v) of the face quad's two triangles.
const QUAD = array<vec2<u32>, 6>(
    vec2(0u, 0u), vec2(1u, 0u), vec2(1u, 1u),
    vec2(0u, 0u), vec2(1u, 1u), vec2(0u, 1u),
);

// Where the pixel's ray meets a face plane.
struct FaceHit {
    // World distance along the normalized pixel ray (valid when finite and > 0).
    t: f32,
    // The hit in object space.
    p_obj: vec3<f32>,
    // The normalized camera-relative world ray.
    dir: vec3<f32>,
}

// The hit of the ray through pixel position `px` with the plane `object[axis] = plane` of
// instance `inst`. t is not finite and positive for an edge-on face (d[axis] = 0) or a
// plane behind the eye: callers discard those.
fn face_hit(inst: Instance, axis: u32, plane: f32, px: vec2<f32>) -> FaceHit {
    let dir = pixel_ray(px);
    let o = (inst.world_to_object * vec4(0.0, 0.0, 0.0, 1.0)).xyz;
    // d is not renormalized, so t is the world distance along `dir`.
    let d = (inst.world_to_object * vec4(dir, 0.0)).xyz;
    let t = (plane - o[axis]) / d[axis];
    return FaceHit(t, o + t * d, dir);
}

fn face_hit_valid(h: FaceHit) -> bool {
    return h.t > 0.0 && h.t < 1e30;
}

// The G-buffer of face `face` (VoxelSlot.face order) hit at `h`, of a voxel coloured
// `albedo` whose stored normal is `normal_bits` (16-bit octahedral, object space).
fn face_gbuffer(inst: Instance, face: u32, h: FaceHit, albedo: vec3<f32>, normal_bits: u32) -> GBuffer {
    let p = h.dir * h.t;
    var out: GBuffer;
    out.albedo = pack4x8unorm(vec4(albedo, 1.0));
    out.normal = vec4(object_normal_world(inst, oct16_normal(normal_bits)), 1.0);
    out.position = vec4(p, dot(p, frame.cam_forward.xyz));
    out.geometric_normal = oct_encode(face_normal_world(inst, face));
    return out;
}
