// SPSM lookup (Lecocq et al. 2014, section 4): `in_shadow` of the lookup
// mode ShadowLookup::Spsm, after common.wgsl. spsm_common.wgsl is
// prepended, and SPSM_TANGENTS, the 3x3 pattern -> silhouette normal table.
//
// For a receiver p (texel position, depth zeta = z / w of the light matrix):
// 1. own texel: empty -> lit (conservative rasterization: no triangle
//    touches the texel); p inside the stored triangle -> its plane decides;
// 2. the 3x3 neighbourhood: any stored triangle containing p whose plane is
//    in front of p -> shadowed; else one containing p at p's depth -> lit
//    (a receiver's mesh edge crossing the texel);
// 3. uncertain: silhouette recovery. Each neighbour's consistent minimum
//    depth tested against zeta gives a 9-bit pattern; all blocked ->
//    shadowed, none -> lit; else the table gives the silhouette's normal n
//    (towards the lit side) and tangent. The occluders' boundary vertices
//    (vertex normal towards the lit side) within two texels along the
//    tangent are projected on it, and the piecewise-linear phi through the
//    nearest one on each side decides: shadowed when phi(t(p)) reaches
//    past p towards the lit side.
// Depth tests use the stored plane with a constant bias SPSM_BIAS (1e-5 of
// the [0, 1] depth range by default) plus, when SPSM_TOLERANCE is 1, the
// packing's own error bound on the extrapolated plane.

// Group 1 is the mode's maps (src/render/lookup.rs): binding 0 the depth
// array (the consistent minimum depth, unused here), binding 1 the texels.
@group(1) @binding(1) var spsm_texels: texture_2d_array<u32>;

fn spsm_load(light: Light, k: vec2<i32>) -> SpsmTexel {
    if any(k < vec2<i32>(0)) || any(k >= vec2<i32>(light.map_size)) {
        var t: SpsmTexel;
        t.kind = 2u;
        t.centre = vec2<f32>(k) + 0.5;
        return t;
    }
    return spsm_decode(textureLoad(spsm_texels, k, light.layer, 0), k, light.map_size);
}

// Consistent depth test of a whole texel: its triangle's minimum depth over
// the part of the texel it covers is in front of p.
fn spsm_texel_blocks(t: SpsmTexel, zeta: f32) -> bool {
    if t.kind == 2u {
        return false;
    }
    if t.kind == 1u {
        return t.depth < zeta - SPSM_BIAS;
    }
    let lowest = spsm_min_depth(t.v0, t.v1, t.v2, t.centre, t.depth, t.gradient, 3.0e38);
    let tolerance = SPSM_TOLERANCE * 0.5 * (t.gradient_error.x + t.gradient_error.y);
    return lowest < zeta - SPSM_BIAS - tolerance;
}

// Outward unit normal of edge a -> b of a triangle with orientation `orient`.
fn spsm_edge_normal(a: vec2<f32>, b: vec2<f32>, orient: f32) -> vec2<f32> {
    let n = orient * vec2<f32>(b.y - a.y, a.x - b.x);
    return n / max(length(n), 1e-20);
}

fn spsm_recover(texels_in: array<SpsmTexel, 9>, pattern: u32, p: vec2<f32>) -> bool {
    var texels = texels_in;
    if pattern == 0u {
        return false;
    }
    if pattern == 0x1ffu {
        return true;
    }
    let n = SPSM_TANGENTS[pattern];
    if all(n == vec2<f32>(0.0)) {
        return (pattern & (1u << 4u)) != 0u;
    }
    let tangent = vec2<f32>(-n.y, n.x);
    // Nearest boundary vertex on each side of p along the tangent: (t, d).
    var left = vec2<f32>(-1e30, 0.0);
    var right = vec2<f32>(1e30, 0.0);
    var found = vec2<bool>(false, false);
    for (var i = 0u; i < 9u; i++) {
        let t = texels[i];
        if (pattern & (1u << i)) == 0u || t.kind != 0u {
            continue;
        }
        var v = array<vec2<f32>, 3>(t.v0, t.v1, t.v2);
        let orient = sign(spsm_cross(t.v1 - t.v0, t.v2 - t.v0));
        for (var k = 0u; k < 3u; k++) {
            let prev = v[(k + 2u) % 3u];
            let next = v[(k + 1u) % 3u];
            let normal = spsm_edge_normal(prev, v[k], orient) + spsm_edge_normal(v[k], next, orient);
            if orient != 0.0 && dot(normal, n) <= 0.0 {
                continue;
            }
            let q = v[k] - p;
            let tv = dot(q, tangent);
            let dv = dot(q, n);
            if abs(tv) > 2.0 {
                continue;
            }
            // Nearest in t; near-ties go to the vertex further towards the lit side.
            if tv <= 0.0 && (tv > left.x + 0.01 || (tv > left.x - 0.01 && dv > left.y)) {
                left = vec2<f32>(tv, dv);
                found.x = true;
            }
            if tv >= 0.0 && (tv < right.x - 0.01 || (tv < right.x + 0.01 && dv > right.y)) {
                right = vec2<f32>(tv, dv);
                found.y = true;
            }
        }
    }
    var phi: f32;
    if found.x && found.y {
        let span = right.x - left.x;
        phi = select(max(left.y, right.y), mix(left.y, right.y, -left.x / span), span > 1e-6);
    } else if found.x {
        phi = left.y;
    } else if found.y {
        phi = right.y;
    } else {
        return (pattern & (1u << 4u)) != 0u;
    }
    // p sits at d = 0: shadowed when the boundary lies on its lit side.
    return phi >= 0.0;
}

fn in_shadow(light: Light, world: vec3<f32>) -> bool {
    let clip = light.clip_from_world * vec4<f32>(world, 1.0);
    if clip.w <= 0.0 {
        return false;
    }
    let ndc = clip.xyz / clip.w;
    if any(abs(ndc.xy) > vec2<f32>(1.0)) {
        return false;
    }
    let p = vec2<f32>(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5) * light.map_size;
    let size = vec2<i32>(light.map_size);
    let k = clamp(vec2<i32>(floor(p)), vec2<i32>(0), size - vec2<i32>(1));
    let zeta = ndc.z;
    let own = spsm_load(light, k);
    if own.kind == 2u {
        return false;
    }
    if own.kind == 1u {
        return own.depth < zeta - SPSM_BIAS;
    }
    if spsm_inside(own, p) {
        let plane = spsm_plane_at(own, p);
        return plane.x < zeta - SPSM_BIAS - SPSM_TOLERANCE * plane.y;
    }
    var texels: array<SpsmTexel, 9>;
    var pattern = 0u;
    // p lies on a neighbour's stored triangle (a receiver mesh edge crosses
    // the own texel): the surface the map holds there is p's own.
    var on_surface = false;
    for (var i = 0u; i < 9u; i++) {
        var t = own;
        if i != 4u {
            t = spsm_load(light, k + vec2<i32>(i32(i % 3u) - 1, i32(i / 3u) - 1));
            if t.kind == 0u && spsm_inside(t, p) {
                let plane = spsm_plane_at(t, p);
                if plane.x < zeta - SPSM_BIAS - SPSM_TOLERANCE * plane.y {
                    return true;
                }
                on_surface = true;
            }
        }
        if spsm_texel_blocks(t, zeta) {
            pattern |= 1u << i;
        }
        texels[i] = t;
    }
    if on_surface {
        return false;
    }
    return spsm_recover(texels, pattern, p);
}
