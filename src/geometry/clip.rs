//! Clipping a [`ConvexPolyhedron`] by a plane into reusable buffers, and the
//! hole-boundary walk that closes the cut (shared with the point hull).
//!
//! Everything a clip needs besides its result lives in a [`ClipWorkspace`],
//! so that repeated clips (every classical method clips a few bodies per
//! call) allocate nothing once the buffers have grown: malloc and free were
//! about a fifth of a focused solve before (issue 15).

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

use super::polyhedron::FaceSpan;
use super::{ConvexPolyhedron, Plane};

/// Scratch buffers for [`ConvexPolyhedron::clip_into`] and the other
/// `_into` operations. Holds no result: any workspace may be used with any
/// body, and its content between calls is meaningless.
#[derive(Clone, Debug, Default)]
pub struct ClipWorkspace {
    dist: Vec<f64>,
    side: Vec<Side>,
    new_index: Vec<usize>,
    /// The cut point of each crossed edge (sorted vertex pair), in the order
    /// made: a clip makes a handful, so a list beats a hash map.
    cuts: Vec<((usize, usize), usize)>,
    /// Per new vertex: on the plane (kept within `eps` of it, or a cut point).
    on_plane: Vec<bool>,
    pub(super) edges: IndexMap<(usize, usize), usize>,
    /// The half-edges by start vertex (the silhouette's face lookup).
    pub(super) half_edges: HalfEdges,
    walker: LoopWalker,
    pub(super) flags: Vec<bool>,
    pub(super) silhouette: Vec<(usize, usize, usize, usize)>,
    /// The second body of a chain of clips (swapped with the result).
    pub(super) spare: ConvexPolyhedron,
    /// Tests only: the general path (the cap's boundary by looking up every
    /// edge's reverse in all faces, the general walk, the renumbering pass),
    /// the reference the fast paths must equal.
    #[cfg(test)]
    pub(super) reference_boundary: bool,
}

impl ClipWorkspace {
    /// An empty workspace; its buffers grow on first use.
    #[must_use]
    pub fn new() -> Self {
        Self::default()
    }
}

/// Where a vertex lies relative to a clipping plane, with tolerance. The
/// discriminants are distinct bits, so that or-ing a face's sides tells at
/// once whether the plane cuts it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
enum Side {
    Inside = 1,
    On = 2,
    Outside = 4,
}

impl Side {
    fn of(distance: f64, eps: f64) -> Side {
        if distance > eps {
            Side::Outside
        } else if distance < -eps {
            Side::Inside
        } else {
            Side::On
        }
    }

    /// Whether an edge between the two sides crosses the plane strictly.
    fn is_opposite(self, other: Side) -> bool {
        self as u8 | other as u8 == Side::Inside as u8 | Side::Outside as u8
    }
}

