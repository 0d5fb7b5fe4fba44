//! A CPU reference of what SGSM tries to recover: the exact list of
//! triangles touching each texel (from the mesh, not from a map), the
//! triangle a conservative pass keeps there (smallest consistent depth),
//! the triangles actually visible from the light inside the texel, and the
//! share of texels whose visible triangles the normal detection
//! recognises ([`detection`]).
//!
//! Everything is in the matrix's texel space with post-projective depth
//! `zeta = z / w`, as the SPSM and SGSM passes; triangles crossing the
//! light's `w = 0` plane are left out (the passes store them depth-only).

use glam::DVec2;

use super::pattern::{MaskWord, Status};
use super::sweep::{Stored, SweepMap, SweepTexel};
use crate::mesh::Scene;
use crate::render::spsm::packing::{self, DecodedTexel};
use crate::LightMatrix;

/// One scene triangle in texel space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Projected {
    /// Vertices in texels (x right, y down).
    pub vertices: [DVec2; 3],
    /// Post-projective depth at each vertex.
    pub zeta: [f64; 3],
}

impl Projected {
    /// Depth gradient per texel; `None` for a triangle seen edge-on.
    #[must_use]
    pub fn gradient(&self) -> Option<DVec2> {
        let [t0, t1, t2] = self.vertices;
        let (e1, e2) = (t1 - t0, t2 - t0);
        let det = e1.perp_dot(e2);
        if det.abs() < 1e-12 {
            return None;
        }
        let (d1, d2) = (self.zeta[1] - self.zeta[0], self.zeta[2] - self.zeta[0]);
        Some(DVec2::new(d1 * e2.y - d2 * e1.y, d2 * e1.x - d1 * e2.x) / det)
    }

    /// The plane's depth at `p`.
    #[must_use]
    pub fn depth_at(&self, p: DVec2) -> f64 {
        self.zeta[0] + self.gradient().unwrap_or(DVec2::ZERO).dot(p - self.vertices[0])
    }

    /// Whether `p` lies in the (closed) triangle.
    #[must_use]
    pub fn contains(&self, p: DVec2) -> bool {
        let v = self.vertices;
        let area = (v[1] - v[0]).perp_dot(v[2] - v[0]);
        area != 0.0 && (0..3).all(|k| area * (v[(k + 1) % 3] - v[k]).perp_dot(p - v[k]) >= 0.0)
    }

    /// The consistent minimum depth over the part of texel `k` the triangle
    /// covers (the triangle clipped to the texel box); `None` when it does
    /// not reach inside.
    #[must_use]
    pub fn min_depth_in(&self, k: [i64; 2]) -> Option<f64> {
        let lo = DVec2::new(k[0] as f64, k[1] as f64);
        let hi = lo + 1.0;
        let mut poly: Vec<DVec2> = self.vertices.to_vec();
        for plane in 0..4 {
            let dist = |p: DVec2| match plane {
                0 => p.x - lo.x,
                1 => hi.x - p.x,
                2 => p.y - lo.y,
                _ => hi.y - p.y,
            };
            let mut next = Vec::with_capacity(poly.len() + 2);
            for i in 0..poly.len() {
                let (p, q) = (poly[i], poly[(i + 1) % poly.len()]);
                let (dp, dq) = (dist(p), dist(q));
                if dp >= 0.0 {
                    next.push(p);
                }
                if (dp >= 0.0) != (dq >= 0.0) {
                    next.push(p + (q - p) * (dp / (dp - dq)));
                }
            }
            poly = next;
            if poly.is_empty() {
                return None;
            }
        }
        poly.iter().map(|p| self.depth_at(*p)).reduce(f64::min)
    }
}

