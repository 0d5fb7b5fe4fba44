//! Convex polyhedra with index-shared faces, built from boxes and frusta and
//! cut by half-spaces.
//!
//! A body keeps its face loops in one flat index array (each face a span of
//! it), so that a body can be rebuilt in place and a solver that reuses its
//! bodies and a [`ClipWorkspace`] allocates nothing once their buffers have
//! grown (issue 15).

use glam::DVec3;

use super::clip::{half_edge_faces, loop_edges, ClipWorkspace, HalfEdges, IndexMap, LoopWalker};
use super::{accurate_cross, default_eps, Plane};

/// The faces of a box or frustum as loops of corner indices.
///
/// Bit 0 of a corner index selects x (0: minimum, or NDC x = -1), bit 1
/// selects y, bit 2 selects z (0: minimum, or the near plane). The loops are
/// counter-clockwise seen from outside when the corners are laid out with the
/// orientation of the index bits, as in an axis-aligned box; for the mirrored
/// layout every loop runs the other way.
const BOX_FACES: [[usize; 4]; 6] = [
    [0, 4, 6, 2], // -x
    [1, 3, 7, 5], // +x
    [0, 1, 5, 4], // -y
    [2, 6, 7, 3], // +y
    [0, 2, 3, 1], // -z, near
    [4, 5, 7, 6], // +z, far
];

/// [`BOX_FACES`] with every loop reversed: the layout of a frustum whose
/// corners are mirrored ([`ConvexPolyhedron::set_frustum_corners`]).
const BOX_FACES_REVERSED: [[usize; 4]; 6] = reverse_loops(BOX_FACES);

/// The loops of `faces`, each run the other way (`[a, b, c, d]` to `[d, c, b, a]`).
const fn reverse_loops(faces: [[usize; 4]; 6]) -> [[usize; 4]; 6] {
    let mut out = [[0; 4]; 6];
    let mut f = 0;
    while f < 6 {
        let mut k = 0;
        while k < 4 {
            out[f][k] = faces[f][3 - k];
            k += 1;
        }
        f += 1;
    }
    out
}

/// Per face `f` and loop edge `k` (`faces[f][k] → faces[f][k + 1]`) of a
/// box layout, the face running the reverse edge: the last one listed, as
/// the silhouette's lookup finds it (`u8::MAX`: none). Made at compile
/// time from the loops themselves.
const fn across_faces(faces: [[usize; 4]; 6]) -> [[u8; 4]; 6] {
    let mut out = [[u8::MAX; 4]; 6];
    let mut f = 0;
    while f < 6 {
        let mut k = 0;
        while k < 4 {
            let (a, b) = (faces[f][k], faces[f][(k + 1) % 4]);
            let mut g = 0;
            while g < 6 {
                let mut m = 0;
                while m < 4 {
                    if faces[g][m] == b && faces[g][(m + 1) % 4] == a {
                        out[f][k] = g as u8;
                    }
                    m += 1;
                }
                g += 1;
            }
            k += 1;
        }
        f += 1;
    }
    out
}

/// [`across_faces`] of [`BOX_FACES`] and of [`BOX_FACES_REVERSED`].
const BOX_ACROSS: [[[u8; 4]; 6]; 2] = [across_faces(BOX_FACES), across_faces(BOX_FACES_REVERSED)];

/// The loops of `faces` one after another, as a body's index list holds them.
const fn flatten(faces: [[usize; 4]; 6]) -> [usize; 24] {
    let mut out = [0; 24];
    let mut i = 0;
    while i < 24 {
        out[i] = faces[i / 4][i % 4];
        i += 1;
    }
    out
}

/// [`flatten`] of [`BOX_FACES`] and of [`BOX_FACES_REVERSED`].
const BOX_INDICES: [[usize; 24]; 2] = [flatten(BOX_FACES), flatten(BOX_FACES_REVERSED)];

/// One face of a [`ConvexPolyhedron`]: an outward plane and a loop of vertex
/// indices (a view into the body).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Face<'a> {
    plane: Plane,
    indices: &'a [usize],
}

impl<'a> Face<'a> {
    /// The face's plane, its normal pointing out of the polyhedron.
    ///
    /// This is the exact plane the face came from (a box side, a frustum side,
    /// a clipping plane, a hull face), never one refitted to the vertices;
    /// see [`ConvexPolyhedron`] for how closely they lie on it.
    #[must_use]
    pub fn plane(&self) -> Plane {
        self.plane
    }

    /// Indices into [`ConvexPolyhedron::vertices`] of the face's corners,
    /// counter-clockwise seen from outside (from where the normal points);
    /// at least three, all distinct. Two adjacent faces share the indices of
    /// their common edge and traverse it in opposite directions.
    #[must_use]
    pub fn indices(&self) -> &'a [usize] {
        self.indices
    }

    /// The directed edges `(from, to)` of the loop, in order.
    pub fn edges(&self) -> impl Iterator<Item = (usize, usize)> + 'a {
        loop_edges(self.indices)
    }
}

/// A face as stored: its plane and its span `start..end` of the body's
/// index array.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct FaceSpan {
    pub(super) plane: Plane,
    pub(super) start: usize,
    pub(super) end: usize,
}

/// A bounded convex polyhedron: indexed vertices and faces with outward
/// planes.
///
/// Either empty (no vertices, no faces) or closed: at least four faces, every
/// vertex used by some face, and every directed edge `(a, b)` of a face
/// matched by the edge `(b, a)` of exactly one other face. Edges are shared
/// by index, so silhouettes can be found by comparing face orientations.
/// Faces keep the exact planes they came from; they are not merged, so
/// coplanar neighbours and collinear vertices may occur after clipping.
///
/// All operations take a distance tolerance `eps`; see
/// [`ConvexPolyhedron::default_eps`]. A vertex lies within `eps` (plus
/// rounding) of each of its faces' planes and inside every other one: vertices
/// within `eps` of a clipping plane are kept as they are rather than moved
/// onto it. The one exception is conservative: where the plane of a new hull
/// face is ill-conditioned (a sliver), it may be pushed out past its
/// vertices rather than cut the body. Non-finite input never panics: it
/// yields an empty body, `None` or an empty plane list as documented.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ConvexPolyhedron {
    pub(super) vertices: Vec<DVec3>,
    pub(super) faces: Vec<FaceSpan>,
    pub(super) indices: Vec<usize>,
}

impl ConvexPolyhedron {
    /// The empty polyhedron.
    #[must_use]
    pub fn empty() -> Self {
        Self::default()
    }

