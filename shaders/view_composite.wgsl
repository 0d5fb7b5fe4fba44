// The viewer's composite pass (src/view/composite.rs): one full-screen
// triangle over the camera pass's colour and depth, adding the overlays.
// Every texture is read with textureLoad at the pixel (no samplers); the
// camera depth is bound as unfilterable float (naga cannot translate a
// textureLoad from a depth texture to GLSL).

struct View {
    world_from_clip: mat4x4<f32>,
    // The selected light's clip_from_world (wgpu conventions).
    light_clip_from_world: mat4x4<f32>,
    // (viewport width, height, map width, height).
    sizes: vec4<f32>,
    // x: density, y: grid, z: error, w: encode sRGB in the shader (the
    // target is not an sRGB format).
    flags: vec4<u32>,
    // Shadow-map corner: (x0, y0, width, height) in pixels; width 0: off.
    map_rect: vec4<f32>,
    // HUD: (x0, y0, width, height) in pixels; width 0: off.
    hud_rect: vec4<f32>,
}

@group(0) @binding(0) var<uniform> view: View;
@group(0) @binding(1) var color_tex: texture_2d<f32>;
@group(0) @binding(2) var depth_tex: texture_2d<f32>;
@group(0) @binding(3) var error_tex: texture_2d<f32>;
@group(0) @binding(4) var map_tex: texture_2d<f32>;
@group(0) @binding(5) var hud_tex: texture_2d<f32>;

@vertex
fn vs_composite(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    // (-1,-1), (3,-1), (-1,3): covers the screen.
    let x = f32((i << 1u) & 2u) * 2.0 - 1.0;
    let y = f32(i & 2u) * 2.0 - 1.0;
    return vec4<f32>(x, y, 0.0, 1.0);
}

// The density colour ramp, the same as `hud::density_color`: log2(b) from
// -4 (b = 1/16, texels much smaller than pixels) to 8 (b = 256, a texel
// covers 16x16 pixels); blue, green (b = 1), yellow (b = 16), red.
fn density_color(b: f32) -> vec3<f32> {
    let t = clamp((log2(max(b, 1e-12)) + 4.0) / 12.0, 0.0, 1.0) * 3.0;
    let blue = vec3<f32>(0.15, 0.3, 1.0);
    let green = vec3<f32>(0.1, 0.85, 0.25);
    let yellow = vec3<f32>(1.0, 0.85, 0.1);
    let red = vec3<f32>(0.95, 0.1, 0.1);
    if t < 1.0 {
        return mix(blue, green, t);
    } else if t < 2.0 {
        return mix(green, yellow, t - 1.0);
    }
    return mix(yellow, red, t - 2.0);
}

fn srgb_encode(c: vec3<f32>) -> vec3<f32> {
    let lo = c * 12.92;
    let hi = 1.055 * pow(c, vec3<f32>(1.0 / 2.4)) - 0.055;
    return select(hi, lo, c <= vec3<f32>(0.0031308));
}

fn inside(p: vec2<f32>, rect: vec4<f32>) -> bool {
    return rect.z > 0.0 && p.x >= rect.x && p.y >= rect.y && p.x < rect.x + rect.z && p.y < rect.y + rect.w;
}

// The selected light's texel coordinates (row 0 at the top) of the surface
// seen at `pixel` with camera depth `depth`; z = 1 inside the map, else 0.
fn texel_at(pixel: vec2<i32>, depth: f32) -> vec3<f32> {
    let viewport = view.sizes.xy;
    let centre = vec2<f32>(pixel) + 0.5;
    // Pixel centre to NDC: row 0 at the top, NDC y up.
    let ndc = vec3<f32>(centre.x / viewport.x * 2.0 - 1.0, 1.0 - centre.y / viewport.y * 2.0, depth);
    let world_h = view.world_from_clip * vec4<f32>(ndc, 1.0);
    let light_clip = view.light_clip_from_world * vec4<f32>(world_h.xyz / world_h.w, 1.0);
    let light_ndc = light_clip.xy / light_clip.w;
    let inside = light_clip.w > 0.0 && all(abs(light_ndc) <= vec2<f32>(1.0));
    return vec3<f32>((light_ndc * vec2<f32>(0.5, -0.5) + 0.5) * view.sizes.zw, select(0.0, 1.0, inside));
}

