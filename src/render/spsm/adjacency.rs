//! Edge adjacency of the scene's meshes for the SPSM pass (issue 16,
//! session 7): per index slot, the slot of the vertex across the edge that
//! starts at that corner, so that the pass can tell a light silhouette edge
//! (the neighbour faces the other way, or there is none) from an edge inside
//! a curved caster's lit side, whose unstored neighbour facet continues the
//! caster (`shaders/spsm_pass.wgsl`, `spsm_inner_edges`).

use std::collections::HashMap;

use glam::Vec3;

/// Marks an edge with no single neighbour (a border or a non-manifold edge).
pub(crate) const NO_NEIGHBOUR: u32 = u32::MAX;

/// For each index slot `s` of `indices` (a triangle list over `positions`),
/// the index slot, offset by `first_slot`, of the vertex opposite edge
/// `corner(s) -> corner(s) + 1` in the one other triangle sharing that edge,
/// or [`NO_NEIGHBOUR`]. Edges are matched by their end positions (bit
/// patterns), so meshes that repeat vertices for flat normals still connect;
/// an edge shared by more than two triangles has no neighbour.
pub(crate) fn opposite_slots(positions: &[Vec3], indices: &[u32], first_slot: u32) -> Vec<u32> {
    let key = |i: u32| positions.get(i as usize).map(|p| p.to_array().map(f32::to_bits));
    let mut edges: HashMap<([u32; 3], [u32; 3]), Vec<usize>> = HashMap::new();
    for s in 0..indices.len() - indices.len() % 3 {
        let next = s - s % 3 + (s + 1) % 3;
        if let (Some(a), Some(b)) = (key(indices[s]), key(indices[next])) {
            if a != b {
                edges.entry(if a < b { (a, b) } else { (b, a) }).or_default().push(s);
            }
        }
    }
    let mut out = vec![NO_NEIGHBOUR; indices.len()];
    for slots in edges.values() {
        if let [a, b] = slots[..] {
            if a / 3 != b / 3 {
                // The vertex after the edge's end in each triangle.
                let opposite = |s: usize| (s - s % 3 + (s + 2) % 3) as u32 + first_slot;
                out[a] = opposite(b);
                out[b] = opposite(a);
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_quad_has_one_inner_edge() {
        // Two triangles of a unit quad, the second repeating its vertices.
        let positions = [
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
        ];
        let adjacent = opposite_slots(&positions, &[0, 1, 2, 3, 4, 5], 10);
        // Edge 1 -> 2 of the first triangle (slot 2 -> 0 is its third edge:
        // 2 -> 0 runs (1,1) -> (0,0)), shared with the second's 3 -> 4.
        assert_eq!(adjacent, vec![NO_NEIGHBOUR, NO_NEIGHBOUR, 15, 11, NO_NEIGHBOUR, NO_NEIGHBOUR]);
    }

    #[test]
    fn a_fin_has_no_neighbour() {
        // Three triangles on one edge (0,0)-(1,0): non-manifold.
        let positions = [Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z, Vec3::new(0.0, -1.0, 0.0)];
        let adjacent = opposite_slots(&positions, &[0, 1, 2, 1, 0, 3, 0, 1, 4], 0);
        assert!(adjacent.iter().all(|&a| a == NO_NEIGHBOUR));
    }
}
