// SPSM pass: conservative rasterization of the scene into one light's
// sub-pixel shadow map (spsm_common.wgsl, prepended, has the texel format).
//
// No CONSERVATIVE_RASTERIZATION on lavapipe or GL, so it is done here
// (Hasselgren et al. 2005, as the paper does): the vertex stage pulls the
// whole triangle from storage buffers (vertex_index = index slot), projects
// it to texel space (after the perspective divide, so w is handled exactly)
// and pushes each edge out by the half-texel box's support along its
// normal, 0.5 (|n.x| + |n.y|) / |n| (half a texel diagonal at 45 degrees),
// plus a 1/64-texel margin against the rasterizer's snapping. The three
// offset lines meet in the expanded triangle. A sliver's expanded triangle
// can be huge (vertex distance ~ offset / sin(angle / 2)); then a right
// triangle around its half-texel-padded bounding box (axis-aligned or
// aligned with its longest edge), whichever is smallest, is drawn instead.
// The fragment stage discards texels whose box does not
// meet the true triangle (exact separating-axis test), so the covered
// texels are exactly those the triangle touches.
//
// Depth buffer: the paper's consistent minimum depth over the part of the
// texel the triangle covers (spsm_min_depth), squeezed monotonically into
// [0, 1] so that casters in front of the near plane still order. Colour:
// the packed closest triangle.
//
// A triangle with a vertex at or behind the light's w = 0 plane cannot be
// projected: it is drawn with its clip coordinates (the hardware clips it)
// and stores a depth-only texel and the standard map's centre-sampled
// depth (the lookup's standard verdict there).

// `ShadowPassRaw` (src/render/uniforms.rs), shared with shadow.wgsl; this
// pass reads the matrix and the map size (clamp.yz).
struct ShadowPass {
    clip_from_world: mat4x4<f32>,
    position: vec4<f32>,
    depth: vec4<f32>,
    clamp: vec4<f32>,
}

@group(0) @binding(0) var<uniform> shadow_pass: ShadowPass;
// The scene's VertexRaw words (7 per vertex: position xyz, normal xyz, albedo).
@group(0) @binding(1) var<storage, read> scene_vertices: array<u32>;
@group(0) @binding(2) var<storage, read> scene_indices: array<u32>;
// Per index slot, the slot of the vertex across the edge starting at that
// corner in the one neighbouring triangle, or 0xffffffff
// (src/render/spsm/adjacency.rs; session 7).
@group(0) @binding(3) var<storage, read> scene_adjacent: array<u32>;
// The centre-sampled depth of the texel (session 5): what a standard shadow
// pass (shadow.wgsl) would store, the minimum over the triangles covering
// the texel centre of their biased linear light depth there, kept as the
// complement of its bits with atomicMax (non-negative floats order as
// their bits) so that the cleared word 0 means "no triangle covers the
// centre". One map's words, row-major with
// the map's width (the renderer binds this light's layer of the buffer with
// a dynamic offset). The lookup falls back to it where its own recovery is
// unsure (spsm_lookup.wgsl, spsm_standard).
@group(1) @binding(0) var<storage, read_write> spsm_centre: array<atomic<u32>>;

struct SpsmVertex {
    @builtin(position) clip: vec4<f32>,
    @location(0) @interpolate(flat) t0: vec2<f32>,
    @location(1) @interpolate(flat) t1: vec2<f32>,
    @location(2) @interpolate(flat) t2: vec2<f32>,
    @location(3) @interpolate(flat) zeta: vec3<f32>,
    // 0: conservative; 1: clipped fallback.
    @location(4) @interpolate(flat) mode: u32,
    // The world positions and clip w of the vertices (the centre-sampled
    // depth: perspective-correct interpolation at the texel centre).
    @location(5) @interpolate(flat) x0: vec3<f32>,
    @location(6) @interpolate(flat) x1: vec3<f32>,
    @location(7) @interpolate(flat) x2: vec3<f32>,
    @location(8) @interpolate(flat) w: vec3<f32>,
    // The world position, interpolated (clipped fallback only: its
    // centre-sampled depth, session 6).
    @location(9) world: vec3<f32>,
    // Edge k's code in bits 8k..8k+7, the parallelogram partner's edge + 1
    // in bits 24..25 (spsm_inner_edges).
    @location(10) @interpolate(flat) inner: u32,
}

