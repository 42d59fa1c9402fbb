// Shared by the smoothing passes (smooth.wgsl, smooth_compute.wgsl): Eq. 1 and the
// 3x3 Gaussian of a voxel pixel's normal. Needs common.inc.wgsl before it, and the globals
// `gbuffer_normal` (texture_2d<f32>) and `normal_sampler` (a filtering sampler).

// MaxI: the largest offset in pixels; MinDist: distance (world units) at and below which
// the offset is MaxI (see smoothing_offset).
override MAX_I: f32 = 1.0;
override MIN_DIST: f32 = 0.5;

// Eq. 1 made total: at Dist = MinDist the quotient is infinite and below it the parabola
// turns back up, so for every Dist <= MinDist (and NaN) the offset is MaxI, which is also
// the limit of Eq. 1 from above. The result is always finite and in [0, MaxI].
fn smoothing_offset(dist: f32) -> f32 {
    let x = dist - MIN_DIST;
    if !(x > 0.0) {
        return MAX_I;
    }
    let q = MAX_I / (x * x);
    return clamp(q, 0.0, MAX_I);
}

// Camera distance of the surface at a pixel, from its depth.
fn camera_distance(px: vec2<f32>, depth: f32) -> f32 {
    let ndc = vec3(px.x * frame.screen.z * 2.0 - 1.0, 1.0 - px.y * frame.screen.w * 2.0, depth);
    let p = frame.inv_view_proj * vec4(ndc, 1.0);
    return length(p.xyz / p.w);
}

// The smoothed normal of the voxel pixel at `pos` whose depth is `depth`.
fn smoothed(pos: vec4<f32>, depth: f32) -> vec4<f32> {
    let p = vec2<i32>(pos.xy);
    let center = textureLoad(gbuffer_normal, p, 0);
    let offset = smoothing_offset(camera_distance(pos.xy, depth));
    var sum = vec3(0.0);
    for (var dy = -1; dy <= 1; dy++) {
        for (var dx = -1; dx <= 1; dx++) {
            // Weights 1-2-1 x 1-2-1 (sum 16; the normalization below makes it irrelevant).
            let w = f32((2 - abs(dx)) * (2 - abs(dy)));
            let uv = (pos.xy + vec2(f32(dx), f32(dy)) * offset) * frame.screen.zw;
            sum += w * textureSampleLevel(gbuffer_normal, normal_sampler, uv, 0.0).xyz;
        }
    }
    return vec4(safe_normalize(sum, center.xyz), center.w);
}
