// SGSM normal detection (the paper's algorithm 1): a compute pass after
// the conservative pass that sweeps one light's map in parallel lines one
// texel apart, one invocation per row, stepping one texel at a time. At
// each step it finds the triangle at the texel's right-hand corners (the
// left-hand ones come from the previous step), groups the four corners by
// plane (the paper's corner normals: the conservative pass's f16 slopes,
// plus the depth at the texel centre) and writes the texel's mask word
// (sgsm_common.wgsl). CPU reference: src/render/sgsm/sweep.rs.

struct SgsmSweep {
    // Map size in texels, its layer.
    size: vec2<u32>,
    layer: u32,
    _pad: u32,
}

@group(0) @binding(0) var<uniform> sgsm_sweep_params: SgsmSweep;
@group(0) @binding(1) var sgsm_in_texels: texture_2d_array<u32>;
@group(0) @binding(2) var sgsm_in_normals: texture_2d_array<u32>;
@group(0) @binding(3) var sgsm_out_masks: texture_storage_2d_array<r32uint, write>;

const SGSM_CONTAINS_EPS: f32 = 2e-3;
const SGSM_SLOPE_REL: f32 = 4e-3;
const SGSM_SLOPE_ABS: f32 = 1e-3;
const SGSM_DEPTH_EPS: f32 = 4e-5;
const SGSM_POKE_MARGIN: f32 = 1e-3;

// A stored triangle: the SPSM texel and its f16 slopes (per texel).
struct SgsmStored {
    // 0 triangle, 1 depth only, 2 empty (SpsmTexel.kind).
    kind: u32,
    texel: SpsmTexel,
    slopes: vec2<f32>,
}

fn sgsm_fetch(k: vec2<i32>) -> SgsmStored {
    var s: SgsmStored;
    let size = vec2<i32>(sgsm_sweep_params.size);
    if any(k < vec2<i32>(0)) || any(k >= size) {
        s.kind = 2u;
        return s;
    }
    let layer = sgsm_sweep_params.layer;
    let map_size = vec2<f32>(sgsm_sweep_params.size);
    // The shape only: the sweep reads the pass's f16 slopes, never the
    // packed gradient (same words; frame time unchanged on lavapipe, issue
    // 17 note, session 12).
    s.texel = spsm_decode_shape(textureLoad(sgsm_in_texels, k, layer, 0), k);
    s.kind = s.texel.kind;
    s.slopes = unpack2x16float(textureLoad(sgsm_in_normals, k, layer, 0).x) / map_size;
    return s;
}

// The decoded 3x3 neighbourhood of the texel being classified, slot
// (dy + 1) * 3 + dx + 1, as sgsm_slot_offset. Every texel a step reads (its
// own, the 3x3 slots, the four corners' 2x2 texels) lies in it, so a step
// decodes only the three texels of the column entering the window instead
// of ~30. Same words bit for bit (issue 17 note, session 6; the sweep is
// about a third of SGSM's frame on lavapipe, session 12).
var<private> sgsm_window: array<SgsmStored, 9>;
var<private> sgsm_window_centre: vec2<i32>;

fn sgsm_at(k: vec2<i32>) -> SgsmStored {
    return sgsm_window[sgsm_window_slot(k)];
}

// The window's slot of texel k: a ring over columns (session 14), column x
// in ring column (x + 3) % 3 (x >= -1), so a step overwrites the column that
// left the window instead of shifting the other two (six decoded texels
// copied per step; the corners index the window by data, so it likely sits
// in per-lane scratch memory on lavapipe and llvmpipe). Same words; the
// sweep's CPU time per frame at 1000² fell by a fifth to a third (issue-17
// note, session 14). Indexing the window by constants only was slower.
fn sgsm_window_slot(k: vec2<i32>) -> i32 {
    return (k.y - sgsm_window_centre.y + 1) * 3 + (k.x + 3) % 3;
}

// Centres the window on (x, y): the first texel of a row decodes all nine,
// each later one decodes the new right column into the left one's place.
fn sgsm_window_load(x: i32, y: i32) {
    sgsm_window_centre = vec2<i32>(x, y);
    for (var dy = 0; dy < 3; dy++) {
        for (var dx = 0; dx < 3; dx++) {
            let k = vec2<i32>(x + dx - 1, y + dy - 1);
            sgsm_window[sgsm_window_slot(k)] = sgsm_fetch(k);
        }
    }
}

