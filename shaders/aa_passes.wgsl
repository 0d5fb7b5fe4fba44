// Sub-pixel antialiased shadows (Pan et al. 2009), `ShadowLookup::SubPixelAa`:
// compute passes after the camera pass, run once per light (`params.light`).
// Prepended: light_depth.wgsl, common.wgsl (group 0: `camera`, `lights`) and
// a stub `in_shadow` (common.wgsl's `shade` needs one; unused here).
// The CPU twins of every step are in src/render/subpixel/{facet,bitmask,reference}.rs.
//
// 1. `silhouette`: one invocation per mesh edge; silhouette edges for the
//    light (boundary, non-manifold, or faces on both sides of the light) are
//    clipped to w > 0 and to the map and walked texel by texel (every texel
//    the segment crosses is marked: a supercover walk).
// 2. `sat_rows`, `sat_cols`: the inclusive summed-area table of the mask.
// 2b. `classify`: one invocation per pixel: the pixel's facet (tangent
//    plane from the camera pass's depth and normal) and its light-space
//    footprint; a pixel with a silhouette texel in it, or whose standard
//    depth compare is uncertain (`depth_uncertain`; it also forces its
//    footprint's tiles active, so that they get lists), is marked for the
//    exact path; every other pixel will keep the standard bit.
// 3. `tile_count`, `tile_scan`, `tile_write`: triangle lists of TILE x TILE
//    texel tiles. A tile is *active* when its neighbourhood (the tile grown
//    by two tiles each side) holds a silhouette texel; a triangle enters
//    the list of every active tile its projected bounding box touches.
// 4. `visibility`: one invocation per pixel: the standard bit in every
//    sample; a marked pixel whose tiles can serve it is queued, and
//    `visibility_exact` (one invocation per queued pixel) finds the facet
//    on its triangle's plane, and every triangle of its tiles clips the
//    facet's samples through four half-plane table lookups, ANDed per
//    triangle, ORed over triangles.
//    Each list entry is first culled against the pixel's footprint with the
//    triangle's own box (written by `tile_count_pass` after the lists, grown
//    by the lists' texel) and tested in one tile only (the tile of the
//    box-footprint overlap's low corner): the same rule the lists apply per
//    tile, applied per pixel, so a triangle is tested at most once and only
//    when its box meets the footprint.

const TILE: u32 = 8u;
// Prepended by gpu.rs: LIST_TILE, the side of the list tiles in texels
// (a divisor of TILE), and PER_TILE = TILE / LIST_TILE. Each TILE x TILE
// tile's triangles are kept in PER_TILE^2 lists, one per LIST_TILE x
// LIST_TILE list tile, so that a pixel scans the entries of the list tiles
// its footprint touches (fewer, since the lists are narrower). Activity
// and the width limit stay per TILE tile: which pixels the exact path
// serves does not change.
// Footprints touching more tiles than this take the standard bit (counted).
const MAX_FOOTPRINT_TILES: u32 = 36u;
const ALL_SAMPLES: u32 = 0xffffffffu;
// Half-plane table (bitmask.rs): 128 directions x 64 offsets over +-0.625 px.
const ANGLES: f32 = 128.0;
const OFFSETS: f32 = 64.0;
const RADIUS: f32 = 0.625;
const TAU: f32 = 6.283185307179586;
const W_EPS: f32 = 1e-6;

// Statistics words per light (see `AaStats` in gpu.rs).
const STAT_PAIRS: u32 = 0u;
const STAT_EXACT: u32 = 1u;
const STAT_OVERFLOW: u32 = 2u;
const STAT_WIDE: u32 = 3u;
const STAT_TESTS: u32 = 4u;
// Pixels queued for the exact path (`visibility` -> `visibility_exact`).
const STAT_QUEUE: u32 = 5u;
// Pixels queued because their depth compare is uncertain (no silhouette
// texel in the footprint).
const STAT_UNCERTAIN: u32 = 6u;
// List entries the exact path read (culled or tested).
const STAT_SCANNED: u32 = 7u;
// Texels the silhouette mask marked (after the depth check).
const STAT_SILHOUETTE: u32 = 8u;
// STATS_PER_LIGHT (the words above, per light) and STATS_WORDS (their
// block, before the tile words) are prepended by src/render/subpixel/gpu.rs.

struct AaParams {
    light: u32,
    tiles_x: u32,
    tiles_y: u32,
    capacity: u32,
    width: u32,
    height: u32,
    edge_count: u32,
    triangle_count: u32,
    bias: f32,
    sample_mask: u32,
    map_w: u32,
    map_h: u32,
    // Index of the summed-area table in `map_words` (after the mask).
    sat_base: u32,
    // List tiles (LIST_TILE) per section of `tile_words` (count, cursor,
    // offset; the forced flags, per TILE tile, fit too).
    tile_stride: u32,
    // Index of the triangles' boxes in `tile_list` (after the lists).
    box_base: u32,
    // Index of the exact path's pixel queue in `tile_list` (after the boxes).
    queue_base: u32,
    // 1: per-pixel box culling on (the default); 0: every entry of the
    // footprint's tiles is tested (the old rule, for tests).
    cull: u32,
    // Index of the validity words in `occlusion` (after every light's
    // occlusion words).
    valid_base: u32,
    // 1: the validity mask on (the default); 0: every sample valid (for
    // tests; a spot light's samples outside its cone stay invalid).
    validity: u32,
    // 1: pixels whose depth compare is uncertain take the exact path (the
    // default); 0: only silhouette pixels do (for tests).
    uncertain: u32,
    // The shadow pass's bias (`ShadowBias`): constant (linear depth
    // units), slope scale, clamp (0: none).
    depth_bias: f32,
    slope_scale: f32,
    bias_clamp: f32,
    // Index of the triangles' screen boxes in `tile_list` (after the map
    // boxes).
    screen_base: u32,
    // 1: the hidden test is gated by the triangle's screen box (the
    // default); 0: every tested triangle runs it (for tests).
    gate: u32,
    // 1: the silhouette pass's depth check on (the default); 0: every
    // texel a silhouette edge crosses is marked (for tests).
    depth_check: u32,
    _pad1: u32,
    _pad2: u32,
}

// a.w: 1 when the edge is a silhouette for every light (boundary or
// non-manifold); else f0, f1 are its two triangles' planes (n, -n.a).
struct Edge {
    a: vec4<f32>,
    b: vec4<f32>,
    f0: vec4<f32>,
    f1: vec4<f32>,
}

// At most 8 storage buffers (wgpu's default limit): the mask and its
// summed-area table share `map_words`; the statistics (STATS_PER_LIGHT words
// per light, first) and the tiles' counts, cursors and offsets share
// `tile_words`; the half-plane table is a uniform array.
@group(1) @binding(0) var<uniform> params: AaParams;
@group(1) @binding(1) var<storage, read> edges: array<Edge>;
@group(1) @binding(2) var<storage, read_write> map_words: array<u32>;
@group(1) @binding(3) var<storage, read_write> tile_words: array<atomic<u32>>;
@group(1) @binding(4) var<storage, read_write> tile_list: array<u32>;
@group(1) @binding(5) var<storage, read> vertex_words: array<f32>;
@group(1) @binding(6) var<storage, read> index_words: array<u32>;
@group(1) @binding(7) var<uniform> table: array<vec4<u32>, 2048>;
@group(1) @binding(8) var<storage, read_write> occlusion: array<u32>;
@group(1) @binding(9) var camera_masks: texture_2d<u32>;
// The frame's shadow maps (the depth compare's), for `depth_uncertain`.
@group(1) @binding(10) var shadow_maps: texture_2d_array<f32>;

// The count, cursor and offset of list tile `list` (`list_index`).
fn count_slot(list: u32) -> u32 {
    return STATS_WORDS + list;
}

fn cursor_slot(list: u32) -> u32 {
    return STATS_WORDS + params.tile_stride + list;
}

fn offset_slot(list: u32) -> u32 {
    return STATS_WORDS + 2u * params.tile_stride + list;
}

fn lists_x() -> u32 {
    return (params.map_w + LIST_TILE - 1u) / LIST_TILE;
}

fn lists_y() -> u32 {
    return (params.map_h + LIST_TILE - 1u) / LIST_TILE;
}

fn list_index(list: vec2<i32>) -> u32 {
    return u32(list.y) * lists_x() + u32(list.x);
}

