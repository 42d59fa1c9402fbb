//#include "common.inc.wgsl"
//#include "fullscreen.inc.wgsl"
//#include "composite.inc.wgsl"
// Deferred composite: directional + ambient Blinn-Phong, the same formula as the CPU
// reference (ssbvb-voxel shading::shade); pixels where nothing was drawn
// are left alone (transparent black when the output is cleared).

@fragment
fn fs_main(@builtin(position) pos: vec4<f32>) -> @location(0) vec4<f32> {
    let s = surface_at(vec2<i32>(pos.xy));
    // The eye is the camera-relative origin.
    return composite_output(shade(s.albedo.rgb, s.normal, -s.position));
}
