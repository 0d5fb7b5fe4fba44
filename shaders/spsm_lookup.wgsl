// SPSM lookup (Lecocq et al. 2014, section 4): `in_shadow` of the lookup
// mode ShadowLookup::Spsm, after common.wgsl. spsm_common.wgsl is
// prepended.
//
// For a receiver p (texel position, depth zeta = z / w of the light matrix):
// 1. own texel: empty -> lit (conservative rasterization: no triangle
//    touches the texel); p inside the stored triangle -> its plane decides;
//    p inside its parallelogram partner (the coplanar mesh neighbour that
//    completes it to a parallelogram, marked by the pass; session 14) and
//    behind its plane -> shadowed;
//    with SPSM_INNER_EDGES, p outside a small one but inside the (grown)
//    neighbour triangle across one of its inner edges (the caster continues
//    there; sessions 7 and 9) and far enough behind its plane -> shadowed;
// 2. the 3x3 neighbourhood: any stored triangle (or its parallelogram
//    partner, which gives no lit verdict) containing p whose plane is
//    in front of p -> shadowed; else p on the own triangle's plane (within
//    the bias and the packing tolerance) -> lit; else p on a neighbour's
//    stored triangle -> lit (a
//    receiver's mesh edge crossing the texel), unless the own triangle is
//    an occluder in front of p and p lies within one facet width of it
//    (spsm_other_surface_lit: a curved caster's unstored outer facet may
//    cover p);
// 3. uncertain: silhouette recovery. Each neighbour's consistent minimum
//    depth tested against zeta gives a 9-bit pattern; all blocked ->
//    shadowed, none -> lit; else the pattern gives the silhouette's normal n
//    (towards the lit side) and tangent, or two (a thin band: both normals
//    of its axis) or four (a blob: the axes) estimates. Per estimate the
//    occluders' boundary vertices (vertex normal towards the lit side)
//    within two texels along the tangent are projected on it, and the
//    piecewise-linear phi through the nearest one on each side decides:
//    shadowed when phi(t(p)) reaches past p towards the lit side; p is
//    shadowed when every estimate says so (the paper's intersection).
// Depth tests use the stored plane with a constant bias SPSM_BIAS (1e-5 of
// the [0, 1] depth range by default) plus, when SPSM_TOLERANCE is 1, the
// packing's own error bound on the extrapolated plane.

// Group 1 is the mode's maps (src/render/lookup.rs): binding 0 the depth
// array (the consistent minimum depth, squeezed by spsm_depth_key in
// spsm_pass.wgsl; bound as unfilterable float), binding 1 the texels.
@group(1) @binding(0) var spsm_depths: texture_2d_array<f32>;
@group(1) @binding(1) var spsm_texels: texture_2d_array<u32>;
// Binding 4: the centre-sampled depth words of spsm_pass.wgsl
// (spsm_store_centre), one block per layer of the maps' texel count rounded
// up to 64 words (256 bytes, the dynamic-offset alignment of the pass).
@group(1) @binding(4) var<storage, read> spsm_centre: array<u32>;

// The standard lookup's verdict at texel `k` for the receiver at `world`,
// from the centre-sampled depth the conservative pass kept beside the
// triangle (session 5): 0 lit, 1 shadowed, 2 unavailable (the buffer is too
// small: maps beyond the device's storage-buffer limit). As
// lookup_depth_compare.wgsl: the nearest surface at the texel centre in
// biased linear light depth against the receiver's.
fn spsm_standard(light: Light, k: vec2<i32>, world: vec3<f32>) -> u32 {
    let dims = textureDimensions(spsm_texels).xy;
    let stride = (dims.x * dims.y + 63u) / 64u * 64u;
    let index = light.layer * stride + u32(k.y) * u32(light.map_size.x) + u32(k.x);
    if index >= arrayLength(&spsm_centre) {
        return 2u;
    }
    let word = spsm_centre[index];
    if word == 0u {
        return 0u;
    }
    let depth = clamp(linear_light_depth(light.position, light.depth.xy, world), 0.0, 1.0);
    return select(0u, 1u, bitcast<f32>(~word) < depth);
}

