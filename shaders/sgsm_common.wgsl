// Sub-geometry shadow maps (SGSM): what the sweep (sgsm_sweep.wgsl) and the
// lookup (sgsm_lookup.wgsl) share. After spsm_common.wgsl and the pattern
// tables SGSM_PATTERNS / SGSM_GROUPS, which the renderer generates from
// src/render/sgsm/pattern.rs (its CPU mirror; see there for the layout).
//
// Mask word (one per texel, written by the sweep):
//   bits 0..9    3x3 slots (3 (dy + 1) + dx + 1) whose stored triangles
//                reach into the texel (take part);
//   bits 9..11   status: 0 empty, 1 full (one plane), 2 pattern,
//                3 unrecognised (the lookup falls back to SPSM);
//   bits 11..15  pattern index (a partition of the four corners by plane);
//   bits 15..31  corner q's slot in bits 15 + 4q (9: empty, 10: unknown).
// Corners: 0 top-left, 1 top-right, 2 bottom-left, 3 bottom-right.

const SGSM_FULL: u32 = 1u;
const SGSM_PATTERN: u32 = 2u;
const SGSM_UNRECOGNISED: u32 = 3u;
const SGSM_CORNER_EMPTY: u32 = 9u;
const SGSM_CORNER_UNKNOWN: u32 = 10u;

// Private copies: dynamically indexed (const arrays are not, on every backend).
var<private> sgsm_patterns: array<u32, 15> = SGSM_PATTERNS;
var<private> sgsm_groups: array<u32, 15> = SGSM_GROUPS;

fn sgsm_word(slots: u32, status: u32, pattern: u32, corners: vec4<u32>) -> u32 {
    var codes = 0u;
    for (var q = 0u; q < 4u; q++) {
        codes |= (corners[q] & 15u) << (15u + 4u * q);
    }
    return (slots & 0x1ffu) | (status << 9u) | ((pattern & 15u) << 11u) | codes;
}

// The pattern index of four corner labels (equal labels: one group).
fn sgsm_pattern_index(labels: vec4<u32>) -> u32 {
    // Canonical restricted growth string, two bits per corner.
    var seen = vec4<u32>(0u);
    var count = 0u;
    var rgs = 0u;
    for (var q = 0u; q < 4u; q++) {
        var k = count;
        for (var r = 0u; r < count; r++) {
            if seen[r] == labels[q] {
                k = r;
                break;
            }
        }
        if k == count {
            seen[count] = labels[q];
            count++;
        }
        rgs |= k << (2u * q);
    }
    for (var i = 0u; i < 15u; i++) {
        if sgsm_patterns[i] == rgs {
            return i;
        }
    }
    return 0u;
}

fn sgsm_slot_offset(slot: u32) -> vec2<i32> {
    return vec2<i32>(i32(slot % 3u) - 1, i32(slot / 3u) - 1);
}

// Whether `p` is inside the stored triangle or within `eps` texels of it
// (never for a degenerate one).
fn sgsm_contains(t: SpsmTexel, p: vec2<f32>, eps: f32) -> bool {
    let area = spsm_cross(t.v1 - t.v0, t.v2 - t.v0);
    if abs(area) < 1e-6 {
        return false;
    }
    var v = array<vec2<f32>, 3>(t.v0, t.v1, t.v2);
    for (var k = 0u; k < 3u; k++) {
        let a = v[k];
        let edge = v[(k + 1u) % 3u] - a;
        if sign(area) * spsm_cross(edge, p - a) / length(edge) < -eps {
            return false;
        }
    }
    return true;
}