fn spsm_world_of(index_slot: u32) -> vec3<f32> {
    let v = scene_indices[index_slot] * 7u;
    return vec3<f32>(bitcast<f32>(scene_vertices[v]), bitcast<f32>(scene_vertices[v + 1u]), bitcast<f32>(scene_vertices[v + 2u]));
}

fn spsm_clip_of(index_slot: u32) -> vec4<f32> {
    return shadow_pass.clip_from_world * vec4<f32>(spsm_world_of(index_slot), 1.0);
}

fn spsm_to_texel(clip: vec4<f32>) -> vec2<f32> {
    let ndc = clip.xy / clip.w;
    return vec2<f32>(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5) * shadow_pass.clamp.yz;
}

fn spsm_texel_to_clip(t: vec2<f32>) -> vec4<f32> {
    let n = t / shadow_pass.clamp.yz;
    return vec4<f32>(n.x * 2.0 - 1.0, 1.0 - n.y * 2.0, 0.5, 1.0);
}

// Intersection of the lines n1·x = c1 and n2·x = c2.
fn spsm_meet(n1: vec2<f32>, c1: f32, n2: vec2<f32>, c2: f32) -> vec2<f32> {
    let det = spsm_cross(n1, n2);
    return vec2<f32>(c1 * n2.y - c2 * n1.y, n1.x * c2 - n2.x * c1) / det;
}

// How far the continuation across an inner edge reaches (session 9): the
// neighbour's opposite vertex is stored moved away from the edge to this
// multiple of its height, SPSM_CONTINUE_CURVED when the triangle meets a
// neighbour at an angle (sine above SPSM_CURVED_SINE: a tessellated
// curved caster, whose facets beyond the neighbour continue towards the
// silhouette), else SPSM_CONTINUE_FLAT (a flat mesh continues in its
// plane). Default preset, first 10 lights (focused+spsm / optimized+spsm;
// the unscaled neighbour 1398.6 / 808.8): curved 3, flat 1: 1321.0 / 783.0;
// curved 3, flat 2: 1361.4 / 693.5 (configuration 5's caster is flat
// meshed); every edge x 2: 1400.7 / 695.0. Issue-16 note, session 9.
const SPSM_CONTINUE_CURVED: f32 = 3.0;
const SPSM_CONTINUE_FLAT: f32 = 2.0;
const SPSM_CURVED_SINE: f32 = 0.02;

// The unit normal (either orientation) of the triangle at index slots
// first..first + 2, in world space; zero when degenerate.
fn spsm_world_normal(first: u32) -> vec3<f32> {
    let a = spsm_world_of(first);
    let n = cross(spsm_world_of(first + 1u) - a, spsm_world_of(first + 2u) - a);
    let l = length(n);
    return select(vec3<f32>(0.0), n / l, l > 0.0);
}

// The triangle's inner edges for the light (session 7): edge k (t_k ->
// t_(k+1)) is inner when the mesh continues across it on the same side of
// the light, i.e. the neighbour's opposite vertex projects to the other
// side of the edge's line than this triangle's third vertex. Edges with no
// neighbour, or whose neighbour folds back (a silhouette edge from the
// light) or cannot be projected, are not inner. Bits 8k..8k+7: edge k's
// code (spsm_edge_code, session 9: where the neighbour's opposite vertex
// lies, moved out by SPSM_CONTINUE_CURVED or SPSM_CONTINUE_FLAT), 0 when
// not inner. Bits 24..25 (session 14): the edge k + 1 across which the
// neighbour completes this triangle to a parallelogram in texel space
// (spsm_is_partner; the longest such edge), 0 for none.
fn spsm_inner_edges(first: u32, t: array<vec2<f32>, 3>, w_scale: f32) -> u32 {
    if !SPSM_INNER_EDGES {
        return 0u;
    }
    var inner = 0u;
    var apex: array<vec2<f32>, 3>;
    var curved = false;
    var partner = 0u;
    var partner_length = 0.0;
    let own_normal = spsm_world_normal(first);
    for (var k = 0u; k < 3u; k++) {
        let across = scene_adjacent[first + k];
        if across >= arrayLength(&scene_indices) {
            continue;
        }
        let c = spsm_clip_of(across);
        if c.w <= 1e-6 * w_scale {
            continue;
        }
        let a = t[k];
        let e = t[(k + 1u) % 3u] - a;
        let o = spsm_to_texel(c);
        let other_normal = spsm_world_normal(across - across % 3u);
        curved = curved || length(cross(own_normal, other_normal)) > SPSM_CURVED_SINE;
        if spsm_cross(e, t[(k + 2u) % 3u] - a) * spsm_cross(e, o - a) < 0.0 {
            inner |= 1u << k;
            apex[k] = o;
            if spsm_is_partner(first, k, across, own_normal, t, o) && dot(e, e) > partner_length {
                partner = k + 1u;
                partner_length = dot(e, e);
            }
        }
    }
    let scale = select(SPSM_CONTINUE_FLAT, SPSM_CONTINUE_CURVED, curved);
    var codes = 0u;
    for (var k = 0u; k < 3u; k++) {
        if (inner & (1u << k)) == 0u {
            continue;
        }
        let a = t[k];
        let b = t[(k + 1u) % 3u];
        let n = normalize(vec2<f32>(a.y - b.y, b.x - a.x));
        let o = apex[k] + (scale - 1.0) * dot(apex[k] - a, n) * n;
        codes |= spsm_edge_code(a, b, o) << (8u * k);
    }
    return codes | (partner << 24u);
}