/// The scene's triangles in `m`'s texel space (those in front of the
/// light's `w = 0` plane), with their indices into the scene's triangle list.
#[must_use]
pub fn project(scene: &Scene, m: &LightMatrix) -> Vec<(usize, Projected)> {
    let texel_from_world = m.texel_from_world();
    let mut out = Vec::new();
    let mut index = 0;
    for object in &scene.objects {
        for tri in object.mesh.indices.chunks_exact(3) {
            let corners = [0, 1, 2].map(|k| {
                let p = object.mesh.positions[tri[k] as usize].as_dvec3().extend(1.0);
                let t = texel_from_world * p;
                let c = m.clip_from_world * p;
                (DVec2::new(t.x / t.w, t.y / t.w), c.z / t.w, t.w)
            });
            if corners.iter().all(|c| c.2 > 1e-9) {
                out.push((index, Projected { vertices: corners.map(|c| c.0), zeta: corners.map(|c| c.1) }));
            }
            index += 1;
        }
    }
    out
}

/// Per texel: every triangle touching it (exact, closed boxes) and the one
/// a conservative pass keeps (smallest consistent depth).
#[derive(Clone, Debug)]
pub struct OverlapMap {
    /// Width in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
    /// Row-major lists of indices into the projected triangles.
    pub lists: Vec<Vec<u32>>,
    /// Row-major kept triangle.
    pub kept: Vec<Option<u32>>,
}

impl OverlapMap {
    /// Bins the triangles into a `width x height` map.
    #[must_use]
    pub fn new(triangles: &[(usize, Projected)], width: u32, height: u32) -> Self {
        let n = (width * height) as usize;
        let mut lists = vec![Vec::new(); n];
        let mut best = vec![(f64::INFINITY, None); n];
        for (i, (_, t)) in triangles.iter().enumerate() {
            let lo = t.vertices[0].min(t.vertices[1]).min(t.vertices[2]).floor() - 1.0;
            let hi = t.vertices[0].max(t.vertices[1]).max(t.vertices[2]).floor() + 1.0;
            if !(lo.is_finite() && hi.is_finite()) {
                continue;
            }
            let x0 = (lo.x.max(0.0)) as i64;
            let y0 = (lo.y.max(0.0)) as i64;
            let x1 = hi.x.min(f64::from(width) - 1.0) as i64;
            let y1 = hi.y.min(f64::from(height) - 1.0) as i64;
            for y in y0..=y1 {
                for x in x0..=x1 {
                    if !packing::texel_touches(t.vertices, [x, y], 0.0) {
                        continue;
                    }
                    let at = (y * i64::from(width) + x) as usize;
                    lists[at].push(i as u32);
                    let depth =
                        t.min_depth_in([x, y]).unwrap_or_else(|| t.zeta.iter().copied().fold(f64::MAX, f64::min));
                    if depth < best[at].0 {
                        best[at] = (depth, Some(i as u32));
                    }
                }
            }
        }
        Self { width, height, lists, kept: best.into_iter().map(|b| b.1).collect() }
    }

    /// The map a conservative pass would write, unquantized, for the CPU
    /// sweep.
    #[must_use]
    pub fn sweep_map(&self, triangles: &[(usize, Projected)]) -> SweepMap {
        let texels = self
            .kept
            .iter()
            .enumerate()
            .map(|(i, kept)| {
                let Some(k) = kept else { return SweepTexel::Empty };
                let t = &triangles[*k as usize].1;
                let centre = DVec2::new((i as u32 % self.width) as f64, (i as u32 / self.width) as f64) + 0.5;
                let gradient = t.gradient().unwrap_or(DVec2::ZERO);
                SweepTexel::Triangle(Stored {
                    spsm: DecodedTexel { vertices: t.vertices, depth: t.depth_at(centre), gradient },
                    centre,
                    slopes: gradient,
                })
            })
            .collect();
        SweepMap { texels, width: self.width, height: self.height }
    }

    /// The triangles visible from the light inside texel `k`: the nearest
    /// one at each of `n x n` sample points and the four corners.
    #[must_use]
    pub fn visible(&self, triangles: &[(usize, Projected)], k: [i64; 2], n: u32) -> Vec<u32> {
        let list = &self.lists[(k[1] * i64::from(self.width) + k[0]) as usize];
        let mut out: Vec<u32> = Vec::new();
        let points = (0..n * n)
            .map(|s| DVec2::new((f64::from(s % n) + 0.5) / f64::from(n), (f64::from(s / n) + 0.5) / f64::from(n)))
            .chain([DVec2::ZERO, DVec2::X, DVec2::Y, DVec2::ONE]);
        for p in points {
            let p = p + DVec2::new(k[0] as f64, k[1] as f64);
            let nearest = list
                .iter()
                .filter(|&&i| triangles[i as usize].1.contains(p))
                .map(|&i| (triangles[i as usize].1.depth_at(p), i))
                .min_by(|a, b| a.0.total_cmp(&b.0));
            if let Some((_, i)) = nearest {
                if !out.contains(&i) {
                    out.push(i);
                }
            }
        }
        out
    }
}

