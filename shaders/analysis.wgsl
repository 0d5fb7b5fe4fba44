// Analysis pass: the camera's view at low resolution (180x180 by default),
// writing only the per-pixel words the optimizer reads back: depth, shadow
// bits, light-facing bits and the normal (see `mask_words` in common.wgsl,
// which is prepended together with the vertex stage `vs_main`).
//
// Two sources, one output. Analysis pixel (x, y) always stands for the
// full-resolution point ((x, y) + 0.5) * viewport / analysis size:
//
// - `fs_analysis_depth` (the default) draws one full-screen triangle and
//   reads the camera pass's depth buffer and masks, so the scene is not drawn
//   a second time. It takes the surface at that point from the nearest
//   full-resolution pixel and the one-sided depth differences that continue
//   its surface (screen-space depth is affine on planes, so this is exact
//   there). Lights whose map is the frame's own (`lights.camera_bits`) take
//   that pixel's bits from the camera pass; the others (the periodic focused
//   maps, listed in `lights.lookup`) are looked up here at the reconstructed
//   world point, with the camera pass's interpolated normal. (The loop runs
//   over that list only: a software rasterizer runs a branch's body even
//   when no lane takes it.)
// - `fs_analysis_geometry` draws the scene again at the analysis resolution
//   (interpolated positions and normals).
//
// Depth goes out as f32 bits in a u32 channel rather than as a float
// target, so that the pass also runs where R32Float is not renderable (GL).

@group(0) @binding(3) var camera_depth: texture_2d<f32>;
@group(0) @binding(4) var camera_masks: texture_2d<u32>;

@fragment
fn fs_analysis_geometry(in: VertexOutput) -> @location(0) vec4<u32> {
    return mask_words(in, shade(in));
}

// Camera depth at full-resolution pixel `p`; 1.0 (background) outside.
fn camera_depth_at(p: vec2<i32>, size: vec2<i32>) -> f32 {
    if any(p < vec2<i32>(0)) || any(p >= size) {
        return 1.0;
    }
    return textureLoad(camera_depth, p, 0).x;
}

// Depth change per pixel along one axis, from the side that continues the
// surface at `centre`: the smaller of the two one-sided differences
// (background neighbours do not count; 0 when both are background).
fn depth_slope(before: f32, centre: f32, after: f32) -> f32 {
    let back = centre - before;
    let ahead = after - centre;
    let has_back = before < 1.0;
    let has_ahead = after < 1.0;
    if has_back && has_ahead {
        return select(ahead, back, abs(back) < abs(ahead));
    }
    if has_back {
        return back;
    }
    if has_ahead {
        return ahead;
    }
    return 0.0;
}

// Inverse of `pack_normal` in common.wgsl.
fn unpack_normal(packed: u32) -> vec3<f32> {
    let p = unpack2x16snorm(packed);
    var n = vec3<f32>(p, 1.0 - abs(p.x) - abs(p.y));
    if n.z < 0.0 {
        n = vec3<f32>((1.0 - abs(p.yx)) * select(vec2<f32>(-1.0), vec2<f32>(1.0), p >= vec2<f32>(0.0)), n.z);
    }
    return normalize(n);
}

// World position of full-resolution screen point `q` (pixels, y down) at
// depth-buffer value `depth`.
fn unproject(q: vec2<f32>, depth: f32, size: vec2<f32>) -> vec3<f32> {
    let ndc = vec2<f32>(2.0 * q.x / size.x - 1.0, 1.0 - 2.0 * q.y / size.y);
    let world = camera.world_from_clip * vec4<f32>(ndc, depth, 1.0);
    return world.xyz / world.w;
}

@fragment
fn fs_analysis_depth(@builtin(position) frag: vec4<f32>) -> @location(0) vec4<u32> {
    let size_px = vec2<i32>(textureDimensions(camera_depth));
    let size = vec2<f32>(size_px);
    // `frag.xy` is the analysis pixel's centre.
    let q = frag.xy * size / camera.params.yz;
    let p = clamp(vec2<i32>(floor(q)), vec2<i32>(0), size_px - vec2<i32>(1));
    let depth = camera_depth_at(p, size_px);
    if depth >= 1.0 {
        return vec4<u32>(bitcast<u32>(1.0), 0u, 0u, 0u);
    }
    let dx = vec2<i32>(1, 0);
    let dy = vec2<i32>(0, 1);
    let slope = vec2<f32>(
        depth_slope(camera_depth_at(p - dx, size_px), depth, camera_depth_at(p + dx, size_px)),
        depth_slope(camera_depth_at(p - dy, size_px), depth, camera_depth_at(p + dy, size_px)),
    );
    // Move from the pixel's centre to `q` along the surface's plane.
    // (Kept below 1.0, which would read as background.)
    let depth_q = clamp(depth + dot(slope, q - (vec2<f32>(p) + 0.5)), 0.0, bitcast<f32>(0x3f7fffffu));
    let world = unproject(q, depth_q, size);
    // The camera pass's words at that pixel (see `mask_words`).
    let words = textureLoad(camera_masks, p, 0);
    let n = unpack_normal(words.w);

    var shadow = words.y & lights.camera_bits;
    var facing = words.z & lights.camera_bits;
    let count = min(lights.lookup_count, MAX_LIGHTS);
    for (var k = 0u; k < count; k++) {
        let i = lights.lookup[k / 4u][k % 4u];
        let light = lights.items[i];
        if dot(n, to_light(light, world)) > 0.0 && in_cone(light, world) && cascade_owns(light, world) {
            facing |= 1u << i;
            if in_shadow(light, world) {
                shadow |= 1u << i;
            }
        }
    }
    return vec4<u32>(bitcast<u32>(depth_q), shadow, facing, words.w);
}
