//! CPU references for the GPU stages of the antialiased lookup (Pan et al.
//! 2009, sections 3.2 and 3.3), small enough to check a GPU implementation
//! against on tiny maps: silhouette edges from the mesh's edge adjacency,
//! the summed-area table over a silhouette mask, and the separating-axis
//! test that keeps a pixel-texel pair only when the projected facet really
//! overlaps the texel.

use std::collections::HashMap;

use glam::{DVec2, DVec4, Vec3};

use crate::mesh::Mesh;

/// The triangles on each side of every edge, computed once per mesh.
/// Vertices are matched by position, snapped to a grid of `1e-6` of the
/// mesh's diagonal (meshes split vertices along normal and texture seams,
/// and a seam's two copies may differ in the last bits, as the UV sphere's
/// `sin(2π)` does), so a seam is not taken for a boundary.
#[derive(Clone, Debug, Default)]
pub struct EdgeAdjacency {
    /// Per edge: its two end points and the triangles holding it (one for
    /// a boundary edge; more than two on non-manifold edges).
    edges: Vec<([Vec3; 2], Vec<u32>)>,
}

impl EdgeAdjacency {
    /// Builds the adjacency of `mesh` (out-of-range indices and triangles
    /// without area, which face no side, are skipped).
    #[must_use]
    pub fn new(mesh: &Mesh) -> Self {
        let cell = mesh.bounds().map_or(1.0, |b| b.diagonal()).max(f64::MIN_POSITIVE) * 1e-6;
        let key = |v: Vec3| v.as_dvec3().to_array().map(|x| (x / cell).round() as i64);
        let mut index: HashMap<([i64; 3], [i64; 3]), usize> = HashMap::new();
        let mut edges: Vec<([Vec3; 2], Vec<u32>)> = Vec::new();
        for (t, tri) in mesh.indices.chunks_exact(3).enumerate() {
            let Some(v) = tri.iter().map(|&i| mesh.positions.get(i as usize).copied()).collect::<Option<Vec<_>>>()
            else {
                continue;
            };
            if (v[1] - v[0]).cross(v[2] - v[0]).length_squared() == 0.0 {
                continue;
            }
            for (a, b) in [(v[0], v[1]), (v[1], v[2]), (v[2], v[0])] {
                let (ka, kb) = (key(a), key(b));
                let k = if ka <= kb { (ka, kb) } else { (kb, ka) };
                let e = *index.entry(k).or_insert_with(|| {
                    edges.push(([a, b], Vec::new()));
                    edges.len() - 1
                });
                edges[e].1.push(t as u32);
            }
        }
        Self { edges }
    }

    /// Every edge: its two end points and the triangles holding it.
    pub fn edges(&self) -> impl Iterator<Item = ([Vec3; 2], &[u32])> {
        self.edges.iter().map(|(e, tris)| (*e, tris.as_slice()))
    }

    /// Number of distinct edges.
    #[must_use]
    pub fn len(&self) -> usize {
        self.edges.len()
    }

    /// Whether the mesh had no edges.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.edges.is_empty()
    }

    /// The silhouette edges for `light` (homogeneous: `(p, 1)` or `(-d, 0)`):
    /// boundary edges, and edges whose triangles face the light on one side
    /// and away from it on the other (non-manifold edges count when their
    /// triangles disagree).
    #[must_use]
    pub fn silhouette(&self, mesh: &Mesh, light: DVec4) -> Vec<[Vec3; 2]> {
        let faces_light = |t: u32| {
            let k = 3 * t as usize;
            let [a, b, c] = [0, 1, 2].map(|i| mesh.positions[mesh.indices[k + i] as usize].as_dvec3());
            let n = (b - a).cross(c - a);
            let to_light = light.truncate() - a * light.w;
            n.dot(to_light) > 0.0
        };
        self.edges
            .iter()
            .filter(|(_, tris)| {
                tris.len() == 1 || {
                    let first = faces_light(tris[0]);
                    tris[1..].iter().any(|&t| faces_light(t) != first)
                }
            })
            .map(|(e, _)| *e)
            .collect()
    }
}

/// The inclusive summed-area table of a `width x height` mask (row-major,
/// row 0 first): entry `(x, y)` is the sum of every mask value at or above
/// and left of it.
#[must_use]
pub fn summed_area(mask: &[u32], width: usize, height: usize) -> Vec<u32> {
    let mut sat = vec![0u32; width * height];
    for y in 0..height {
        let mut row = 0u32;
        for x in 0..width {
            row += mask[y * width + x];
            sat[y * width + x] = row + if y > 0 { sat[(y - 1) * width + x] } else { 0 };
        }
    }
    sat
}

/// The sum of the mask over texels `[x0, x1] x [y0, y1]` (inclusive) from
/// its summed-area table: four reads.
#[must_use]
pub fn rect_sum(sat: &[u32], width: usize, (x0, y0): (usize, usize), (x1, y1): (usize, usize)) -> u32 {
    let at = |x: usize, y: usize| sat[y * width + x];
    // Wrapping: the partial sums may dip below zero; the total cannot.
    let mut sum = at(x1, y1);
    if x0 > 0 {
        sum = sum.wrapping_sub(at(x0 - 1, y1));
    }
    if y0 > 0 {
        sum = sum.wrapping_sub(at(x1, y0 - 1));
    }
    if x0 > 0 && y0 > 0 {
        sum = sum.wrapping_add(at(x0 - 1, y0 - 1));
    }
    sum
}