// The verdict of path `path` (an SPSM_PATH_* bit): the standard lookup's
// where SPSM_FALLBACK covers the path, else SPSM's own.
fn spsm_decide(light: Light, k: vec2<i32>, world: vec3<f32>, path: u32, own_verdict: bool) -> bool {
    if (SPSM_FALLBACK & path) == 0u {
        return own_verdict;
    }
    let standard = spsm_standard(light, k, world);
    return select(own_verdict, standard == 1u, standard != 2u);
}

// The consistent minimum depth the pass stored for texel `k` (inside the
// map): the inverse of spsm_depth_key, exact to f32 (no packing error).
fn spsm_min_depth_at(light: Light, k: vec2<i32>) -> f32 {
    let s = 2.0 * textureLoad(spsm_depths, k, light.layer, 0).x - 1.0;
    return s / max(1.0 - abs(s), 1e-30);
}

// The texel at `k` without its derivatives (spsm_decode_shape); outside
// the map an empty texel.
fn spsm_load_shape(light: Light, k: vec2<i32>) -> SpsmTexel {
    if any(k < vec2<i32>(0)) || any(k >= vec2<i32>(light.map_size)) {
        var t: SpsmTexel;
        t.kind = 2u;
        t.partner = 3u;
        t.centre = vec2<f32>(k) + 0.5;
        return t;
    }
    return spsm_decode_shape(textureLoad(spsm_texels, k, light.layer, 0), k);
}

// `t`, loaded from texel `k` by spsm_load_shape, with its derivatives.
fn spsm_slopes(light: Light, t: SpsmTexel, k: vec2<i32>) -> SpsmTexel {
    if t.kind != 0u {
        return t;
    }
    return spsm_with_slopes(t, textureLoad(spsm_texels, k, light.layer, 0), light.map_size);
}

// The whole texel at `k` (also used by sgsm_lookup.wgsl).
fn spsm_load(light: Light, k: vec2<i32>) -> SpsmTexel {
    return spsm_slopes(light, spsm_load_shape(light, k), k);
}

// Consistent depth test of a whole texel: its triangle's minimum depth over
// the part of the texel it covers (read from the depth array, as the pass
// computed it from the unpacked triangle; session 3: it was recomputed here
// from the packed one, nine polygon clips per lookup) is in front of p.
// `slack` is added to the bias: with SPSM_TOLERANCE, half the own texel's
// derivative quantization step (before session 3 each neighbour's own,
// decoded for all nine; the own texel's keeps the figures and the cost down).
fn spsm_texel_blocks(light: Light, t: SpsmTexel, k: vec2<i32>, zeta: f32, slack: f32) -> bool {
    if t.kind == 2u {
        return false;
    }
    return spsm_min_depth_at(light, k) < zeta - SPSM_BIAS - select(0.0, slack, t.kind == 0u);
}

// Outward unit normal of edge a -> b of a triangle with orientation `orient`.
fn spsm_edge_normal(a: vec2<f32>, b: vec2<f32>, orient: f32) -> vec2<f32> {
    let n = orient * vec2<f32>(b.y - a.y, a.x - b.x);
    return n / max(length(n), 1e-20);
}

// Offset of slot i of the 3x3 neighbourhood.
fn spsm_slot(i: u32) -> vec2<f32> {
    return vec2<f32>(f32(i % 3u) - 1.0, f32(i / 3u) - 1.0);
}

