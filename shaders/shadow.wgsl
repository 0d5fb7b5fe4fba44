// Shadow pass: depth only, one light per pass. The light's matrix comes at
// a dynamic offset of one uniform buffer (one 256-byte slot per light).
//
// The matrix maps world space to the light's clip space in wgpu conventions
// (depth [0, 1], NDC y up); the viewport covers only the light's own
// rectangle of its layer, so NDC [-1, 1] lands on texels [0, map_size).
// The stored depth is linear light depth with the bias of `ShadowBias`
// applied in `fs_shadow` (see below).

struct ShadowPass {
    clip_from_world: mat4x4<f32>,
    // Homogeneous light position: (p, 1) for a point or spot light, (-d, 0)
    // for a directional light travelling along d.
    position: vec4<f32>,
    // Linear light depth: (min distance, 1 / (max - min), constant bias,
    // slope scale).
    depth: vec4<f32>,
    // x: largest bias (0: unclamped).
    clamp: vec4<f32>,
}

@group(0) @binding(0) var<uniform> shadow_pass: ShadowPass;

struct ShadowVertex {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
}

@vertex
fn vs_shadow(@location(0) position: vec3<f32>) -> ShadowVertex {
    var out: ShadowVertex;
    out.clip = shadow_pass.clip_from_world * vec4<f32>(position, 1.0);
    out.world = position;
    return out;
}

// The stored depth is *linear* light depth, not the matrix's z / w: the
// distance from the light along its ray (|x - l| for a point light, d·x for
// a directional one), normalized to the map's range. A warped map (PSM,
// LiSPSM, scene-optimized) spends its projective depth across the map rather
// than along the rays, which leaves too little depth between a caster and
// its receiver; linear depth keeps that separation the same for every
// method. The matrix's z still clips at near and far. The bias is applied
// here (hardware depth bias does not reach a written frag_depth): constant
// plus slope-scaled on the linear depth.
@fragment
fn fs_shadow(in: ShadowVertex) -> @builtin(frag_depth) f32 {
    let depth = linear_light_depth(shadow_pass.position, shadow_pass.depth.xy, in.world);
    let slope = max(abs(dpdx(depth)), abs(dpdy(depth)));
    var bias = shadow_pass.depth.z + shadow_pass.depth.w * slope;
    if shadow_pass.clamp.x > 0.0 {
        bias = min(bias, shadow_pass.clamp.x);
    }
    return clamp(depth + bias, 0.0, 1.0);
}
