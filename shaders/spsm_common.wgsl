// Sub-pixel shadow maps (Lecocq et al. 2014): the texel format and the
// geometry shared by the SPSM pass (spsm_pass.wgsl) and the SPSM lookup
// (spsm_lookup.wgsl). The renderer prepends constants SPSM_EXPONENT,
// SPSM_BIAS, SPSM_TOLERANCE, SPSM_INNER_EDGES and others (see src/render/spsm/mod.rs).
//
// Space. Everything happens in the map's texel space (x right, y down,
// texel k covers [k, k + 1)) with the matrix's own post-projective depth
// zeta = clip.z / clip.w. lixel's *stored* standard depth is linear light
// depth (distance along the rays), which is not affine on a triangle seen
// by a point light; zeta is: for any linear q, q / w restricted to a plane
// is affine in (x / w, y / w). zeta is monotone along every light ray (each
// ray is a line of constant NDC xy and w is linear along it) and lies in
// [0, 1] over the region the map must hold (lixel's DepthRange), so it is
// the paper's depth z~ of "SPSM space".
//
// Texel (Rgba32Uint):
//   x, y, z: the closest triangle's vertices v0, v1, v2 relative to the texel
//            centre, in texels, as two f16 each (pack2x16float). With
//            SPSM_INNER_EDGES (SpsmOptions::inner_edges): a small
//            triangle (twice its area below SPSM_FACET_AREA texels², every
//            offset component within SPSM_FLAG_REACH) with an inner edge
//            (the mesh continues across it on the light's side; session 7,
//            spsm_pass.wgsl, spsm_inner_edges) is stored compact instead
//            (session 9): bits 30..26 of x are all set (v0.y's f16
//            exponent all ones: inf or NaN, which plain offsets never are)
//            and the other 91 bits of x, y, z (x's low 26 bits, then bit
//            31, then y and z; spsm_field_get) hold edge k's 8-bit code
//            (bits 8k..8k+7; 0: not inner, else the neighbour triangle's
//            opposite vertex, spsm_edge_code) and, from bit 24, the six
//            offsets in 11-bit fixed point over [-4, 4) (1/256 texel);
//   w:       bits 31..16: zeta at the texel centre on the triangle's plane,
//            16-bit unorm over [-1/16, 17/16];
//            bits 15..0: the plane's gradient (dzeta/dx, dzeta/dy), never 0:
//            SPSM_GRADIENT_CODE 1 (the default, session 6): bits 15..8 the
//            log magnitude per texel (1: zero; c >= 2: SPSM_LOG_MIN
//            e^(SPSM_LOG_STEP (c - 2))), bits 7..0 the direction (2 pi k /
//            256); 0: the paper's power-quantized 8-bit code (eq. 3, codes
//            0..=254, stored + 1) of dzeta/dx and dzeta/dy in units of the
//            map's [0, 1] extent per axis (texel slope times the map size).
//            src/render/spsm/packing.rs (GradientCode) mirrors both and
//            says why the log-polar code replaced the paper's.
//   w & 0xffff = 0: no triangle. All words zero (the cleared value) is an
//   empty texel (nothing drawn); x = 1 a depth-only texel (a triangle
//   crossing the light's w = 0 plane, rasterized the standard way).

const SPSM_DEPTH_LO: f32 = -0.0625;
const SPSM_DEPTH_SPAN: f32 = 1.125;
const SPSM_DEPTH_ONLY: u32 = 1u;
const SPSM_HALF_PI: f32 = 1.5707963;
// Largest normalized slope angle: tan stays finite.
const SPSM_MAX_ANGLE: f32 = 0.999999;
// Largest f16 vertex offset in texels (f16 max is 65504).
const SPSM_MAX_OFFSET: f32 = 60000.0;

fn spsm_encode_depth(z: f32) -> u32 {
    return u32(round(clamp((z - SPSM_DEPTH_LO) / SPSM_DEPTH_SPAN, 0.0, 1.0) * 65535.0));
}

fn spsm_decode_depth(code: u32) -> f32 {
    return f32(code) / 65535.0 * SPSM_DEPTH_SPAN + SPSM_DEPTH_LO;
}

