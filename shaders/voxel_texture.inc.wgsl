// Base-colour textures of the GPU voxelizer (gpu_voxelize/inputs.rs packs them), included
// by gpu_voxelize.wgsl and gpu_voxelize_exact.wgsl, which declare `corner_colors` (RGBA
// per corner), `corner_uvs` (per corner: u, v, texture index or −1, 0) and `textures` (per
// texture: first texel word, width, height, 0; then RGBA8 texels). The sample is the CPU voxelizer's: bilinear, wrapping,
// uv (0, 0) at the top-left corner of texel row 0.

fn voxel_texel(first: u32, w: i32, h: i32, x: i32, y: i32) -> vec4<f32> {
    let xi = ((x % w) + w) % w;
    let yi = ((y % h) + h) % h;
    return unpack4x8unorm(textures[first + u32(yi * w + xi)]);
}

fn sample_voxel_texture(index: u32, uv: vec2<f32>) -> vec4<f32> {
    let head = 4u * index;
    let first = textures[head];
    let w = i32(textures[head + 1u]);
    let h = i32(textures[head + 2u]);
    let x = uv.x * f32(w) - 0.5;
    let y = uv.y * f32(h) - 0.5;
    let x0 = floor(x);
    let y0 = floor(y);
    let fx = x - x0;
    let fy = y - y0;
    // Wrapped first, so texel indices stay small whatever the uv.
    let xi = i32(x0 - floor(x0 / f32(w)) * f32(w));
    let yi = i32(y0 - floor(y0 / f32(h)) * f32(h));
    let a = voxel_texel(first, w, h, xi, yi);
    let b = voxel_texel(first, w, h, xi + 1, yi);
    let c = voxel_texel(first, w, h, xi, yi + 1);
    let d = voxel_texel(first, w, h, xi + 1, yi + 1);
    let top = a + (b - a) * fx;
    let bottom = c + (d - c) * fx;
    return top + (bottom - top) * fy;
}

// Triangle `t`'s colour at barycentric weights `w` (clamped to the triangle): the corner
// colours interpolated, times its texture at the interpolated uv (a non-finite uv is 0, 0).
fn voxel_color(t: u32, w: vec3<f32>, corner_colors_at: mat3x4<f32>) -> vec4<f32> {
    let color = w.x * corner_colors_at[0] + w.y * corner_colors_at[1] + w.z * corner_colors_at[2];
    let u0 = corner_uvs[3u * t];
    let index = u0.z;
    if index < 0.0 {
        return color;
    }
    var uv = w.x * u0.xy + w.y * corner_uvs[3u * t + 1u].xy + w.z * corner_uvs[3u * t + 2u].xy;
    if !all(abs(uv) < vec2(3.0e38)) {
        uv = vec2(0.0);
    }
    return color * sample_voxel_texture(u32(index), uv);
}

// Triangle `t`'s colour at point `x` of its 2D projection `q0, q1, q2` (the raster path's
// pixel centre, the exact path's column centre): 2D barycentrics clamped to the triangle
// and renormalized (a third each where the projection has no area), then `voxel_color` of
// its corner colours (`corner_colors`, declared by the includer).
fn voxel_color_at(t: u32, q0: vec2<f32>, q1: vec2<f32>, q2: vec2<f32>, x: vec2<f32>) -> vec4<f32> {
    let area = (q1.x - q0.x) * (q2.y - q0.y) - (q1.y - q0.y) * (q2.x - q0.x);
    var w = vec3(1.0 / 3.0);
    if area != 0.0 {
        let w1 = ((x.x - q0.x) * (q2.y - q0.y) - (x.y - q0.y) * (q2.x - q0.x)) / area;
        let w2 = ((q1.x - q0.x) * (x.y - q0.y) - (q1.y - q0.y) * (x.x - q0.x)) / area;
        w = max(vec3(1.0 - w1 - w2, w1, w2), vec3(0.0));
        w = w / max(w.x + w.y + w.z, 1e-20);
    }
    let corner_colors_at = mat3x4(
        corner_colors[3u * t],
        corner_colors[3u * t + 1u],
        corner_colors[3u * t + 2u],
    );
    return voxel_color(t, w, corner_colors_at);
}
