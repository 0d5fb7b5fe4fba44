//! [`SolveWorkspace`]: the reusable buffers behind [`ShadowProblem::solve`],
//! and a cache of what depends only on the camera and the scene bounds.
//!
//! Why: an engine solves every light's matrix every frame, with the same
//! camera for all its lights and often the same camera from frame to frame.
//! Each classical method builds a few convex bodies, clips them and fits a
//! map; done with fresh buffers that was hundreds of allocations per solve,
//! and the view frustum's planes and the visible receivers `V ∩ R` (the same
//! for every point and directional light) were rebuilt per light. A
//! workspace keeps the buffers (bodies, point lists, plane lists, the clip's
//! and the fit's scratch) and the camera-only results; once warm, a solve
//! allocates nothing.
//!
//! The cache is keyed by the camera's matrices, clip distances and the scene
//! bounds compared bit for bit, and by the plane tolerance; on any change it
//! is rebuilt. Cached and rebuilt results are the same computation on the
//! same input, so the matrices are bit-identical to an uncached solve
//! (`tests/optimize_workspace.rs` checks this over random and hard cases).
//! Spot lights clip the receivers by their own frustum before the view
//! frustum, so their visible receivers depend on the light too: the cache
//! keeps those of the last spot light solved twice in a row (its bits), and
//! so PSM's hull `conv(V ∪ l) ∩ S ∩ L` of the last light.
//!
//! A second cache holds the last caster body (the caster box clipped by the
//! region between a body and the light): most of a solve on a fixed camera
//! once `V ∩ R` is cached. It is keyed by the light, the casters' bounds and
//! the tolerance (bits) and by the body it was built around (compared bit
//! for bit), so it hits when the same light is solved again around the same
//! body: several methods for one light in a row, or one workspace per light
//! from frame to frame while camera and light stand still.

use std::cell::Cell;

use glam::{DMat4, DVec2, DVec3};

use crate::camera::Camera;
use crate::caster_bounds::CasterBounds;
use crate::fit::FitWorkspace;
use crate::geometry::{ClipWorkspace, ConvexPolyhedron, Plane};
use crate::light::Light;
use crate::scene::{Aabb, SceneBounds};

/// Reusable buffers for solving many [`ShadowProblem`](crate::ShadowProblem)s,
/// with a cache of the camera-only bodies.
///
/// [`ShadowProblem::solve`](crate::ShadowProblem::solve) uses one per thread
/// (kept in a thread-local); [`ShadowProblem::solve_with`](crate::ShadowProblem::solve_with)
/// takes one explicitly. Once its buffers have grown to the largest problem
/// solved, solving allocates nothing. Results never depend on what the
/// workspace held before: its camera-only cache is keyed by the camera's
/// matrices, clip distances and the scene bounds (bit for bit) and the plane
/// tolerance, and rebuilt on any change; its per-light entries (the caster
/// body, a spot light's visible receivers, PSM's hull) are keyed by the
/// light's bits as well, and kept only once the same light comes twice in a
/// row. For frame-to-frame reuse under a still camera keep one workspace per
/// light: a workspace shared by many lights hits only the camera cache.
#[derive(Clone, Debug)]
pub struct SolveWorkspace {
    pub(crate) clip: ClipWorkspace,
    pub(crate) fit: FitWorkspace,
    /// Light coordinates of the points a map is fitted around.
    pub(crate) xs: Vec<DVec3>,
    /// Their projections on the image plane.
    pub(crate) image: Vec<DVec2>,
    /// Unit directions for the enclosing cone.
    pub(crate) units: Vec<DVec3>,
    bodies: Vec<ConvexPolyhedron>,
    points: Vec<Vec<DVec3>>,
    planes: Vec<Vec<Plane>>,
    pub(crate) view: ViewCache,
    pub(crate) casters: CasterCache<ConvexPolyhedron>,
    /// The same for the casters' bounds (the solves' depth range).
    pub(crate) caster_bounds: CasterCache<CasterBounds>,
}

