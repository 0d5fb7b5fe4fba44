// Supersampled standard lookup (ShadowLookup::Supersampled, see
// src/render/subpixel/supersample.rs): after each jittered camera pass, one
// invocation per pixel copies that pass's shadow and facing bits of every
// light into bit `sample` of the pixel's words.
//
// words: occluded words [light][pixel], then valid words [light][pixel]
// (valid: the sub-sample's surface faces the light; occluded: valid and the
// depth compare finds it shadowed). Cleared to zero before the first pass.

struct Params {
    sample: u32,
    width: u32,
    height: u32,
    lights: u32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var masks: texture_2d<u32>;
@group(0) @binding(2) var<storage, read_write> words: array<u32>;

@compute @workgroup_size(8, 8)
fn gather(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= params.width || id.y >= params.height {
        return;
    }
    // See `mask_words` in common.wgsl: y shadow bits, z light-facing bits.
    let m = textureLoad(masks, vec2<i32>(id.xy), 0);
    let pixels = params.width * params.height;
    let pixel = id.y * params.width + id.x;
    let bit = 1u << params.sample;
    for (var l = 0u; l < params.lights; l++) {
        if ((m.z >> l) & 1u) == 0u {
            continue;
        }
        let i = l * pixels + pixel;
        words[params.lights * pixels + i] |= bit;
        if ((m.y >> l) & 1u) != 0u {
            words[i] |= bit;
        }
    }
}
