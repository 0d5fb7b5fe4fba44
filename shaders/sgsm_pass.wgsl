// SGSM pass: SPSM's conservative pass (spsm_pass.wgsl, whose fragment
// entry the renderer renames spsm_fragment) plus a second target with what
// the normal detection needs: the stored triangle's plane slopes
// (dzeta per map extent along x and y, two f16; zero for depth-only
// texels). In the matrix's post-projective space these slopes are the
// plane's normal (-sx, -sy, 1) up to scale: two triangles on one plane
// have the same, neighbouring facets of a curved surface differ.

struct SgsmOutput {
    @location(0) texel: vec4<u32>,
    @location(1) normal: u32,
    @builtin(frag_depth) depth: f32,
}

@fragment
fn fs_shadow(in: SpsmVertex) -> SgsmOutput {
    let spsm = spsm_fragment(in);
    var out: SgsmOutput;
    out.texel = spsm.texel;
    out.depth = spsm.depth;
    out.normal = 0u;
    if in.mode == 0u {
        let slopes = spsm_gradient(in.t0, in.t1, in.t2, in.zeta) * shadow_pass.clamp.yz;
        out.normal = pack2x16float(clamp(slopes, vec2<f32>(-60000.0), vec2<f32>(60000.0)));
    }
    return out;
}