/// Whether the convex polygon `poly` (in texel units, either winding)
/// overlaps texel `(x, y)` (the square `[x, x + 1] x [y, y + 1]`). By the
/// separating-axis theorem only the texel's two axes and the polygon's
/// edge normals need testing; the paper skips the texel's when the texel
/// lies in the polygon's bounding rectangle.
#[must_use]
pub fn polygon_overlaps_texel(poly: &[DVec2], x: i64, y: i64) -> bool {
    let lo = DVec2::new(x as f64, y as f64);
    let corners = [lo, lo + DVec2::X, lo + DVec2::Y, lo + DVec2::ONE];
    let separated = |axis: DVec2| {
        let project = |pts: &mut dyn Iterator<Item = DVec2>| {
            pts.map(|p| axis.dot(p)).fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| (a.min(v), b.max(v)))
        };
        let (p0, p1) = project(&mut poly.iter().copied());
        let (t0, t1) = project(&mut corners.iter().copied());
        p1 < t0 || t1 < p0
    };
    if separated(DVec2::X) || separated(DVec2::Y) {
        return false;
    }
    (0..poly.len()).all(|i| {
        let edge = poly[(i + 1) % poly.len()] - poly[i];
        edge == DVec2::ZERO || !separated(edge.perp())
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::primitives;

    #[test]
    fn a_closed_mesh_has_no_boundary_and_a_sphere_a_silhouette_loop() {
        let sphere = primitives::sphere(1.0, 800);
        let adjacency = EdgeAdjacency::new(&sphere);
        assert!(!adjacency.is_empty());
        // Lit from far above: the silhouette runs around the equator.
        let edges = adjacency.silhouette(&sphere, DVec4::new(0.0, 100.0, 0.0, 1.0));
        assert!(!edges.is_empty());
        for [a, b] in &edges {
            assert!(a.y.abs() < 0.35 && b.y.abs() < 0.35, "{a} {b}");
        }
        // Every vertex of a closed loop has an even number of silhouette edges.
        let mut degree: HashMap<[i64; 3], usize> = HashMap::new();
        for e in &edges {
            for v in e {
                *degree.entry(v.as_dvec3().to_array().map(|x| (x * 1e5).round() as i64)).or_default() += 1;
            }
        }
        assert!(degree.values().all(|d| d % 2 == 0), "{degree:?}");
    }

    #[test]
    fn every_edge_of_a_lone_triangle_is_a_silhouette() {
        let mesh =
            Mesh { positions: vec![Vec3::ZERO, Vec3::X, Vec3::Z], normals: vec![Vec3::Y; 3], indices: vec![0, 1, 2] };
        let adjacency = EdgeAdjacency::new(&mesh);
        assert_eq!(adjacency.len(), 3);
        assert_eq!(adjacency.silhouette(&mesh, DVec4::new(0.0, -1.0, 0.0, 0.0)).len(), 3);
    }

    #[test]
    fn summed_area_rectangles_match_direct_sums() {
        let (w, h) = (13usize, 7usize);
        let mask: Vec<u32> = (0..w * h).map(|i| u32::from((i * 7 + i / 5) % 3 == 0)).collect();
        let sat = summed_area(&mask, w, h);
        for y0 in 0..h {
            for y1 in y0..h {
                for x0 in 0..w {
                    for x1 in x0..w {
                        let direct: u32 =
                            (y0..=y1).flat_map(|y| (x0..=x1).map(move |x| (x, y))).map(|(x, y)| mask[y * w + x]).sum();
                        assert_eq!(rect_sum(&sat, w, (x0, y0), (x1, y1)), direct);
                    }
                }
            }
        }
    }

    #[test]
    fn separating_axes_find_overlaps_of_a_thin_diagonal_quad() {
        // A thin quad along the diagonal: its bounding box holds texels it misses.
        let quad = [DVec2::new(0.2, 0.0), DVec2::new(4.0, 3.8), DVec2::new(3.8, 4.0), DVec2::new(0.0, 0.2)];
        assert!(polygon_overlaps_texel(&quad, 0, 0));
        assert!(polygon_overlaps_texel(&quad, 2, 2));
        assert!(!polygon_overlaps_texel(&quad, 3, 0), "off the diagonal, inside the bounding box");
        assert!(!polygon_overlaps_texel(&quad, 0, 3));
        // Against dense point sampling of the texel.
        for x in 0..4 {
            for y in 0..4 {
                let inside = |p: DVec2| {
                    (0..4).all(|i| {
                        let (a, b) = (quad[i], quad[(i + 1) % 4]);
                        (b - a).perp_dot(p - a) >= 0.0
                    })
                };
                let sampled = (0..=40).any(|i| {
                    (0..=40).any(|j| inside(DVec2::new(x as f64 + i as f64 / 40.0, y as f64 + j as f64 / 40.0)))
                });
                if sampled {
                    assert!(polygon_overlaps_texel(&quad, x, y), "texel ({x}, {y})");
                }
            }
        }
    }
}