// The list tiles of TILE tiles `t` (xy first, zw last), clamped into the
// map's list tiles.
fn tiles_lists(t: vec4<i32>) -> vec4<i32> {
    let last = vec2<i32>(i32(lists_x()) - 1, i32(lists_y()) - 1);
    return vec4<i32>(t.xy * PER_TILE, min(t.zw * PER_TILE + vec2<i32>(PER_TILE - 1), last));
}

// Non-zero when an uncertain pixel's footprint touches the tile.
fn forced_slot(tile: u32) -> u32 {
    return STATS_WORDS + 3u * params.tile_stride + tile;
}

fn add_stat(which: u32, value: u32) {
    atomicAdd(&tile_words[params.light * STATS_PER_LIGHT + which], value);
}

// Dispatches are 2D when one dimension would exceed the workgroup limit.
fn flat_id(gid: vec3<u32>, groups: vec3<u32>) -> u32 {
    return gid.x + gid.y * groups.x * 64u;
}

fn map_size() -> vec2<f32> {
    return vec2<f32>(f32(params.map_w), f32(params.map_h));
}

// Map position in texels of a clip-space point with w > 0.
fn to_texel(clip: vec4<f32>) -> vec2<f32> {
    let ndc = clip.xy / clip.w;
    return vec2<f32>(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5) * map_size();
}

fn mark(cell: vec2<i32>) {
    map_words[u32(cell.y) * params.map_w + u32(cell.x)] = 1u;
}

// The silhouette pass's depth check (Pan et al. 2009, section 3.2): a walked
// texel is marked only when the edge's nearest linear light depth over the
// texel (`near`) is not behind the light's depth map by more than
// DEPTH_CHECK_MARGIN, the map's depth taken as the *largest* over the texel
// and its eight neighbours. The shadow pass's map (binding 10, the standard
// depth compare's; the aa passes run after it) holds at each texel centre
// the depth of the nearest surface there plus the shadow pass's bias, which
// only moves it away from the light. Conservative, so that a texel bounding
// a visible shadow edge is not dropped (its pixels would take the standard
// compare's full lit/shadowed verdict):
// - the edge's own surface (the front face it bounds, or its neighbour
//   across the texel) stores at the texel centre, at most half a texel
//   from the edge point on each axis, its depth there plus its slope-scaled
//   bias (slope scale 2 by default, unclamped), so at least the edge
//   point's depth: a visible edge is not behind its own surface;
// - just beyond a visible edge (outside the surface it bounds) lies
//   whatever the light sees past it, no nearer than the edge, and of a
//   texel's 3x3 centres some lie beyond any line through the texel; the
//   neighbourhood's largest depth sees it (and the map's clear value, 1,
//   where nothing lies beyond);
// - a nearer surface that covers only part of the texel has its own
//   outline crossing the texel, which marks it.
// Only a texel whose nine centres all see surfaces nearer than every point
// of the edge inside it is dropped: the edge there is hidden behind
// something closer to the light, and its shadow edge lies inside that
// surface's shadow (both sides shadowed). Depths are clamped into [0, 1]
// like the stored ones, so an edge beyond the map's range is never dropped
// against the clear value.
const DEPTH_CHECK_MARGIN: f32 = 1e-5;

// The largest stored depth of `cell` and its eight neighbours (clamped into
// the map).
fn neighbourhood_depth(light: Light, cell: vec2<i32>) -> f32 {
    let last = vec2<i32>(i32(params.map_w) - 1, i32(params.map_h) - 1);
    var deepest = 0.0;
    for (var k = 0; k < 9; k++) {
        let at = clamp(cell + vec2<i32>(k % 3 - 1, k / 3 - 1), vec2<i32>(0), last);
        deepest = max(deepest, textureLoad(shadow_maps, at, light.layer, 0).x);
    }
    return deepest;
}

// The nearest clamped linear light depth of the world segment a + u (b - a)
// over u in [ua, ub]: the distance to a point light is convex along the
// segment (least at the foot of the perpendicular, clamped into the
// interval), a directional light's depth is linear (least at an end).
fn segment_near(light: Light, a: vec3<f32>, b: vec3<f32>, ua: f32, ub: f32) -> f32 {
    let l = light.position;
    let d = b - a;
    var near = min(
        linear_light_depth(l, light.depth.xy, a + d * ua),
        linear_light_depth(l, light.depth.xy, a + d * ub),
    );
    let dd = dot(d, d);
    if l.w > 0.0 && dd > 0.0 {
        let foot = clamp(dot(l.xyz - a, d) / dd, ua, ub);
        near = min(near, linear_light_depth(l, light.depth.xy, a + d * foot));
    }
    return clamp(near, 0.0, 1.0);
}

@compute @workgroup_size(64)
fn silhouette(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let e = flat_id(gid, groups);
    if e >= params.edge_count {
        return;
    }
    let edge = edges[e];
    let light = lights.items[params.light];
    let l = light.position;
    if edge.a.w == 0.0 && (dot(edge.f0, l) > 0.0) == (dot(edge.f1, l) > 0.0) {
        return;
    }
    var c0 = light.clip_from_world * vec4<f32>(edge.a.xyz, 1.0);
    var c1 = light.clip_from_world * vec4<f32>(edge.b.xyz, 1.0);
    if c0.w <= W_EPS && c1.w <= W_EPS {
        return;
    }
    // The world points of c0 and c1 (clip space is affine in world space,
    // so clipping moves both alike).
    var w0 = edge.a.xyz;
    var w1 = edge.b.xyz;
    if c0.w <= W_EPS {
        let f = (W_EPS - c0.w) / (c1.w - c0.w);
        c0 = mix(c0, c1, f);
        w0 = mix(w0, w1, f);
    }
    if c1.w <= W_EPS {
        let f = (W_EPS - c1.w) / (c0.w - c1.w);
        c1 = mix(c1, c0, f);
        w1 = mix(w1, w0, f);
    }
    let p0 = to_texel(c0);
    let d = to_texel(c1) - p0;
    // Clip the segment to the map rectangle (Liang-Barsky).
    var t0 = 0.0;
    var t1 = 1.0;
    let size = map_size();
    for (var axis = 0; axis < 2; axis++) {
        if abs(d[axis]) < 1e-20 {
            if p0[axis] < 0.0 || p0[axis] > size[axis] {
                return;
            }
        } else {
            let ta = (0.0 - p0[axis]) / d[axis];
            let tb = (size[axis] - p0[axis]) / d[axis];
            t0 = max(t0, min(ta, tb));
            t1 = min(t1, max(ta, tb));
        }
    }
    if t0 > t1 {
        return;
    }
    let q0 = p0 + d * t0;
    let dd = d * (t1 - t0);
    let last = vec2<i32>(i32(params.map_w) - 1, i32(params.map_h) - 1);
    var cell = clamp(vec2<i32>(floor(q0)), vec2<i32>(0), last);
    let end = clamp(vec2<i32>(floor(q0 + dd)), vec2<i32>(0), last);
    let step = vec2<i32>(select(-1, 1, dd.x >= 0.0), select(-1, 1, dd.y >= 0.0));
    let big = 1e30;
    let delta = vec2<f32>(select(big, 1.0 / abs(dd.x), dd.x != 0.0), select(big, 1.0 / abs(dd.y), dd.y != 0.0));
    var t_max = vec2<f32>(big);
    if dd.x != 0.0 {
        t_max.x = (f32(cell.x) + select(0.0, 1.0, dd.x > 0.0) - q0.x) / dd.x;
    }
    if dd.y != 0.0 {
        t_max.y = (f32(cell.y) + select(0.0, 1.0, dd.y > 0.0) - q0.y) / dd.y;
    }
    let n = abs(end.x - cell.x) + abs(end.y - cell.y);
    // The depth check reads each cell's stretch of the walk [s_in, s_out]
    // (s along q0 + dd s) grown by a texel's length on each side (f32 ties
    // at texel corners may step an axis early); s maps to the map
    // segment's parameter t, then perspective-correctly to the clip (and
    // world) segment's u.
    let pad = 1.0 / max(max(abs(dd.x), abs(dd.y)), 1.0);
    var s_in = 0.0;
    for (var k = 0; k <= n; k++) {
        let s_out = select(min(min(t_max.x, t_max.y), 1.0), 1.0, k == n);
        let ta = t0 + (t1 - t0) * clamp(s_in - pad, 0.0, 1.0);
        let tb = t0 + (t1 - t0) * clamp(s_out + pad, 0.0, 1.0);
        let ua = ta * c0.w / ((1.0 - ta) * c1.w + ta * c0.w);
        let ub = tb * c0.w / ((1.0 - tb) * c1.w + tb * c0.w);
        if params.depth_check == 0u || segment_near(light, w0, w1, ua, ub) <= neighbourhood_depth(light, cell) + DEPTH_CHECK_MARGIN {
            mark(cell);
        }
        if k == n {
            break;
        }
        s_in = s_out;
        // Every step moves one cell towards `end`; an axis already there
        // never moves (f32 ties at texel corners).
        let move_x = cell.y == end.y || (cell.x != end.x && t_max.x < t_max.y);
        if move_x {
            cell.x += step.x;
            t_max.x += delta.x;
        } else {
            cell.y += step.y;
            t_max.y += delta.y;
        }
    }
}