    /// Whether the polyhedron is empty (has no faces).
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.faces.is_empty()
    }

    /// Makes the body empty, keeping its buffers for reuse.
    pub fn clear(&mut self) {
        self.vertices.clear();
        self.faces.clear();
        self.indices.clear();
    }

    /// Makes this body a copy of `other`, reusing its buffers (unlike
    /// `*self = other.clone()`, this does not allocate once they are large
    /// enough).
    pub fn copy_from(&mut self, other: &Self) {
        self.vertices.clone_from(&other.vertices);
        self.faces.clone_from(&other.faces);
        self.indices.clone_from(&other.indices);
    }

    /// Whether `other` is the same body bit for bit: vertices, face loops
    /// and face planes (`-0.0` differs from `0.0`; a NaN equals itself).
    /// Whatever is computed from a body alone is the same for both.
    pub(crate) fn bit_eq(&self, other: &Self) -> bool {
        // Component by component: comparing `[u64; 3]` arrays called
        // `memcmp` per vertex.
        let same = |a: &DVec3, b: &DVec3| {
            (a.x.to_bits() == b.x.to_bits()) & (a.y.to_bits() == b.y.to_bits()) & (a.z.to_bits() == b.z.to_bits())
        };
        self.indices == other.indices
            && self.vertices.len() == other.vertices.len()
            && self.faces.len() == other.faces.len()
            && self.vertices.iter().zip(&other.vertices).all(|(a, b)| same(a, b))
            && self.faces.iter().zip(&other.faces).all(|(a, b)| {
                a.start == b.start
                    && a.end == b.end
                    && same(&a.plane.normal, &b.plane.normal)
                    && a.plane.offset.to_bits() == b.plane.offset.to_bits()
            })
    }

    /// The vertices, indexed by [`Face::indices`].
    #[must_use]
    pub fn vertices(&self) -> &[DVec3] {
        &self.vertices
    }

    /// The faces, in order.
    pub fn faces(&self) -> impl ExactSizeIterator<Item = Face<'_>> + Clone + '_ {
        self.faces.iter().map(|span| self.view(span))
    }

    /// The number of faces.
    #[must_use]
    pub fn face_count(&self) -> usize {
        self.faces.len()
    }

    /// Face `k` (in the order of [`faces`](Self::faces)); `None` past the last.
    #[must_use]
    pub fn face(&self, k: usize) -> Option<Face<'_>> {
        self.faces.get(k).map(|span| self.view(span))
    }

    fn view(&self, span: &FaceSpan) -> Face<'_> {
        Face { plane: span.plane, indices: &self.indices[span.start..span.end] }
    }

    /// The face planes: the polyhedron is the intersection of their insides.
    pub fn planes(&self) -> impl ExactSizeIterator<Item = Plane> + '_ {
        self.faces.iter().map(|span| span.plane)
    }

    /// The mean of the vertices (an interior point of a non-degenerate
    /// body; not the centre of mass). `DVec3::ZERO` when empty.
    #[must_use]
    pub fn centroid(&self) -> DVec3 {
        if self.vertices.is_empty() {
            return DVec3::ZERO;
        }
        self.vertices.iter().sum::<DVec3>() / self.vertices.len() as f64
    }

    /// The diagonal of the bounding box; `0.0` when empty.
    #[must_use]
    pub fn scale(&self) -> f64 {
        self.aabb().map_or(0.0, |(min, max)| norm(max - min))
    }

    /// The default tolerance for this body: [`default_eps`] of its
    /// [`scale`](Self::scale), but of at least `1e-3` times its largest
    /// coordinate magnitude, so that a small body far from the origin still
    /// gets a tolerance well above the rounding of its coordinates.
    #[must_use]
    pub fn default_eps(&self) -> f64 {
        let magnitude = self.vertices.iter().fold(0.0, |m: f64, v| m.max(v.abs().max_element()));
        default_eps(self.scale().max(1e-3 * magnitude))
    }

    /// Whether `p` lies inside every face plane, up to `eps`. Always `false`
    /// when empty or for a NaN point.
    #[must_use]
    pub fn contains(&self, p: DVec3, eps: f64) -> bool {
        !self.is_empty() && self.faces.iter().all(|f| f.plane.signed_distance(p) <= eps)
    }

    /// The bounding box `(min, max)`; `None` when empty.
    #[must_use]
    pub fn aabb(&self) -> Option<(DVec3, DVec3)> {
        let first = *self.vertices.first()?;
        Some(self.vertices.iter().fold((first, first), |(min, max), &v| (min.min(v), max.max(v))))
    }

    /// The enclosed volume; `0.0` when empty.
    ///
    /// # Algorithm
    ///
    /// The sum over faces of the pyramids from the centroid `c`:
    /// `V = Σ area · (-signed_distance(c)) / 3`, each area from the cross
    /// products of the face's triangle fan around its own centre, projected
    /// on the face normal. Unlike summing tetrahedra `v0 · (v1 × v2)`, no
    /// term is larger than the pyramid it measures, so thin bodies (a padded
    /// flat box) keep full relative precision.
    #[must_use]
    pub fn volume(&self) -> f64 {
        let c = self.centroid();
        let mut three_volume = 0.0;
        for face in self.faces() {
            let corner = |i: usize| self.vertices[i];
            let center = face.indices.iter().map(|&i| corner(i)).sum::<DVec3>() / face.indices.len() as f64;
            let twice_area: DVec3 = face.edges().map(|(a, b)| (corner(a) - center).cross(corner(b) - center)).sum();
            let height = -face.plane.signed_distance(c);
            three_volume += 0.5 * twice_area.dot(face.plane.normal) * height;
        }
        three_volume / 3.0
    }

    /// The axis-aligned box `[min, max]`.
    ///
    /// A box thinner than `pad = 1e-9 * |max - min| + 1e-12 + 64 ε |coordinates|`
    /// in some axis (flat or a single point) is padded symmetrically to
    /// thickness `pad` there: the result is a superset of the input, thin
    /// enough not to matter and thick enough that every face stays
    /// well-defined (the last term keeps the padding above the spacing of
    /// `f64` values at the box's coordinates). Empty when `min > max` in any
    /// axis or any coordinate is not finite.
    #[must_use]
    pub fn from_aabb(min: DVec3, max: DVec3) -> Self {
        let mut body = Self::empty();
        body.set_aabb(min, max);
        body
    }

    /// Makes this body the box [`from_aabb`](Self::from_aabb) builds,
    /// reusing its buffers.
    pub fn set_aabb(&mut self, min: DVec3, max: DVec3) {
        self.clear();
        let Some((min, max)) = padded_box(min, max) else {
            return;
        };
        let pick = |bit: bool, lo: f64, hi: f64| if bit { hi } else { lo };
        self.vertices.extend((0..8).map(|i| {
            DVec3::new(pick(i & 1 != 0, min.x, max.x), pick(i & 2 != 0, min.y, max.y), pick(i & 4 != 0, min.z, max.z))
        }));
        // The loops at once, then their spans (what `push_face` per face makes).
        self.indices.extend_from_slice(&BOX_INDICES[0]);
        let planes = box_planes(min, max);
        self.faces.extend((0..6).map(|f| FaceSpan { plane: planes[f], start: 4 * f, end: 4 * f + 4 }));
    }

    /// Appends a face with the given loop.
    fn push_face(&mut self, plane: Plane, indices: &[usize]) {
        let start = self.indices.len();
        self.indices.extend_from_slice(indices);
        self.faces.push(FaceSpan { plane, start, end: self.indices.len() });
    }

    /// The frustum (any hexahedron with planar, convex faces) with the given
    /// corners.
    ///
    /// Corner `i` has NDC x = -1 if bit 0 of `i` is clear and +1 if it is
    /// set; bit 1 likewise selects y; bit 2 selects the near (clear) or far
    /// (set) plane. Either handedness works: faces are oriented outwards
    /// using the corners' centroid.
    ///
    /// Returns `None` if a corner is not finite, a face has no area, the
    /// centroid is not more than the [default tolerance](default_eps) inside
    /// every face, or a corner lies outside a face plane by more than that
    /// tolerance (twisted or non-convex corners). A frustum whose near plane
    /// is a single point (a pyramid) is therefore rejected.
    ///
    /// # Algorithm
    ///
    /// Each face plane is the Newell normal of its quad through the quad's
    /// centre, which is exact for planar quads and a least-squares fit
    /// otherwise.
    #[must_use]
    pub fn from_frustum_corners(corners: &[DVec3; 8]) -> Option<Self> {
        let mut body = Self::empty();
        body.set_frustum_corners(corners).then_some(body)
    }

    /// Makes this body the frustum [`from_frustum_corners`](Self::from_frustum_corners)
    /// builds, reusing its buffers; returns `false` (and leaves the body
    /// empty) where that returns `None`.
    pub fn set_frustum_corners(&mut self, corners: &[DVec3; 8]) -> bool {
        self.clear();
        if !corners.iter().all(|c| c.is_finite()) {
            return false;
        }
        let (min, max) = corners[1..].iter().fold((corners[0], corners[0]), |(lo, hi), &c| (lo.min(c), hi.max(c)));
        let magnitude = min.abs().max(max.abs()).max_element();
        let eps = default_eps(norm(max - min).max(1e-3 * magnitude));
        let centroid = corners.iter().sum::<DVec3>() / 8.0;

        let mut inward = 0;
        for (f, indices) in BOX_FACES.iter().enumerate() {
            let quad = indices.map(|i| corners[i]);
            let center = quad.iter().sum::<DVec3>() / 4.0;
            let newell: DVec3 = (0..4).map(|k| (quad[k] - center).cross(quad[(k + 1) % 4] - center)).sum();
            let Some(normal) = newell.try_normalize() else {
                self.clear();
                return false;
            };
            let plane = Plane { normal, offset: -normal.dot(center) };
            let d = plane.signed_distance(centroid);
            if d > eps {
                inward += 1;
            } else if d >= -eps {
                self.clear();
                return false;
            }
            self.faces.push(FaceSpan { plane, start: 4 * f, end: 4 * f + 4 });
        }
        // The loops at once (what `push_face` per face makes), each reversed
        // with its plane flipped when the corners are mirrored.
        match inward {
            0 => self.indices.extend_from_slice(&BOX_INDICES[0]),
            6 => {
                for span in &mut self.faces {
                    span.plane = span.plane.flipped();
                }
                self.indices.extend_from_slice(&BOX_INDICES[1]);
            }
            _ => {
                self.clear();
                return false;
            }
        }
        let convex = self.faces.iter().all(|f| corners.iter().all(|&c| f.plane.signed_distance(c) <= eps));
        if convex {
            self.vertices.extend_from_slice(corners);
        } else {
            self.clear();
        }
        convex
    }

    /// The part of the polyhedron inside `plane` (signed distance `<= 0`).
    ///
    /// Vertices within `eps` of the plane count as on it and are kept as they
    /// are. If no vertex lies more than `eps` outside, the polyhedron is
    /// returned unchanged; if none lies more than `eps` inside, the result is
    /// empty (what would remain is at most `eps` thick). A non-finite plane
    /// gives an empty result; a negative or NaN `eps` counts as zero.
    ///
    /// This allocates the result and scratch buffers; [`clip_into`](Self::clip_into)
    /// reuses them.
    ///
    /// # Algorithm
    ///
    /// Each face loop is clipped Sutherland–Hodgman style. An edge crossing
    /// the plane strictly (one end more than `eps` inside, the other more
    /// than `eps` outside) gets one new vertex, shared by both faces of the
    /// edge through a cache keyed by the edge's sorted vertex pair; edges
    /// ending on the plane get none. Faces left with fewer than three
    /// vertices, or with no vertex strictly inside (they lie in the cap), are
    /// dropped. The surviving faces leave a hole bounded by on-plane
    /// vertices, and the cap face follows the hole's boundary edges in
    /// reverse, so the result is closed and index-shared by construction,
    /// with no angular sorting that rounding could upset. The cap's plane is
    /// `plane` itself; other faces keep their planes; unused vertices are
    /// dropped. (Where faces nearly parallel to `plane` make the
    /// classification noisy at the `eps` level, the hole's boundary can touch
    /// itself at a vertex; it is then closed by one cap face per simple loop,
    /// so every edge still has exactly two faces.)
    #[must_use]
    pub fn clip(&self, plane: &Plane, eps: f64) -> Self {
        let mut out = Self::empty();
        self.clip_into(plane, eps, &mut out, &mut ClipWorkspace::default());
        out
    }

    /// [`clip`](Self::clip) into `out` (its previous content is replaced),
    /// with scratch buffers from `workspace`: no allocation once `out` and
    /// the workspace have grown to the body's size.
    pub fn clip_into(&self, plane: &Plane, eps: f64, out: &mut Self, workspace: &mut ClipWorkspace) {
        if !self.clip_core(plane, eps, out, workspace) {
            out.copy_from(self);
        }
    }

    /// The polyhedron clipped by every plane in turn (see [`clip`](Self::clip)).
    #[must_use]
    pub fn clip_all<'a>(&self, planes: impl IntoIterator<Item = &'a Plane>, eps: f64) -> Self {
        let mut body = self.clone();
        body.clip_all_in_place(planes, eps, &mut ClipWorkspace::default());
        body
    }

    /// [`clip_all`](Self::clip_all) into `out` (its previous content is
    /// replaced), reusing `workspace`.
    pub fn clip_all_into<'a>(
        &self,
        planes: impl IntoIterator<Item = &'a Plane>,
        eps: f64,
        out: &mut Self,
        workspace: &mut ClipWorkspace,
    ) {
        out.copy_from(self);
        out.clip_all_in_place(planes, eps, workspace);
    }

    /// Replaces the body by [`clip_all`](Self::clip_all) of it, reusing its
    /// buffers and `workspace`.
    pub fn clip_all_in_place<'a>(
        &mut self,
        planes: impl IntoIterator<Item = &'a Plane>,
        eps: f64,
        workspace: &mut ClipWorkspace,
    ) {
        // The spare body is taken once for the chain (`clip_core` does not
        // use it).
        let mut next = std::mem::take(&mut workspace.spare);
        for plane in planes {
            if self.is_empty() {
                break;
            }
            if self.clip_core(plane, eps, &mut next, workspace) {
                std::mem::swap(self, &mut next);
            }
        }
        workspace.spare = next;
    }

    /// The intersection with the box `[min, max]`, padded like
    /// [`from_aabb`](Self::from_aabb) when flat; empty for an invalid box.
    #[must_use]
    pub fn intersect_aabb(&self, min: DVec3, max: DVec3, eps: f64) -> Self {
        match padded_box(min, max) {
            Some((min, max)) => self.clip_all(&box_planes(min, max), eps),
            None => Self::empty(),
        }
    }

    /// The half-spaces whose intersection is `conv(self ∪ {p})`.
    ///
    /// These are the planes of the faces that do not see `p` (`p` at most
    /// `eps` outside them), plus, for each silhouette edge between a face
    /// that sees `p` and one that does not, the plane of the hull's face
    /// through the edge and `p`, oriented outwards (see
    /// [`hull_with_point`](Self::hull_with_point) for how it is chosen when
    /// ill-conditioned). When `p` is inside (within `eps`), these are just
    /// the face planes.
    ///
    /// Every plane returned has all vertices of `self` and `p` inside it to
    /// within `eps`, so the half-spaces always contain the hull; for
    /// non-degenerate input they describe it exactly. Empty when `self` is
    /// empty or `p` is not finite: there is then nothing to bound, and the
    /// caller must not read the empty list as "everywhere".
    #[must_use]
    pub fn hull_with_point_planes(&self, p: DVec3, eps: f64) -> Vec<Plane> {
        let mut planes = Vec::new();
        self.hull_with_point_planes_into(p, eps, &mut planes, &mut ClipWorkspace::default());
        planes
    }

    /// [`hull_with_point_planes`](Self::hull_with_point_planes) into `planes`
    /// (cleared first), reusing `workspace`.
    pub fn hull_with_point_planes_into(
        &self,
        p: DVec3,
        eps: f64,
        planes: &mut Vec<Plane>,
        workspace: &mut ClipWorkspace,
    ) {
        planes.clear();
        if self.is_empty() || !p.is_finite() {
            return;
        }
        let ClipWorkspace { flags: sees_p, half_edges: edges, silhouette, .. } = workspace;
        sees_p.clear();
        sees_p.extend(self.planes().map(|plane| plane.signed_distance(p) > eps));
        planes.extend(self.planes().zip(sees_p.iter()).filter(|&(_, &sees)| !sees).map(|(plane, _)| plane));
        self.silhouette(sees_p, edges, silhouette);
        for &(a, b, seeing, across) in silhouette.iter() {
            let plane = self.cone_face_plane(a, b, p, self.faces[seeing].plane, self.faces[across].plane, eps);
            if !planes.contains(&plane) {
                planes.push(plane);
            }
        }
    }

    /// The convex hull `conv(self ∪ {p})`.
    ///
    /// A clone when `p` is inside (within `eps`); empty when `self` is empty
    /// or `p` is not finite. Faces that see `p` (`p` more than `eps` outside
    /// them) are replaced by triangles joining `p` to the silhouette; the
    /// other faces and their vertex indices are kept. The face planes are
    /// those of [`hull_with_point_planes`](Self::hull_with_point_planes).
    ///
    /// # Algorithm
    ///
    /// The faces not seeing `p` form a surface with one hole, whose boundary
    /// is the silhouette; each boundary edge `(a, b)`, taken in the hole's
    /// orientation, gets the triangle `(a, b, p)`. Its plane has normal
    /// `(b - a) × (p - a)` (so `a, b, p` run counter-clockwise from
    /// outside), evaluated with fused multiply-adds so that it passes within
    /// rounding of `a`, `b` and `p`. That plane is ill-conditioned when `p`
    /// nearly lies on the line of a short edge, and rounding can then tilt
    /// it through the body; it is then pushed out, and replaced by the plane
    /// of the face across the edge, or by the plane of the face seeing `p`
    /// moved out to `p`, whichever passes closest to `a`, `b` and `p` (all
    /// three contain the hull). Should rounding ever make the silhouette
    /// touch itself (it is then not one simple loop), the hull is instead
    /// built by clipping a box around `self` and `p` by the hull's planes.
    #[must_use]
    pub fn hull_with_point(&self, p: DVec3, eps: f64) -> Self {
        if self.is_empty() || !p.is_finite() {
            return Self::empty();
        }
        let kept: Vec<FaceSpan> =
            self.faces.iter().filter(|face| face.plane.signed_distance(p) <= eps).copied().collect();
        if kept.len() == self.faces.len() {
            return self.clone();
        }
        let mut kept_edges = IndexMap::default();
        half_edge_faces(&mut kept_edges, &kept, &self.indices);
        let mut walker = LoopWalker::default();
        walker.collect_boundary(&kept, &self.indices, &kept_edges);
        let mut loops: Vec<Vec<usize>> = Vec::new();
        walker.walk(self.vertices.len(), |cycle| loops.push(cycle.to_vec()));
        let (Some(silhouette), None) = (loops.pop(), loops.pop()) else {
            return self.hull_by_clipping(p, eps);
        };

        let mut all_edges = IndexMap::default();
        half_edge_faces(&mut all_edges, &self.faces, &self.indices);
        let apex = self.vertices.len();
        let mut hull = Self::empty();
        hull.vertices.extend_from_slice(&self.vertices);
        hull.vertices.push(p);
        for span in &kept {
            hull.push_face(span.plane, &self.indices[span.start..span.end]);
        }
        for (k, &a) in silhouette.iter().enumerate() {
            let b = silhouette[(k + 1) % silhouette.len()];
            let (Some(&across), Some(&seeing)) = (kept_edges.get(&(b, a)), all_edges.get(&(a, b))) else {
                return self.hull_by_clipping(p, eps);
            };
            let plane = self.cone_face_plane(a, b, p, self.faces[seeing].plane, kept[across].plane, eps);
            hull.push_face(plane, &[a, b, apex]);
        }
        hull.finish_parts(&mut Vec::new());
        hull
    }

    /// The half-spaces of the unbounded body `{x + t * dir : x ∈ self, t >= 0}`
    /// (the polyhedron swept to infinity along `dir`). Clip a box by them to
    /// get a bounded body.
    ///
    /// These are the planes of the faces with `normal · dir <= 0`, plus, for
    /// each silhouette edge between such a face and one facing along `dir`,
    /// the plane containing the edge and `dir`, oriented outwards.
    ///
    /// Every plane returned has all vertices of `self` inside it to within
    /// `eps` and is parallel to `dir` or faces against it, so the half-spaces
    /// always contain the swept body; for non-degenerate input they describe
    /// it exactly. A zero `dir` gives the face planes; an empty `self` or a
    /// non-finite `dir` gives an empty list (see
    /// [`hull_with_point_planes`](Self::hull_with_point_planes)).
    ///
    /// # Algorithm
    ///
    /// Faces are split by the exact sign of `normal · dir`, not with a
    /// tolerance: a face kept although `dir` leaves it would cut the sweep
    /// off at a distance that grows without bound as the face nears
    /// parallel, while a nearly parallel face swept although it faces
    /// against `dir` only yields silhouette planes that nearly coincide with
    /// it. The silhouette plane through edge `(a, b)` of a face facing along
    /// `dir` has normal `(b - a) × dir`, evaluated with fused multiply-adds.
    #[must_use]
    pub fn extrusion_planes(&self, dir: DVec3, eps: f64) -> Vec<Plane> {
        let mut planes = Vec::new();
        self.extrusion_planes_into(dir, eps, &mut planes, &mut ClipWorkspace::default());
        planes
    }

    /// [`extrusion_planes`](Self::extrusion_planes) into `planes` (cleared
    /// first), reusing `workspace`.
    pub fn extrusion_planes_into(&self, dir: DVec3, eps: f64, planes: &mut Vec<Plane>, workspace: &mut ClipWorkspace) {
        planes.clear();
        if self.is_empty() {
            return;
        }
        // Scaling by the largest component first avoids overflow for huge `dir`.
        let Some(dir) = (dir / dir.abs().max_element()).try_normalize() else {
            if dir == DVec3::ZERO {
                planes.extend(self.planes());
            }
            return;
        };
        let ClipWorkspace { flags: swept, half_edges: edges, silhouette, .. } = workspace;
        swept.clear();
        swept.extend(self.planes().map(|plane| plane.normal.dot(dir) > 0.0));
        planes.extend(self.planes().zip(swept.iter()).filter(|&(_, &s)| !s).map(|(plane, _)| plane));
        self.silhouette(swept, edges, silhouette);
        for &(a, b, _, _) in silhouette.iter() {
            let (va, vb) = (self.vertices[a], self.vertices[b]);
            planes.extend(self.supporting_plane(accurate_cross(vb - va, dir), va, eps).map(|(plane, _)| plane));
        }
    }

    /// Empties the body when fewer than four faces remain (no volume) or a
    /// vertex overflowed; returns whether it is still non-empty.
    pub(super) fn finish_checks(&mut self) -> bool {
        if self.faces.len() < 4 || !self.vertices.iter().all(|v| v.is_finite()) {
            self.clear();
            return false;
        }
        true
    }

    /// Drops unused vertices (renumbering the faces); empties the body when
    /// fewer than four faces remain (no volume) or a vertex overflowed.
    /// `new_index` is scratch.
    pub(super) fn finish_parts(&mut self, new_index: &mut Vec<usize>) {
        if !self.finish_checks() {
            return;
        }
        new_index.clear();
        new_index.resize(self.vertices.len(), usize::MAX);
        let mut marked = 0;
        for &i in &self.indices {
            if new_index[i] == usize::MAX {
                new_index[i] = 0;
                marked += 1;
            }
        }
        if marked == self.vertices.len() {
            // Every vertex used: the numbering stays as it is.
            return;
        }
        let mut used = 0;
        for (i, slot) in new_index.iter_mut().enumerate() {
            if *slot != usize::MAX {
                *slot = used;
                self.vertices[used] = self.vertices[i];
                used += 1;
            }
        }
        self.vertices.truncate(used);
        for i in &mut self.indices {
            *i = new_index[*i];
        }
    }

    /// The directed edges `(a, b)` of faces marked in `removed` whose
    /// reverse `(b, a)` belongs to a face not marked, as
    /// `(a, b, removed face, other face)`, into `out`; `edge_faces` is
    /// scratch.
    fn silhouette(&self, removed: &[bool], edge_faces: &mut HalfEdges, out: &mut Vec<(usize, usize, usize, usize)>) {
        out.clear();
        // (The size test here, the table out of line: other bodies pay two
        // compares.)
        let box_sized = self.vertices.len() == 8 && self.faces.len() == 6;
        if (box_sized && self.silhouette_of_box(removed, out)) || self.silhouette_small(removed, out) {
            return;
        }
        out.clear();
        edge_faces.build(self.vertices.len(), &self.faces, &self.indices);
        for (f, face) in self.faces().enumerate().filter(|&(f, _)| removed[f]) {
            for (a, b) in face.edges() {
                match edge_faces.face(b, a) {
                    Some(across) if !removed[across] => out.push((a, b, f, across)),
                    _ => {}
                }
            }
        }
    }

    /// [`silhouette`](Self::silhouette) for a body laid out as a box or
    /// frustum is made (eight vertices, the six loops of [`BOX_FACES`], or
    /// all of them reversed, in that order), such as the view frustum `V`
    /// whose towards-light planes every PSM solve takes: the face across
    /// each edge comes from a table made from the same loops at compile
    /// time ([`BOX_ACROSS`]) instead of the per-call edge lists, so the
    /// same list, appended to `out` (empty before). Returns `false`, `out`
    /// untouched, for any other layout.
    #[inline(never)]
    fn silhouette_of_box(&self, removed: &[bool], out: &mut Vec<(usize, usize, usize, usize)>) -> bool {
        if self.vertices.len() != 8 || self.faces.len() != 6 || self.indices.len() != 24 || removed.len() < 6 {
            return false;
        }
        let layout = if self.indices[..] == BOX_INDICES[0] {
            0
        } else if self.indices[..] == BOX_INDICES[1] {
            1
        } else {
            return false;
        };
        if !self.faces.iter().enumerate().all(|(f, face)| face.start == 4 * f && face.end == 4 * f + 4) {
            return false;
        }
        let (loops, across) = (if layout == 0 { &BOX_FACES } else { &BOX_FACES_REVERSED }, &BOX_ACROSS[layout]);
        for f in 0..6 {
            if !removed[f] {
                continue;
            }
            for k in 0..4 {
                let g = usize::from(across[f][k]);
                if g < 6 && !removed[g] {
                    out.push((loops[f][k], loops[f][(k + 1) % 4], f, g));
                }
            }
        }
        true
    }

    /// [`silhouette`](Self::silhouette) for a small body (at most 64
    /// vertices, fewer than 255 faces and directed edges), with the edges
    /// chained by start vertex in stack arrays instead of [`HalfEdges`]: the
    /// same lookup (the last face listed that runs the reverse edge), so the
    /// same list, appended to `out`. Returns `false` (`out` then
    /// meaningless) when the body does not fit.
    fn silhouette_small(&self, removed: &[bool], out: &mut Vec<(usize, usize, usize, usize)>) -> bool {
        const NONE: u8 = u8::MAX;
        if self.vertices.len() > 64 || self.faces.len() >= usize::from(NONE) || self.indices.len() >= usize::from(NONE)
        {
            return false;
        }
        // Per vertex, the last directed edge leaving it; per directed edge
        // `a → b`, `(b, face, the previous edge leaving a)`.
        let mut head = [NONE; 64];
        // (Zeros, so that the array is set by `memset`.)
        let mut edges = [(0u8, 0u8, 0u8); 256];
        let mut count = 0usize;
        for (f, face) in self.faces.iter().enumerate() {
            let loop_indices = &self.indices[face.start..face.end];
            let Some(&first) = loop_indices.first() else { continue };
            for (k, &a) in loop_indices.iter().enumerate() {
                let b = loop_indices.get(k + 1).copied().unwrap_or(first);
                // (`b` is checked as the start of the loop's next edge
                // before the lookups below read `head[b]`.)
                if a >= 64 {
                    return false;
                }
                edges[count] = (b as u8, f as u8, head[a]);
                head[a] = count as u8;
                count += 1;
            }
        }
        for (f, face) in self.faces.iter().enumerate() {
            if !removed[f] {
                continue;
            }
            let loop_indices = &self.indices[face.start..face.end];
            let Some(&first) = loop_indices.first() else { continue };
            for (k, &a) in loop_indices.iter().enumerate() {
                let b = loop_indices.get(k + 1).copied().unwrap_or(first);
                // The face of `b → a`.
                let mut e = head[b];
                while e != NONE {
                    let (to, across, previous) = edges[usize::from(e)];
                    if usize::from(to) == a {
                        if !removed[usize::from(across)] {
                            out.push((a, b, f, usize::from(across)));
                        }
                        break;
                    }
                    e = previous;
                }
            }
        }
        true
    }

    /// The plane of the face `(a, b, p)` of `conv(self ∪ {p})` along the
    /// silhouette edge `a → b` of the face with plane `seeing`, across from
    /// the face with plane `across` (see
    /// [`hull_with_point`](Self::hull_with_point)).
    fn cone_face_plane(&self, a: usize, b: usize, p: DVec3, seeing: Plane, across: Plane, eps: f64) -> Plane {
        // Candidates containing `self` and `p`, with how far the corners
        // `a`, `b`, `p` of the new face lie from them.
        let moved_out = seeing.signed_distance(p);
        let raised = Plane { normal: seeing.normal, offset: seeing.offset - moved_out };
        let mut best = (across, across.signed_distance(p).abs());
        if moved_out < best.1 {
            best = (raised, moved_out);
        }
        let (va, vb) = (self.vertices[a], self.vertices[b]);
        if let Some((plane, pushed)) = self.supporting_plane(accurate_cross(vb - va, p - va), va, eps) {
            if pushed <= best.1 {
                best = (plane, pushed);
            }
        }
        best.0
    }

    /// The plane through `anchor` with outward normal along `normal`, and how
    /// far it had to be pushed outwards (`0.0` if not at all) so that no
    /// vertex lies more than `eps` outside it. `None` for a zero or
    /// non-finite `normal`.
    fn supporting_plane(&self, normal: DVec3, anchor: DVec3, eps: f64) -> Option<(Plane, f64)> {
        let normal = normal.try_normalize()?;
        let mut plane = Plane { normal, offset: -normal.dot(anchor) };
        // The largest distance from 0 by plain compares (`f64::max` checks
        // for NaN each time; a NaN is passed over either way, and a zero's
        // sign decides nothing below).
        let mut excess = 0.0;
        for &v in &self.vertices {
            let d = plane.signed_distance(v);
            if d > excess {
                excess = d;
            }
        }
        if excess > eps {
            plane.offset -= excess;
            return Some((plane, excess));
        }
        Some((plane, 0.0))
    }

    /// [`hull_with_point`](Self::hull_with_point) by clipping a box around
    /// `self` and `p` with the hull's planes.
    fn hull_by_clipping(&self, p: DVec3, eps: f64) -> Self {
        let Some((min, max)) = self.aabb() else {
            return Self::empty();
        };
        let (min, max) = (min.min(p), max.max(p));
        let margin = DVec3::splat(0.01 * norm(max - min) + eps);
        Self::from_aabb(min - margin, max + margin).clip_all(&self.hull_with_point_planes(p, eps), eps)
    }
}