impl ConvexPolyhedron {
    /// The clip of [`clip`](Self::clip) (see there for the algorithm) into
    /// `out`; returns `false`, leaving `out` untouched, when the result is
    /// `self` unchanged.
    ///
    /// The common cut (no vertex within `eps` of the plane) takes a shorter
    /// road to the same result: the cap's edges are noted while the faces
    /// are cut (consecutive cut points of a face), its loop is traced
    /// directly when the boundary is one simple cycle, and the search for
    /// unused vertices is skipped (every kept vertex is then in a kept
    /// face). The arithmetic is the same, so the body is the same bit for
    /// bit (`cap_boundary_fast_path_equals_reference` compares it with the
    /// general path).
    pub(super) fn clip_core(&self, plane: &Plane, eps: f64, out: &mut Self, workspace: &mut ClipWorkspace) -> bool {
        if self.is_empty() || !plane.is_finite() {
            out.clear();
            return true;
        }
        let eps = eps.max(0.0);
        #[cfg(test)]
        let reference = workspace.reference_boundary;
        #[cfg(not(test))]
        let reference = false;
        if !reference {
            if let Some(changed) = self.clip_small(plane, eps, out) {
                return changed;
            }
        }
        let ClipWorkspace { dist, side, new_index, cuts, on_plane, edges, walker, .. } = workspace;
        dist.clear();
        dist.extend(self.vertices.iter().map(|&v| plane.signed_distance(v)));
        side.clear();
        // How many vertices lie inside, on and outside the plane (indexed
        // by the side's bit).
        let mut count = [0usize; 5];
        side.extend(dist.iter().map(|&d| {
            let s = Side::of(d, eps);
            count[s as usize] += 1;
            s
        }));
        if count[Side::Outside as usize] == 0 {
            return false;
        }
        out.clear();
        if count[Side::Inside as usize] == 0 {
            return true;
        }
        // With no vertex on the plane, the plane edges are exactly the
        // consecutive cut points of each cut face (noted below).
        let simple = !reference && count[Side::On as usize] == 0;

        // Kept vertices first, under their new indices; cut points follow.
        let Self { vertices, faces, indices } = out;
        new_index.clear();
        new_index.resize(self.vertices.len(), usize::MAX);
        on_plane.clear();
        // Zipped, not indexed: no bounds checks per vertex.
        for ((&v, &s), slot) in self.vertices.iter().zip(side.iter()).zip(new_index.iter_mut()) {
            if s != Side::Outside {
                *slot = vertices.len();
                vertices.push(v);
                on_plane.push(s == Side::On);
            }
        }
        let kept = vertices.len();
        cuts.clear();
        let along = &mut walker.targets;
        along.clear();
        let mut dropped_inside = false;
        for face in &self.faces {
            let start = indices.len();
            let along_start = along.len();
            let loop_indices = &self.indices[face.start..face.end];
            // The sides present in the face: the plane cuts it only when it
            // has vertices strictly on both sides. Otherwise the edge scan
            // below would make no cut point and note no plane edge: a face
            // with nothing outside is kept as it is (renumbered), and one
            // with nothing strictly inside is dropped.
            // (The reference path scans every face.)
            let present = if reference { 0xff } else { loop_indices.iter().fold(0u8, |m, &a| m | side[a] as u8) };
            let has_inside = present & Side::Inside as u8 != 0;
            if present & Side::Outside as u8 == 0 {
                if has_inside && loop_indices.len() >= 3 {
                    indices.extend(loop_indices.iter().map(|&a| new_index[a]));
                    faces.push(FaceSpan { plane: face.plane, start, end: indices.len() });
                } else {
                    dropped_inside |= has_inside;
                }
                continue;
            }
            if !has_inside {
                continue;
            }
            let mut keeps_inside = false;
            // The last cut pushed, if it is the last index pushed.
            let mut last_cut = usize::MAX;
            // The edges `(a, b)` in loop order, each vertex's side looked
            // up once (carried from `b` to the next edge's `a`).
            let Some((&first, rest)) = loop_indices.split_first() else { continue };
            let (mut a, mut side_a) = (first, side[first]);
            for &b in rest.iter().chain(std::iter::once(&first)) {
                let side_b = side[b];
                if side_a != Side::Outside {
                    keeps_inside |= side_a == Side::Inside;
                    indices.push(new_index[a]);
                    last_cut = usize::MAX;
                }
                if side_a.is_opposite(side_b) {
                    let key = (a.min(b), a.max(b));
                    let cut = match cuts.iter().find(|(k, _)| *k == key) {
                        Some(&(_, cut)) => cut,
                        None => {
                            let (i, j) = key;
                            let t = dist[i] / (dist[i] - dist[j]);
                            vertices.push(self.vertices[i].lerp(self.vertices[j], t));
                            cuts.push((key, vertices.len() - 1));
                            vertices.len() - 1
                        }
                    };
                    if simple && last_cut != usize::MAX {
                        along.extend([last_cut, cut]);
                    }
                    indices.push(cut);
                    last_cut = cut;
                }
                (a, side_a) = (b, side_b);
            }
            // A face with nothing strictly inside lies in the cap (to within
            // eps): the cap replaces it.
            if keeps_inside && indices.len() - start >= 3 {
                if simple && last_cut != usize::MAX && is_cut(on_plane, vertices.len(), indices[start]) {
                    // The loop's closing edge runs from the last cut to the
                    // first index, itself a cut: it comes last, as in a scan
                    // of the face's edges.
                    along.extend([last_cut, indices[start]]);
                }
                faces.push(FaceSpan { plane: face.plane, start, end: indices.len() });
            } else {
                dropped_inside |= keeps_inside;
                // Its plane edges must not count.
                along.truncate(along_start);
                indices.truncate(start);
            }
        }

        // The new vertices on the plane: kept ones within eps of it, then
        // every cut point.
        on_plane.resize(vertices.len(), true);
        let mut traced = false;
        if simple {
            // The plane edges reversed without looking for each one's
            // reverse among them (quadratic): when they trace one simple
            // cycle of three or more, none has its reverse there (an edge
            // and its reverse would close a cycle of two), so the checked
            // boundary is the same. Otherwise the checked one is made.
            walker.reverse_along();
            traced = walker.boundary_len() >= 3
                && walker.trace_simple(vertices.len(), |cycle| {
                    let start = indices.len();
                    indices.extend_from_slice(cycle);
                    faces.push(FaceSpan { plane: *plane, start, end: indices.len() });
                });
            if !traced {
                walker.boundary_from_along();
            }
        } else {
            walker.collect_cap_boundary(faces, indices, on_plane);
        }
        #[cfg(test)]
        if reference {
            half_edge_faces(edges, faces, indices);
            walker.collect_boundary(faces, indices, edges);
        }
        #[cfg(not(test))]
        let _ = edges;
        let cap = |cycle: &[usize]| {
            let start = indices.len();
            indices.extend_from_slice(cycle);
            faces.push(FaceSpan { plane: *plane, start, end: indices.len() });
        };
        if !traced && (reference || !walker.trace_simple(vertices.len(), cap)) {
            walker.walk(vertices.len(), |cycle| {
                let start = indices.len();
                indices.extend_from_slice(cycle);
                faces.push(FaceSpan { plane: *plane, start, end: indices.len() });
            });
        }
        if simple && !dropped_inside {
            // Every kept vertex is in a kept face (it is strictly inside) and
            // so is every cut point: nothing to renumber.
            //
            // The kept vertices are finite (every body's are: each
            // constructor and clip checks them), so only the cut points can
            // have overflowed: the same test as `finish_checks` without
            // scanning the kept ones.
            if faces.len() < 4 || !vertices[kept..].iter().all(|v| v.is_finite()) {
                out.clear();
            }
        } else {
            out.finish_parts(new_index);
        }
        true
    }
}