fn sgsm_window_step() {
    sgsm_window_centre.x += 1;
    for (var dy = 0; dy < 3; dy++) {
        let k = sgsm_window_centre + vec2<i32>(1, dy - 1);
        sgsm_window[sgsm_window_slot(k)] = sgsm_fetch(k);
    }
}

fn sgsm_plane(s: SgsmStored, p: vec2<f32>) -> f32 {
    return s.texel.depth + dot(s.slopes, p - s.texel.centre);
}

// The corner at integer point c: x 0 triangle / 1 empty / 2 unknown, yz the
// texel holding its triangle.
fn sgsm_corner(c: vec2<i32>) -> vec3<i32> {
    let point = vec2<f32>(c);
    var best = 3.0e38;
    var found = vec2<i32>(0);
    var any_found = false;
    var unknown = false;
    for (var i = 0; i < 4; i++) {
        let k = c + vec2<i32>(i % 2 - 1, i / 2 - 1);
        let s = sgsm_at(k);
        if s.kind == 2u {
            return vec3<i32>(1, 0, 0);
        }
        if s.kind == 1u {
            unknown = true;
            continue;
        }
        if sgsm_contains(s.texel, point, SGSM_CONTAINS_EPS) {
            let depth = sgsm_plane(s, point);
            if !any_found || depth < best {
                best = depth;
                found = k;
                any_found = true;
            }
        }
    }
    if any_found && !unknown {
        return vec3<i32>(0, found);
    }
    return vec3<i32>(2, 0, 0);
}

fn sgsm_same_plane(a: vec2<i32>, b: vec2<i32>, at: vec2<f32>) -> bool {
    if all(a == b) {
        return true;
    }
    let sa = sgsm_at(a);
    let sb = sgsm_at(b);
    if sa.kind != 0u || sb.kind != 0u {
        return false;
    }
    let size = vec2<f32>(sgsm_sweep_params.size);
    let ea = sa.slopes * size;
    let eb = sb.slopes * size;
    let tol = max(abs(ea), abs(eb)) * SGSM_SLOPE_REL + SGSM_SLOPE_ABS;
    if any(abs(ea - eb) > tol) {
        return false;
    }
    let depth_tol = SGSM_DEPTH_EPS + 1.5e-3 * (abs(sa.slopes.x) + abs(sa.slopes.y) + abs(sb.slopes.x) + abs(sb.slopes.y));
    return abs(sgsm_plane(sa, at) - sgsm_plane(sb, at)) <= depth_tol;
}

// Whether the stored triangle overlaps the texel box at `c` shrunk by
// SGSM_POKE_MARGIN (separating axes, as packing::texel_touches).
fn sgsm_reaches_into(t: SpsmTexel, c: vec2<f32>) -> bool {
    let h = 0.5 - SGSM_POKE_MARGIN;
    let lo = min(t.v0, min(t.v1, t.v2));
    let hi = max(t.v0, max(t.v1, t.v2));
    if any(lo > c + h) || any(hi < c - h) {
        return false;
    }
    let orient = sign(spsm_cross(t.v1 - t.v0, t.v2 - t.v0));
    if orient == 0.0 {
        let d = t.v1 - t.v0;
        let n = vec2<f32>(-d.y, d.x);
        return abs(dot(n, c - t.v0)) <= h * (abs(n.x) + abs(n.y));
    }
    var v = array<vec2<f32>, 3>(t.v0, t.v1, t.v2);
    for (var k = 0u; k < 3u; k++) {
        let a = v[k];
        let b = v[(k + 1u) % 3u];
        let n = orient * vec2<f32>(b.y - a.y, a.x - b.x);
        if dot(n, c - a) - h * (abs(n.x) + abs(n.y)) > 0.0 {
            return false;
        }
    }
    return true;
}