// Eq. (3): Q(d) = 127 (1 + a^n), a = 2 atan(d) / pi (odd power: sign kept).
fn spsm_encode_slope(d: f32) -> u32 {
    let a = clamp(atan(d) / SPSM_HALF_PI, -SPSM_MAX_ANGLE, SPSM_MAX_ANGLE);
    let q = 127.0 * (1.0 + sign(a) * pow(abs(a), SPSM_EXPONENT));
    return u32(clamp(round(q), 0.0, 254.0));
}

// Eq. (4) for a (possibly fractional) code q.
fn spsm_decode_slope(q: f32) -> f32 {
    let s = clamp(q / 127.0 - 1.0, -1.0, 1.0);
    if s == 0.0 {
        return 0.0;
    }
    let a = clamp(sign(s) * pow(abs(s), 1.0 / SPSM_EXPONENT), -SPSM_MAX_ANGLE, SPSM_MAX_ANGLE);
    return tan(a * SPSM_HALF_PI);
}

// Half a quantization step of code `q` around its decoded value.
fn spsm_slope_error(q: u32) -> f32 {
    let d = spsm_decode_slope(f32(q));
    let lo = spsm_decode_slope(max(f32(q) - 0.5, 0.0));
    let hi = spsm_decode_slope(min(f32(q) + 0.5, 254.0));
    return max(abs(d - lo), abs(hi - d));
}

const SPSM_TAU: f32 = 6.2831853;

// The 16-bit code of gradient `g` (zeta per texel) on a map of `map_size`.
fn spsm_encode_gradient(g: vec2<f32>, map_size: vec2<f32>) -> u32 {
    if SPSM_GRADIENT_CODE == 0u {
        let slopes = g * map_size;
        return ((spsm_encode_slope(slopes.x) + 1u) << 8u) | (spsm_encode_slope(slopes.y) + 1u);
    }
    let m = length(g);
    if !(m >= SPSM_LOG_MIN * exp(-0.5 * SPSM_LOG_STEP)) {
        return 1u << 8u;
    }
    let c = 2u + u32(clamp(round(log(m / SPSM_LOG_MIN) / SPSM_LOG_STEP), 0.0, 253.0));
    let turn = atan2(g.y, g.x) / SPSM_TAU;
    let k = u32(i32(round(turn * 256.0)) & 255);
    return (c << 8u) | k;
}

// The gradient (xy, zeta per texel) of a 16-bit code and its error bound
// per axis (zw; mirrored by packing::gradient_error).
fn spsm_decode_gradient(bits: u32, map_size: vec2<f32>) -> vec4<f32> {
    let hi = (bits >> 8u) & 0xffu;
    let lo = bits & 0xffu;
    if SPSM_GRADIENT_CODE == 0u {
        let qx = max(hi, 1u) - 1u;
        let qy = max(lo, 1u) - 1u;
        let g = vec2<f32>(spsm_decode_slope(f32(qx)), spsm_decode_slope(f32(qy))) / map_size;
        let e = vec2<f32>(spsm_slope_error(qx), spsm_slope_error(qy)) / map_size;
        return vec4<f32>(g, e);
    }
    if hi < 2u {
        return vec4<f32>(0.0, 0.0, SPSM_LOG_MIN, SPSM_LOG_MIN);
    }
    let m = SPSM_LOG_MIN * exp(SPSM_LOG_STEP * f32(hi - 2u));
    let angle = f32(lo) / 256.0 * SPSM_TAU;
    let half = exp(0.5 * SPSM_LOG_STEP);
    let e = m * (half - 1.0) + m * half * (SPSM_TAU / 512.0);
    return vec4<f32>(m * cos(angle), m * sin(angle), e, e);
}

// Small facets whose offsets all lie within this (every component, in
// texels) may be stored compact (SPSM_INNER_EDGES).
const SPSM_FLAG_REACH: f32 = 4.0;
// A small stored triangle (twice its area below this, in texels²) is taken
// for a facet of a finely tessellated curved surface (session 4).
const SPSM_FACET_AREA: f32 = 2.0;
// The compact texel's marker: bits 30..26 of word x.
const SPSM_COMPACT_MARK: u32 = 0x7c000000u;
// Session 14: a triangle thinner than this in texel space (twice its area
// over its longest edge) is edge-on to the light and not stored.
const SPSM_MIN_HEIGHT: f32 = 0.0009765625;
// The parallelogram partner (spsm_is_partner in spsm_pass.wgsl): how far,
// per axis in texels, the neighbour's opposite vertex may lie from the
// completion the lookup rebuilds.
const SPSM_PARTNER_SLACK: f32 = 0.0078125;
// A compact texel's edge code for a parallelogram partner too thin for an
// (h, s) code: h's bits 0 (never a code's), s's 15.
const SPSM_PARTNER_CODE: u32 = 0xf0u;