// The silhouette estimate of a 3x3 depth-test pattern (bit i set where
// slot i blocks the receiver; neither none nor all): xy the unit normal of
// the estimated silhouette, z the kind: 0 one-sided (normal from the
// blocked to the free side), 1 two-sided (a thin blocked band along the
// tangent: free on both sides, test both normals), 2 no direction (a
// blocked blob: test the four axis directions). As in the paper, blocked
// texels without a 4-connected blocked neighbour are left out of the
// estimate (an edge cannot pass between them unnoticed) unless that
// leaves none. Mirrored on the CPU by `packing::silhouette_estimate`.
fn spsm_silhouette(pattern: u32) -> vec3<f32> {
    var connected = 0u;
    for (var i = 0u; i < 9u; i++) {
        if ((pattern >> i) & 1u) == 0u {
            continue;
        }
        let x = i % 3u;
        var around = 0u;
        if x > 0u {
            around |= 1u << (i - 1u);
        }
        if x < 2u {
            around |= 1u << (i + 1u);
        }
        if i >= 3u {
            around |= 1u << (i - 3u);
        }
        if i < 6u {
            around |= 1u << (i + 3u);
        }
        if (pattern & around) != 0u {
            connected |= 1u << i;
        }
    }
    let kept = select(pattern, connected, connected != 0u);
    var sum_kept = vec2<f32>(0.0);
    var sum_free = vec2<f32>(0.0);
    var n_kept = 0.0;
    var n_free = 0.0;
    var moments = vec3<f32>(0.0);
    for (var i = 0u; i < 9u; i++) {
        let o = spsm_slot(i);
        if ((kept >> i) & 1u) != 0u {
            sum_kept += o;
            n_kept += 1.0;
            moments += vec3<f32>(o.x * o.x, o.y * o.y, o.x * o.y);
        }
        if ((pattern >> i) & 1u) == 0u {
            sum_free += o;
            n_free += 1.0;
        }
    }
    let c = sum_kept / n_kept;
    let d = sum_free / n_free - c;
    if length(d) > 1e-3 {
        return vec3<f32>(normalize(d), 0.0);
    }
    // Balanced: the principal axis of the kept texels is the tangent.
    let sxx = moments.x / n_kept - c.x * c.x;
    let syy = moments.y / n_kept - c.y * c.y;
    let sxy = moments.z / n_kept - c.x * c.y;
    if abs(sxx - syy) + abs(sxy) < 1e-3 {
        return vec3<f32>(0.0, 0.0, 2.0);
    }
    let theta = 0.5 * atan2(2.0 * sxy, sxx - syy);
    return vec3<f32>(-sin(theta), cos(theta), 1.0);
}

// The nearest boundary vertex on each side of p along the tangent so far:
// (t, d) on the left (t <= 0) and right (t >= 0), and whether found.
struct SpsmSideState {
    left: vec2<f32>,
    right: vec2<f32>,
    found: vec2<bool>,
}

// Vertex `v` (between `prev` and `next` of a triangle with orientation
// `orient`) offered to the side state: kept when it faces `n`, lies within
// two texels of p along the tangent and is nearer than the side's current
// one (near-ties go to the vertex further towards the free side).
fn spsm_side_vertex(s: SpsmSideState, prev: vec2<f32>, v: vec2<f32>, next: vec2<f32>, orient: f32, p: vec2<f32>, n: vec2<f32>) -> SpsmSideState {
    var out = s;
    let normal = spsm_edge_normal(prev, v, orient) + spsm_edge_normal(v, next, orient);
    if orient != 0.0 && dot(normal, n) <= 0.0 {
        return out;
    }
    let q = v - p;
    let tv = dot(q, vec2<f32>(-n.y, n.x));
    let dv = dot(q, n);
    if abs(tv) > 2.0 {
        return out;
    }
    if tv <= 0.0 && (tv > out.left.x + 0.01 || (tv > out.left.x - 0.01 && dv > out.left.y)) {
        out.left = vec2<f32>(tv, dv);
        out.found.x = true;
    }
    if tv >= 0.0 && (tv < out.right.x - 0.01 || (tv < out.right.x + 0.01 && dv > out.right.y)) {
        out.right = vec2<f32>(tv, dv);
        out.found.y = true;
    }
    return out;
}