// Whether the neighbour triangle across edge k (its opposite vertex at index
// slot `across`, projected to `o`) is this triangle's parallelogram partner
// (session 14): coplanar in the world (so this triangle's stored plane is
// also the partner's) and its opposite vertex within SPSM_PARTNER_SLACK
// texels of the parallelogram completion t_k + t_(k+1) - t_(k+2), which the
// lookup rebuilds from the stored vertices alone (spsm_in_partner). The two
// triangles of a planar quad seen by a directional light (a box's faces, a
// grid); a thin quad's two slivers each hold only part of its width, and
// each texel keeps one of them.
fn spsm_is_partner(first: u32, k: u32, across: u32, own_normal: vec3<f32>, t: array<vec2<f32>, 3>, o: vec2<f32>) -> bool {
    let completion = t[k] + t[(k + 1u) % 3u] - t[(k + 2u) % 3u];
    if any(abs(o - completion) > vec2<f32>(SPSM_PARTNER_SLACK)) {
        return false;
    }
    let d = spsm_world_of(across) - spsm_world_of(first + k);
    return abs(dot(own_normal, d)) <= 1e-4 * length(d);
}

@vertex
fn vs_shadow(@builtin(vertex_index) slot: u32) -> SpsmVertex {
    let first = slot - slot % 3u;
    let corner = slot % 3u;
    var c = array<vec4<f32>, 3>(spsm_clip_of(first), spsm_clip_of(first + 1u), spsm_clip_of(first + 2u));
    var out: SpsmVertex;
    let w_scale = max(abs(c[0].w), max(abs(c[1].w), abs(c[2].w)));
    if min(c[0].w, min(c[1].w, c[2].w)) <= 1e-6 * w_scale {
        out.clip = c[corner];
        out.mode = 1u;
        out.world = spsm_world_of(first + corner);
        return out;
    }
    var t = array<vec2<f32>, 3>(spsm_to_texel(c[0]), spsm_to_texel(c[1]), spsm_to_texel(c[2]));
    // An edge-on triangle (its height in texel space below SPSM_MIN_HEIGHT
    // and below 1e-4 of its longest edge, so that tiny facets stay: a face
    // parallel to the light's rays, such as a box's side face under a light
    // square to it) covers no area a ray could hit, but touches the texels
    // along its segment. Session 14: stored with its nearest vertex's depth,
    // it won every texel along a thin box's shadow from the faces that do
    // cover the receivers (the lookup never finds p inside a zero-area
    // triangle), so the shadow was lost. Not drawn: all three corners at one
    // point outside the clip volume.
    let span_max = max(length(t[1] - t[0]), max(length(t[2] - t[1]), length(t[0] - t[2])));
    let height = abs(spsm_cross(t[1] - t[0], t[2] - t[0])) / max(span_max, 1e-30);
    if height < SPSM_MIN_HEIGHT && height < 1e-4 * span_max {
        out.clip = vec4<f32>(2.0, 2.0, 0.5, 1.0);
        return out;
    }
    out.t0 = t[0];
    out.t1 = t[1];
    out.t2 = t[2];
    out.zeta = vec3<f32>(c[0].z / c[0].w, c[1].z / c[1].w, c[2].z / c[2].w);
    out.mode = 0u;
    out.x0 = spsm_world_of(first);
    out.x1 = spsm_world_of(first + 1u);
    out.x2 = spsm_world_of(first + 2u);
    out.w = vec3<f32>(c[0].w, c[1].w, c[2].w);
    out.inner = spsm_inner_edges(first, t, w_scale);
    // Hardware conservative rasterization (RendererOptions::hardware_conservative):
    // the rasterizer finds every texel the true triangle touches, and
    // fs_shadow keeps exactly those; z = w / 2 as the padded path's 0.5
    // (fs_shadow writes its own depth). A degenerate triangle keeps the box
    // below (a rasterizer may drop zero-area triangles).
    if SPSM_HARDWARE_CONSERVATIVE && spsm_cross(t[1] - t[0], t[2] - t[0]) != 0.0 {
        out.clip = vec4<f32>(c[corner].xy, 0.5 * c[corner].w, c[corner].w);
        return out;
    }

    // The padded bounding box and the right triangle (lo, lo + 2 (hi - lo) x, lo + 2 (hi - lo) y) around it.
    let margin = 0.5 + 1.0 / 64.0;
    let lo = min(t[0], min(t[1], t[2])) - margin;
    let hi = max(t[0], max(t[1], t[2])) + margin;
    let span = (hi - lo) * 2.01;
    var box_area = 0.5 * span.x * span.y;
    var box_corner = lo;
    if corner == 1u {
        box_corner = lo + vec2<f32>(span.x, 0.0);
    } else if corner == 2u {
        box_corner = lo + vec2<f32>(0.0, span.y);
    }
    // The same around the box aligned with the longest edge (u along it, v
    // across), padded by the texel box's support: a long diagonal sliver's
    // axis-aligned box grows with its length squared, this one linearly
    // (issue 16, session 3: such slivers made SPSM frames ~100x a standard
    // one in the timing harness).
    let e = array<vec2<f32>, 3>(t[1] - t[0], t[2] - t[1], t[0] - t[2]);
    let l = vec3<f32>(dot(e[0], e[0]), dot(e[1], e[1]), dot(e[2], e[2]));
    var longest = e[0];
    if l.y >= l.x && l.y >= l.z {
        longest = e[1];
    } else if l.z >= l.x && l.z >= l.y {
        longest = e[2];
    }
    if dot(longest, longest) > 0.0 {
        let u = normalize(longest);
        let v = vec2<f32>(-u.y, u.x);
        let pad = margin * (abs(u.x) + abs(u.y));
        let tu = vec3<f32>(dot(t[0], u), dot(t[1], u), dot(t[2], u));
        let tv = vec3<f32>(dot(t[0], v), dot(t[1], v), dot(t[2], v));
        let lo_uv = vec2<f32>(min(tu.x, min(tu.y, tu.z)), min(tv.x, min(tv.y, tv.z))) - pad;
        let hi_uv = vec2<f32>(max(tu.x, max(tu.y, tu.z)), max(tv.x, max(tv.y, tv.z))) + pad;
        let span_uv = (hi_uv - lo_uv) * 2.01;
        let area_uv = 0.5 * span_uv.x * span_uv.y;
        if area_uv < box_area {
            box_area = area_uv;
            let o = lo_uv.x * u + lo_uv.y * v;
            box_corner = o;
            if corner == 1u {
                box_corner = o + span_uv.x * u;
            } else if corner == 2u {
                box_corner = o + span_uv.y * v;
            }
        }
    }

    // Edge k runs t[k] -> t[k + 1]; its outward normal and offset line.
    let orient = sign(spsm_cross(t[1] - t[0], t[2] - t[0]));
    var grown = array<vec2<f32>, 3>(t[0], t[1], t[2]);
    var ok = orient != 0.0;
    if ok {
        var n: array<vec2<f32>, 3>;
        var d: array<f32, 3>;
        for (var k = 0u; k < 3u; k++) {
            let a = t[k];
            let b = t[(k + 1u) % 3u];
            n[k] = orient * vec2<f32>(b.y - a.y, a.x - b.x);
            d[k] = dot(n[k], a) + margin * (abs(n[k].x) + abs(n[k].y));
        }
        // Vertex k lies on edges k - 1 and k.
        for (var k = 0u; k < 3u; k++) {
            let j = (k + 2u) % 3u;
            grown[k] = spsm_meet(n[j], d[j], n[k], d[k]);
        }
        let area = 0.5 * abs(spsm_cross(grown[1] - grown[0], grown[2] - grown[0]));
        ok = area < box_area && all(abs(grown[0]) < vec2<f32>(1e7)) && all(abs(grown[1]) < vec2<f32>(1e7))
            && all(abs(grown[2]) < vec2<f32>(1e7));
    }
    out.clip = spsm_texel_to_clip(select(box_corner, grown[corner], ok));
    return out;
}

