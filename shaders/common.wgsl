// Shared declarations of the camera and analysis passes: prepended to
// camera.wgsl and analysis.wgsl by the renderer (WGSL has no includes),
// together with the shadow lookup's own file (`shaders/lookup_*.wgsl`, chosen by
// `ShadowLookup`), which binds the maps in group 1 and defines
// `fn in_shadow(light: Light, world: vec3<f32>) -> bool`.
//
// Conventions (wgpu's): right-handed world, clip depth in [0, 1], NDC y up,
// framebuffer and texture row 0 at the top.

const MAX_LIGHTS: u32 = 32u;
struct Camera {
    clip_from_world: mat4x4<f32>,
    // The inverse (computed in f64 on the CPU), for the analysis pass's
    // reconstruction of world positions from the camera's depth.
    world_from_clip: mat4x4<f32>,
    // xyz: eye position in world space.
    eye: vec4<f32>,
    // x: ambient light level; yz: analysis resolution; w: unused.
    params: vec4<f32>,
    // dot(view_depth, (world, 1)): distance along the view direction.
    view_depth: vec4<f32>,
}

struct Light {
    clip_from_world: mat4x4<f32>,
    // Homogeneous light position: (p, 1) for a point or spot light, (-d, 0)
    // for a directional light travelling along d (the point at infinity it
    // comes from). `to_light` below handles both.
    position: vec4<f32>,
    // rgb: radiance scale; a: unused.
    color: vec4<f32>,
    // The light's map occupies texels [0, map_size) at the top-left of its
    // layer of the shadow-map array (layers are as large as the largest map).
    map_size: vec2<f32>,
    layer: u32,
    // Bit 0: a cascade (`cascade_weight`, `cascade_owns`).
    flags: u32,
    // Linear light depth: (min distance, 1 / (max - min), ..); see
    // shadow.wgsl. zw: the view depths [z, w) where a cascade owns the
    // mask bits (flags bit 0).
    depth: vec4<f32>,
    // A spot light's cone: (unit axis, cos of the half-angle); w < -1 for
    // lights without one.
    spot: vec4<f32>,
    // A cascade's weight over view depth: 0 before x, rising to 1 at y, 1
    // to z, falling to 0 at w (flags bit 0).
    cascade: vec4<f32>,
}

struct Lights {
    count: u32,
    // Analysis pass only (the camera pass ignores them): bit i set when
    // light i's map is the frame's own, so the camera pass's bits apply; the
    // other lights' indices, four per vector, and how many there are.
    camera_bits: u32,
    lookup_count: u32,
    _pad: u32,
    lookup: array<vec4<u32>, 8>,
    items: array<Light, MAX_LIGHTS>,
}

@group(0) @binding(0) var<uniform> camera: Camera;
@group(0) @binding(1) var<uniform> lights: Lights;

struct VertexInput {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) albedo: vec4<f32>,
}

struct VertexOutput {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) albedo: vec3<f32>,
}

@vertex
fn vs_main(vertex: VertexInput) -> VertexOutput {
    var out: VertexOutput;
    out.clip = camera.clip_from_world * vec4<f32>(vertex.position, 1.0);
    out.world = vertex.position;
    out.normal = vertex.normal;
    out.albedo = vertex.albedo.rgb;
    return out;
}

// The full-screen passes' vertex stage (the depth analysis, the deferred
// camera pass): one triangle covering the target: (-1, -1), (3, -1), (-1, 3).
@vertex
fn vs_fullscreen(@builtin(vertex_index) index: u32) -> @builtin(position) vec4<f32> {
    let corner = vec2<f32>(f32((index << 1u) & 2u), f32(index & 2u));
    return vec4<f32>(corner * 2.0 - 1.0, 0.0, 1.0);
}

// Unnormalised direction from `world` towards the light.
fn to_light(light: Light, world: vec3<f32>) -> vec3<f32> {
    return light.position.xyz - world * light.position.w;
}

// Whether the light reaches `world` at all: inside a spot light's cone
// (always for other lights). Outside it the surface is unlit, not shadowed.
fn in_cone(light: Light, world: vec3<f32>) -> bool {
    let to_world = world - light.position.xyz;
    return light.spot.w < -1.0 || dot(light.spot.xyz, to_world) >= light.spot.w * length(to_world);
}

