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