/// The most vertices (and cut points) [`ConvexPolyhedron::clip_small`]
/// handles: one bit each in a `u64`.
const SMALL: usize = 64;

impl ConvexPolyhedron {
    /// [`clip_core`](Self::clip_core)'s simple road for a body of at most
    /// [`SMALL`] vertices, without its scratch buffers: the sides as bit
    /// masks, the new indices, cut edges and cap links in small arrays, the
    /// distances recomputed for the few crossed edges (the same expression,
    /// so the same bits). Makes exactly what `clip_core` makes, in the same
    /// order, or returns `None` (having perhaps written into `out`) where
    /// that needs its general road: a vertex within `eps` of the plane (or a
    /// NaN distance), more than [`SMALL`] vertices or cut points, a face
    /// too short, or a cap boundary that is not one simple cycle of three
    /// or more edges. `eps` is non-negative and the body is not empty.
    fn clip_small(&self, plane: &Plane, eps: f64, out: &mut Self) -> Option<bool> {
        let n = self.vertices.len();
        if n > SMALL {
            return None;
        }
        let (mut outside, mut inside) = (0u64, 0u64);
        for (i, &v) in self.vertices.iter().enumerate() {
            let d = plane.signed_distance(v);
            outside |= u64::from(d > eps) << i;
            inside |= u64::from(d < -eps) << i;
        }
        if outside == 0 {
            return Some(false);
        }
        out.clear();
        if inside == 0 {
            return Some(true);
        }
        let all = if n == SMALL { u64::MAX } else { (1u64 << n) - 1 };
        if (outside | inside) != all {
            // A vertex on the plane (or a NaN distance).
            return self.clip_small_on(plane, outside, inside, out);
        }
        let Self { vertices, faces, indices } = out;
        let mut new_index = [0u8; SMALL];
        for (i, &v) in self.vertices.iter().enumerate() {
            if inside & (1u64 << i) != 0 {
                new_index[i] = vertices.len() as u8;
                vertices.push(v);
            }
        }
        let kept = vertices.len();
        // Cut `c` (vertex `kept + c`) lies on the edge `cut_keys[c]`
        // (sorted pair packed); `link[c]` is the cap boundary's next cut
        // after it (`u8::MAX`: none yet).
        let mut cut_keys = [0u16; SMALL];
        let mut link = [u8::MAX; SMALL];
        let mut cut_count = 0usize;
        // The cap boundary: its edge count and first vertex.
        let mut boundary_len = 0usize;
        let mut boundary_start = usize::MAX;
        for face in &self.faces {
            let loop_indices = &self.indices[face.start..face.end];
            if loop_indices.len() < 3 {
                return None;
            }
            let mut mask = 0u64;
            for &a in loop_indices {
                mask |= 1u64 << (a % SMALL);
            }
            if mask & outside == 0 {
                let start = indices.len();
                indices.extend(loop_indices.iter().map(|&a| usize::from(new_index[a % SMALL])));
                faces.push(FaceSpan { plane: face.plane, start, end: indices.len() });
                continue;
            }
            if mask & inside == 0 {
                continue;
            }
            let start = indices.len();
            // The last cut pushed, if it is the last index pushed.
            let mut last_cut = usize::MAX;
            let is_out = |a: usize| outside & (1u64 << (a % SMALL)) != 0;
            // One edge `a → b` of the loop: the kept start, then the cut.
            macro_rules! edge {
                ($a:expr, $a_out:expr, $b:expr, $b_out:expr) => {{
                    let (a, a_out, b, b_out) = ($a, $a_out, $b, $b_out);
                    if !a_out {
                        indices.push(usize::from(new_index[a % SMALL]));
                        last_cut = usize::MAX;
                    }
                    if a_out != b_out {
                        let (i, j) = (a.min(b), a.max(b));
                        let key = ((i as u16) << 8) | j as u16;
                        let cut = match cut_keys[..cut_count].iter().position(|&k| k == key) {
                            Some(c) => c,
                            None => {
                                if cut_count == SMALL {
                                    return None;
                                }
                                let (di, dj) =
                                    (plane.signed_distance(self.vertices[i]), plane.signed_distance(self.vertices[j]));
                                let t = di / (di - dj);
                                vertices.push(self.vertices[i].lerp(self.vertices[j], t));
                                cut_keys[cut_count] = key;
                                cut_count += 1;
                                cut_count - 1
                            }
                        };
                        if last_cut != usize::MAX {
                            // The plane edge `last_cut → cut`, reversed on the cap.
                            if link[cut] != u8::MAX {
                                return None;
                            }
                            link[cut] = last_cut as u8;
                            if boundary_len == 0 {
                                boundary_start = cut;
                            }
                            boundary_len += 1;
                        }
                        indices.push(kept + cut);
                        last_cut = cut;
                    }
                }};
            }
            let first = loop_indices[0];
            let first_out = is_out(first);
            for pair in loop_indices.windows(2) {
                edge!(pair[0], is_out(pair[0]), pair[1], is_out(pair[1]));
            }
            let last = loop_indices[loop_indices.len() - 1];
            edge!(last, is_out(last), first, first_out);
            // The closing edge, from the last cut to the first index when
            // that is a cut too.
            if last_cut != usize::MAX && indices[start] >= kept {
                let cut = indices[start] - kept;
                if link[cut] != u8::MAX {
                    return None;
                }
                link[cut] = last_cut as u8;
                if boundary_len == 0 {
                    boundary_start = cut;
                }
                boundary_len += 1;
            }
            faces.push(FaceSpan { plane: face.plane, start, end: indices.len() });
        }
        if boundary_len < 3 {
            return None;
        }
        // The cap: one simple cycle through `boundary_len` cut points.
        let start = indices.len();
        push_cap_cycle(indices, &link, boundary_start, boundary_len, kept)?;
        faces.push(FaceSpan { plane: *plane, start, end: indices.len() });
        if faces.len() < 4 || !vertices[kept..].iter().all(|v| v.is_finite()) {
            out.clear();
        }
        Some(true)
    }
}