// The smallest doubled area (texel space) whose sign tells a full texel's
// partner mark (spsm_order_offsets, spsm_decode_shape): well above the
// rounding of the cross product of its offsets.
fn spsm_partner_margin(d0: vec2<f32>, d1: vec2<f32>, d2: vec2<f32>) -> f32 {
    let e1 = d1 - d0;
    let e2 = d2 - d0;
    return 1e-5 * (dot(e1, e1) + dot(e2, e2));
}

fn spsm_pack_offset(v: vec2<f32>) -> u32 {
    return pack2x16float(clamp(v, vec2<f32>(-SPSM_MAX_OFFSET), vec2<f32>(SPSM_MAX_OFFSET)));
}

// Bits [p, p + n) of the 96-bit words w (x, y, z; bit p of the whole is
// bit p % 32 of word p / 32), n <= 16.
fn spsm_phys_get(w: vec3<u32>, p: u32, n: u32) -> u32 {
    let i = p / 32u;
    let b = p % 32u;
    let first = min(n, 32u - b);
    var v = extractBits(w[i], b, first);
    if first < n {
        v |= extractBits(w[i + 1u], 0u, n - first) << first;
    }
    return v;
}

fn spsm_phys_put(w: vec3<u32>, p: u32, n: u32, value: u32) -> vec3<u32> {
    var out = w;
    let i = p / 32u;
    let b = p % 32u;
    let first = min(n, 32u - b);
    out[i] = insertBits(out[i], value, b, first);
    if first < n {
        out[i + 1u] = insertBits(out[i + 1u], value >> first, 0u, n - first);
    }
    return out;
}

// Logical bit l of a compact texel's 91 payload bits: the words' bits
// without the marker's 26..30.
fn spsm_field_get(w: vec3<u32>, l: u32, n: u32) -> u32 {
    if l < 26u && l + n > 26u {
        let lo = 26u - l;
        return spsm_phys_get(w, l, lo) | (spsm_phys_get(w, 31u, n - lo) << lo);
    }
    return spsm_phys_get(w, select(l, l + 5u, l >= 26u), n);
}

fn spsm_field_put(w: vec3<u32>, l: u32, n: u32, value: u32) -> vec3<u32> {
    if l < 26u && l + n > 26u {
        let lo = 26u - l;
        return spsm_phys_put(spsm_phys_put(w, l, lo, value), 31u, n - lo, value >> lo);
    }
    return spsm_phys_put(w, select(l, l + 5u, l >= 26u), n, value);
}

fn spsm_fixed_offset(v: f32) -> u32 {
    return u32(clamp(round((v + 4.0) * 256.0), 0.0, 2047.0));
}

// The compact texel words x, y, z of offsets v0, v1, v2 and edge codes
// `codes` (8 bits per edge).
fn spsm_pack_compact(v0: vec2<f32>, v1: vec2<f32>, v2: vec2<f32>, codes: u32) -> vec3<u32> {
    var w = vec3<u32>(SPSM_COMPACT_MARK, 0u, 0u);
    w = spsm_field_put(w, 0u, 24u - 8u, codes & 0xffffu);
    w = spsm_field_put(w, 16u, 8u, codes >> 16u);
    w = spsm_field_put(w, 24u, 11u, spsm_fixed_offset(v0.x));
    w = spsm_field_put(w, 35u, 11u, spsm_fixed_offset(v0.y));
    w = spsm_field_put(w, 46u, 11u, spsm_fixed_offset(v1.x));
    w = spsm_field_put(w, 57u, 11u, spsm_fixed_offset(v1.y));
    w = spsm_field_put(w, 68u, 11u, spsm_fixed_offset(v2.x));
    w = spsm_field_put(w, 79u, 11u, spsm_fixed_offset(v2.y));
    return w;
}

fn spsm_compact_offset(w: vec3<u32>, l: u32) -> vec2<f32> {
    return vec2<f32>(f32(spsm_field_get(w, l, 11u)), f32(spsm_field_get(w, l + 11u, 11u))) / 256.0 - 4.0;
}