// One silhouette side: the occluders' boundary vertices facing `n` (the
// free side) within two texels along the tangent are projected on it, and
// the piecewise-linear phi through the nearest one on each side of p
// decides: 1 shadowed when phi(t(p)) reaches past p towards `n`, 0 lit,
// 2 when no boundary vertex was found. The blocked texels of the 3x3
// around `k` are loaded again here (session 3: a private array of the nine
// decoded texels, dynamically indexed, made the lookup several times
// slower on llvmpipe).
fn spsm_side(light: Light, k: vec2<i32>, pattern: u32, p: vec2<f32>, n: vec2<f32>) -> u32 {
    var s: SpsmSideState;
    s.left = vec2<f32>(-1e30, 0.0);
    s.right = vec2<f32>(1e30, 0.0);
    s.found = vec2<bool>(false, false);
    for (var i = 0u; i < 9u; i++) {
        if (pattern & (1u << i)) == 0u {
            continue;
        }
        let t = spsm_load_shape(light, k + vec2<i32>(i32(i % 3u) - 1, i32(i / 3u) - 1));
        if t.kind != 0u {
            continue;
        }
        let orient = sign(spsm_cross(t.v1 - t.v0, t.v2 - t.v0));
        s = spsm_side_vertex(s, t.v2, t.v0, t.v1, orient, p, n);
        s = spsm_side_vertex(s, t.v0, t.v1, t.v2, orient, p, n);
        s = spsm_side_vertex(s, t.v1, t.v2, t.v0, orient, p, n);
    }
    var phi: f32;
    if s.found.x && s.found.y {
        let span = s.right.x - s.left.x;
        phi = select(max(s.left.y, s.right.y), mix(s.left.y, s.right.y, -s.left.x / span), span > 1e-6);
    } else if s.found.x {
        phi = s.left.y;
    } else if s.found.y {
        phi = s.right.y;
    } else {
        return 2u;
    }
    // p sits at d = 0: shadowed when the boundary lies on its free side.
    return select(0u, 1u, phi >= 0.0);
}

fn spsm_recover(light: Light, k: vec2<i32>, pattern: u32, p: vec2<f32>) -> bool {
    if pattern == 0u {
        return false;
    }
    if pattern == 0x1ffu {
        return true;
    }
    let centre = (pattern & (1u << 4u)) != 0u;
    let estimate = spsm_silhouette(pattern);
    if !SPSM_THIN && estimate.z != 0.0 {
        // One tangent only: no direction, the own texel's depth test.
        return centre;
    }
    var count = 1u;
    if estimate.z == 1.0 {
        count = 2u;
    } else if estimate.z == 2.0 {
        count = 4u;
    }
    // Several tangent estimates: shadowed only where every one says so (the
    // paper's intersection); a side without boundary vertices defers to the
    // own texel's consistent depth test. Estimate j: the normal, its
    // opposite (a thin band), or the four axis directions (a blob).
    for (var j = 0u; j < count; j++) {
        var n = select(estimate.xy, -estimate.xy, j == 1u);
        if estimate.z == 2.0 {
            let sign_j = select(1.0, -1.0, (j & 1u) != 0u);
            n = select(vec2<f32>(sign_j, 0.0), vec2<f32>(0.0, sign_j), j >= 2u);
        }
        let side = spsm_side(light, k, pattern, p, n);
        if side == 0u || (side == 2u && !centre) {
            return false;
        }
    }
    return true;
}

// The paths of in_shadow that SPSM_FALLBACK (a bit set per path) may hand
// to the standard lookup (spsm_decide). SGSM adds its plane paths.
const SPSM_PATH_OWN: u32 = 1u;
const SPSM_PATH_NEIGHBOUR: u32 = 2u;
const SPSM_PATH_OWN_PLANE: u32 = 4u;
const SPSM_PATH_SURFACE: u32 = 8u;
const SPSM_PATH_UNIFORM: u32 = 16u;
const SPSM_PATH_RECOVER: u32 = 32u;
const SGSM_PATH_PLANE_LIT: u32 = 64u;
const SGSM_PATH_PLANE_SHADOWED: u32 = 128u;
// A depth-only texel (a triangle crossing the light's w = 0 plane): its
// 16-bit z / w at the texel centre against p's, constant bias only.
const SPSM_PATH_DEPTH_ONLY: u32 = 256u;
// p lies outside the own triangle only across its inner edges and its
// plane is in front of p (spsm_continues_to).
const SPSM_PATH_CONTINUED: u32 = 512u;
// p lies in the own triangle's parallelogram partner (spsm_in_partner,
// session 14) and its plane is in front of p: shadowed. (Partners give
// shadowed verdicts only.)
const SPSM_PATH_PARTNER: u32 = 1024u;