// One invocation before `silhouette`, writing a statistics word that every
// dispatch's bindings hold read-write: the backend then orders the shadow
// pass's writes to the maps before the silhouette pass reads them (see
// `encode` in gpu.rs).
@compute @workgroup_size(1)
fn settle() {
    atomicStore(&tile_words[params.light * STATS_PER_LIGHT + STAT_SILHOUETTE], 0u);
}

@compute @workgroup_size(64)
fn sat_rows(@builtin(global_invocation_id) gid: vec3<u32>) {
    let y = gid.x;
    if y >= params.map_h {
        return;
    }
    var run = 0u;
    for (var x = 0u; x < params.map_w; x++) {
        let i = y * params.map_w + x;
        run += map_words[i];
        map_words[params.sat_base + i] = run;
    }
}

@compute @workgroup_size(64)
fn sat_cols(@builtin(global_invocation_id) gid: vec3<u32>) {
    let x = gid.x;
    if x >= params.map_w {
        return;
    }
    var run = 0u;
    for (var y = 0u; y < params.map_h; y++) {
        let i = y * params.map_w + x;
        run += map_words[params.sat_base + i];
        map_words[params.sat_base + i] = run;
    }
    // The last column's sum is the table's corner: every marked texel.
    if x == params.map_w - 1u {
        atomicStore(&tile_words[params.light * STATS_PER_LIGHT + STAT_SILHOUETTE], run);
    }
}

// Silhouette texels in [lo, hi] (inclusive, clamped into the map): four reads,
// wrapping arithmetic as in `reference::rect_sum`.
fn rect_sum(lo_in: vec2<i32>, hi_in: vec2<i32>) -> u32 {
    let last = vec2<i32>(i32(params.map_w) - 1, i32(params.map_h) - 1);
    let lo = clamp(lo_in, vec2<i32>(0), last);
    let hi = clamp(hi_in, vec2<i32>(0), last);
    if any(hi < lo) {
        return 0u;
    }
    let w = params.map_w;
    let s = params.sat_base;
    var sum = map_words[s + u32(hi.y) * w + u32(hi.x)];
    if lo.x > 0 {
        sum -= map_words[s + u32(hi.y) * w + u32(lo.x - 1)];
    }
    if lo.y > 0 {
        sum -= map_words[s + u32(lo.y - 1) * w + u32(hi.x)];
    }
    if lo.x > 0 && lo.y > 0 {
        sum += map_words[s + u32(lo.y - 1) * w + u32(lo.x - 1)];
    }
    return sum;
}

// A tile gets a triangle list when its neighbourhood holds a silhouette
// texel or an uncertain pixel's footprint touches it.
fn tile_active(tile: vec2<i32>) -> bool {
    let t = i32(TILE);
    if atomicLoad(&tile_words[forced_slot(u32(tile.y) * params.tiles_x + u32(tile.x))]) != 0u {
        return true;
    }
    return rect_sum(tile * t - vec2<i32>(2 * t), tile * t + vec2<i32>(3 * t - 1)) > 0u;
}

fn vertex(t: u32, k: u32) -> vec3<f32> {
    let i = index_words[3u * t + k] * 7u;
    return vec3<f32>(vertex_words[i], vertex_words[i + 1u], vertex_words[i + 2u]);
}

// A triangle's projected bounding box in texels (xy low, zw high); the
// whole map when it crosses w = 0; empty (z < x) when it lies behind the
// light.
fn triangle_box(t: u32) -> vec4<f32> {
    let light = lights.items[params.light];
    var lo = vec2<f32>(1e30);
    var hi = vec2<f32>(-1e30);
    var behind = 0u;
    for (var k = 0u; k < 3u; k++) {
        let clip = light.clip_from_world * vec4<f32>(vertex(t, k), 1.0);
        if clip.w <= W_EPS {
            behind++;
        } else {
            let p = to_texel(clip);
            lo = min(lo, p);
            hi = max(hi, p);
        }
    }
    if behind == 3u {
        return vec4<f32>(0.0, 0.0, -1.0, -1.0);
    }
    if behind > 0u {
        return vec4<f32>(vec2<f32>(0.0), map_size());
    }
    return vec4<f32>(lo, hi);
}

// Texel index range of a point range, clamped into the map first (in f32:
// a far box corner must not overflow the conversion).
fn texel_of(p: vec2<f32>) -> vec2<i32> {
    let last = vec2<f32>(f32(params.map_w) - 1.0, f32(params.map_h) - 1.0);
    return vec2<i32>(clamp(floor(p), vec2<f32>(0.0), last));
}

// The list tiles a triangle's box (grown by a texel) touches: xy the
// first, zw the last; empty (z < x) when it misses the map or lies behind
// the light.
fn triangle_lists(b: vec4<f32>) -> vec4<i32> {
    let empty = vec4<i32>(0, 0, -1, -1);
    let size = map_size();
    if b.z < b.x || any(b.zw < vec2<f32>(-1.0)) || any(b.xy > size + vec2<f32>(1.0)) {
        return empty;
    }
    let a = texel_of(b.xy - vec2<f32>(1.0));
    let c = texel_of(b.zw + vec2<f32>(1.0));
    return vec4<i32>(a / i32(LIST_TILE), c / i32(LIST_TILE));
}

// The most TILE tiles a triangle's box may span along x or along y for
// `enter_lists`: its loops run (rows) x (columns + 1) iterations, and the CPU
// backends (llvmpipe, lavapipe) end an invocation's loops after 65 535
// iterations, all loops together (a SIMD batch's lanes share the count, so
// the bound is per side: 240 x 241 = 57 840). Reached only by maps wider
// than 1920 texels (240 tiles of 8).
const ENTER_MAX_SIDE: i32 = 240;

// Whether the lists `r` (list tiles) span more TILE tiles than
// `enter_lists` may visit (ENTER_MAX_SIDE).
fn enter_too_long(r: vec4<i32>) -> bool {
    if r.z < r.x {
        return false;
    }
    let rows = r.w / PER_TILE - r.y / PER_TILE + 1;
    let cols = r.z / PER_TILE - r.x / PER_TILE + 1;
    return rows > ENTER_MAX_SIDE || cols > ENTER_MAX_SIDE;
}

// Adds triangle `t` to the lists `r` (list tiles, `triangle_lists`) of
// active TILE tiles: counts them (`write` false) or writes them.
fn enter_lists(t: u32, r: vec4<i32>, write: bool) {
    if r.z < r.x {
        return;
    }
    for (var ty = r.y / PER_TILE; ty <= r.w / PER_TILE; ty++) {
        for (var tx = r.x / PER_TILE; tx <= r.z / PER_TILE; tx++) {
            if !tile_active(vec2<i32>(tx, ty)) {
                continue;
            }
            let lo = max(r.xy, vec2<i32>(tx, ty) * PER_TILE);
            let hi = min(r.zw, vec2<i32>(tx, ty) * PER_TILE + vec2<i32>(PER_TILE - 1));
            // The tile's list tiles (at most 2x2: PER_TILE <= 2) written out, not looped:
            // llvmpipe ends an invocation's loops after 65 535 iterations
            // (see ENTER_MAX_SIDE).
            enter_list(t, lo, hi, vec2<i32>(0, 0), write);
            enter_list(t, lo, hi, vec2<i32>(1, 0), write);
            enter_list(t, lo, hi, vec2<i32>(0, 1), write);
            enter_list(t, lo, hi, vec2<i32>(1, 1), write);
        }
    }
}