// The packed offsets x, y, z of a full texel put in the order that carries
// the parallelogram partner (session 14, spsm_decode_shape): edge
// `partner` - 1 first (v0 -> v1) and a positive orientation where there is
// a partner, else a non-positive orientation. The orientation is judged on
// the decoded offsets, with the lookup's margin spsm_partner_margin twice
// over (no partner is marked on a triangle too thin to tell).
fn spsm_order_offsets(words: vec3<u32>, partner: u32) -> vec3<u32> {
    let d = array<vec2<f32>, 3>(unpack2x16float(words.x), unpack2x16float(words.y), unpack2x16float(words.z));
    let w = array<u32, 3>(words.x, words.y, words.z);
    let area2 = spsm_cross(d[1] - d[0], d[2] - d[0]);
    let margin = spsm_partner_margin(d[0], d[1], d[2]);
    if partner != 0u && abs(area2) > 2.0 * margin {
        let k = partner - 1u;
        let a = w[k];
        let b = w[(k + 1u) % 3u];
        let c = w[(k + 2u) % 3u];
        return select(vec3<u32>(b, a, c), vec3<u32>(a, b, c), area2 > 0.0);
    }
    return select(words, vec3<u32>(words.x, words.z, words.y), area2 > 0.0);
}

// Monotone squeeze of zeta (any real) into the depth buffer's [0, 1].
fn spsm_depth_key(zeta: f32) -> f32 {
    return 0.5 + 0.5 * zeta / (1.0 + abs(zeta));
}