impl Default for SolveWorkspace {
    fn default() -> Self {
        Self::new()
    }
}

impl SolveWorkspace {
    /// An empty workspace with the camera cache on; buffers grow on first use.
    #[must_use]
    pub fn new() -> Self {
        Self::with_cache(true)
    }

    /// An empty workspace that recomputes the camera-only bodies on every
    /// solve (for comparisons; the results are the same).
    #[must_use]
    pub fn uncached() -> Self {
        Self::with_cache(false)
    }

    fn with_cache(enabled: bool) -> Self {
        Self {
            clip: ClipWorkspace::default(),
            fit: FitWorkspace::default(),
            xs: Vec::new(),
            image: Vec::new(),
            units: Vec::new(),
            bodies: Vec::new(),
            points: Vec::new(),
            planes: Vec::new(),
            view: ViewCache { enabled, ..ViewCache::default() },
            casters: CasterCache { enabled, ..CasterCache::default() },
            caster_bounds: CasterCache { enabled, ..CasterCache::default() },
        }
    }

    /// A body from the pool (content unspecified); give it back with
    /// [`put_body`](Self::put_body).
    pub(crate) fn take_body(&mut self) -> ConvexPolyhedron {
        self.bodies.pop().unwrap_or_default()
    }

    pub(crate) fn put_body(&mut self, body: ConvexPolyhedron) {
        self.bodies.push(body);
    }

    /// An empty point list from the pool; give it back with
    /// [`put_points`](Self::put_points).
    pub(crate) fn take_points(&mut self) -> Vec<DVec3> {
        let mut points = self.points.pop().unwrap_or_default();
        points.clear();
        points
    }

    pub(crate) fn put_points(&mut self, points: Vec<DVec3>) {
        self.points.push(points);
    }

    /// An empty plane list from the pool; give it back with
    /// [`put_planes`](Self::put_planes).
    pub(crate) fn take_planes(&mut self) -> Vec<Plane> {
        let mut planes = self.planes.pop().unwrap_or_default();
        planes.clear();
        planes
    }

    pub(crate) fn put_planes(&mut self, planes: Vec<Plane>) {
        self.planes.push(planes);
    }
}

/// The camera-only results of the last problem's camera and bounds.
#[derive(Clone, Debug, Default)]
pub(crate) struct ViewCache {
    enabled: bool,
    key: Option<ViewKey>,
    /// The view frustum's planes (valid whenever `key` is set).
    pub(crate) planes: Vec<Plane>,
    /// `V ∩ R`, the visible receivers of a light without its own frustum.
    pub(crate) visible: Option<ConvexPolyhedron>,
    /// The view frustum as a body.
    pub(crate) view_body: Option<ConvexPolyhedron>,
    /// `V ∩ R ∩ L` of a spot light.
    pub(crate) spot: LightEntry,
    /// PSM's hull `conv(V ∪ l) ∩ S ∩ L`.
    pub(crate) psm_hull: LightEntry,
    /// PSM's optical axis around that hull, for the last key asked.
    psm_axis: Option<PsmAxisMemo>,
    /// Retired bodies, kept for their buffers.
    spare: Vec<ConvexPolyhedron>,
    /// Counts the key's changes: a body lent out of the cache goes back
    /// only under the key it was made for.
    generation: u64,
}

/// The key of PSM's optical axis around its hull under the camera cache's
/// key ([`ViewCache::psm_axis`]): the light's bits, then what else the axis
/// reads (see `methods::psm`).
pub(crate) type PsmAxisKey = [u64; 13];

/// PSM's optical axis (`None`: the hull's directions fit in no cone), with
/// the camera cache's key generation and the axis key it was found under.
#[derive(Clone, Copy, Debug)]
struct PsmAxisMemo {
    generation: u64,
    key: PsmAxisKey,
    axis: Option<DVec3>,
}

/// A body lent out of the camera cache, with the key generation it was made
/// under.
pub(crate) struct Lent {
    pub(crate) body: ConvexPolyhedron,
    pub(crate) generation: u64,
}