// Largest facet width assumed for an unstored outer facet, in texels.
const SPSM_FACET_WIDTH: f32 = 1.0;

// Whether p lies outside triangle t by more than the width of the facet
// that may sit unstored next to it: for a small t (a curved mesh's facet
// near its silhouette from the light, where the conservative pass keeps the
// facet nearest the light and loses the thinner outer one that shades p),
// t's height over the edge p lies beyond, at most SPSM_FACET_WIDTH; for a
// large one zero (a flat face's edge is the silhouette). Session 4, default
// preset configuration 3: the outer facets of a tessellated cylinder and
// sphere were missing from every texel around p, so a floor triangle stored
// next door made p lit (false light along whole shadow edges).
fn spsm_beyond_facet(t: SpsmTexel, p: vec2<f32>) -> bool {
    let area2 = spsm_cross(t.v1 - t.v0, t.v2 - t.v0);
    let orient = sign(area2);
    let d0 = dot(p - t.v0, spsm_edge_normal(t.v0, t.v1, orient));
    let d1 = dot(p - t.v1, spsm_edge_normal(t.v1, t.v2, orient));
    let d2 = dot(p - t.v2, spsm_edge_normal(t.v2, t.v0, orient));
    var d = d0;
    var e = length(t.v1 - t.v0);
    if d1 > d {
        d = d1;
        e = length(t.v2 - t.v1);
    }
    if d2 > d {
        d = d2;
        e = length(t.v0 - t.v2);
    }
    let height = abs(area2) / max(e, 1e-6);
    let width = select(0.0, min(height, SPSM_FACET_WIDTH), abs(area2) < SPSM_FACET_AREA);
    return d > width;
}

// Whether the caster of triangle t continues to p (session 7): p lies
// outside t, a small stored facet, inside the neighbour triangle across one
// of t's inner edges (the pass's codes, spsm_inner_edges; session 9: before,
// only beyond inner edges, and the wedge beyond a sliver's inner edge
// reached far past its neighbour), so p's part of the texel holds the
// mesh's next facet, unstored (a tessellated curved caster's thin outer
// facets lose every texel to the facet nearer the light); t's plane stands
// in for it.
fn spsm_continues_to(t: SpsmTexel, p: vec2<f32>) -> bool {
    let area2 = spsm_cross(t.v1 - t.v0, t.v2 - t.v0);
    let orient = sign(area2);
    if !SPSM_INNER_EDGES || t.inner == 0u || orient == 0.0 || abs(area2) >= SPSM_FACET_AREA {
        return false;
    }
    let v = array<vec2<f32>, 3>(t.v0, t.v1, t.v2);
    for (var k = 0u; k < 3u; k++) {
        let code = (t.inner >> (8u * k)) & 0xffu;
        if code == 0u || code == SPSM_PARTNER_CODE {
            continue;
        }
        let a = v[k];
        let b = v[(k + 1u) % 3u];
        let n = spsm_edge_normal(a, b, orient);
        if dot(p - a, n) <= 0.0 {
            continue;
        }
        // p beyond edge k: inside the neighbour (a, b, apex), its apex
        // moved out (spsm_inner_edges)?
        let o = spsm_edge_apex(a, b, n, code);
        if spsm_cross(o - b, p - b) * orient <= 0.0 && spsm_cross(a - o, p - o) * orient <= 0.0 {
            return true;
        }
    }
    return false;
}

// How far behind a caster, in multiples of the caster facet's own longest
// edge (world units, along the light ray), a receiver must lie for
// spsm_continues_to to shadow it: nearer, p may be the caster's own next
// facet (its lit side curving away from the plane of the stored one).