/// One row of the detection table.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct DetectionRow {
    /// Texels in the class.
    pub texels: u64,
    /// Of those, texels whose visible triangles the sweep recognised.
    pub recognised: u64,
}

/// The detection rate by the number of triangles visible in a texel.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Detection {
    /// Texels with a triangle.
    pub covered: u64,
    /// Texels with 1, 2, 3, 4 and more than 4 visible triangles.
    pub rows: [DetectionRow; 5],
    /// Texels touched by 2, 3, 4 and more than 4 triangles (visible or not).
    pub touching: [u64; 4],
}

impl Detection {
    /// The share recognised of the texels with 2 to 4 visible triangles.
    #[must_use]
    pub fn rate_2_to_4(&self) -> f64 {
        let (t, r) = self.rows[1..4].iter().fold((0, 0), |(t, r), row| (t + row.texels, r + row.recognised));
        if t == 0 {
            return f64::NAN;
        }
        r as f64 / t as f64
    }
}

/// Whether two projected triangles lie on one plane (depth agreeing at
/// both's vertices within `tolerance`).
fn coplanar(a: &Projected, b: &Projected, tolerance: f64) -> bool {
    b.vertices.iter().zip(b.zeta).all(|(p, z)| (a.depth_at(*p) - z).abs() <= tolerance)
        && a.vertices.iter().zip(a.zeta).all(|(p, z)| (b.depth_at(*p) - z).abs() <= tolerance)
}