impl Lent {
    pub(crate) fn new(body: ConvexPolyhedron, generation: u64) -> Self {
        Self { body, generation }
    }
}

/// A body that depends on the camera cache's key and on one light: kept,
/// under the light's bits, once the same light has built it twice in a row
/// (a workspace whose lights change every solve then copies nothing).
#[derive(Clone, Debug, Default)]
pub(crate) struct LightEntry {
    /// The last light that built the body.
    seen: Option<[u64; 8]>,
    /// The kept body and its light.
    kept: Option<([u64; 8], ConvexPolyhedron)>,
}

impl LightEntry {
    /// Copies the body kept for `light` into `out`; returns whether there
    /// was one.
    pub(crate) fn get_into(&self, light: &[u64; 8], out: &mut ConvexPolyhedron) -> bool {
        match &self.kept {
            Some((key, body)) if key == light => {
                out.copy_from(body);
                true
            }
            _ => false,
        }
    }

    /// Notes that `light` built `body` under the prepared camera: keeps a
    /// copy (buffers from `spare`) when the previous light to build it was
    /// the same.
    fn store(&mut self, enabled: bool, spare: &mut Vec<ConvexPolyhedron>, light: [u64; 8], body: &ConvexPolyhedron) {
        if !enabled {
            return;
        }
        if self.seen == Some(light) {
            let mut cached = match self.kept.take() {
                Some((_, cached)) => cached,
                None => spare.pop().unwrap_or_default(),
            };
            cached.copy_from(body);
            self.kept = Some((light, cached));
        } else {
            self.seen = Some(light);
        }
    }

    /// Forgets the body (the camera cache's key changed).
    fn retire(&mut self, spare: &mut Vec<ConvexPolyhedron>) {
        spare.extend(self.kept.take().map(|(_, body)| body));
        self.seen = None;
    }
}

/// What the cached results depend on.
#[derive(Clone, Copy, Debug)]
struct ViewKey {
    camera: Camera,
    bounds: SceneBounds,
    eps: f64,
}

impl ViewKey {
    /// Cameras with bit-identical matrices (the engine's and the normalised
    /// ones) and clip distances, the same viewport and conventions;
    /// bit-identical bounds and tolerance.
    fn same(&self, camera: &Camera, bounds: &SceneBounds, eps: f64) -> bool {
        let (a, b) = (&self.camera, camera);
        // The floats bit for bit, without early exits within a matrix (a
        // hit, the case worth making cheap, compares them all anyway; the
        // matrices were copied into arrays and compared twice before, ~750
        // instructions a call), then the camera's other fields. Its source
        // depth mapping is not compared: it follows from the source
        // matrices and the conventions, and nothing cached depends on it.
        let mat = |x: DMat4, y: DMat4| bits_eq(x.as_ref(), y.as_ref());
        let vec = |x: DVec3, y: DVec3| bits_eq(x.as_ref(), y.as_ref());
        let (p, q) = (&self.bounds, bounds);
        mat(a.view_from_world(), b.view_from_world())
            && mat(a.clip_from_view(), b.clip_from_view())
            && mat(a.source_view_from_world(), b.source_view_from_world())
            && mat(a.source_clip_from_view(), b.source_clip_from_view())
            && bits_eq(&[a.z_near(), a.z_far(), self.eps], &[b.z_near(), b.z_far(), eps])
            && vec(p.casters.min, q.casters.min)
            && vec(p.casters.max, q.casters.max)
            && vec(p.receivers.min, q.receivers.min)
            && vec(p.receivers.max, q.receivers.max)
            && a.viewport() == b.viewport()
            && a.conventions() == b.conventions()
    }
}

/// Whether two float slices hold the same bits (`-0.0` differs from `0.0`, a
/// NaN equals itself); no early exit, so that it vectorizes.
fn bits_eq(a: &[f64], b: &[f64]) -> bool {
    a.len() == b.len() && a.iter().zip(b).fold(true, |same, (x, y)| same & (x.to_bits() == y.to_bits()))
}