impl ConvexPolyhedron {
    /// [`clip_small`](Self::clip_small) where some vertices lie within `eps`
    /// of the plane (neither in `outside` nor in `inside`): `clip_core`'s
    /// general road, for at most [`SMALL`] new vertices, with the same
    /// steps in the same order. The faces are cut as there (an edge is cut
    /// only between strictly inside and strictly outside), the cap's
    /// boundary is the plane edges (both ends on the plane) whose reverse
    /// is not among them, reversed, in the faces' order, traced as
    /// `LoopWalker::trace_simple` does. `None` (with `out` perhaps written)
    /// where `clip_core` would walk a boundary that is not one simple cycle
    /// or renumber (a kept vertex left in no face), or the body or its
    /// pieces do not fit, or a distance is NaN.
    #[inline(never)]
    fn clip_small_on(&self, plane: &Plane, outside: u64, inside: u64, out: &mut Self) -> Option<bool> {
        let Self { vertices, faces, indices } = out;
        let n = self.vertices.len();
        let all_old = if n == SMALL { u64::MAX } else { (1u64 << n) - 1 };
        let mut new_index = [0u8; SMALL];
        // The new vertices on the plane: kept ones within eps of it, and
        // (below) every cut point.
        let mut on_plane = 0u64;
        for (i, &v) in self.vertices.iter().enumerate() {
            if outside & (1u64 << i) == 0 {
                if inside & (1u64 << i) == 0 {
                    if plane.signed_distance(v).is_nan() {
                        return None;
                    }
                    on_plane |= 1u64 << vertices.len();
                }
                new_index[i] = vertices.len() as u8;
                vertices.push(v);
            }
        }
        let kept = vertices.len();
        let mut cut_keys = [0u16; SMALL];
        // The input vertices in kept faces: every one not outside is
        // pushed there, and the cap runs only through such vertices and
        // cut points (which are all pushed), so a kept vertex is used in the
        // result exactly when it is here.
        let mut used = 0u64;
        for face in &self.faces {
            let loop_indices = &self.indices[face.start..face.end];
            if loop_indices.len() < 3 {
                return None;
            }
            let mut mask = 0u64;
            for &a in loop_indices {
                mask |= 1u64 << (a % SMALL);
            }
            if mask & inside == 0 {
                // Nothing strictly inside: in the cap (to within eps).
                continue;
            }
            let start = indices.len();
            used |= mask;
            if mask & outside == 0 {
                indices.extend(loop_indices.iter().map(|&a| usize::from(new_index[a % SMALL])));
                faces.push(FaceSpan { plane: face.plane, start, end: indices.len() });
                continue;
            }
            let is_out = |a: usize| outside & (1u64 << (a % SMALL)) != 0;
            let is_in = |a: usize| inside & (1u64 << (a % SMALL)) != 0;
            let first = loop_indices[0];
            for (k, &a) in loop_indices.iter().enumerate() {
                let b = if k + 1 == loop_indices.len() { first } else { loop_indices[k + 1] };
                if !is_out(a) {
                    indices.push(usize::from(new_index[a % SMALL]));
                }
                if (is_out(a) && is_in(b)) || (is_in(a) && is_out(b)) {
                    let (i, j) = (a.min(b), a.max(b));
                    let key = ((i as u16) << 8) | j as u16;
                    let cut_count = vertices.len() - kept;
                    let cut = match cut_keys[..cut_count].iter().position(|&k| k == key) {
                        Some(c) => kept + c,
                        None => {
                            if vertices.len() == SMALL {
                                return None;
                            }
                            let (di, dj) =
                                (plane.signed_distance(self.vertices[i]), plane.signed_distance(self.vertices[j]));
                            let t = di / (di - dj);
                            vertices.push(self.vertices[i].lerp(self.vertices[j], t));
                            cut_keys[cut_count] = key;
                            on_plane |= 1u64 << (vertices.len() - 1);
                            vertices.len() - 1
                        }
                    };
                    indices.push(cut);
                }
            }
            if indices.len() - start < 3 {
                return None;
            }
            faces.push(FaceSpan { plane: face.plane, start, end: indices.len() });
        }
        // The plane edges, in the faces' order, then those without their
        // reverse, reversed: the cap's boundary, each vertex's one edge out
        // in `link` (a second one: not one simple cycle).
        let mut along = [(0u8, 0u8); 2 * SMALL];
        let mut along_len = 0;
        for face in faces.iter() {
            let loop_indices = &indices[face.start..face.end];
            let on = loop_indices.iter().fold(0u64, |m, &a| m | 1u64 << a) & on_plane;
            if on & on.wrapping_sub(1) == 0 {
                // At most one vertex on the plane: no plane edge.
                continue;
            }
            for (k, &a) in loop_indices.iter().enumerate() {
                let b = if k + 1 == loop_indices.len() { loop_indices[0] } else { loop_indices[k + 1] };
                if on_plane & (1u64 << a) != 0 && on_plane & (1u64 << b) != 0 {
                    if along_len == along.len() {
                        return None;
                    }
                    along[along_len] = (a as u8, b as u8);
                    along_len += 1;
                }
            }
        }
        let along = &along[..along_len];
        let mut link = [u8::MAX; SMALL];
        let mut boundary_len = 0usize;
        let mut boundary_start = usize::MAX;
        for &(a, b) in along {
            if along.iter().any(|&(c, d)| c == b && d == a) {
                continue;
            }
            // The boundary edge `b → a`.
            if link[usize::from(b)] != u8::MAX {
                return None;
            }
            link[usize::from(b)] = a;
            if boundary_len == 0 {
                boundary_start = usize::from(b);
            }
            boundary_len += 1;
        }
        if boundary_len > 0 {
            let start = indices.len();
            push_cap_cycle(indices, &link, boundary_start, boundary_len, 0)?;
            faces.push(FaceSpan { plane: *plane, start, end: indices.len() });
        }
        // `finish_parts`: at least four faces, finite cut points (the kept
        // vertices are), every vertex used.
        if faces.len() < 4 || !vertices[kept..].iter().all(|v| v.is_finite()) {
            out.clear();
            return Some(true);
        }
        if used & !outside != all_old & !outside {
            // A kept vertex in no kept face (possible only through the
            // tolerance): `finish_parts` renumbers.
            return None;
        }
        Some(true)
    }
}