// List tile `lo + d` of a tile's range [lo, hi] (`enter_lists`), when in it.
fn enter_list(t: u32, lo: vec2<i32>, hi: vec2<i32>, d: vec2<i32>, write: bool) {
    let at = lo + d;
    if any(at > hi) {
        return;
    }
    let list = list_index(at);
    if !write {
        atomicAdd(&tile_words[count_slot(list)], 1u);
        return;
    }
    let slot = atomicLoad(&tile_words[offset_slot(list)]) + atomicAdd(&tile_words[cursor_slot(list)], 1u);
    // Past the capacity: dropped; the tile's pixels see the overflow and
    // keep the standard bit.
    if slot < params.capacity {
        tile_list[slot] = t;
    }
}

fn stored_box(t: u32) -> vec4<f32> {
    return load_box(params.box_base + 4u * t);
}

// The four floats `store_box` wrote from index `i` of `tile_list`.
fn load_box(i: u32) -> vec4<f32> {
    return vec4<f32>(
        bitcast<f32>(tile_list[i]),
        bitcast<f32>(tile_list[i + 1u]),
        bitcast<f32>(tile_list[i + 2u]),
        bitcast<f32>(tile_list[i + 3u]),
    );
}

// A triangle's bounding box on the screen in pixels (xy low, zw high);
// unbounded when a vertex lies at or behind the eye's plane.
fn screen_box(t: u32) -> vec4<f32> {
    let size = vec2<f32>(f32(params.width), f32(params.height));
    var lo = vec2<f32>(1e30);
    var hi = vec2<f32>(-1e30);
    for (var k = 0u; k < 3u; k++) {
        let clip = camera.clip_from_world * vec4<f32>(vertex(t, k), 1.0);
        if clip.w <= W_EPS {
            return vec4<f32>(vec2<f32>(-1e30), vec2<f32>(1e30));
        }
        let ndc = clip.xy / clip.w;
        let p = vec2<f32>(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5) * size;
        lo = min(lo, p);
        hi = max(hi, p);
    }
    return vec4<f32>(lo, hi);
}

// A box's four floats as words of `tile_list` from index `i`.
fn store_box(i: u32, b: vec4<f32>) {
    tile_list[i] = bitcast<u32>(b.x);
    tile_list[i + 1u] = bitcast<u32>(b.y);
    tile_list[i + 2u] = bitcast<u32>(b.z);
    tile_list[i + 3u] = bitcast<u32>(b.w);
}

@compute @workgroup_size(64)
fn tile_count_pass(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let t = flat_id(gid, groups);
    if t >= params.triangle_count {
        return;
    }
    let b = triangle_box(t);
    store_box(params.box_base + 4u * t, b);
    store_box(params.screen_base + 4u * t, screen_box(t));
    let r = triangle_lists(b);
    if enter_too_long(r) {
        // Refused, never cut silently: list 0's count is raised past the
        // capacity, so every list's end lies past it and every pixel of the
        // light keeps the standard bit, counted in STAT_OVERFLOW (and
        // STAT_PAIRS reads above the capacity).
        atomicMax(&tile_words[count_slot(0u)], params.capacity + 1u);
        return;
    }
    enter_lists(t, r, false);
}

// Per invocation of `tile_scan`: the sum of lists [i, i + SCAN_BLOCK) that
// lie below `end` (`offsets` false), or their offsets from `run` written
// (true); returns the running sum. Straight-line: llvmpipe ends a shader
// invocation's loops after 65 535 iterations, all loops together, and a map
// of 1024² texels has 65 536 lists of 4x4.
fn scan_block(i: u32, end: u32, run: u32, offsets: bool) -> u32 {
    var r = scan_one(i, end, run, offsets);
    r = scan_one(i + 1u, end, r, offsets);
    r = scan_one(i + 2u, end, r, offsets);
    r = scan_one(i + 3u, end, r, offsets);
    r = scan_one(i + 4u, end, r, offsets);
    r = scan_one(i + 5u, end, r, offsets);
    r = scan_one(i + 6u, end, r, offsets);
    return scan_one(i + 7u, end, r, offsets);
}

fn scan_one(i: u32, end: u32, run: u32, offsets: bool) -> u32 {
    if i >= end {
        return run;
    }
    if offsets {
        atomicStore(&tile_words[offset_slot(i)], run);
    }
    return run + atomicLoad(&tile_words[count_slot(i)]);
}

const SCAN_BLOCK: u32 = 8u;
var<workgroup> chunk_sums: array<u32, 64>;

// One workgroup of 64: the exclusive prefix sum of the list counts, each
// invocation over a chunk of the lists (summed, then the chunks' sums
// scanned in the workgroup, then the offsets written), SCAN_BLOCK lists per
// loop iteration (`scan_block`).
@compute @workgroup_size(64)
fn tile_scan(@builtin(local_invocation_index) lid: u32) {
    let total = lists_x() * lists_y();
    let chunk = (total + 63u) / 64u;
    let first = min(lid * chunk, total);
    let end = min(first + chunk, total);
    var sum = 0u;
    for (var i = first; i < end; i += SCAN_BLOCK) {
        sum = scan_block(i, end, sum, false);
    }
    chunk_sums[lid] = sum;
    workgroupBarrier();
    var run = 0u;
    for (var j = 0u; j < lid; j++) {
        run += chunk_sums[j];
    }
    for (var i = first; i < end; i += SCAN_BLOCK) {
        run = scan_block(i, end, run, true);
    }
    if lid == 63u {
        add_stat(STAT_PAIRS, run);
    }
}

@compute @workgroup_size(64)
fn tile_write(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let t = flat_id(gid, groups);
    if t >= params.triangle_count {
        return;
    }
    let r = triangle_lists(stored_box(t));
    if enter_too_long(r) {
        return;
    }
    enter_lists(t, r, true);
}

// The table's mask of line (a, b, c): samples s with a s.x + b s.y + c >= 0
// (HalfPlaneTable::lookup).
fn table_lookup(line: vec3<f32>) -> u32 {
    let len = length(line.xy);
    if !(len > 0.0) {
        return select(0u, ALL_SAMPLES, line.z >= 0.0);
    }
    let e = (dot(line.xy, vec2<f32>(0.5)) + line.z) / len;
    if e >= RADIUS {
        return ALL_SAMPLES;
    }
    if e <= -RADIUS {
        return 0u;
    }
    let turns = atan2(line.y, line.x) / TAU;
    let a = i32(round(turns * ANGLES));
    let angle = u32(((a % 128) + 128) % 128);
    let offset = min(u32(floor((e + RADIUS) / (2.0 * RADIUS) * OFFSETS)), 63u);
    let i = angle * 64u + offset;
    // The word's component by selects rather than a dynamic vector index
    // (which llvmpipe spills to memory).
    let w = table[i / 4u];
    let j = i % 4u;
    return select(select(w.x, w.y, j == 1u), select(w.z, w.w, j == 3u), j >= 2u);
}

// A plane through points a, b (w = 1) and the homogeneous light l.
fn plane_through_light(a: vec3<f32>, b: vec3<f32>, l: vec4<f32>) -> vec4<f32> {
    let n = cross(b - a, l.xyz - a * l.w);
    return vec4<f32>(n, -dot(n, a));
}

// Whether the origin lies inside edge p -> q of a triangle with third
// vertex r and normal `normal`, within `tol` (scaled by the edge).
fn inside_edge(p: vec3<f32>, q: vec3<f32>, r: vec3<f32>, normal: vec3<f32>, tol: f32) -> bool {
    let edge = cross(normal, q - p);
    let inside = sign(dot(edge, r - p));
    return !(-dot(edge, p) * inside < -tol * length(edge));
}

// Whether the origin (the pixel's point) lies on triangle (v0, v1, v2)
// (within `tol` of its plane and of its inside): the pixel's own triangle,
// which must not shadow its facet. The vertices are separate values, not a
// private array: llvmpipe spills dynamically indexed private arrays to
// memory, which cost this pass several times its arithmetic.
fn holds(v0: vec3<f32>, v1: vec3<f32>, v2: vec3<f32>, normal: vec3<f32>, scale: f32, tol: f32) -> bool {
    if abs(dot(normal, v0)) > tol * scale {
        return false;
    }
    return inside_edge(v0, v1, v2, normal, tol) && inside_edge(v1, v2, v0, normal, tol)
        && inside_edge(v2, v0, v1, normal, tol);
}