impl ViewCache {
    /// Makes the cache hold the results for this camera, bounds and
    /// tolerance: keeps them when the key matches (and the cache is on),
    /// otherwise drops them and recomputes the view planes with `planes`.
    pub(crate) fn prepare(
        &mut self,
        camera: &Camera,
        bounds: &SceneBounds,
        eps: f64,
        planes: impl FnOnce(&mut Vec<Plane>),
    ) {
        if self.enabled && self.key.as_ref().is_some_and(|k| k.same(camera, bounds, eps)) {
            return;
        }
        self.key = Some(ViewKey { camera: *camera, bounds: *bounds, eps });
        self.generation = self.generation.wrapping_add(1);
        planes(&mut self.planes);
        self.spare.extend(self.visible.take());
        self.spare.extend(self.view_body.take());
        self.spot.retire(&mut self.spare);
        self.psm_hull.retire(&mut self.spare);
    }

    /// Notes that spot light `light` built the visible receivers `body`.
    pub(crate) fn store_spot(&mut self, light: [u64; 8], body: &ConvexPolyhedron) {
        self.spot.store(self.enabled, &mut self.spare, light, body);
    }

    /// Notes that `light` built PSM's hull `body`.
    pub(crate) fn store_psm_hull(&mut self, light: [u64; 8], body: &ConvexPolyhedron) {
        self.psm_hull.store(self.enabled, &mut self.spare, light, body);
    }

    /// A body for a result about to be cached (buffers from a retired one).
    /// Lends the cached `V ∩ R` (taken out of the cache, no copy), if held.
    pub(crate) fn lend_visible(&mut self) -> Option<Lent> {
        let generation = self.generation;
        self.visible.take().map(|body| Lent { body, generation })
    }

    /// Takes back a body lent by [`Self::lend_visible`], or made by
    /// [`Self::lent`] to be cached as `V ∩ R`; one whose key has changed
    /// meanwhile, or whose place a newer body took, is kept as spare.
    pub(crate) fn return_visible(&mut self, lent: Lent) {
        if lent.generation == self.generation && self.visible.is_none() {
            self.visible = Some(lent.body);
        } else {
            self.spare.push(lent.body);
        }
    }

    /// `body`, made under the current key, as if lent by the cache.
    pub(crate) fn lent(&self, body: ConvexPolyhedron) -> Lent {
        Lent { body, generation: self.generation }
    }

    /// Lends the PSM hull kept for `light` (taken out of the cache, no
    /// copy), if held.
    pub(crate) fn lend_psm_hull(&mut self, light: &[u64; 8]) -> Option<Lent> {
        if !matches!(&self.psm_hull.kept, Some((key, _)) if key == light) {
            return None;
        }
        let generation = self.generation;
        self.psm_hull.kept.take().map(|(_, body)| Lent { body, generation })
    }

    /// Takes back a hull [`Self::lend_psm_hull`] lent for `light`; one
    /// whose key has changed meanwhile, or whose place a newer hull took,
    /// is kept as spare.
    pub(crate) fn return_psm_hull(&mut self, light: [u64; 8], lent: Lent) {
        if lent.generation == self.generation && self.psm_hull.kept.is_none() {
            self.psm_hull.kept = Some((light, lent.body));
        } else {
            self.spare.push(lent.body);
        }
    }

    /// PSM's optical axis around its hull, as found under the current
    /// camera key for `key` ([`Self::store_psm_axis`]); `None` when not
    /// held. The axis is a function of the camera key and `key` alone (the
    /// hull is), so a still light and camera find it without the cone.
    pub(crate) fn psm_axis(&self, key: &PsmAxisKey) -> Option<Option<DVec3>> {
        match &self.psm_axis {
            Some(memo) if memo.generation == self.generation && memo.key == *key => Some(memo.axis),
            _ => None,
        }
    }