/// Whether new vertex `i` (of `vertex_count` so far) is a cut point: while
/// the faces are cut, `on_plane` covers the kept vertices only.
fn is_cut(on_plane: &[bool], vertex_count: usize, i: usize) -> bool {
    i >= on_plane.len() && i < vertex_count
}

/// The directed edges `(from, to)` of a face loop, in order.
pub(super) fn loop_edges(indices: &[usize]) -> impl Iterator<Item = (usize, usize)> + '_ {
    // Indexing, not `cycle().skip(1)`: the skip was a visible cost of every clip.
    let n = indices.len();
    (0..n).map(move |k| (indices[k], indices[if k + 1 == n { 0 } else { k + 1 }]))
}

/// A hash map keyed by vertex indices. The keys are small trusted integers
/// and the maps are only looked up, never iterated (results do not depend on
/// hashing), so a multiply-rotate hash replaces SipHash, which was ~40% of a
/// focused solve (callgrind, issue 15).
pub(super) type IndexMap<K, V> = HashMap<K, V, BuildHasherDefault<IndexHasher>>;

/// Multiply-rotate hasher for [`IndexMap`].
#[derive(Clone, Copy, Default)]
pub(super) struct IndexHasher(u64);

impl Hasher for IndexHasher {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u64(u64::from(b));
        }
    }
    fn write_u64(&mut self, x: u64) {
        self.0 = (self.0.rotate_left(5) ^ x).wrapping_mul(0x517c_c1b7_2722_0a95);
    }
    fn write_usize(&mut self, x: usize) {
        self.write_u64(x as u64);
    }
}