// The shadow half-space of edge p -> q (third vertex r) as seen from the
// homogeneous light l: the plane through the edge and the light, oriented
// towards r; w = 2 (no half-space: the triangle is edge-on to the light).
fn edge_half_space(p: vec3<f32>, q: vec3<f32>, r: vec3<f32>, l: vec4<f32>) -> vec4<f32> {
    let h = plane_through_light(p, q, l);
    let side = dot(h, vec4<f32>(r, 1.0));
    if !(abs(side) > 1e-6 * length(h.xyz) * length(r - p)) {
        return vec4<f32>(0.0);
    }
    return h * sign(side);
}

// The table's mask of half-space h over the facet (columns c0, c1, c2).
fn half_space_mask(cols: array<vec4<f32>, 3>, h: vec4<f32>) -> u32 {
    return table_lookup(vec3<f32>(dot(cols[0], h), dot(cols[1], h), dot(cols[2], h)));
}

// The samples of a facet (columns c0, c1, c2) inside the shadow of the
// triangle (v0, v1, v2) (in the facet's frame, centred on the pixel's point)
// cast by the homogeneous point l: `facet::shadow_half_spaces` and
// `occluded_mask` for one triangle. With l the light: the occluded samples;
// with l the eye: the samples whose facet point the triangle hides from the
// camera (their view rays meet it first).
fn triangle_mask(v0: vec3<f32>, v1: vec3<f32>, v2: vec3<f32>, cols: array<vec4<f32>, 3>, l: vec4<f32>, bias: f32) -> u32 {
    let normal = cross(v1 - v0, v2 - v0);
    let scale = length(normal);
    if !(scale > 0.0) {
        return 0u;
    }
    // The triangle's own plane, facing away from l and pushed away from it
    // by the bias, first: it rejects most triangles behind the facet.
    let plane = vec4<f32>(normal, -dot(normal, v0));
    let towards = dot(plane, l);
    if towards == 0.0 {
        return 0u;
    }
    var mask = half_space_mask(cols, plane * -sign(towards) - vec4<f32>(0.0, 0.0, 0.0, bias * scale));
    // The pixel's own triangle occludes nothing. Both tests only return 0,
    // so their order does not change the result; the plane's (one table
    // lookup) rejects more triangles for less than `holds` (three edges).
    if mask == 0u || holds(v0, v1, v2, normal, scale, bias) {
        return 0u;
    }
    let h0 = edge_half_space(v0, v1, v2, l);
    let h1 = edge_half_space(v1, v2, v0, l);
    let h2 = edge_half_space(v2, v0, v1, l);
    if all(h0 == vec4<f32>(0.0)) || all(h1 == vec4<f32>(0.0)) || all(h2 == vec4<f32>(0.0)) {
        return 0u;
    }
    mask &= half_space_mask(cols, h0);
    if mask == 0u {
        return 0u;
    }
    mask &= half_space_mask(cols, h1);
    if mask == 0u {
        return 0u;
    }
    return mask & half_space_mask(cols, h2);
}

fn unpack_normal(word: u32) -> vec3<f32> {
    let p = unpack2x16snorm(word);
    var n = vec3<f32>(p, 1.0 - abs(p.x) - abs(p.y));
    if n.z < 0.0 {
        let s = select(vec2<f32>(-1.0), vec2<f32>(1.0), n.xy >= vec2<f32>(0.0));
        n = vec3<f32>((1.0 - abs(n.yx)) * s, n.z);
    }
    return normalize(n);
}

// The near-plane point of pixel (px, py) at pixel-local offset s.
fn pixel_near(px: u32, py: u32, s: vec2<f32>, size: vec2<f32>) -> vec3<f32> {
    let ndc = vec2<f32>((f32(px) + s.x) / size.x * 2.0 - 1.0, 1.0 - (f32(py) + s.y) / size.y * 2.0);
    let h = camera.world_from_clip * vec4<f32>(ndc, 0.0, 1.0);
    return h.xyz / h.w;
}

// A pixel's facet (facet.rs, Facet::new) on the plane through its point
// with normal n, in a frame centred on that point (f32 loses too much on far
// pixels in world coordinates): view rays D(s) = D0 s.x + D1 s.y + D2 from
// the eye E meet the plane n.x = 0 at X(s) = ((n.D(s)) E - (n.E) D(s), n.D(s)),
// linear in s: the columns. `ok` false when the plane is seen edge-on.
struct FacetCols {
    ok: bool,
    cols: array<vec4<f32>, 3>,
}

fn facet_cols(n: vec3<f32>, eye: vec3<f32>, d0: vec3<f32>, d1: vec3<f32>, d2: vec3<f32>) -> FacetCols {
    let ne = dot(n, eye);
    var f: FacetCols;
    f.cols = array<vec4<f32>, 3>(
        vec4<f32>(dot(n, d0) * eye - ne * d0, dot(n, d0)),
        vec4<f32>(dot(n, d1) * eye - ne * d1, dot(n, d1)),
        vec4<f32>(dot(n, d2) * eye - ne * d2, dot(n, d2)),
    );
    let mid = f.cols[0] * 0.5 + f.cols[1] * 0.5 + f.cols[2];
    f.ok = abs(mid.w) > 0.0;
    if mid.w < 0.0 {
        f.cols = array<vec4<f32>, 3>(-f.cols[0], -f.cols[1], -f.cols[2]);
    }
    return f;
}

// A facet's footprint in the light's map (texels) and its size; `ok`
// false when a corner is behind the camera or the light.
struct Footprint {
    ok: bool,
    lo: vec2<f32>,
    hi: vec2<f32>,
    diameter: f32,
}

fn facet_footprint(
    cols: array<vec4<f32>, 3>,
    eye: vec3<f32>,
    rays: array<vec3<f32>, 3>,
    point: vec3<f32>,
    light: Light,
) -> Footprint {
    var out: Footprint;
    out.ok = false;
    out.lo = vec2<f32>(1e30);
    out.hi = vec2<f32>(-1e30);
    out.diameter = 0.0;
    var first = vec3<f32>(0.0);
    for (var k = 0u; k < 4u; k++) {
        let s = vec2<f32>(f32(k & 1u), f32(k >> 1u));
        let x = cols[0] * s.x + cols[1] * s.y + cols[2];
        if !(x.w > 0.0) {
            return out;
        }
        let local = x.xyz / x.w;
        // In front of the camera, as Facet::new asks.
        if !(dot(local - eye, rays[0] * s.x + rays[1] * s.y + rays[2]) > 0.0) {
            return out;
        }
        if k == 0u {
            first = local;
        } else {
            out.diameter = max(out.diameter, distance(local, first));
        }
        let clip = light.clip_from_world * vec4<f32>(local + point, 1.0);
        if !(clip.w > 0.0) {
            return out;
        }
        let texel = to_texel(clip);
        out.lo = min(out.lo, texel);
        out.hi = max(out.hi, texel);
    }
    out.ok = true;
    return out;
}

// The tiles of a footprint: (first tile, last tile); x of the first > x of
// the last when the footprint misses the map.
fn footprint_tiles(fp: Footprint) -> vec4<i32> {
    let map = map_size();
    if any(fp.hi < vec2<f32>(0.0)) || any(fp.lo >= map) {
        return vec4<i32>(1, 0, 0, 0);
    }
    let last = vec2<i32>(i32(params.map_w) - 1, i32(params.map_h) - 1);
    let ta = clamp(vec2<i32>(floor(fp.lo)), vec2<i32>(0), last) / i32(TILE);
    let tb = clamp(vec2<i32>(floor(fp.hi)), vec2<i32>(0), last) / i32(TILE);
    return vec4<i32>(ta, tb);
}

// The list tiles of a footprint that meets the map (as `footprint_tiles`).
fn footprint_lists(fp: Footprint) -> vec4<i32> {
    let last = vec2<i32>(i32(params.map_w) - 1, i32(params.map_h) - 1);
    let ta = clamp(vec2<i32>(floor(fp.lo)), vec2<i32>(0), last) / i32(LIST_TILE);
    let tb = clamp(vec2<i32>(floor(fp.hi)), vec2<i32>(0), last) / i32(LIST_TILE);
    return vec4<i32>(ta, tb);
}

// Why a footprint's tiles cannot serve the exact path: 0 they can;
// STAT_WIDE (too many tiles, or one without a list); STAT_OVERFLOW (a list
// did not fit).
fn tiles_unusable(t: vec4<i32>) -> u32 {
    if u32((t.z - t.x + 1) * (t.w - t.y + 1)) > MAX_FOOTPRINT_TILES {
        return STAT_WIDE;
    }
    for (var ty = t.y; ty <= t.w; ty++) {
        for (var tx = t.x; tx <= t.z; tx++) {
            if !tile_active(vec2<i32>(tx, ty)) {
                return STAT_WIDE;
            }
        }
    }
    // The lists are laid out in index order: of the tiles' lists, the one
    // of the highest index ends furthest.
    let r = tiles_lists(t);
    let list = list_index(r.zw);
    if atomicLoad(&tile_words[offset_slot(list)]) + atomicLoad(&tile_words[count_slot(list)]) > params.capacity {
        return STAT_OVERFLOW;
    }
    return 0u;
}

