// SGSM lookup: `in_shadow` of the lookup mode ShadowLookup::Sgsm, after
// common.wgsl, spsm_common.wgsl, spsm_lookup.wgsl (whose in_shadow the
// renderer renames spsm_in_shadow: the fallback), the pattern tables and
// sgsm_common.wgsl. The renderer also prepends `sgsm_count(path)`, which
// adds one to a path's counter when counting is on (SgsmOptions).
//
// For a receiver p (texel position, depth zeta = z / w):
// 1. own texel empty -> lit; depth-only -> its depth; p inside the own
//    stored triangle -> its plane decides (as SPSM);
// 2. the sweep's word says the texel lies on one plane (full) -> that
//    plane (corner 0's triangle) decides;
// 3. a recognised pattern (every stored triangle reaching into the texel
//    lies on a corner plane): of the participating triangles (the word's
//    slot bits) those containing p; the nearest one's plane decides (each
//    plane's packing tolerance counted, so p is shadowed exactly when one
//    of them is in front of it);
// 4. otherwise (unrecognised, or p on none of them) SPSM's lookup.

@group(1) @binding(2) var sgsm_masks: texture_2d_array<u32>;

const SGSM_PATH_OUTSIDE: u32 = 0u;
const SGSM_PATH_EMPTY: u32 = 1u;
const SGSM_PATH_DEPTH_ONLY: u32 = 2u;
const SGSM_PATH_OWN: u32 = 3u;
const SGSM_PATH_FULL: u32 = 4u;
const SGSM_PATH_PATTERN: u32 = 5u;
const SGSM_PATH_FALLBACK: u32 = 6u;

fn sgsm_plane_test(t: SpsmTexel, p: vec2<f32>, zeta: f32) -> bool {
    let plane = spsm_plane_at(t, p);
    return plane.x < zeta - SPSM_BIAS - SPSM_TOLERANCE * plane.y;
}

fn in_shadow(light: Light, world: vec3<f32>) -> bool {
    let m = map_position(light, world);
    if m.w == 0.0 {
        sgsm_count(SGSM_PATH_OUTSIDE);
        return false;
    }
    let p = m.xy;
    let k = map_texel(light, p);
    let zeta = m.z;
    let own = spsm_load(light, k);
    if own.kind == 2u {
        sgsm_count(SGSM_PATH_EMPTY);
        return false;
    }
    if own.kind == 1u {
        sgsm_count(SGSM_PATH_DEPTH_ONLY);
        return spsm_decide(light, k, world, SPSM_PATH_DEPTH_ONLY, own.depth < zeta - SPSM_BIAS);
    }
    // The own triangle's parallelogram partner (issue 16, session 14) only
    // where its plane is in front of p, as in spsm_lookup.wgsl.
    if spsm_inside(own, p) || (spsm_in_partner(own, p) && sgsm_plane_test(own, p, zeta)) {
        sgsm_count(SGSM_PATH_OWN);
        return spsm_decide(light, k, world, SPSM_PATH_OWN, sgsm_plane_test(own, p, zeta));
    }
    let word = textureLoad(sgsm_masks, k, light.layer, 0).x;
    let status = (word >> 9u) & 3u;
    if status == SGSM_FULL {
        let slot = (word >> 15u) & 15u;
        let full = sgsm_plane_test(spsm_load(light, k + sgsm_slot_offset(slot)), p, zeta);
        if full || spsm_other_surface_lit(own, p, zeta) {
            sgsm_count(SGSM_PATH_FULL);
            return spsm_decide(light, k, world, select(SGSM_PATH_PLANE_LIT, SGSM_PATH_PLANE_SHADOWED, full), full);
        }
    }
    if status == SGSM_PATTERN {
        // Every triangle reaching into the texel is on a corner plane: the
        // nearest participating one containing p decides.
        var best = 3.0e38;
        var found = false;
        for (var slot = 0u; slot < 9u; slot++) {
            if (word & (1u << slot)) == 0u {
                continue;
            }
            let t = spsm_load(light, k + sgsm_slot_offset(slot));
            if t.kind == 0u && (sgsm_contains(t, p, 0.0) || (spsm_in_partner(t, p) && sgsm_plane_test(t, p, zeta))) {
                // Nearest counting each plane's packing tolerance: shadowed
                // exactly when some containing plane is in front of p.
                let plane = spsm_plane_at(t, p);
                let depth = plane.x + SPSM_TOLERANCE * plane.y;
                if !found || depth < best {
                    best = depth;
                    found = true;
                }
            }
        }
        if found && (best < zeta - SPSM_BIAS || spsm_other_surface_lit(own, p, zeta)) {
            sgsm_count(SGSM_PATH_PATTERN);
            let shadowed = best < zeta - SPSM_BIAS;
            return spsm_decide(light, k, world, select(SGSM_PATH_PLANE_LIT, SGSM_PATH_PLANE_SHADOWED, shadowed), shadowed);
        }
    }
    sgsm_count(SGSM_PATH_FALLBACK);
    return spsm_in_shadow(light, world);
}