    /// Keeps PSM's optical axis `axis` found for `key` under the current
    /// camera key (nothing when the cache is off).
    pub(crate) fn store_psm_axis(&mut self, key: PsmAxisKey, axis: Option<DVec3>) {
        if self.enabled {
            self.psm_axis = Some(PsmAxisMemo { generation: self.generation, key, axis });
        }
    }

    pub(crate) fn spare_body(&mut self) -> ConvexPolyhedron {
        self.spare.pop().unwrap_or_default()
    }
}

/// The last caster body built, with what it was built from.
///
/// Bodies are kept only once the same key has come twice in a row (the
/// first time only the key is noted): a workspace whose lights change on
/// every solve (random cameras, many lights through one workspace) then
/// pays a key comparison per solve, not two body copies.
#[derive(Clone, Debug, Default)]
pub(crate) struct CasterCache<T> {
    enabled: bool,
    /// The key of the last caster body built.
    seen: Option<CasterKey>,
    /// The key of the bodies below, when they are valid.
    key: Option<CasterKey>,
    /// The body the casters were found for (compared bit for bit).
    focus: ConvexPolyhedron,
    casters: T,
    /// `casters` is out on loan ([`CasterCache::lend`]): the field holds a
    /// placeholder until it comes back.
    lent: bool,
}

/// A cached value copied in and out reusing its buffers.
pub(crate) trait CopyFrom {
    /// Makes `self` equal to `other`.
    fn copy_from(&mut self, other: &Self);
}

impl CopyFrom for ConvexPolyhedron {
    fn copy_from(&mut self, other: &Self) {
        ConvexPolyhedron::copy_from(self, other);
    }
}

/// The inputs of a caster body besides the body it is built around: the
/// light, the casters' bounds and the plane tolerance, as bits.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct CasterKey {
    light: [u64; 8],
    casters: [u64; 6],
    eps: u64,
}

impl CasterKey {
    pub(crate) fn new(light: &Light, casters: &Aabb, eps: f64) -> Self {
        let v = |d: DVec3| d.to_array().map(f64::to_bits);
        let (min, max) = (v(casters.min), v(casters.max));
        Self { light: light_bits(light), casters: [min[0], min[1], min[2], max[0], max[1], max[2]], eps: eps.to_bits() }
    }
}

/// A light's kind and parameters as bits (a cache key).
pub(crate) fn light_bits(light: &Light) -> [u64; 8] {
    let v = |d: DVec3| d.to_array().map(f64::to_bits);
    match *light {
        Light::Directional { direction } => {
            let d = v(direction);
            [0, d[0], d[1], d[2], 0, 0, 0, 0]
        }
        Light::Point { position } => {
            let p = v(position);
            [1, p[0], p[1], p[2], 0, 0, 0, 0]
        }
        Light::Spot { position, direction, outer_half_angle_radians } => {
            let (p, d) = (v(position), v(direction));
            [2, p[0], p[1], p[2], d[0], d[1], d[2], outer_half_angle_radians.to_bits()]
        }
    }
}

impl<T: CopyFrom> CasterCache<T> {
    /// Copies the cached casters into `out` if they were found for `key`
    /// around a body bit-equal to `focus`; returns whether they were.
    pub(crate) fn get_into(&self, key: &CasterKey, focus: &ConvexPolyhedron, out: &mut T) -> bool {
        let hit = self.enabled && !self.lent && self.key.as_ref() == Some(key) && self.focus.bit_eq(focus);
        if hit {
            out.copy_from(&self.casters);
        }
        hit
    }

    /// Replaces the kept casters by `casters` (the same casters, with what
    /// was learnt about them since, such as
    /// [`CasterBounds`]'s remembered answers) if they are the ones kept for
    /// `key` around `focus`.
    pub(crate) fn refresh(&mut self, key: &CasterKey, focus: &ConvexPolyhedron, casters: &T) {
        if self.enabled && !self.lent && self.key.as_ref() == Some(key) && self.focus.bit_eq(focus) {
            self.casters.copy_from(casters);
        }
    }

