// Camera pass: the scene seen by the viewer with hard shadows of up to 32
// lights. common.wgsl (prepended) declares the bindings, the vertex stage
// `vs_main` and the shadow lookup.

// Colour only (the frame loop's picture).
@fragment
fn fs_color(in: VertexOutput) -> @location(0) vec4<f32> {
    // The target is sRGB: the hardware encodes this linear colour.
    return vec4<f32>(shade(in).color, 1.0);
}

struct ColorAndMasks {
    @location(0) color: vec4<f32>,
    // See `mask_words` in common.wgsl.
    @location(1) masks: vec4<u32>,
}

// Colour plus the full-resolution per-pixel masks (for experiments).
@fragment
fn fs_color_masks(in: VertexOutput) -> ColorAndMasks {
    let shading = shade(in);
    var out: ColorAndMasks;
    out.color = vec4<f32>(shading.color, 1.0);
    out.masks = mask_words(in, shading);
    return out;
}

// ---- View capture and deferred shading (Renderer::capture_view) ----
//
// The experiment sees every configuration through one camera, so the scene
// is drawn from it once into a capture: per pixel the interpolated world
// position and normal as f32 bits, the depth-buffer value and the albedo.
// Frames with that camera then run the camera pass as one full-screen
// triangle that rebuilds the fragment's inputs from the capture and shades
// them with the same `shade` and `mask_words`: the depth test kept the same
// fragment, so the shadow, facing and normal words are bit-identical to a
// drawn pass; only the colour sees an 8-bit albedo.

@group(2) @binding(0) var captured_surface: texture_2d<u32>;
@group(2) @binding(1) var captured_normal: texture_2d<u32>;

struct Capture {
    // World position (f32 bits), depth-buffer value (f32 bits).
    @location(0) surface: vec4<u32>,
    // Interpolated normal (f32 bits), albedo (unorm 8-bit RGB).
    @location(1) normal: vec4<u32>,
}

@fragment
fn fs_capture(in: VertexOutput) -> Capture {
    var out: Capture;
    out.surface = vec4<u32>(bitcast<vec3<u32>>(in.world), bitcast<u32>(in.clip.z));
    out.normal = vec4<u32>(bitcast<vec3<u32>>(in.normal), pack4x8unorm(vec4<f32>(in.albedo, 0.0)));
    return out;
}

// The captured fragment at `position`; background pixels (depth 1, never
// written) are discarded, keeping the pass's clear values as a drawn pass does.
fn captured_fragment(position: vec4<f32>) -> VertexOutput {
    let p = vec2<i32>(position.xy);
    let s = textureLoad(captured_surface, p, 0);
    let depth = bitcast<f32>(s.w);
    if depth >= 1.0 {
        discard;
    }
    let n = textureLoad(captured_normal, p, 0);
    var in: VertexOutput;
    in.clip = vec4<f32>(position.xy, depth, 1.0);
    in.world = bitcast<vec3<f32>>(s.xyz);
    in.normal = bitcast<vec3<f32>>(n.xyz);
    in.albedo = unpack4x8unorm(n.w).rgb;
    return in;
}

struct DeferredColor {
    @location(0) color: vec4<f32>,
    @builtin(frag_depth) depth: f32,
}

@fragment
fn fs_deferred_color(@builtin(position) position: vec4<f32>) -> DeferredColor {
    let in = captured_fragment(position);
    var out: DeferredColor;
    out.color = vec4<f32>(shade(in).color, 1.0);
    out.depth = in.clip.z;
    return out;
}

struct DeferredColorAndMasks {
    @location(0) color: vec4<f32>,
    @location(1) masks: vec4<u32>,
    @builtin(frag_depth) depth: f32,
}

@fragment
fn fs_deferred_color_masks(@builtin(position) position: vec4<f32>) -> DeferredColorAndMasks {
    let in = captured_fragment(position);
    let shading = shade(in);
    var out: DeferredColorAndMasks;
    out.color = vec4<f32>(shading.color, 1.0);
    out.masks = mask_words(in, shading);
    out.depth = in.clip.z;
    return out;
}