/// The valid box `[min, max]` with flat axes padded (see
/// [`ConvexPolyhedron::from_aabb`]); `None` when inverted or not finite.
pub(crate) fn padded_box(min: DVec3, max: DVec3) -> Option<(DVec3, DVec3)> {
    let extent = max - min;
    if !(min.is_finite() && max.is_finite() && extent.is_finite()) || min.cmpgt(max).any() {
        return None;
    }
    let magnitude = min.abs().max(max.abs()).max_element();
    let pad = 1e-9 * norm(extent) + 1e-12 + 64.0 * f64::EPSILON * magnitude;
    let (mut min, mut max) = (min, max);
    for axis in 0..3 {
        if max[axis] - min[axis] < pad {
            let mid = 0.5 * (min[axis] + max[axis]);
            min[axis] = mid - 0.5 * pad;
            max[axis] = mid + 0.5 * pad;
        }
    }
    Some((min, max))
}

/// `|v|` without overflow or underflow in the squares.
fn norm(v: DVec3) -> f64 {
    let largest = v.abs().max_element();
    if largest > 0.0 && largest.is_finite() {
        largest * (v / largest).length()
    } else {
        largest
    }
}

/// The planes of the box `[min, max]`, in [`BOX_FACES`] order.
fn box_planes(min: DVec3, max: DVec3) -> [Plane; 6] {
    let plane = |normal: DVec3, offset: f64| Plane { normal, offset };
    [
        plane(DVec3::NEG_X, min.x),
        plane(DVec3::X, -max.x),
        plane(DVec3::NEG_Y, min.y),
        plane(DVec3::Y, -max.y),
        plane(DVec3::NEG_Z, min.z),
        plane(DVec3::Z, -max.z),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    const EPS: f64 = 1e-9;

    fn unit_cube() -> ConvexPolyhedron {
        ConvexPolyhedron::from_aabb(DVec3::ZERO, DVec3::ONE)
    }

    /// A hundred unit cubes, each cut by up to eight random planes through
    /// its middle; `visit` sees the body after every cut that leaves one.
    fn for_random_clipped_cubes<R: FnMut() -> f64>(
        random: &mut R,
        workspace: &mut ClipWorkspace,
        mut visit: impl FnMut(&ConvexPolyhedron, &mut R),
    ) {
        for _ in 0..100 {
            let mut body = unit_cube();
            for _ in 0..8 {
                let n = DVec3::new(random() - 0.5, random() - 0.5, random() - 0.5);
                let Some(n) = n.try_normalize() else { continue };
                let plane = Plane::from_point_normal(body.centroid() + n * (random() - 0.5) * 0.5, n);
                let mut next = ConvexPolyhedron::empty();
                body.clip_into(&plane, 1e-9, &mut next, workspace);
                if next.is_empty() {
                    break;
                }
                body = next;
                visit(&body, random);
            }
        }
    }

    /// The shared [`ConvexPolyhedron::sanity_check`], plus a centroid inside
    /// and a positive volume.
    fn assert_valid(body: &ConvexPolyhedron) {
        if let Err(e) = body.sanity_check(1e-9 * body.scale().max(1.0)) {
            panic!("{e}");
        }
        if body.is_empty() {
            return;
        }
        assert!(body.contains(body.centroid(), 0.0));
        assert!(body.volume() > 0.0);
    }

    #[test]
    fn cube_basics() {
        let cube = unit_cube();
        assert_valid(&cube);
        assert_eq!(cube.vertices().len(), 8);
        assert_eq!(cube.faces().len(), 6);
        assert!((cube.volume() - 1.0).abs() < 1e-15);
        assert_eq!(cube.centroid(), DVec3::splat(0.5));
        assert!((cube.scale() - 3f64.sqrt()).abs() < 1e-15);
        assert_eq!(cube.aabb(), Some((DVec3::ZERO, DVec3::ONE)));
        assert!(cube.contains(DVec3::ONE, 0.0));
        assert!(!cube.contains(DVec3::new(1.1, 0.5, 0.5), EPS));
        assert!(!cube.contains(DVec3::NAN, EPS));
        assert!((cube.default_eps() - 1e-9 * 3f64.sqrt()).abs() < 1e-20);
    }

    #[test]
    fn empty_body() {
        let e = ConvexPolyhedron::empty();
        assert!(e.is_empty());
        assert_eq!(e.volume(), 0.0);
        assert_eq!(e.scale(), 0.0);
        assert_eq!(e.aabb(), None);
        assert!(!e.contains(DVec3::ZERO, 1.0));
        assert!(e.clip(&Plane::from_point_normal(DVec3::ZERO, DVec3::X), EPS).is_empty());
        assert!(e.hull_with_point(DVec3::ZERO, EPS).is_empty());
        assert!(e.hull_with_point_planes(DVec3::ZERO, EPS).is_empty());
        assert!(e.extrusion_planes(DVec3::X, EPS).is_empty());
    }

    #[test]
    fn flat_and_invalid_boxes() {
        let flat = ConvexPolyhedron::from_aabb(DVec3::new(0.0, 2.0, 0.0), DVec3::new(4.0, 2.0, 3.0));
        assert_valid(&flat);
        let (min, max) = flat.aabb().unwrap();
        let thickness = max.y - min.y;
        assert!(thickness > 0.0 && thickness < 1e-8, "{thickness}");
        assert!(min.y < 2.0 && max.y > 2.0);

        let point = ConvexPolyhedron::from_aabb(DVec3::splat(1e5), DVec3::splat(1e5));
        assert_valid(&point);
        assert!(point.contains(DVec3::splat(1e5), 0.0));

        assert!(ConvexPolyhedron::from_aabb(DVec3::ONE, DVec3::ZERO).is_empty());
        assert!(ConvexPolyhedron::from_aabb(DVec3::new(0.0, 0.0, 1.0), DVec3::new(1.0, 1.0, 0.0)).is_empty());
        assert!(ConvexPolyhedron::from_aabb(DVec3::NAN, DVec3::ONE).is_empty());
        assert!(ConvexPolyhedron::from_aabb(DVec3::ZERO, DVec3::INFINITY).is_empty());
    }

    #[test]
    fn clip_in_half() {
        let half = unit_cube().clip(&Plane::from_point_normal(DVec3::splat(0.5), DVec3::X), EPS);
        assert_valid(&half);
        assert_eq!((half.vertices().len(), half.faces().len()), (8, 6));
        assert!((half.volume() - 0.5).abs() < 1e-15);
        assert_eq!(half.aabb(), Some((DVec3::ZERO, DVec3::new(0.5, 1.0, 1.0))));
    }

    #[test]
    fn clip_corner() {
        let plane = Plane::from_point_normal(DVec3::new(1.0, 1.0, 0.75), DVec3::ONE);
        let body = unit_cube().clip(&plane, EPS);
        assert_valid(&body);
        assert_eq!((body.vertices().len(), body.faces().len()), (10, 7));
        // Cut-off corner: tetrahedron with legs 0.25.
        assert!((body.volume() - (1.0 - 0.25f64.powi(3) / 6.0)).abs() < 1e-14);
        let cap = body.faces().last().unwrap();
        assert_eq!(cap.plane(), plane);
        assert_eq!(cap.indices().len(), 3);
    }

    #[test]
    fn clip_through_vertices() {
        // Through four vertices: the cut runs along existing edges.
        let plane = Plane::from_point_normal(DVec3::ZERO, DVec3::new(1.0, 0.0, -1.0));
        let prism = unit_cube().clip(&plane, EPS);
        assert_valid(&prism);
        assert_eq!((prism.vertices().len(), prism.faces().len()), (6, 5));
        assert!((prism.volume() - 0.5).abs() < 1e-15);

        // Touching a single vertex from outside: unchanged.
        let touching = Plane::from_point_normal(DVec3::ONE, DVec3::ONE);
        assert_eq!(unit_cube().clip(&touching, EPS), unit_cube());
        // Touching from inside: only a vertex would remain.
        assert!(unit_cube().clip(&touching.flipped(), EPS).is_empty());
        // A face on the plane, the rest outside: nothing with volume remains.
        let face_plane = Plane::from_point_normal(DVec3::ZERO, DVec3::X);
        assert!(unit_cube().clip(&face_plane, EPS).is_empty());
        assert_eq!(unit_cube().clip(&face_plane.flipped(), EPS), unit_cube());
        // Within eps of a face: counts as on it.
        let near = Plane::from_point_normal(DVec3::new(1.0 - 1e-12, 0.0, 0.0), DVec3::X);
        assert_eq!(unit_cube().clip(&near, EPS), unit_cube());
    }

    #[test]
    fn clip_by_bad_planes() {
        let nan = Plane { normal: DVec3::NAN, offset: 0.0 };
        assert!(unit_cube().clip(&nan, EPS).is_empty());
        let zero = Plane::from_point_normal(DVec3::ZERO, DVec3::ZERO);
        assert!(unit_cube().clip(&zero, EPS).is_empty());
        // NaN eps counts as zero.
        let half = unit_cube().clip(&Plane::from_point_normal(DVec3::splat(0.5), DVec3::Y), f64::NAN);
        assert!((half.volume() - 0.5).abs() < 1e-15);
    }

    #[test]
    fn clip_all_and_intersect_aabb() {
        let planes: Vec<Plane> =
            [DVec3::X, DVec3::Y, DVec3::Z].iter().map(|&n| Plane::from_point_normal(DVec3::splat(0.5), n)).collect();
        let small = unit_cube().clip_all(&planes, EPS);
        assert!((small.volume() - 0.125).abs() < 1e-15);
        let boxed = unit_cube().intersect_aabb(DVec3::splat(0.25), DVec3::splat(2.0), EPS);
        assert!((boxed.volume() - 0.75f64.powi(3)).abs() < 1e-14);
        assert!(unit_cube().intersect_aabb(DVec3::splat(2.0), DVec3::splat(3.0), EPS).is_empty());
        assert!(unit_cube().intersect_aabb(DVec3::ONE, DVec3::ZERO, EPS).is_empty());
    }

    fn frustum_corners(mirror: bool) -> [DVec3; 8] {
        let (near, far, t) = (0.5, 4.0, 0.75);
        std::array::from_fn(|i| {
            let x = if i & 1 == 0 { -1.0 } else { 1.0 };
            let y = if i & 2 == 0 { -1.0 } else { 1.0 };
            let z = if i & 4 == 0 { near } else { far };
            let p = DVec3::new(x * t * z, y * t * z, -z);
            if mirror {
                p * DVec3::new(-1.0, 1.0, 1.0)
            } else {
                p
            }
        })
    }

    #[test]
    fn frustum_either_handedness() {
        let (near, far, t) = (0.5f64, 4.0f64, 0.75f64);
        let expected = 4.0 * t * t * (far.powi(3) - near.powi(3)) / 3.0;
        for mirror in [false, true] {
            let f = ConvexPolyhedron::from_frustum_corners(&frustum_corners(mirror)).unwrap();
            assert_valid(&f);
            assert!((f.volume() - expected).abs() < 1e-12 * expected);
            assert!(f.contains(DVec3::new(0.0, 0.0, -1.0), 0.0));
            assert!(!f.contains(DVec3::new(0.0, 0.0, -0.4), EPS));
        }
    }

    #[test]
    fn degenerate_frusta() {
        let mut c = frustum_corners(false);
        c[3] = DVec3::NAN;
        assert!(ConvexPolyhedron::from_frustum_corners(&c).is_none());
        // Near face collapsed to a point.
        let mut c = frustum_corners(false);
        for corner in &mut c[..4] {
            *corner = DVec3::ZERO;
        }
        assert!(ConvexPolyhedron::from_frustum_corners(&c).is_none());
        // Twisted: two far corners swapped.
        let mut c = frustum_corners(false);
        c.swap(4, 5);
        assert!(ConvexPolyhedron::from_frustum_corners(&c).is_none());
        // Flat.
        let c: [DVec3; 8] = std::array::from_fn(|i| DVec3::new((i & 1) as f64, ((i >> 1) & 1) as f64, 0.0));
        assert!(ConvexPolyhedron::from_frustum_corners(&c).is_none());
    }

    #[test]
    fn hull_with_point_above_face() {
        let cube = unit_cube();
        let p = DVec3::new(0.5, 0.5, 3.0);
        let hull = cube.hull_with_point(p, EPS);
        assert_valid(&hull);
        assert_eq!((hull.vertices().len(), hull.faces().len()), (9, 9));
        assert!((hull.volume() - (1.0 + 2.0 / 3.0)).abs() < 1e-14);
        let planes = cube.hull_with_point_planes(p, EPS);
        assert_eq!(planes.len(), 9);
        let mut from_planes: Vec<Plane> = hull.planes().collect();
        let key =
            |a: &Plane, b: &Plane| a.to_homogeneous().to_array().partial_cmp(&b.to_homogeneous().to_array()).unwrap();
        from_planes.sort_by(key);
        let mut sorted = planes.clone();
        sorted.sort_by(key);
        assert_eq!(from_planes, sorted);
        for plane in &planes {
            assert!(plane.signed_distance(p).abs() < 1e-15 || plane.signed_distance(p) < 0.0);
        }
    }

    #[test]
    fn hull_with_point_inside_or_on() {
        let cube = unit_cube();
        for p in [DVec3::splat(0.5), DVec3::ONE, DVec3::new(1.0 + 1e-12, 0.5, 0.5)] {
            assert_eq!(cube.hull_with_point(p, EPS), cube);
            assert_eq!(cube.hull_with_point_planes(p, EPS), cube.planes().collect::<Vec<_>>());
        }
        assert!(cube.hull_with_point(DVec3::NAN, EPS).is_empty());
        assert!(cube.hull_with_point_planes(DVec3::INFINITY, EPS).is_empty());
    }

    #[test]
    fn hull_with_point_beyond_corner() {
        let hull = unit_cube().hull_with_point(DVec3::splat(2.0), EPS);
        assert_valid(&hull);
        // Three faces see p; their three far vertices... only (1,1,1) is lost.
        assert_eq!(hull.vertices().len(), 8);
        assert!(!hull.vertices().contains(&DVec3::ONE));
        // 3 kept faces + 6 triangles to the 6-edge silhouette.
        assert_eq!(hull.faces().len(), 9);
        assert!((hull.volume() - (1.0 + 3.0 * (1.0 / 3.0))).abs() < 1e-14);
    }

    #[test]
    fn hull_with_point_grazing_an_edge() {
        // p sees the top face (by more than eps) and the right face by less
        // than eps: the plane through their common edge and p would cut the
        // cube, so the right face's own plane bounds the hull there.
        let cube = unit_cube();
        let p = DVec3::new(1.0 + 0.5 * EPS, 0.5, 1.0 + 2.0 * EPS);
        let planes = cube.hull_with_point_planes(p, EPS);
        for plane in &planes {
            for &v in cube.vertices() {
                assert!(plane.signed_distance(v) <= EPS, "{plane:?} cuts {v}");
            }
            assert!(plane.signed_distance(p) <= EPS);
        }
        let hull = cube.hull_with_point(p, EPS);
        assert_valid(&hull);
        assert!((hull.volume() - 1.0).abs() < 1e-8);
    }

    #[test]
    fn extrude_cube() {
        let cube = unit_cube();
        let planes = cube.extrusion_planes(DVec3::new(0.0, 0.0, -2.0), EPS);
        assert_eq!(planes.len(), 9);
        let swept = ConvexPolyhedron::from_aabb(DVec3::splat(-10.0), DVec3::splat(10.0)).clip_all(&planes, EPS);
        assert_valid(&swept);
        let (min, max) = swept.aabb().unwrap();
        assert!((min - DVec3::new(0.0, 0.0, -10.0)).length() < 1e-14 && (max - DVec3::ONE).length() < 1e-14);

        // Diagonal sweep: a slanted prism.
        let dir = DVec3::new(1.0, 1.0, 1.0);
        let planes = cube.extrusion_planes(dir, EPS);
        let swept = ConvexPolyhedron::from_aabb(DVec3::splat(-10.0), DVec3::splat(10.0)).clip_all(&planes, EPS);
        assert_valid(&swept);
        assert!(swept.contains(DVec3::splat(9.5), EPS));
        assert!(swept.contains(DVec3::ZERO, EPS));
        assert!(!swept.contains(DVec3::new(5.0, 0.0, 0.0), EPS));
        assert!(!swept.contains(DVec3::splat(-0.1), EPS));

        assert_eq!(cube.extrusion_planes(DVec3::ZERO, EPS), cube.planes().collect::<Vec<_>>());
        assert!(cube.extrusion_planes(DVec3::NAN, EPS).is_empty());
        assert_eq!(cube.extrusion_planes(DVec3::new(0.0, 1e300, 0.0), EPS).len(), 9);
    }

    #[test]
    fn hole_loops_split_a_pinched_boundary() {
        let face = |indices: Vec<usize>| (Plane { normal: DVec3::Z, offset: 0.0 }, indices);
        // Loops as sorted lists of cycles each starting at its least vertex.
        let loops = |faces: &[(Plane, Vec<usize>)]| {
            let mut loops = super::super::clip::walk_loops(faces);
            for l in &mut loops {
                let least = l.iter().enumerate().min_by_key(|&(_, v)| v).map_or(0, |(i, _)| i);
                l.rotate_left(least);
            }
            loops.sort();
            loops
        };
        // One quad: one hole, its loop reversed.
        assert_eq!(loops(&[face(vec![0, 1, 2, 3])]), vec![vec![0, 3, 2, 1]]);
        // Two triangles touching at vertex 0: a figure-eight boundary.
        assert_eq!(loops(&[face(vec![0, 1, 2]), face(vec![0, 3, 4])]), vec![vec![0, 2, 1], vec![0, 4, 3]]);
        // Closed: no hole.
        let cube: Vec<_> = unit_cube().faces().map(|f| (f.plane(), f.indices().to_vec())).collect();
        assert!(loops(&cube).is_empty());
    }

    /// The clip's fast paths equal the general one bit for bit: the cap
    /// boundary from plane edges alone (or, with no vertex on the plane, the
    /// consecutive cut points noted while cutting), the cap traced directly
    /// as one loop, and no renumbering pass, against the reference (every
    /// edge's reverse looked up in all faces, the general walk, the
    /// renumbering pass), over random cuts: planes through vertices and
    /// along faces (on-plane vertices and edges), thick tolerances, slivers.
    #[test]
    fn cap_boundary_fast_path_equals_reference() {
        let mut random = crate::test_rng::unit(0x2545_f491_4f6c_dd1d_u64);
        let (mut fast, mut reference) = (ClipWorkspace::default(), ClipWorkspace::default());
        reference.reference_boundary = true;
        let mut cuts = 0;
        for _ in 0..300 {
            let mut body = unit_cube();
            for _ in 0..12 {
                let n = DVec3::new(random() - 0.5, random() - 0.5, random() - 0.5);
                let Some(n) = n.try_normalize() else { continue };
                // Through a vertex, through a face's centre, or anywhere.
                let k = (random() * body.vertices().len() as f64) as usize % body.vertices().len().max(1);
                let through = match (random() * 3.0) as usize {
                    0 => body.vertices()[k],
                    1 => body.centroid(),
                    _ => body.centroid() + n * (random() - 0.5) * 0.5,
                };
                let plane = if random() < 0.3 {
                    // Through an edge: both its ends on the plane, the edge
                    // shared by two faces that may both stay.
                    let face = body.face(k % body.face_count()).expect("a face");
                    let (a, b) = face.edges().next().expect("an edge");
                    let (va, vb) = (body.vertices()[a], body.vertices()[b]);
                    match (vb - va).cross(n).try_normalize() {
                        Some(normal) => Plane::from_point_normal(va, normal),
                        None => continue,
                    }
                } else {
                    Plane::from_point_normal(through, n)
                };
                let eps = [1e-9, 1e-3, 0.05][(random() * 3.0) as usize % 3];
                let (mut a, mut b) = (ConvexPolyhedron::empty(), ConvexPolyhedron::empty());
                body.clip_into(&plane, eps, &mut a, &mut fast);
                body.clip_into(&plane, eps, &mut b, &mut reference);
                assert_eq!(a, b);
                assert!(a.bit_eq(&b));
                cuts += 1;
                if a.is_empty() {
                    break;
                }
                body = a;
            }
        }
        assert!(cuts > 1000);
    }

    /// The silhouette's half-edge lookup (grouped by start vertex) finds
    /// the same face as a map of every directed edge filled in face order,
    /// for every vertex pair of random clipped bodies, on faces with a
    /// repeated edge (the last face wins) and out of range.
    #[test]
    fn small_silhouette_equals_the_half_edge_one() {
        let mut random = crate::test_rng::unit(0x6a09_e667_f3bc_c908_u64);
        let (mut half, mut workspace) = (HalfEdges::default(), ClipWorkspace::default());
        let (mut small, mut reference) = (Vec::new(), Vec::new());
        let mut check = |body: &ConvexPolyhedron, removed: &[bool]| {
            small.clear();
            assert!(body.silhouette_small(removed, &mut small));
            half.build(body.vertices.len(), &body.faces, &body.indices);
            reference.clear();
            for (f, face) in body.faces().enumerate().filter(|&(f, _)| removed[f]) {
                for (a, b) in face.edges() {
                    match half.face(b, a) {
                        Some(across) if !removed[across] => reference.push((a, b, f, across)),
                        _ => {}
                    }
                }
            }
            assert_eq!(small, reference);
            usize::from(!small.is_empty())
        };
        let mut silhouettes = 0;
        for_random_clipped_cubes(&mut random, &mut workspace, |body, random| {
            let removed: Vec<bool> = (0..body.face_count()).map(|_| random() < 0.4).collect();
            silhouettes += check(body, &removed);
        });
        assert!(silhouettes > 100, "{silhouettes}");
        // A directed edge run by two faces: the later face is across.
        let mut doubled = unit_cube();
        let first = doubled.faces[0];
        let start = doubled.indices.len();
        doubled.indices.extend_from_within(first.start..first.end);
        doubled.faces.push(FaceSpan { plane: first.plane, start, end: doubled.indices.len() });
        check(&doubled, &[false, true, true, true, true, false, false]);
    }

    /// The box layout's table gives the half-edge lookup's silhouette for
    /// boxes and frusta of both handednesses, for every set of removed
    /// faces; other layouts (a clipped cube, a reordered loop) are left to
    /// the general lookup.
    #[test]
    fn box_silhouette_equals_the_half_edge_one() {
        let mut half = HalfEdges::default();
        let reference = |body: &ConvexPolyhedron, removed: &[bool], half: &mut HalfEdges| {
            half.build(body.vertices.len(), &body.faces, &body.indices);
            let mut list = Vec::new();
            for (f, face) in body.faces().enumerate().filter(|&(f, _)| removed[f]) {
                for (a, b) in face.edges() {
                    match half.face(b, a) {
                        Some(across) if !removed[across] => list.push((a, b, f, across)),
                        _ => {}
                    }
                }
            }
            list
        };
        let bodies = [
            unit_cube(),
            ConvexPolyhedron::from_frustum_corners(&frustum_corners(false)).unwrap(),
            ConvexPolyhedron::from_frustum_corners(&frustum_corners(true)).unwrap(),
        ];
        assert_ne!(bodies[1].indices, bodies[2].indices, "both layouts");
        let mut edges = 0;
        for body in &bodies {
            for mask in 0..64u32 {
                let removed: Vec<bool> = (0..6).map(|f| mask & (1 << f) != 0).collect();
                let mut fast = Vec::new();
                assert!(body.silhouette_of_box(&removed, &mut fast));
                assert_eq!(fast, reference(body, &removed, &mut half), "mask {mask}");
                edges += fast.len();
            }
        }
        assert!(edges > 500, "{edges}");
        let clipped = unit_cube().clip(&Plane::from_point_normal(DVec3::splat(0.9), DVec3::ONE.normalize()), 1e-12);
        let mut reordered = unit_cube();
        reordered.indices[0..4].rotate_left(1);
        for body in [clipped, reordered] {
            let removed = vec![true; body.face_count()];
            assert!(!body.silhouette_of_box(&removed, &mut Vec::new()));
        }
    }

    #[test]
    fn half_edges_equal_the_edge_map() {
        let mut random = crate::test_rng::unit(0x9e37_79b9_7f4a_7c15_u64);
        let (mut half, mut map, mut workspace) = (HalfEdges::default(), IndexMap::default(), ClipWorkspace::default());
        let mut check = |body: &ConvexPolyhedron, half: &mut HalfEdges| {
            half.build(body.vertices.len(), &body.faces, &body.indices);
            half_edge_faces(&mut map, &body.faces, &body.indices);
            let n = body.vertices.len() + 2;
            for a in 0..n {
                for b in 0..n {
                    assert_eq!(half.face(a, b), map.get(&(a, b)).copied(), "edge {a} -> {b}");
                }
            }
        };
        for_random_clipped_cubes(&mut random, &mut workspace, |body, _| check(body, &mut half));
        // A directed edge run by two faces: the map keeps the later face.
        let mut doubled = unit_cube();
        let first = doubled.faces[0];
        let start = doubled.indices.len();
        doubled.indices.extend_from_within(first.start..first.end);
        doubled.faces.push(FaceSpan { plane: first.plane, start, end: doubled.indices.len() });
        check(&doubled, &mut half);
    }

    #[test]
    fn repeated_clipping_stays_closed() {
        // Many planes through nearly the same line: near-degenerate cuts.
        let mut body = unit_cube();
        for k in 0..50 {
            let angle = 0.3 + 1e-7 * k as f64;
            let n = DVec3::new(angle.cos(), angle.sin(), 1e-3 * k as f64);
            body = body.clip(&Plane::from_point_normal(DVec3::splat(0.5), n), EPS);
            assert_valid(&body);
        }
    }
}