// Whether list entry `tri` of list tile `tile` is tested for a footprint
// [lo, hi] (texels): the triangle's box grown by the lists' texel meets it,
// and `tile` is the list tile of the overlap's low corner. That list tile
// is one of the footprint's and lists the triangle (its box's list tiles
// hold the corner too, and the corner's TILE tile is one of the
// footprint's, all active), so every triangle whose box meets the footprint
// is tested exactly once. Always true with culling off (`params.cull` 0).
fn entry_meets(tri: u32, tile: vec2<i32>, lo: vec2<f32>, hi: vec2<f32>) -> bool {
    if params.cull == 0u {
        return true;
    }
    let b = stored_box(tri);
    let blo = b.xy - vec2<f32>(1.0);
    let bhi = b.zw + vec2<f32>(1.0);
    if any(blo > hi) || any(bhi < lo) {
        return false;
    }
    return all(texel_of(max(blo, lo)) / i32(LIST_TILE) == tile);
}

// The unit geometric normal of a triangle holding the pixel's point (the
// origin; `p` its texel position inside footprint list tiles `t`), turned
// towards `n`; `n` when none does. With culling on only triangles whose box
// (grown by a texel) holds `p`, in `p`'s list tile, are tried: a triangle within
// `tol` of the point projects within a texel of it unless `tol` exceeds a
// texel. Of several such triangles (a shared edge or vertex) the one of the
// lowest index: the tile lists' order comes from atomics and differs from
// run to run, and the first match would make the result differ with it.
fn face_normal(t_in: vec4<i32>, p: vec2<f32>, point: vec3<f32>, n: vec3<f32>, tol: f32) -> vec3<f32> {
    var t = t_in;
    if params.cull != 0u {
        let own = texel_of(p) / i32(LIST_TILE);
        t = vec4<i32>(own, own);
    }
    var best = 0xffffffffu;
    var normal = n;
    // As the exact scan (`visibility_exact`): one flat loop, BLOCK entries
    // culled per iteration, so that a long list stays within llvmpipe's
    // loop limit.
    var scan = list_scan(t);
    var hits = 0u;
    loop {
        if hits == 0u {
            let step = list_scan_step(&scan);
            if step == SCAN_DONE {
                break;
            }
            if step == SCAN_MOVED {
                continue;
            }
            hits = block_hits(scan.base, scan.n, scan.tile, p, p);
            if hits == 0u {
                continue;
            }
        }
        let tri = tile_list[scan.base + firstTrailingBit(hits)];
        hits &= hits - 1u;
        if tri >= best {
            continue;
        }
        let v0 = vertex(tri, 0u) - point;
        let v1 = vertex(tri, 1u) - point;
        let v2 = vertex(tri, 2u) - point;
        let g = cross(v1 - v0, v2 - v0);
        let scale = length(g);
        if scale > 0.0 && holds(v0, v1, v2, g, scale, tol) {
            best = tri;
            normal = g / scale * select(-1.0, 1.0, dot(g, n) >= 0.0);
        }
    }
    return normal;
}

// What a pixel's classification found: the facet on the masks' normal, its
// footprint and tiles; `exact` when a silhouette texel lies in the
// footprint (else the pixel keeps the standard bit).
struct Pixel {
    exact: bool,
    point: vec3<f32>,
    eye: vec3<f32>,
    rays: array<vec3<f32>, 3>,
    n: vec3<f32>,
    facet: FacetCols,
    fp: Footprint,
    t: vec4<i32>,
}

fn pixel_facet(id: u32, words: vec4<u32>, light: Light) -> Pixel {
    var out: Pixel;
    out.exact = false;
    let px = id % params.width;
    let py = id / params.width;
    let depth = bitcast<f32>(words.x);
    let size = vec2<f32>(f32(params.width), f32(params.height));
    let centre_ndc = vec2<f32>((f32(px) + 0.5) / size.x * 2.0 - 1.0, 1.0 - (f32(py) + 0.5) / size.y * 2.0);
    let hp = camera.world_from_clip * vec4<f32>(centre_ndc, depth, 1.0);
    out.point = hp.xyz / hp.w;
    let near = pixel_near(px, py, vec2<f32>(0.0), size);
    out.rays = array<vec3<f32>, 3>(
        pixel_near(px, py, vec2<f32>(1.0, 0.0), size) - near,
        pixel_near(px, py, vec2<f32>(0.0, 1.0), size) - near,
        near - camera.eye.xyz,
    );
    out.eye = camera.eye.xyz - out.point;
    // First the facet on the masks' (interpolated) normal: it decides
    // whether the pixel takes the exact path.
    out.n = unpack_normal(words.w);
    out.facet = facet_cols(out.n, out.eye, out.rays[0], out.rays[1], out.rays[2]);
    if !out.facet.ok {
        return out;
    }
    out.fp = facet_footprint(out.facet.cols, out.eye, out.rays, out.point, light);
    if !out.fp.ok {
        return out;
    }
    out.t = footprint_tiles(out.fp);
    out.exact = out.t.x <= out.t.z && rect_sum(vec2<i32>(floor(out.fp.lo)), vec2<i32>(floor(out.fp.hi))) > 0u;
    return out;
}

// The change of linear light depth from the pixel's point to `point +
// local` (no cancellation of two large distances).
fn depth_change(light: Light, point: vec3<f32>, local: vec3<f32>) -> f32 {
    let p = light.position;
    if p.w > 0.0 {
        let a = point - p.xyz;
        return dot(2.0 * a + local, local) / (length(a + local) + length(a)) * light.depth.y;
    }
    return dot(local, -p.xyz) * light.depth.y;
}

// Facet corner `s` of a pixel: its map position relative to the point's
// (texels, xy) and its linear light depth relative to the point's (z).
fn corner_in_map(pixel: Pixel, light: Light, s: vec2<f32>, centre: vec2<f32>) -> vec3<f32> {
    let cols = pixel.facet.cols;
    let x = cols[0] * s.x + cols[1] * s.y + cols[2];
    let local = x.xyz / x.w;
    let texel = to_texel(light.clip_from_world * vec4<f32>(local + pixel.point, 1.0));
    return vec3<f32>(texel - centre, depth_change(light, pixel.point, local));
}

// The receiver's linear-depth slope per map texel (the larger of the two
// axes, as the shadow pass's `dpdx`, `dpdy`), from its facet's footprint;
// negative when the footprint is degenerate (the facet edge-on to the light).
fn facet_depth_slope(pixel: Pixel, light: Light, centre: vec2<f32>) -> f32 {
    let c0 = corner_in_map(pixel, light, vec2<f32>(0.0, 0.0), centre);
    let e1 = corner_in_map(pixel, light, vec2<f32>(1.0, 0.0), centre) - c0;
    let e2 = corner_in_map(pixel, light, vec2<f32>(0.0, 1.0), centre) - c0;
    let det = e1.x * e2.y - e1.y * e2.x;
    if !(abs(det) > 1e-12) {
        return -1.0;
    }
    // The gradient g with g . e1.xy = e1.z and g . e2.xy = e2.z.
    let g = vec2<f32>(e1.z * e2.y - e2.z * e1.y, e1.x * e2.z - e2.x * e1.z) / det;
    return max(abs(g.x), abs(g.y));
}

