// Shadow pass: depth only, one light per pass. The light's matrix comes at
// a dynamic offset of one uniform buffer (one 256-byte slot per light).
//
// The matrix maps world space to the light's clip space in wgpu conventions
// (depth [0, 1], NDC y up); the viewport covers only the light's own
// rectangle of its layer, so NDC [-1, 1] lands on texels [0, map_size).
// Depth bias (slope-scaled, see `ShadowBias`) is applied by the rasterizer.

struct ShadowPass {
    clip_from_world: mat4x4<f32>,
}

@group(0) @binding(0) var<uniform> shadow_pass: ShadowPass;

@vertex
fn vs_shadow(@location(0) position: vec3<f32>) -> @builtin(position) vec4<f32> {
    return shadow_pass.clip_from_world * vec4<f32>(position, 1.0);
}