/// Fills `map` (cleared first) with each directed edge of the faces and the
/// index of its face.
pub(super) fn half_edge_faces(map: &mut IndexMap<(usize, usize), usize>, faces: &[FaceSpan], indices: &[usize]) {
    map.clear();
    for (i, face) in faces.iter().enumerate() {
        map.extend(loop_edges(&indices[face.start..face.end]).map(|edge| (edge, i)));
    }
}

/// The directed edges of a body's faces chained by start vertex (no
/// hashing, one pass): the face of edge `a → b` is found among the few edges
/// leaving `a`, latest first.
#[derive(Clone, Debug, Default)]
pub(super) struct HalfEdges {
    /// Per vertex, the last directed edge leaving it (`usize::MAX`: none).
    head: Vec<usize>,
    /// `(b, face, the previous edge leaving a)` per directed edge `a → b`,
    /// in face order.
    edges: Vec<(usize, usize, usize)>,
}

impl HalfEdges {
    /// Rebuilds for `faces` over `vertex_count` vertices.
    pub(super) fn build(&mut self, vertex_count: usize, faces: &[FaceSpan], indices: &[usize]) {
        let Self { head, edges } = self;
        head.clear();
        head.resize(vertex_count, usize::MAX);
        edges.clear();
        for (f, face) in faces.iter().enumerate() {
            for (a, b) in loop_edges(&indices[face.start..face.end]) {
                // Every index is a vertex of the body; growing only keeps
                // a malformed body from indexing out of range.
                if a >= head.len() {
                    head.resize(a + 1, usize::MAX);
                }
                edges.push((b, f, head[a]));
                head[a] = edges.len() - 1;
            }
        }
    }