// Whether the standard depth compare at a facing pixel whose footprint
// holds no silhouette texel may still be wrong: the map's depth s at the
// point's texel lies within the bias band of the receiver's depth r (or
// the facet's footprint is degenerate, so that the band is unknown). A
// surface grazing the light is not uncertain by itself (session 7 took
// every facing pixel within 5 degrees of grazing: lights 1-5 degrees above
// the horizon sent the whole floor, ~100 000 pixels, to the exact path,
// and the words it wrote scored exactly as the band test's alone on the
// default preset's four such lights and on quick). With the receiver's
// slope per texel σ and the bias its own plane gets, b = constant + slope
// scale × σ (clamped as the shadow pass clamps it), its own plane stores
// at that texel's centre (at most half a texel away on each axis)
// r + b ± σ. So s − r below max(b − 1.5σ, 0) means another surface wrote
// the texel from less than a bias above the receiver (a leak: the bias
// lights a shadowed point) or the receiver's own plane shadows itself
// (acne), and s − r above −(b + σ) means a shadowing writer lies within a
// bias of the receiver (a contact). Outside the band the compare is
// certain, the writer far from the receiver's own plane on one side.
fn depth_uncertain(pixel: Pixel, light: Light) -> bool {
    let m = map_position(light, pixel.point);
    if m.w == 0.0 {
        return false;
    }
    let sigma = facet_depth_slope(pixel, light, m.xy);
    if sigma < 0.0 {
        return true;
    }
    var b = params.depth_bias + params.slope_scale * sigma;
    if params.bias_clamp > 0.0 {
        b = min(b, params.bias_clamp);
    }
    let stored = textureLoad(shadow_maps, map_texel(light, m.xy), light.layer, 0).x;
    let r = clamp(linear_light_depth(light.position, light.depth.xy, pixel.point), 0.0, 1.0);
    let diff = stored - r;
    return diff > -(b + sigma) && diff < max(b - 1.5 * sigma, 0.0);
}

// Why a pixel may take the exact path (`classify` -> `visibility`).
const KIND_SILHOUETTE: u32 = 1u;
const KIND_UNCERTAIN: u32 = 2u;

// Classification, one invocation per pixel, before the lists: a facing
// pixel whose footprint holds a silhouette texel, or whose depth compare is
// uncertain (`depth_uncertain`; such a pixel also forces its footprint's
// tiles active), leaves its kind and footprint tiles in its two words for
// `visibility` (tile indices below 2^14: maps narrower than 2^17 texels);
// every other pixel leaves 0 in the first.
@compute @workgroup_size(64)
fn classify(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let id = flat_id(gid, groups);
    let pixels = params.width * params.height;
    if id >= pixels {
        return;
    }
    let out = params.light * pixels + id;
    occlusion[out] = 0u;
    let words = textureLoad(camera_masks, vec2<u32>(id % params.width, id / params.width), 0);
    if (words.z & (1u << params.light)) == 0u || bitcast<f32>(words.x) >= 1.0 {
        return;
    }
    let light = lights.items[params.light];
    let pixel = pixel_facet(id, words, light);
    let t = pixel.t;
    if !pixel.fp.ok || t.x > t.z {
        return;
    }
    var kind = KIND_SILHOUETTE;
    if !pixel.exact {
        if params.uncertain == 0u || u32((t.z - t.x + 1) * (t.w - t.y + 1)) > MAX_FOOTPRINT_TILES
            || !depth_uncertain(pixel, light) {
            return;
        }
        kind = KIND_UNCERTAIN;
        for (var ty = t.y; ty <= t.w; ty++) {
            for (var tx = t.x; tx <= t.z; tx++) {
                atomicStore(&tile_words[forced_slot(u32(ty) * params.tiles_x + u32(tx))], 1u);
            }
        }
    }
    occlusion[out] = u32(t.x) | (u32(t.y) << 14u) | (kind << 28u);
    occlusion[params.valid_base + out] = u32(t.z) | (u32(t.w) << 14u);
}

// After the lists, one invocation per pixel: every pixel gets its standard
// bit in every sample; a pixel `classify` found (a silhouette texel in its
// footprint or an uncertain depth compare) whose tiles can serve it is
// queued (its index appended to the queue in `tile_list`, counted in
// STAT_QUEUE) for `visibility_exact`, which then runs over the queued
// pixels only: they are a few percent of the screen and lie in runs along
// shadow edges, so the expensive path no longer runs in SIMD lanes beside
// pixels that left early.
@compute @workgroup_size(64)
fn visibility(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let id = flat_id(gid, groups);
    let pixels = params.width * params.height;
    if id >= pixels {
        return;
    }
    let words = textureLoad(camera_masks, vec2<u32>(id % params.width, id / params.width), 0);
    let standard = select(0u, ALL_SAMPLES, (words.y & (1u << params.light)) != 0u) & params.sample_mask;
    let out = params.light * pixels + id;
    let lo = occlusion[out];
    let hi = occlusion[params.valid_base + out];
    occlusion[out] = standard;
    occlusion[params.valid_base + out] = params.sample_mask;
    let kind = lo >> 28u;
    if kind == 0u {
        return;
    }
    let field = (1u << 14u) - 1u;
    let t = vec4<i32>(vec4<u32>(lo & field, (lo >> 14u) & field, hi & field, (hi >> 14u) & field));
    let why = tiles_unusable(t);
    if why != 0u {
        add_stat(why, 1u);
        return;
    }
    if kind == KIND_UNCERTAIN {
        add_stat(STAT_UNCERTAIN, 1u);
    }
    let slot = atomicAdd(&tile_words[params.light * STATS_PER_LIGHT + STAT_QUEUE], 1u);
    tile_list[params.queue_base + slot] = id;
}

// List entries culled per iteration of the exact scan (`block_hits`).
const BLOCK: u32 = 8u;

// Entry `u` of a block (from index `base` of `tile_list`, `n` entries) as
// bit `u` when it is in the block and `entry_meets` accepts it.
fn entry_hit(base: u32, u: u32, n: u32, tile: vec2<i32>, lo: vec2<f32>, hi: vec2<f32>) -> u32 {
    if u >= n {
        return 0u;
    }
    return select(0u, 1u << u, entry_meets(tile_list[base + u], tile, lo, hi));
}

// The entries of a block of at most BLOCK that `entry_meets` accepts, as
// bits; written out (no loop) so that the scan's iterations stay few.
fn block_hits(base: u32, n: u32, tile: vec2<i32>, lo: vec2<f32>, hi: vec2<f32>) -> u32 {
    return entry_hit(base, 0u, n, tile, lo, hi) | entry_hit(base, 1u, n, tile, lo, hi)
        | entry_hit(base, 2u, n, tile, lo, hi) | entry_hit(base, 3u, n, tile, lo, hi)
        | entry_hit(base, 4u, n, tile, lo, hi) | entry_hit(base, 5u, n, tile, lo, hi)
        | entry_hit(base, 6u, n, tile, lo, hi) | entry_hit(base, 7u, n, tile, lo, hi);
}

// A flat walk over the entries of list tiles `lists` (x0, y0, x1, y1, row
// by row), one step per loop iteration of its caller: a step either moves to
// the next list tile or hands out the next block of at most BLOCK entries
// (`base`, `n`) of the current one. The callers cull a block with
// `block_hits` and test its hits one per iteration, so that a scan takes
// about tests + entries / BLOCK + list tiles iterations (see
// `visibility_exact` on llvmpipe's loop limit).
struct ListScan {
    origin: vec2<i32>,
    span: i32,
    last: i32,
    li: i32,
    tile: vec2<i32>,
    start: u32,
    count: u32,
    k: u32,
    base: u32,
    n: u32,
}

fn list_scan(lists: vec4<i32>) -> ListScan {
    let span = lists.z - lists.x + 1;
    let tile = lists.xy;
    let list = list_index(tile);
    return ListScan(lists.xy, span, span * (lists.w - lists.y + 1) - 1, 0, tile,
        atomicLoad(&tile_words[offset_slot(list)]), atomicLoad(&tile_words[count_slot(list)]),
        0u, 0u, 0u);
}

// What a `list_scan_step` did.
const SCAN_DONE: u32 = 0u;
const SCAN_MOVED: u32 = 1u;
const SCAN_BLOCK_READY: u32 = 2u;

fn list_scan_step(s: ptr<function, ListScan>) -> u32 {
    if (*s).k >= (*s).count {
        if (*s).li >= (*s).last {
            return SCAN_DONE;
        }
        (*s).li += 1;
        (*s).tile = (*s).origin + vec2<i32>((*s).li % (*s).span, (*s).li / (*s).span);
        let list = list_index((*s).tile);
        (*s).start = atomicLoad(&tile_words[offset_slot(list)]);
        (*s).count = atomicLoad(&tile_words[count_slot(list)]);
        (*s).k = 0u;
        return SCAN_MOVED;
    }
    (*s).n = min(BLOCK, (*s).count - (*s).k);
    (*s).base = (*s).start + (*s).k;
    (*s).k += (*s).n;
    return SCAN_BLOCK_READY;
}

// Whether the walk ended before its last list tile's last entry.
fn list_scan_unfinished(s: ListScan) -> bool {
    return s.li < s.last || s.k < s.count;
}

