// Analysis pass: the camera's view at low resolution (180x180 by default),
// writing only the per-pixel words the optimizer reads back: depth, shadow
// bits, light-facing bits and the normal (see `mask_words` in common.wgsl,
// which is prepended together with the vertex stage `vs_main`).
//
// Depth goes out as f32 bits in a u32 channel rather than as a float
// target, so that the pass also runs where R32Float is not renderable (GL).

@fragment
fn fs_analysis(in: VertexOutput) -> @location(0) vec4<u32> {
    return mask_words(in, shade(in));
}