// Edge a -> b's code of the neighbour triangle's opposite vertex o (on
// the far side of the edge's line): bits 3..0 its height h over the line
// in texels, floor(2 log2 h) + 9 (1..=15: h from 1/16 to 8, rounded down
// so that the decoded neighbour lies inside the true one's strip; 0: not
// inner, or h below 1/16), bits 7..4 its position along the edge
// s = (o - a).(b - a) / |b - a|², round(5 (s + 1)) (0..=15: s from -1 to
// 2 in steps of 0.2).
fn spsm_edge_code(a: vec2<f32>, b: vec2<f32>, o: vec2<f32>) -> u32 {
    let e = b - a;
    let l2 = dot(e, e);
    if !(l2 > 0.0) {
        return 0u;
    }
    let h = abs(spsm_cross(e, o - a)) / sqrt(l2);
    if !(h >= 0.0625) {
        return 0u;
    }
    let hq = u32(clamp(floor(2.0 * log2(h) + 9.0), 1.0, 15.0));
    let s = dot(o - a, e) / l2;
    let sq = u32(clamp(round(5.0 * (s + 1.0)), 0.0, 15.0));
    return hq | (sq << 4u);
}

// The opposite vertex of code `code` (nonzero) of edge a -> b, on the side
// of outward normal `n` (unit).
fn spsm_edge_apex(a: vec2<f32>, b: vec2<f32>, n: vec2<f32>, code: u32) -> vec2<f32> {
    let h = exp2((f32(code & 15u) - 9.0) * 0.5);
    let s = f32(code >> 4u) * 0.2 - 1.0;
    return a + s * (b - a) + h * n;
}

// Signed doubled area (texel space).
fn spsm_cross(a: vec2<f32>, b: vec2<f32>) -> f32 {
    return a.x * b.y - a.y * b.x;
}

// zeta gradient per texel of the plane through (t_k, z_k); zero for a
// degenerate triangle.
fn spsm_gradient(t0: vec2<f32>, t1: vec2<f32>, t2: vec2<f32>, z: vec3<f32>) -> vec2<f32> {
    let e1 = t1 - t0;
    let e2 = t2 - t0;
    let det = spsm_cross(e1, e2);
    if abs(det) < 1e-12 {
        return vec2<f32>(0.0);
    }
    let dz1 = z.y - z.x;
    let dz2 = z.z - z.x;
    return vec2<f32>(dz1 * e2.y - dz2 * e1.y, dz2 * e1.x - dz1 * e2.x) / det;
}

// Whether the texel box centred at `c` (half size 0.5) and the triangle
// overlap (closed sets): separating axes x, y and the three edge normals.
fn spsm_box_overlaps(t0: vec2<f32>, t1: vec2<f32>, t2: vec2<f32>, c: vec2<f32>) -> bool {
    let lo = min(t0, min(t1, t2));
    let hi = max(t0, max(t1, t2));
    if any(lo > c + 0.5) || any(hi < c - 0.5) {
        return false;
    }
    let orient = sign(spsm_cross(t1 - t0, t2 - t0));
    if orient == 0.0 {
        // A segment or a point: its bounding box decides, plus the line's normal.
        let d = select(t1 - t0, t2 - t0, dot(t2 - t0, t2 - t0) > dot(t1 - t0, t1 - t0));
        let n = vec2<f32>(-d.y, d.x);
        return abs(dot(n, c - t0)) <= 0.5 * (abs(n.x) + abs(n.y));
    }
    var p = array<vec2<f32>, 3>(t0, t1, t2);
    for (var k = 0u; k < 3u; k++) {
        let a = p[k];
        let b = p[(k + 1u) % 3u];
        // Outward normal of edge a -> b.
        let n = orient * vec2<f32>(b.y - a.y, a.x - b.x);
        if dot(n, c - a) - 0.5 * (abs(n.x) + abs(n.y)) > 0.0 {
            return false;
        }
    }
    return true;
}