// Where `world` falls in the light's map, for the lookups: xy the position
// in texels (x: NDC [-1, 1] -> [0, width); y flipped, texture row 0 at the
// top; texel k covers [k, k + 1)), z the NDC depth, w 1 — or w 0 when the
// point is behind the light's image plane or outside the map (lit).
fn map_position(light: Light, world: vec3<f32>) -> vec4<f32> {
    let clip = light.clip_from_world * vec4<f32>(world, 1.0);
    if clip.w <= 0.0 {
        return vec4<f32>(0.0);
    }
    let ndc = clip.xyz / clip.w;
    if any(abs(ndc.xy) > vec2<f32>(1.0)) {
        return vec4<f32>(0.0);
    }
    return vec4<f32>(vec2<f32>(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5) * light.map_size, ndc.z, 1.0);
}

// The texel holding map position `p` (clamped into the map).
fn map_texel(light: Light, p: vec2<f32>) -> vec2<i32> {
    return clamp(vec2<i32>(floor(p)), vec2<i32>(0), vec2<i32>(light.map_size) - vec2<i32>(1));
}

// Whether `light` sets its mask bits at `world`: always, except for a
// cascade (flags bit 0) outside the view depths it owns. The cascades of one
// sun own consecutive ranges split at the middle of each blend band, so
// exactly one of them sets bits per pixel; the CPU twin is
// `lixel::cascade::CascadeChoice::bit_owner`.
fn cascade_owns(light: Light, world: vec3<f32>) -> bool {
    if (light.flags & 1u) == 0u {
        return true;
    }
    let d = dot(camera.view_depth, vec4<f32>(world, 1.0));
    return d >= light.depth.z && d < light.depth.w;
}

// The weight of `light`'s lighting at `world`: 1, except for a cascade
// (flags bit 0): 0 outside its ramps, blending linearly with its
// neighbours across the blend bands; the weights of one sun's cascades add
// up to 1. The CPU twin is `lixel::cascade::Splits::choose`.
fn cascade_weight(light: Light, world: vec3<f32>) -> f32 {
    if (light.flags & 1u) == 0u {
        return 1.0;
    }
    let d = dot(camera.view_depth, vec4<f32>(world, 1.0));
    let r = light.cascade;
    if d < r.x || d >= r.w {
        return 0.0;
    }
    if d < r.y {
        return (d - r.x) / (r.y - r.x);
    }
    if d > r.z {
        return (r.w - d) / (r.w - r.z);
    }
    return 1.0;
}

struct Shading {
    // Linear RGB.
    color: vec3<f32>,
    // Bit i: light i is blocked here (only set where `facing` is).
    shadow: u32,
    // Bit i: light i reaches the surface, occluders aside: it faces the
    // light (interpolated normal · to-light > 0) inside a spot light's cone.
    facing: u32,
}

fn shade(in: VertexOutput) -> Shading {
    var out: Shading;
    let n = normalize(in.normal);
    out.color = camera.params.x * in.albedo;
    out.shadow = 0u;
    out.facing = 0u;
    let count = min(lights.count, MAX_LIGHTS);
    for (var i = 0u; i < count; i++) {
        let light = lights.items[i];
        // A cascade lights with its weight; only the cascade owning the
        // pixel sets bits (see cascade_owns).
        let weight = cascade_weight(light, in.world);
        if weight <= 0.0 {
            continue;
        }
        let owns = cascade_owns(light, in.world);
        let n_dot_l = dot(n, normalize(to_light(light, in.world)));
        if n_dot_l > 0.0 && in_cone(light, in.world) {
            let shadowed = in_shadow(light, in.world);
            if owns {
                out.facing |= 1u << i;
                out.shadow |= select(0u, 1u << i, shadowed);
            }
            if !shadowed {
                out.color += in.albedo * light.color.rgb * (n_dot_l * weight);
            }
        }
    }
    return out;
}

// Octahedral encoding of a unit normal into two signed-normalised 16-bit
// values (Cigolle et al. 2014), packed in one u32.
fn pack_normal(n: vec3<f32>) -> u32 {
    var p = n.xy / (abs(n.x) + abs(n.y) + abs(n.z));
    if n.z < 0.0 {
        p = (1.0 - abs(p.yx)) * select(vec2<f32>(-1.0), vec2<f32>(1.0), p >= vec2<f32>(0.0));
    }
    return pack2x16snorm(p);
}

// The per-pixel words read back by the experiments and the optimizer:
// x: depth-buffer value as f32 bits (the target is cleared to 1.0's bits),
// y: shadow bits, z: light-facing bits, w: octahedral normal.
fn mask_words(in: VertexOutput, shading: Shading) -> vec4<u32> {
    // `clip.z` in a fragment shader is the depth-buffer value in [0, 1].
    return vec4<u32>(bitcast<u32>(in.clip.z), shading.shadow, shading.facing, pack_normal(normalize(in.normal)));
}