// The linear light depth (light_depth.wgsl) of the triangle's plane at
// texel position `q`: the world point there by perspective-correct
// barycentrics (weights b_i / w_i).
fn spsm_linear_depth_at(in: SpsmVertex, q: vec2<f32>) -> f32 {
    let b = vec3<f32>(spsm_cross(in.t2 - in.t1, q - in.t1), spsm_cross(in.t0 - in.t2, q - in.t2), spsm_cross(in.t1 - in.t0, q - in.t0)) / in.w;
    let x = (b.x * in.x0 + b.y * in.x1 + b.z * in.x2) / (b.x + b.y + b.z);
    return linear_light_depth(shadow_pass.position, shadow_pass.depth.xy, x);
}

// A triangle covering texel centre `c` (edges included) offers its linear
// light depth there to the texel's centre-sampled depth, biased as
// shadow.wgsl biases a standard map: constant plus slope scale times the
// larger change over one texel (here from the plane at c + x and c + y
// rather than the rasterizer's dpdx / dpdy), clamped when a clamp is set.
fn spsm_store_centre(in: SpsmVertex, c: vec2<f32>) {
    let t0 = in.t0;
    let t1 = in.t1;
    let t2 = in.t2;
    let area = spsm_cross(t1 - t0, t2 - t0);
    let e0 = spsm_cross(t1 - t0, c - t0) * area;
    let e1 = spsm_cross(t2 - t1, c - t1) * area;
    let e2 = spsm_cross(t0 - t2, c - t2) * area;
    if area == 0.0 || e0 < 0.0 || e1 < 0.0 || e2 < 0.0 {
        return;
    }
    let depth = spsm_linear_depth_at(in, c);
    let slope = max(abs(spsm_linear_depth_at(in, c + vec2<f32>(1.0, 0.0)) - depth), abs(spsm_linear_depth_at(in, c + vec2<f32>(0.0, 1.0)) - depth));
    spsm_offer_centre(c, depth, slope);
}

