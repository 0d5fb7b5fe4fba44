// Shadow lookup `ShadowLookup::DepthCompare`: the standard hard shadow test
// against one depth per texel. Prepended to the camera and analysis passes
// with common.wgsl (which declares `Light` and `linear_light_depth`).
//
// Every lookup file binds its maps in group 1 (the layout of its map format,
// see src/render/lookup.rs) and defines
// `fn in_shadow(light: Light, world: vec3<f32>) -> bool`, whose result
// becomes the light's shadow bit in the masks and the analysis readback.

// One layer per shadow-pass slot (`light.layer`), as large as the largest map.
// Depth textures are bound as unfilterable float textures: naga cannot
// translate `textureLoad` from a depth texture to GLSL (the GL backend).
@group(1) @binding(0) var shadow_maps: texture_2d_array<f32>;

// Hard shadow test of `world` against the light's map. Points outside the
// map, or behind the light's image plane, count as lit.
fn in_shadow(light: Light, world: vec3<f32>) -> bool {
    let clip = light.clip_from_world * vec4<f32>(world, 1.0);
    if clip.w <= 0.0 {
        return false;
    }
    let ndc = clip.xyz / clip.w;
    if any(abs(ndc.xy) > vec2<f32>(1.0)) {
        return false;
    }
    // NDC to texels. x: [-1, 1] -> [0, width). y: NDC y is up but texture
    // row 0 is at the top, so flip. Texel k covers [k, k + 1); the shadow
    // pass rasterized it at its centre k + 0.5, so `floor` picks the texel
    // whose sample is nearest in the sense of the rasterizer's coverage.
    let texel = vec2<f32>(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5) * light.map_size;
    let size = vec2<i32>(light.map_size);
    let coords = clamp(vec2<i32>(floor(texel)), vec2<i32>(0), size - vec2<i32>(1));
    let stored = textureLoad(shadow_maps, coords, light.layer, 0).x;
    // Linear light depth, as the shadow pass stored it (see shadow.wgsl);
    // receivers beyond the far end compare as at it.
    let depth = clamp(linear_light_depth(light.position, light.depth.xy, world), 0.0, 1.0);
    return stored < depth;
}