// The paper's consistent minimum depth (section 4): the smallest depth of
// the triangle's plane (zeta_c at `c`, gradient `g`) over the part of the
// texel box at `c` the triangle covers. That part is convex and the depth
// affine, so the minimum is at one of its vertices: a box corner inside the
// triangle, or an end of a triangle edge clipped to the box (Liang-Barsky;
// this covers the triangle's vertices inside the box and the edges'
// crossings of the box). Session 3: replaces a Sutherland-Hodgman clip
// whose dynamically indexed polygon arrays were slow on llvmpipe; same
// set of candidate points. Returns `fallback` when nothing is left.
fn spsm_min_depth(t0: vec2<f32>, t1: vec2<f32>, t2: vec2<f32>, c: vec2<f32>, zeta_c: f32, g: vec2<f32>, fallback: f32) -> f32 {
    let lo = c - 0.5;
    let hi = c + 0.5;
    var best = 3.0e38;
    // The corner where the plane is lowest over the whole box: when the
    // triangle covers it, it is the answer (every interior texel).
    let low_corner = c - 0.5 * sign(g);
    let orient = spsm_cross(t1 - t0, t2 - t0);
    let inside_low = orient != 0.0 && spsm_cross(t1 - t0, low_corner - t0) * orient >= 0.0
        && spsm_cross(t2 - t1, low_corner - t1) * orient >= 0.0 && spsm_cross(t0 - t2, low_corner - t2) * orient >= 0.0;
    if inside_low {
        return zeta_c + dot(g, low_corner - c);
    }
    if orient != 0.0 {
        for (var k = 0u; k < 4u; k++) {
            let q = vec2<f32>(select(lo.x, hi.x, (k & 1u) != 0u), select(lo.y, hi.y, (k & 2u) != 0u));
            if spsm_cross(t1 - t0, q - t0) * orient >= 0.0 && spsm_cross(t2 - t1, q - t1) * orient >= 0.0
                && spsm_cross(t0 - t2, q - t2) * orient >= 0.0 {
                best = min(best, zeta_c + dot(g, q - c));
            }
        }
    }
    best = min(best, spsm_clipped_edge_min(t0, t1, lo, hi, c, zeta_c, g));
    best = min(best, spsm_clipped_edge_min(t1, t2, lo, hi, c, zeta_c, g));
    best = min(best, spsm_clipped_edge_min(t2, t0, lo, hi, c, zeta_c, g));
    return select(fallback, best, best < 3.0e38);
}

// The plane's smallest depth over segment a -> b clipped to the box [lo, hi]
// (3e38 when the segment misses it).
fn spsm_clipped_edge_min(a: vec2<f32>, b: vec2<f32>, lo: vec2<f32>, hi: vec2<f32>, c: vec2<f32>, zeta_c: f32, g: vec2<f32>) -> f32 {
    let d = b - a;
    var t_in = 0.0;
    var t_out = 1.0;
    for (var axis = 0u; axis < 2u; axis++) {
        let da = d[axis];
        let pa = a[axis];
        if da == 0.0 {
            if pa < lo[axis] || pa > hi[axis] {
                return 3.0e38;
            }
        } else {
            let t0 = (lo[axis] - pa) / da;
            let t1 = (hi[axis] - pa) / da;
            t_in = max(t_in, min(t0, t1));
            t_out = min(t_out, max(t0, t1));
        }
    }
    if t_in > t_out {
        return 3.0e38;
    }
    // Clamp the ends into the box against rounding.
    let p = clamp(a + t_in * d, lo, hi);
    let q = clamp(a + t_out * d, lo, hi);
    return min(zeta_c + dot(g, p - c), zeta_c + dot(g, q - c));
}

// One decoded texel.
struct SpsmTexel {
    // 0: a triangle; 1: depth only; 2: empty.
    kind: u32,
    // Bits 8k..8k+7: edge v_k -> v_(k+1)'s code (spsm_edge_code; 0: not
    // inner, the mesh does not continue across it on the light's side).
    inner: u32,
    // The edge k (v_k -> v_(k+1)) across which the mesh's coplanar
    // neighbour completes the triangle to a parallelogram (session 14,
    // spsm_in_partner); 3: none.
    partner: u32,
    // Vertices in absolute texel coordinates.
    v0: vec2<f32>,
    v1: vec2<f32>,
    v2: vec2<f32>,
    // The texel's centre.
    centre: vec2<f32>,
    // zeta at the centre on the plane.
    depth: f32,
    // zeta per texel.
    gradient: vec2<f32>,
    // Quantization bound of `gradient` (per texel).
    gradient_error: vec2<f32>,
}