// Offers `depth` (linear light depth at texel centre `c`, changing by
// `slope` over one texel) to the texel's centre-sampled depth with
// shadow.wgsl's bias.
fn spsm_offer_centre(c: vec2<f32>, depth: f32, slope: f32) {
    var bias = shadow_pass.depth.z + shadow_pass.depth.w * slope;
    if shadow_pass.clamp.x > 0.0 {
        bias = min(bias, shadow_pass.clamp.x);
    }
    let width = u32(shadow_pass.clamp.y);
    let index = u32(c.y) * width + u32(c.x);
    if index < arrayLength(&spsm_centre) && u32(c.x) < width {
        atomicMax(&spsm_centre[index], ~bitcast<u32>(clamp(depth + bias, 0.0, 1.0)));
    }
}

struct SpsmOutput {
    @location(0) texel: vec4<u32>,
    @builtin(frag_depth) depth: f32,
}

@fragment
fn fs_shadow(in: SpsmVertex) -> SpsmOutput {
    var out: SpsmOutput;
    // The clipped fallback's linear light depth and its change over a
    // texel, as shadow.wgsl computes them (derivatives before any branch).
    let fallback_depth = linear_light_depth(shadow_pass.position, shadow_pass.depth.xy, in.world);
    let fallback_slope = max(abs(dpdx(fallback_depth)), abs(dpdy(fallback_depth)));
    if in.mode == 1u {
        // Clipped fallback: the hardware's depth z / w at the texel centre,
        // and the standard map's centre-sampled depth (session 6: these
        // texels, triangles crossing the light's w = 0 plane such as a
        // floor under a PSM-like warp, had only the 16-bit z / w and the
        // constant bias, and showed as acne).
        spsm_offer_centre(in.clip.xy, fallback_depth, fallback_slope);
        let zeta = in.clip.z;
        out.texel = vec4<u32>(SPSM_DEPTH_ONLY, 0u, 0u, spsm_encode_depth(zeta) << 16u);
        out.depth = spsm_depth_key(zeta);
        return out;
    }
    let c = floor(in.clip.xy) + 0.5;
    if !spsm_box_overlaps(in.t0, in.t1, in.t2, c) {
        discard;
    }
    let g = spsm_gradient(in.t0, in.t1, in.t2, in.zeta);
    let lowest = min(in.zeta.x, min(in.zeta.y, in.zeta.z));
    let highest = max(in.zeta.x, max(in.zeta.y, in.zeta.z));
    var zeta_c: f32;
    var min_depth: f32;
    if all(g == vec2<f32>(0.0)) && (highest > lowest) {
        // Degenerate (edge-on) triangle: its nearest vertex, conservatively.
        zeta_c = lowest;
        min_depth = lowest;
    } else {
        zeta_c = in.zeta.x + dot(g, c - in.t0);
        min_depth = clamp(spsm_min_depth(in.t0, in.t1, in.t2, c, zeta_c, g, lowest), lowest, highest);
        spsm_store_centre(in, c);
    }
    let reach = max(max(abs(in.t0 - c), abs(in.t1 - c)), abs(in.t2 - c));
    let codes = in.inner & 0xffffffu;
    let partner = in.inner >> 24u;
    out.texel = vec4<u32>(
        spsm_pack_offset(in.t0 - c),
        spsm_pack_offset(in.t1 - c),
        spsm_pack_offset(in.t2 - c),
        (spsm_encode_depth(zeta_c) << 16u) | spsm_encode_gradient(g, shadow_pass.clamp.yz),
    );
    if SPSM_INNER_EDGES {
        out.texel = vec4<u32>(spsm_order_offsets(out.texel.xyz, partner), out.texel.w);
    }
    let area2 = abs(spsm_cross(in.t1 - in.t0, in.t2 - in.t0));
    var compact_codes = codes;
    if partner != 0u && ((codes >> (8u * (partner - 1u))) & 0xffu) == 0u {
        // A partner too thin for an edge code (h below 1/16 texel).
        compact_codes |= SPSM_PARTNER_CODE << (8u * (partner - 1u));
    }
    if SPSM_INNER_EDGES && compact_codes != 0u && area2 < SPSM_FACET_AREA && all(reach < vec2<f32>(SPSM_FLAG_REACH)) {
        let w = spsm_pack_compact(in.t0 - c, in.t1 - c, in.t2 - c, compact_codes);
        out.texel.x = w.x;
        out.texel.y = w.y;
        out.texel.z = w.z;
    }
    out.depth = spsm_depth_key(min_depth);
    return out;
}