    /// The face of directed edge `a → b`; the last one listed if several
    /// faces run it (what a map filled in face order would hold).
    pub(super) fn face(&self, a: usize, b: usize) -> Option<usize> {
        let mut e = *self.head.get(a)?;
        while let Some(&(to, face, previous)) = self.edges.get(e) {
            if to == b {
                return Some(face);
            }
            e = previous;
        }
        None
    }
}

/// The holes in a surface of faces, each as a simple loop of vertex indices
/// in the order a face filling it runs (counter-clockwise from outside).
///
/// # Algorithm
///
/// A boundary edge is a directed edge `(a, b)` whose reverse is in no face;
/// a face filling the hole runs it as `b → a`. These reversed edges form a
/// balanced directed graph (every vertex has as many in as out), which a
/// walk splits into simple cycles: follow unused edges, and whenever the walk
/// returns to a vertex already on its path, cut off the loop it closed.
/// Normally there is one hole with a simple boundary; a boundary touching
/// itself at a vertex yields several loops. The edges leaving a vertex are
/// kept in one flat array (counting sort by vertex) and taken last first.
#[derive(Clone, Debug, Default)]
pub(super) struct LoopWalker {
    /// Reversed boundary edges `(from, to)`, in the order the faces run them.
    boundary: Vec<(usize, usize)>,
    /// Per vertex, where its edges start in `targets` (one extra entry).
    offset: Vec<usize>,
    /// Per vertex, how many of its edges are still unused.
    left: Vec<usize>,
    targets: Vec<usize>,
    path: Vec<usize>,
}

impl LoopWalker {
    /// Collects the boundary edges of the faces; `edge_faces` is their
    /// [`half_edge_faces`].
    pub(super) fn collect_boundary(
        &mut self,
        faces: &[FaceSpan],
        indices: &[usize],
        edge_faces: &IndexMap<(usize, usize), usize>,
    ) {
        self.boundary.clear();
        for face in faces {
            for (a, b) in loop_edges(&indices[face.start..face.end]) {
                if !edge_faces.contains_key(&(b, a)) {
                    self.boundary.push((b, a));
                }
            }
        }
    }

    /// Collects the boundary edges of the faces left by a clip, where
    /// `on_plane` marks the vertices on the clipping plane.
    ///
    /// Only an edge with both ends on the plane can lack its reverse: the
    /// clip keeps every face with a vertex strictly inside, and such a
    /// vertex's edges (to a kept neighbour or to the cut point on the edge
    /// towards an outside one) appear reversed in the face across, which
    /// meets the same vertex and the same shared cut point. So the few edges
    /// along the plane are matched among themselves, in the faces' order,
    /// which finds exactly the edges (and the order) a lookup of every edge's
    /// reverse in all faces would.
    pub(super) fn collect_cap_boundary(&mut self, faces: &[FaceSpan], indices: &[usize], on_plane: &[bool]) {
        let along = &mut self.targets;
        // `along` holds the plane edges as pairs `a, b`, flattened.
        along.clear();
        for face in faces {
            for (a, b) in loop_edges(&indices[face.start..face.end]) {
                if on_plane[a] && on_plane[b] {
                    along.extend([a, b]);
                }
            }
        }
        self.boundary_from_along();
    }

    /// The plane edges held flattened in `targets`, each reversed, in order,
    /// as the boundary: [`Self::boundary_from_along`] without dropping the
    /// edges whose reverse is there too.
    pub(super) fn reverse_along(&mut self) {
        let Self { boundary, targets: along, .. } = self;
        boundary.clear();
        boundary.extend(along.chunks_exact(2).map(|edge| (edge[1], edge[0])));
    }

    /// The number of boundary edges collected.
    pub(super) fn boundary_len(&self) -> usize {
        self.boundary.len()
    }

    /// The boundary edges among the plane edges held flattened in
    /// `targets`: those whose reverse is not there, reversed, in order.
    pub(super) fn boundary_from_along(&mut self) {
        let Self { boundary, targets: along, .. } = self;
        boundary.clear();
        for edge in along.chunks_exact(2) {
            let (a, b) = (edge[0], edge[1]);
            if !along.chunks_exact(2).any(|e| e[0] == b && e[1] == a) {
                boundary.push((b, a));
            }
        }
    }