// The local inverse of the light's projection at `world`: the rows of the
// inverse Jacobian of (texel x, texel y, zeta) with respect to world
// position, so that a small (texel, zeta) offset v maps to the world offset
// (dot(r[0], v), dot(r[1], v), dot(r[2], v)). Zero rows when singular.
fn spsm_world_rows(light: Light, world: vec3<f32>) -> array<vec3<f32>, 3> {
    let clip = light.clip_from_world * vec4<f32>(world, 1.0);
    let ndc = clip.xyz / clip.w;
    var c: array<vec3<f32>, 3>;
    for (var i = 0u; i < 3u; i++) {
        let d = light.clip_from_world[i];
        let n = (d.xyz - ndc * d.w) / clip.w;
        c[i] = vec3<f32>(0.5 * n.x * light.map_size.x, -0.5 * n.y * light.map_size.y, n.z);
    }
    let r = array<vec3<f32>, 3>(cross(c[1], c[2]), cross(c[2], c[0]), cross(c[0], c[1]));
    let det = dot(c[0], r[0]);
    if det == 0.0 {
        return array<vec3<f32>, 3>(vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0));
    }
    return array<vec3<f32>, 3>(r[0] / det, r[1] / det, r[2] / det);
}

// The world offset of the (texel, zeta) offset `v` (spsm_world_rows).
fn spsm_world_offset(r: array<vec3<f32>, 3>, v: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(dot(r[0], v), dot(r[1], v), dot(r[2], v));
}

// How far from a small stored facet's plane, in multiples of p's distance
// to the facet's farthest vertex (world units), a receiver must lie for
// spsm_continues_to to shadow it (spsm_behind_facet). Session 7, first 20
// default lights: 1 gave focused+spsm 2074 (16, with the own-plane
// nearness test kept, 1267, but fixed neither configuration 5 nor
// tests/render_spsm.rs's cylinder).
const SPSM_CONTINUE_GAP: f32 = 1.0;

// Whether the receiver at `world` (depth zeta at p) lies farther from the
// plane of triangle t, measured along the plane's normal in world units (the
// projection taken as affine around p), than SPSM_CONTINUE_GAP times its
// distance along the plane to t's farthest vertex: a surface through p that
// continues t's caster (curving away from t's plane at most at right angles)
// stays nearer, so p is a receiver behind the caster, not its own next facet.
fn spsm_behind_facet(light: Light, world: vec3<f32>, t: SpsmTexel, p: vec2<f32>, zeta: f32) -> bool {
    let r = spsm_world_rows(light, world);
    let v = array<vec2<f32>, 3>(t.v0, t.v1, t.v2);
    let e1 = spsm_world_offset(r, vec3<f32>(v[1] - v[0], dot(t.gradient, v[1] - v[0])));
    let e2 = spsm_world_offset(r, vec3<f32>(v[2] - v[0], dot(t.gradient, v[2] - v[0])));
    let normal = cross(e1, e2);
    if dot(normal, normal) == 0.0 {
        return false;
    }
    let gap = abs(dot(spsm_world_offset(r, vec3<f32>(0.0, 0.0, zeta - spsm_plane_at(t, p).x)), normalize(normal)));
    var reach = 0.0;
    for (var k = 0u; k < 3u; k++) {
        let d = p - v[k];
        reach = max(reach, length(spsm_world_offset(r, vec3<f32>(d, dot(t.gradient, d)))));
    }
    return gap > SPSM_CONTINUE_GAP * reach;
}

// Whether a stored surface through p other than the own texel's triangle
// `own` (p outside it) may make p lit: `own` is not an occluder in front of
// p (by more than the bias and the packing tolerance), or, except with
// SPSM_THIN, p lies beyond the facet width of it (spsm_beyond_facet). Also
// gates SGSM's plane paths (sgsm_lookup.wgsl).
fn spsm_other_surface_lit(own: SpsmTexel, p: vec2<f32>, zeta: f32) -> bool {
    let plane = spsm_plane_at(own, p);
    let slack = SPSM_BIAS + SPSM_TOLERANCE * plane.y;
    let near = plane.x >= zeta - slack;
    return near || (!SPSM_THIN && spsm_beyond_facet(own, p) && !spsm_continues_to(own, p));
}