fn depth_at(pixel: vec2<i32>) -> f32 {
    let clamped = clamp(pixel, vec2<i32>(0), vec2<i32>(view.sizes.xy) - 1);
    return textureLoad(depth_tex, clamped, 0).r;
}

// The texel step one pixel along `axis`: the central difference on a
// plane (camera depth is affine in screen space on a plane, so its second
// difference vanishes), else the one-sided difference towards the
// neighbour whose depth is closer (the same surface) — no overlay bleeds
// across silhouettes.
fn texel_step(pixel: vec2<i32>, depth: f32, texel: vec2<f32>, axis: vec2<i32>) -> vec2<f32> {
    let d_plus = depth_at(pixel + axis);
    let d_minus = depth_at(pixel - axis);
    let forward = texel_at(pixel + axis, d_plus).xy - texel;
    let backward = texel - texel_at(pixel - axis, d_minus).xy;
    let df = d_plus - depth;
    let db = depth - d_minus;
    if abs(df - db) <= 0.25 * max(abs(df), abs(db)) + 2e-7 {
        return 0.5 * (forward + backward);
    }
    return select(backward, forward, abs(df) < abs(db));
}

@fragment
fn fs_composite(@builtin(position) position: vec4<f32>) -> @location(0) vec4<f32> {
    let pixel = vec2<i32>(position.xy);
    // Loaded from an sRGB texture: linear colour.
    var color = textureLoad(color_tex, pixel, 0).rgb;
    let depth = textureLoad(depth_tex, pixel, 0).r;
    let here = texel_at(pixel, depth);
    let texel = here.xy;
    let surface = depth < 1.0;
    let in_map = here.z > 0.0;
    // J = d(texel)/d(pixel) by differences with the neighbours.
    let dx = texel_step(pixel, depth, texel, vec2<i32>(1, 0));
    let dy = texel_step(pixel, depth, texel, vec2<i32>(0, 1));
    let width = abs(dx) + abs(dy);

    if view.flags.x != 0u && surface {
        if in_map {
            // b = ||J||_F^2 / det(J)^2 (score::badness_of_jacobian).
            let det = dx.x * dy.y - dx.y * dy.x;
            let frob = dot(dx, dx) + dot(dy, dy);
            let b = select(1e12, frob / (det * det), abs(det) > 0.0);
            color = mix(color, density_color(b), 0.65);
        } else {
            // Outside the map: grey.
            color = mix(color, vec3<f32>(0.25), 0.6);
        }
    }
    if view.flags.y != 0u && surface && in_map {
        let f = fract(texel);
        let line = any(min(f, 1.0 - f) < width * 0.75);
        // Fades out where texels get smaller than about 3 pixels.
        let fade = clamp(1.6 - 4.0 * max(width.x, width.y), 0.0, 1.0);
        if line {
            color = mix(color, vec3<f32>(1.0, 0.95, 0.2), 0.8 * fade);
        }
    }
    if view.flags.z != 0u {
        let e = textureLoad(error_tex, pixel, 0);
        color = mix(color, e.rgb, e.a);
    }
    let p = position.xy;
    if inside(p, view.map_rect) {
        let map_pixel = vec2<i32>((p - view.map_rect.xy) / view.map_rect.zw * view.sizes.zw);
        color = textureLoad(map_tex, map_pixel, 0).rgb;
    }
    if inside(p, view.hud_rect) {
        let h = textureLoad(hud_tex, vec2<i32>(p - view.hud_rect.xy), 0);
        color = mix(color, h.rgb, h.a);
    }
    if view.flags.w != 0u {
        color = srgb_encode(color);
    }
    return vec4<f32>(color, 1.0);
}