/// The detection rate of the mask words `words` (row-major, from the CPU or
/// the GPU sweep of the same map): a texel is recognised when its word is
/// full or a pattern and every triangle visible in it is the kept triangle
/// of the texel or lies on the plane of one of the word's corner
/// triangles (the kept triangles of the slots it names), i.e. the lookup
/// can rebuild each visible part on the right plane.
#[must_use]
pub fn detection(
    triangles: &[(usize, Projected)],
    overlap: &OverlapMap,
    words: &[MaskWord],
    samples: u32,
) -> Detection {
    let mut out = Detection::default();
    let (w, h) = (i64::from(overlap.width), i64::from(overlap.height));
    for y in 0..h {
        for x in 0..w {
            let at = (y * w + x) as usize;
            let Some(own) = overlap.kept[at] else { continue };
            out.covered += 1;
            let touching = overlap.lists[at].len();
            if touching >= 2 {
                out.touching[(touching - 2).min(3)] += 1;
            }
            let visible = overlap.visible(triangles, [x, y], samples);
            if visible.is_empty() {
                continue;
            }
            let row = &mut out.rows[(visible.len() - 1).min(4)];
            row.texels += 1;
            let word = words[at];
            if !matches!(word.status(), Status::Full | Status::Pattern) {
                continue;
            }
            let corner_tris: Vec<u32> = (0..4)
                .map(|q| word.corner(q))
                .filter(|&s| s < 9)
                .filter_map(|s| {
                    let (tx, ty) = (x + i64::from(s % 3) - 1, y + i64::from(s / 3) - 1);
                    (tx >= 0 && ty >= 0 && tx < w && ty < h).then(|| overlap.kept[(ty * w + tx) as usize]).flatten()
                })
                .collect();
            let known = |v: u32| {
                v == own
                    || corner_tris
                        .iter()
                        .any(|&c| c == v || coplanar(&triangles[c as usize].1, &triangles[v as usize].1, 1e-7))
            };
            if visible.iter().all(|&v| known(v)) {
                row.recognised += 1;
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::super::pattern;
    use super::*;

    /// `n` triangles fanned around the centre of texel (1, 1) of a 3x3 map,
    /// reaching past the map: all on one plane, or each on its own plane.
    fn fan(n: usize, planar: bool) -> Vec<(usize, Projected)> {
        let centre = DVec2::splat(1.5);
        let at = |k: usize| {
            let a = 0.3 + std::f64::consts::TAU * k as f64 / n as f64;
            centre + 6.0 * DVec2::new(a.cos(), a.sin())
        };
        (0..n)
            .map(|k| {
                let vertices = [centre, at(k), at(k + 1)];
                let slope = if planar { DVec2::new(0.01, -0.004) } else { DVec2::new(0.01 * (k as f64 + 1.0), 0.0) };
                (k, Projected { vertices, zeta: vertices.map(|v| 0.5 + slope.dot(v - centre)) })
            })
            .collect()
    }

    /// The overlap map, the CPU sweep's words and the detection table.
    fn detect(tris: &[(usize, Projected)]) -> (OverlapMap, Vec<MaskWord>, Detection) {
        let overlap = OverlapMap::new(tris, 3, 3);
        let words = overlap.sweep_map(tris).sweep();
        let d = detection(tris, &overlap, &words, 8);
        (overlap, words, d)
    }

    /// A texel where `n` fanned triangles meet is in the class of `n`
    /// visible triangles. One plane is a full texel, recognised whatever
    /// `n`; separate planes are a pattern of `n` groups up to four (one
    /// plane per corner) and unrecognised above (a plane reaching no corner).
    #[test]
    fn fans_count_in_their_class() {
        // (Two triangles fanned around a point are degenerate: n from 3.)
        for n in 3..=7 {
            for planar in [true, false] {
                let tris = fan(n, planar);
                let (overlap, words, d) = detect(&tris);
                assert_eq!(overlap.lists[4].len(), n, "n {n}: every fan triangle touches the centre texel");
                assert_eq!(overlap.visible(&tris, [1, 1], 8).len(), n, "n {n}");
                assert_eq!(d.covered, 9);
                let word = words[4];
                match (planar, n) {
                    (true, _) => assert_eq!(word.status(), Status::Full, "n {n}: {word:?}"),
                    (false, 3 | 4) => {
                        assert_eq!(word.status(), Status::Pattern, "n {n}: {word:?}");
                        assert_eq!(pattern::groups(word.pattern()).unwrap().len(), n, "n {n}: {word:?}");
                    }
                    (false, _) => assert_eq!(word.status(), Status::Unrecognised, "n {n}: {word:?}"),
                }
                if n >= 5 {
                    // Only the centre texel sees five or more sectors.
                    let expected = DetectionRow { texels: 1, recognised: u64::from(planar) };
                    assert_eq!(d.rows[4], expected, "n {n}, planar {planar}: {d:?}");
                } else {
                    let class = d.rows[n - 1];
                    assert!(class.texels >= 1 && class.recognised >= 1, "n {n}, planar {planar}: {d:?}");
                }
            }
        }
    }

    /// A small occluder inside a texel, reaching none of its corners, is
    /// visible there but not recognised: the corners cannot explain it (the
    /// lookup falls back to SPSM).
    #[test]
    fn an_occluder_between_the_corners_is_not_recognised() {
        let (_, _, without) = detect(&fan(3, true));
        assert_eq!(without.rows[2], DetectionRow { texels: 1, recognised: 1 }, "{without:?}");
        let mut tris = fan(3, true);
        let c = DVec2::splat(1.5);
        let vertices = [c + DVec2::new(-0.3, -0.2), c + DVec2::new(0.3, -0.2), c + DVec2::new(0.0, 0.3)];
        tris.push((3, Projected { vertices, zeta: [0.2; 3] }));
        let (overlap, words, d) = detect(&tris);
        assert_eq!(overlap.kept[4], Some(3), "the occluder is kept: it is nearest");
        assert_eq!(overlap.visible(&tris, [1, 1], 8).len(), 4, "the occluder and three fan triangles");
        assert_eq!(words[4].status(), Status::Unrecognised, "{:?}", words[4]);
        assert_eq!(d.rows[3], DetectionRow { texels: 1, recognised: 0 }, "{d:?}");
    }
}