fn in_shadow(light: Light, world: vec3<f32>) -> bool {
    let m = map_position(light, world);
    if m.w == 0.0 {
        return false;
    }
    let p = m.xy;
    let k = map_texel(light, p);
    let zeta = m.z;
    let own = spsm_load(light, k);
    if own.kind == 2u {
        return false;
    }
    if own.kind == 1u {
        return spsm_decide(light, k, world, SPSM_PATH_DEPTH_ONLY, own.depth < zeta - SPSM_BIAS);
    }
    let own_plane = spsm_plane_at(own, p);
    let own_slack = SPSM_BIAS + SPSM_TOLERANCE * own_plane.y;
    if spsm_inside(own, p) {
        return spsm_decide(light, k, world, SPSM_PATH_OWN, own_plane.x < zeta - own_slack);
    }
    // In the partner: shadowed when its plane is in front of p; else the
    // paths below (a partner lit verdict lost shadows: the partner was not
    // the nearest surface over p's part of the texel; default preset,
    // configuration 8).
    if own_plane.x < zeta - own_slack && spsm_in_partner(own, p) {
        return spsm_decide(light, k, world, SPSM_PATH_PARTNER, true);
    }
    if own_plane.x < zeta - own_slack && spsm_continues_to(own, p) && spsm_behind_facet(light, world, own, p, zeta) {
        return spsm_decide(light, k, world, SPSM_PATH_CONTINUED, true);
    }
    // No occluder found so far. p counts as lit when it lies on the own
    // texel's closest triangle's plane, extended to p, within the bias and
    // the packing tolerance (the paper's lit classification), or on a
    // neighbour's stored triangle (a receiver's mesh edge crosses the texel;
    // also when p lies beyond a facet width of the own triangle,
    // spsm_other_surface_lit). Anything else goes on to the pattern: the
    // silhouette recovery, or the standard verdict where SPSM_FALLBACK
    // covers those paths (the default). Until issue 16's session 14 "on the
    // plane" also allowed the plane's depth change across one texel (a
    // curved receiver's neighbouring facet, session 4): under perspective
    // warps a coarse texel's stored triangle is often grazing, and that band
    // called receivers lit that lay well behind an unstored occluder
    // (default preset, 10 lights: plane-optimal+spsm 1.4-2.8x the standard
    // lookup's misclassified pixels; now 0.79x).
    let own_clear = spsm_other_surface_lit(own, p, zeta);
    let pattern_slack = SPSM_TOLERANCE * 0.5 * (own.gradient_error.x + own.gradient_error.y);
    var pattern = 0u;
    let on_own_plane = abs(own_plane.x - zeta) <= own_slack;
    var on_surface = false;
    for (var i = 0u; i < 9u; i++) {
        var t = own;
        let ki = k + vec2<i32>(i32(i % 3u) - 1, i32(i / 3u) - 1);
        if i != 4u {
            t = spsm_load_shape(light, ki);
            let inside = t.kind == 0u && spsm_inside(t, p);
            if inside || (t.kind == 0u && spsm_in_partner(t, p)) {
                let plane = spsm_plane_at(spsm_slopes(light, t, ki), p);
                if plane.x < zeta - SPSM_BIAS - SPSM_TOLERANCE * plane.y {
                    return spsm_decide(light, k, world, SPSM_PATH_NEIGHBOUR, true);
                }
                on_surface = on_surface || (inside && own_clear);
            }
        }
        if spsm_texel_blocks(light, t, ki, zeta, pattern_slack) {
            pattern |= 1u << i;
        }
    }
    if on_own_plane {
        return spsm_decide(light, k, world, SPSM_PATH_OWN_PLANE, false);
    }
    if on_surface {
        return spsm_decide(light, k, world, SPSM_PATH_SURFACE, false);
    }
    if pattern == 0u || pattern == 0x1ffu {
        return spsm_decide(light, k, world, SPSM_PATH_UNIFORM, pattern != 0u);
    }
    return spsm_decide(light, k, world, SPSM_PATH_RECOVER, spsm_recover(light, k, pattern, p));
}
