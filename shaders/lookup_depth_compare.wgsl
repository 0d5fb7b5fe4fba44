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
    let m = map_position(light, world);
    if m.w == 0.0 {
        return false;
    }
    // The shadow pass rasterized texel k at its centre k + 0.5, so `floor`
    // picks the texel whose sample is nearest in the sense of the
    // rasterizer's coverage.
    let coords = map_texel(light, m.xy);
    let stored = textureLoad(shadow_maps, coords, light.layer, 0).x;
    // Linear light depth, as the shadow pass stored it (see shadow.wgsl);
    // receivers beyond the far end compare as at it.
    let depth = clamp(linear_light_depth(light.position, light.depth.xy, world), 0.0, 1.0);
    return stored < depth;
}