fn sgsm_classify(k: vec2<i32>, corners: array<vec3<i32>, 4>) -> u32 {
    let own = sgsm_at(k);
    if own.kind == 2u {
        return 0u;
    }
    var codes = vec4<u32>(SGSM_CORNER_UNKNOWN);
    if own.kind == 1u {
        return sgsm_word(0u, SGSM_UNRECOGNISED, 0u, codes);
    }
    var unknown = false;
    for (var q = 0u; q < 4u; q++) {
        let c = corners[q];
        if c.x == 1 {
            codes[q] = SGSM_CORNER_EMPTY;
        } else if c.x == 2 {
            unknown = true;
        } else {
            let d = c.yz - k;
            codes[q] = u32((d.y + 1) * 3 + d.x + 1);
        }
    }
    let centre = vec2<f32>(k) + 0.5;
    // The 3x3 slots whose stored triangles reach into the texel.
    var slots = 0u;
    for (var slot = 0u; slot < 9u; slot++) {
        let s = sgsm_at(k + sgsm_slot_offset(slot));
        if s.kind == 0u && sgsm_reaches_into(s.texel, centre) {
            slots |= 1u << slot;
        }
    }
    if unknown {
        return sgsm_word(slots, SGSM_UNRECOGNISED, 0u, codes);
    }
    var labels = vec4<u32>(4u);
    var planes = 0u;
    var has_empty = false;
    for (var q = 0u; q < 4u; q++) {
        if corners[q].x != 0 {
            has_empty = true;
            continue;
        }
        labels[q] = q;
        for (var r = 0u; r < q; r++) {
            if corners[r].x == 0 && sgsm_same_plane(corners[r].yz, corners[q].yz, centre) {
                labels[q] = labels[r];
                break;
            }
        }
        if labels[q] == q {
            planes++;
        }
    }
    // Every stored triangle of the 3x3 reaching into the texel must lie on
    // a corner plane (else geometry reaching no corner pokes into it).
    var explained = true;
    for (var slot = 0u; slot < 9u && explained; slot++) {
        if (slots & (1u << slot)) == 0u {
            continue;
        }
        let t = k + sgsm_slot_offset(slot);
        var on_corner_plane = false;
        for (var q = 0u; q < 4u; q++) {
            on_corner_plane = on_corner_plane || (corners[q].x == 0 && sgsm_same_plane(corners[q].yz, t, centre));
        }
        explained = on_corner_plane;
    }
    var status = SGSM_PATTERN;
    if planes == 0u || !explained {
        status = SGSM_UNRECOGNISED;
    } else if planes == 1u && !has_empty {
        status = SGSM_FULL;
    }
    return sgsm_word(slots, status, sgsm_pattern_index(labels), codes);
}

// Texels per invocation: a row is swept in segments of this many texels,
// one invocation each (SEGMENT in src/render/sgsm/gpu.rs). The CPU backends
// (llvmpipe, lavapipe) end every loop of an invocation once it has run
// 65 535 loop iterations, all loops together; a texel costs up to ≈ 230
// (its loops counted as written), so a whole 1024-texel row was cut near
// its middle. 128 texels stay below ≈ 30 000. The segment starts as a row
// did (window and corners loaded at its first texel), so the words are the
// same.
const SGSM_SEGMENT: i32 = 128;

@compute @workgroup_size(64)
fn sgsm_sweep(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = vec2<i32>(sgsm_sweep_params.size);
    let y = i32(id.x);
    let start = i32(id.y) * SGSM_SEGMENT;
    if y >= size.y || start >= size.x {
        return;
    }
    let end = min(start + SGSM_SEGMENT, size.x);
    sgsm_window_load(start, y);
    var top = sgsm_corner(vec2<i32>(start, y));
    var bottom = sgsm_corner(vec2<i32>(start, y + 1));
    for (var x = start; x < end; x++) {
        if x > start {
            sgsm_window_step();
        }
        let next_top = sgsm_corner(vec2<i32>(x + 1, y));
        let next_bottom = sgsm_corner(vec2<i32>(x + 1, y + 1));
        let word = sgsm_classify(vec2<i32>(x, y), array<vec3<i32>, 4>(top, next_top, bottom, next_bottom));
        textureStore(sgsm_out_masks, vec2<i32>(x, y), sgsm_sweep_params.layer, vec4<u32>(word, 0u, 0u, 0u));
        top = next_top;
        bottom = next_bottom;
    }
}