// Whether triangle `tri` may hide a sample of pixel `xy` (its top-left
// corner) from the camera: its screen box meets the pixel grown by a
// quarter pixel. Its hidden samples are those whose view rays cross it, so
// they lie inside its screen projection up to the half-plane table's error
// (under 0.03 px), and the samples lie 1/16 px inside the pixel: a box
// that misses the grown pixel hides none, and the test can be skipped
// without changing a word. Always true with the gate off (`params.gate`).
fn on_screen_near(tri: u32, xy: vec2<f32>) -> bool {
    if params.gate == 0u {
        return true;
    }
    let b = load_box(params.screen_base + 4u * tri);
    return all(b.xy <= xy + vec2<f32>(1.25)) && all(b.zw >= xy - vec2<f32>(0.25));
}

// Whether facet point `s` (pixel-local) of a pixel lies inside a spot
// light's cone (`in_cone`, from the light's position without the facet
// frame's round trip through world coordinates).
fn facet_in_cone(cols: array<vec4<f32>, 3>, point: vec3<f32>, light: Light, s: vec2<f32>) -> bool {
    let x = cols[0] * s.x + cols[1] * s.y + cols[2];
    let to_world = (point - light.position.xyz) + x.xyz / x.w;
    return dot(light.spot.xyz, to_world) >= light.spot.w * length(to_world);
}

// The samples (of `params.sample_mask`) whose facet points a spot light's
// cone holds; every sample for other lights. Outside the cone a surface is
// unlit, not shadowed: the coverage truth leaves such samples out of its
// valid ones, as the standard lookup leaves a pixel whose centre lies
// outside out of the facing bits. The cone (half-angle below 90 degrees)
// and the facet (the image of the unit square) are convex, so when the
// facet's four corners lie inside, every sample does: only pixels at the
// cone's edge test their samples, in a loop of at most 32 iterations that
// runs before the scan (the loop limiter, see `visibility_exact`, cannot
// end it unseen: the scan after it would be cut short too and counted).
fn cone_samples(cols: array<vec4<f32>, 3>, point: vec3<f32>, light: Light) -> u32 {
    if light.spot.w < -1.0 {
        return params.sample_mask;
    }
    let corners = u32(facet_in_cone(cols, point, light, vec2<f32>(0.0, 0.0)))
        + u32(facet_in_cone(cols, point, light, vec2<f32>(1.0, 0.0)))
        + u32(facet_in_cone(cols, point, light, vec2<f32>(0.0, 1.0)))
        + u32(facet_in_cone(cols, point, light, vec2<f32>(1.0, 1.0)));
    if corners == 4u {
        return params.sample_mask;
    }
    // SAMPLE_POSITIONS (subpixel/mod.rs) is prepended by gpu.rs; a
    // function-scope copy for the runtime index.
    var positions = SAMPLE_POSITIONS;
    var word = 0u;
    for (var s = 0u; s < 32u; s++) {
        let bit = 1u << s;
        if (params.sample_mask & bit) != 0u && facet_in_cone(cols, point, light, positions[s]) {
            word |= bit;
        }
    }
    return word;
}

// The exact path, one invocation per queued pixel (an indirect dispatch
// sized by `exact_args` in gpu.rs; the last workgroup's invocations past
// the queue's length return at once).
@compute @workgroup_size(64)
fn visibility_exact(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let slot = flat_id(gid, groups);
    if slot >= atomicLoad(&tile_words[params.light * STATS_PER_LIGHT + STAT_QUEUE]) {
        return;
    }
    let id = tile_list[params.queue_base + slot];
    let words = textureLoad(camera_masks, vec2<u32>(id % params.width, id / params.width), 0);
    let light = lights.items[params.light];
    let pixel = pixel_facet(id, words, light);
    let point = pixel.point;
    let eye = pixel.eye;
    let rays = pixel.rays;
    let n = pixel.n;
    var facet = pixel.facet;
    var fp = pixel.fp;
    // Then Pan et al.'s facet: the plane of the triangle holding the
    // pixel's point (found among its tiles' triangles), when its footprint
    // is served by tiles as well.
    let centre = light.clip_from_world * vec4<f32>(point, 1.0);
    let p = clamp(to_texel(centre), fp.lo, fp.hi);
    let face = face_normal(footprint_lists(fp), p, point, n, params.bias + 0.01 * fp.diameter);
    if any(face != n) {
        let f = facet_cols(face, eye, rays[0], rays[1], rays[2]);
        if f.ok {
            let g = facet_footprint(f.cols, eye, rays, point, light);
            let gt = footprint_tiles(g);
            if g.ok && gt.x <= gt.z && tiles_unusable(gt) == 0u {
                facet = f;
                fp = g;
            }
        }
    }
    // Triangles holding the pixel's own point (its triangle) are skipped;
    // the others' planes are pushed away from the light by the scene bias
    // plus a hundredth of the facet's size (the depth buffer's error in the
    // reconstructed point).
    let bias = params.bias + 0.01 * fp.diameter;
    let l = vec4<f32>(light.position.xyz - point * light.position.w, light.position.w);
    // The eye in the facet's frame: a triangle between it and the facet
    // hides the samples behind it (the paper's validity mask).
    let e = vec4<f32>(eye, 1.0);
    // A spot light's cone, per sample (bits of the sample mask; before the
    // scan's loop).
    let cone = cone_samples(facet.cols, point, light);
    let pixel_xy = vec2<f32>(f32(id % params.width), f32(id / params.width));
    var occluded = 0u;
    var hidden = 0u;
    var tests = 0u;
    var scanned = 0u;
    // One flat loop over the footprint's list tiles, their entries culled
    // BLOCK at a time in straight-line code (`block_hits`) and the hits
    // tested one per iteration. llvmpipe and lavapipe end every loop of an
    // invocation once 65 535 loop iterations have run in it, all loops
    // together (gallivm's loop limiter; a nested scan of a wide footprint's
    // lists reached it and silently skipped the rest): this form takes
    // about tests + entries / BLOCK + list tiles iterations, and a scan that
    // still ends before its last list tile without every sample occluded
    // (cut short by such a limit) leaves the pixel its standard bit,
    // counted as wide.
    var scan = list_scan(footprint_lists(fp));
    var hits = 0u;
    var full = false;
    loop {
        if hits == 0u {
            let step = list_scan_step(&scan);
            if step == SCAN_DONE {
                break;
            }
            if step == SCAN_MOVED {
                continue;
            }
            hits = block_hits(scan.base, scan.n, scan.tile, fp.lo, fp.hi);
            scanned += scan.n;
            if hits == 0u {
                continue;
            }
        }
        let tri = tile_list[scan.base + firstTrailingBit(hits)];
        hits &= hits - 1u;
        tests += 1u;
        let v0 = vertex(tri, 0u) - point;
        let v1 = vertex(tri, 1u) - point;
        let v2 = vertex(tri, 2u) - point;
        occluded |= triangle_mask(v0, v1, v2, facet.cols, l, bias);
        if (occluded & params.sample_mask) == params.sample_mask {
            // The block's hits left untested are not counted as read.
            scanned -= countOneBits(hits);
            full = true;
            break;
        }
        if params.validity != 0u && on_screen_near(tri, pixel_xy) {
            hidden |= triangle_mask(v0, v1, v2, facet.cols, e, bias);
        }
    }
    if !full && (list_scan_unfinished(scan) || hits != 0u) {
        add_stat(STAT_WIDE, 1u);
        return;
    }
    add_stat(STAT_EXACT, 1u);
    add_stat(STAT_TESTS, tests);
    add_stat(STAT_SCANNED, scanned);
    let pixels = params.width * params.height;
    let out = params.light * pixels + id;
    occlusion[out] = occluded & params.sample_mask;
    // Samples outside a spot light's cone are never valid (`cone_samples`).
    // Every sample occluded: visibility 0 whatever is valid (and the walk
    // stopped early, in the lists' atomic order): all valid (in the cone).
    // Every sample hidden: no facet sample to trust; all valid (in the
    // cone; the occlusion as is). No sample in the cone (the pixel's centre
    // is, so only sampling misses the cone): all valid.
    var valid = ~hidden & cone;
    if (occluded & params.sample_mask) == params.sample_mask || valid == 0u {
        valid = cone;
    }
    if valid == 0u {
        valid = params.sample_mask;
    }
    occlusion[params.valid_base + out] = valid;
}