    /// [`walk`](Self::walk) for the common boundary, one simple cycle in
    /// which every vertex has one edge out: hands `emit` the loop the walk
    /// would (from the first edge's start on) and returns `true`. Returns
    /// `false`, emitting nothing, for any other boundary (the caller then
    /// walks it). `vertex_count` bounds the vertex indices (larger ones, from
    /// no clip, also take the walk).
    pub(super) fn trace_simple(&mut self, vertex_count: usize, mut emit: impl FnMut(&[usize])) -> bool {
        let Self { boundary, path, left: next, .. } = self;
        let k = boundary.len();
        if k == 0 {
            return true;
        }
        // Each vertex's one edge out, by vertex: a second edge out of the
        // same vertex means the boundary is not one simple cycle.
        next.clear();
        next.resize(vertex_count, usize::MAX);
        for &(from, to) in boundary.iter() {
            match next.get_mut(from) {
                Some(slot) if *slot == usize::MAX && to != usize::MAX => *slot = to,
                _ => return false,
            }
        }
        path.clear();
        let start = boundary[0].0;
        let mut v = start;
        loop {
            path.push(v);
            let Some(&w) = next.get(v).filter(|&&w| w != usize::MAX) else {
                return false;
            };
            if w == start {
                break;
            }
            if path.len() == k {
                return false;
            }
            v = w;
        }
        if path.len() != k {
            return false;
        }
        emit(path);
        true
    }

    /// Splits the collected boundary (over vertices `0..vertex_count`) into
    /// loops, handing each to `emit` as it closes.
    pub(super) fn walk(&mut self, vertex_count: usize, mut emit: impl FnMut(&[usize])) {
        let Self { boundary, offset, left, targets, path } = self;
        if boundary.is_empty() {
            return;
        }
        offset.clear();
        offset.resize(vertex_count + 1, 0);
        for &(from, _) in boundary.iter() {
            offset[from + 1] += 1;
        }
        for v in 0..vertex_count {
            offset[v + 1] += offset[v];
        }
        left.clear();
        left.resize(vertex_count, 0);
        targets.clear();
        targets.resize(boundary.len(), 0);
        for &(from, to) in boundary.iter() {
            targets[offset[from] + left[from]] = to;
            left[from] += 1;
        }
        for &(start, _) in boundary.iter() {
            path.clear();
            path.push(start);
            while let Some(&v) = path.last() {
                if left[v] == 0 {
                    break;
                }
                left[v] -= 1;
                let w = targets[offset[v] + left[v]];
                if let Some(i) = path.iter().position(|&u| u == w) {
                    emit(&path[i..]);
                    path.truncate(i);
                }
                path.push(w);
            }
        }
    }
}

/// Pushes a small clip's cap as vertex indices `offset + point`: the cycle of
/// cut points from `start` along `link` (each point's successor, `u8::MAX`
/// for none). `None` (the caller takes the general clip) unless the links
/// close one simple cycle through exactly `len` points.
#[inline(always)]
fn push_cap_cycle(indices: &mut Vec<usize>, link: &[u8], start: usize, len: usize, offset: usize) -> Option<()> {
    let first = indices.len();
    let mut point = start;
    loop {
        indices.push(offset + point);
        let next = link[point];
        if next == u8::MAX {
            return None;
        }
        if usize::from(next) == start {
            break;
        }
        if indices.len() - first == len {
            return None;
        }
        point = usize::from(next);
    }
    (indices.len() - first == len).then_some(())
}

/// The loops [`LoopWalker`] finds for the given faces (for tests).
#[cfg(test)]
pub(super) fn walk_loops(faces: &[(Plane, Vec<usize>)]) -> Vec<Vec<usize>> {
    let mut body = ConvexPolyhedron::empty();
    let mut vertex_count = 0;
    for (plane, loop_indices) in faces {
        let start = body.indices.len();
        body.indices.extend_from_slice(loop_indices);
        body.faces.push(FaceSpan { plane: *plane, start, end: body.indices.len() });
        vertex_count = vertex_count.max(loop_indices.iter().max().map_or(0, |&m| m + 1));
    }
    let mut edges = IndexMap::default();
    half_edge_faces(&mut edges, &body.faces, &body.indices);
    let mut walker = LoopWalker::default();
    walker.collect_boundary(&body.faces, &body.indices, &edges);
    let mut loops = Vec::new();
    walker.walk(vertex_count, |cycle| loops.push(cycle.to_vec()));
    loops
}