    /// Notes that `casters` were found for `key` around `focus`; keeps them
    /// when the previous ones were found for the same key.
    pub(crate) fn store(&mut self, key: CasterKey, focus: &ConvexPolyhedron, casters: &T) {
        if !self.enabled {
            return;
        }
        if self.seen == Some(key) {
            // Whatever is out on loan is superseded.
            self.lent = false;
            self.key = Some(key);
            self.focus.copy_from(focus);
            self.casters.copy_from(casters);
        } else {
            self.seen = Some(key);
        }
    }
}

impl<T: Default> CasterCache<T> {
    /// The kept casters themselves (no copy) if they were found for `key`
    /// around a body bit-equal to `focus`: what [`Self::get_into`] would
    /// copy. While out, the cache answers no query; hand them back (with
    /// what was learnt about them) by [`Self::give_back`].
    pub(crate) fn lend(&mut self, key: &CasterKey, focus: &ConvexPolyhedron) -> Option<T> {
        let hit = self.enabled && !self.lent && self.key.as_ref() == Some(key) && self.focus.bit_eq(focus);
        hit.then(|| {
            self.lent = true;
            std::mem::take(&mut self.casters)
        })
    }

    /// Takes back the casters [`Self::lend`] gave out, unless the cache
    /// moved on meanwhile (then they are dropped).
    pub(crate) fn give_back(&mut self, casters: T) {
        if self.lent {
            self.casters = casters;
            self.lent = false;
        }
    }
}

thread_local! {
    /// Boxed, so that lending it out moves a pointer, not the buffers' headers.
    static WORKSPACE: Cell<Option<Box<SolveWorkspace>>> = const { Cell::new(None) };
}

/// Runs `f` with this thread's workspace. A nested call (the workspace is
/// then out in use) or a call while the thread shuts down gets a fresh one.
pub(crate) fn with_workspace<R>(f: impl FnOnce(&mut SolveWorkspace) -> R) -> R {
    let mut workspace = WORKSPACE.try_with(Cell::take).ok().flatten().unwrap_or_default();
    let result = f(&mut workspace);
    // Fails only while the thread shuts down; the buffers are then dropped.
    let _ = WORKSPACE.try_with(|cell| cell.set(Some(workspace)));
    result
}

#[cfg(test)]
mod tests {
    use super::*;

    fn key(x: f64) -> CasterKey {
        let light = Light::Point { position: DVec3::new(x, 2.0, 3.0) };
        CasterKey::new(&light, &Aabb { min: DVec3::ZERO, max: DVec3::ONE }, 1e-9)
    }

    #[test]
    fn lent_casters_are_served_to_no_one_and_come_back() {
        let focus = ConvexPolyhedron::from_aabb(DVec3::ZERO, DVec3::ONE);
        let kept = ConvexPolyhedron::from_aabb(DVec3::ZERO, DVec3::splat(2.0));
        let mut cache = CasterCache::<ConvexPolyhedron> { enabled: true, ..CasterCache::default() };
        cache.store(key(1.0), &focus, &kept);
        cache.store(key(1.0), &focus, &kept);
        let mut out = ConvexPolyhedron::empty();
        assert!(cache.lend(&key(2.0), &focus).is_none(), "another light");
        let lent = cache.lend(&key(1.0), &focus).expect("kept for this light and body");
        assert!(lent.bit_eq(&kept));
        // While out: no copy of the placeholder, no second loan.
        assert!(!cache.get_into(&key(1.0), &focus, &mut out));
        assert!(cache.lend(&key(1.0), &focus).is_none());
        cache.give_back(lent);
        assert!(cache.get_into(&key(1.0), &focus, &mut out) && out.bit_eq(&kept));
        // Casters stored while one is out supersede it.
        let lent = cache.lend(&key(1.0), &focus).unwrap();
        let newer = ConvexPolyhedron::from_aabb(DVec3::ZERO, DVec3::splat(3.0));
        cache.store(key(1.0), &focus, &newer);
        cache.give_back(lent);
        assert!(cache.get_into(&key(1.0), &focus, &mut out) && out.bit_eq(&newer));
    }
}