fn spsm_decode(words: vec4<u32>, texel: vec2<i32>, map_size: vec2<f32>) -> SpsmTexel {
    return spsm_with_slopes(spsm_decode_shape(words, texel), words, map_size);
}

// The texel without its derivatives (`gradient` and `gradient_error` stay
// zero): the kind, centre depth and vertices, all a lookup needs from most
// of its 3x3 neighbours (session 3: decoding every neighbour's slopes, six
// pow and six tan each, was a good part of the lookup's cost).
fn spsm_decode_shape(words: vec4<u32>, texel: vec2<i32>) -> SpsmTexel {
    var out: SpsmTexel;
    out.centre = vec2<f32>(texel) + 0.5;
    out.partner = 3u;
    out.depth = spsm_decode_depth(words.w >> 16u);
    if (words.w & 0xffffu) == 0u {
        out.kind = select(2u, 1u, words.x == SPSM_DEPTH_ONLY);
        return out;
    }
    out.kind = 0u;
    if SPSM_INNER_EDGES && (words.x & SPSM_COMPACT_MARK) == SPSM_COMPACT_MARK {
        let w = words.xyz;
        out.inner = spsm_field_get(w, 0u, 16u) | (spsm_field_get(w, 16u, 8u) << 16u);
        out.v0 = out.centre + spsm_compact_offset(w, 24u);
        out.v1 = out.centre + spsm_compact_offset(w, 46u);
        out.v2 = out.centre + spsm_compact_offset(w, 68u);
        for (var k = 0u; k < 3u; k++) {
            if ((out.inner >> (8u * k)) & 0xffu) == SPSM_PARTNER_CODE {
                out.partner = k;
            }
        }
        return out;
    }
    let d0 = unpack2x16float(words.x);
    let d1 = unpack2x16float(words.y);
    let d2 = unpack2x16float(words.z);
    out.v0 = out.centre + d0;
    out.v1 = out.centre + d1;
    out.v2 = out.centre + d2;
    // The full texel's partner mark (spsm_order_offsets): a positive
    // orientation of the stored offsets, the partner across v0 -> v1.
    if SPSM_INNER_EDGES && spsm_cross(d1 - d0, d2 - d0) > spsm_partner_margin(d0, d1, d2) {
        out.partner = 0u;
    }
    return out;
}

// Whether `p` lies in the parallelogram partner of triangle t (session 14):
// the triangle (a, b, a + b - c) across its partner edge a -> b (closed).
fn spsm_in_partner(t: SpsmTexel, p: vec2<f32>) -> bool {
    if t.partner > 2u {
        return false;
    }
    let v = array<vec2<f32>, 3>(t.v0, t.v1, t.v2);
    let a = v[t.partner];
    let b = v[(t.partner + 1u) % 3u];
    let c = v[(t.partner + 2u) % 3u];
    var q: SpsmTexel;
    q.v0 = b;
    q.v1 = a;
    q.v2 = a + b - c;
    return spsm_inside(q, p);
}

// `t` (from spsm_decode_shape of the same words) with its derivatives.
fn spsm_with_slopes(t: SpsmTexel, words: vec4<u32>, map_size: vec2<f32>) -> SpsmTexel {
    var out = t;
    if t.kind != 0u {
        return out;
    }
    let g = spsm_decode_gradient(words.w & 0xffffu, map_size);
    out.gradient = g.xy;
    out.gradient_error = g.zw;
    return out;
}

// Whether `p` lies in the triangle (closed; never for a degenerate one).
fn spsm_inside(t: SpsmTexel, p: vec2<f32>) -> bool {
    let area = spsm_cross(t.v1 - t.v0, t.v2 - t.v0);
    if abs(area) < 1e-6 {
        return false;
    }
    let e0 = spsm_cross(t.v1 - t.v0, p - t.v0) * area;
    let e1 = spsm_cross(t.v2 - t.v1, p - t.v1) * area;
    let e2 = spsm_cross(t.v0 - t.v2, p - t.v2) * area;
    return e0 >= 0.0 && e1 >= 0.0 && e2 >= 0.0;
}

// The stored plane's depth at `p` and its error bound from the packing.
fn spsm_plane_at(t: SpsmTexel, p: vec2<f32>) -> vec2<f32> {
    let d = p - t.centre;
    return vec2<f32>(t.depth + dot(t.gradient, d), dot(t.gradient_error, abs(d)));
}
