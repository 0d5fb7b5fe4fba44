//! [`ShadowProblem`]: one validated camera, light, scene and map size, and the
//! convex bodies every method builds on.

use glam::DVec3;

use crate::camera::Camera;
use crate::caster_bounds::CasterBounds;
use crate::error::{check_range, Result};
use crate::fit::AffineFitOptions;
use crate::geometry::{ConvexPolyhedron, Plane};
use crate::light::{Light, LightFrame};
use crate::matrix::{Fallback, LightMatrix, Method, Placement};
use crate::scene::{Aabb, SceneBounds, ShadowMapSize};
use crate::tolerance::Tolerances;
use crate::workspace::{light_bits, with_workspace, CasterKey, Lent, SolveWorkspace};

/// Sides of the pyramid that stands in for a spot light's cone (it
/// circumscribes the cone, so it never loses a lit point).
const SPOT_PYRAMID_SIDES: usize = 8;

/// One shadow-map problem: a camera, a light, where casters and receivers are,
/// and the map's size, validated once. Every method is a call on it.
///
/// ```
/// use glam::{DVec3, UVec2};
/// use lixel::{Aabb, Camera, Light, Parameterization, SceneBounds, ShadowMapSize, ShadowProblem};
///
/// let camera = Camera::look_at(
///     DVec3::new(0.0, 1.7, 0.0), DVec3::new(0.0, 1.0, -10.0), DVec3::Y,
///     60f64.to_radians(), UVec2::new(1024, 768), 0.1, 100.0)?;
/// let floor = Aabb::from_corners(DVec3::new(-50.0, 0.0, -50.0), DVec3::new(50.0, 0.0, 50.0));
/// let objects = Aabb::from_corners(DVec3::new(-50.0, 0.0, -50.0), DVec3::new(50.0, 5.0, 50.0));
/// let bounds = SceneBounds { casters: objects, receivers: objects.union(&floor) };
/// let sun = Light::directional(DVec3::new(1.0, -1.0, 0.3));
/// let problem = ShadowProblem::new(camera, sun, bounds, ShadowMapSize::square(2048))?;
/// let matrix = problem.solve(&Parameterization::LiSpsm(Default::default()))?;
/// assert!(matrix.covers(DVec3::new(0.0, 0.0, -10.0), 1e-9));
/// # Ok::<(), lixel::LixelError>(())
/// ```
#[derive(Clone, Debug)]
pub struct ShadowProblem {
    camera: Camera,
    light: Light,
    bounds: SceneBounds,
    map: ShadowMapSize,
    fit: AffineFitOptions,
    tolerances: Tolerances,
    scale: f64,
}

impl ShadowProblem {
    /// Validates the inputs.
    ///
    /// # Errors
    /// Whatever [`Light::validate`], [`SceneBounds::validate`] and
    /// [`ShadowMapSize::validate`] report, and
    /// [`OutOfRange`](crate::LixelError::OutOfRange) when the eye, the light
    /// or the bounds have a coordinate beyond [`MAX_COORDINATE`](crate::MAX_COORDINATE).
    /// A [`Camera`] is otherwise valid by construction.
    pub fn new(camera: Camera, light: Light, bounds: SceneBounds, map: ShadowMapSize) -> Result<Self> {
        light.validate()?;
        bounds.validate()?;
        map.validate()?;
        check_range(&camera.eye().to_array(), "camera eye")?;
        if let Some(l) = light.position() {
            check_range(&l.to_array(), "light position")?;
        }
        check_range(&[bounds.casters.min.to_array(), bounds.casters.max.to_array()].concat(), "caster bounds")?;
        check_range(&[bounds.receivers.min.to_array(), bounds.receivers.max.to_array()].concat(), "receiver bounds")?;
        let scene = bounds.scene();
        let mut scale = scene.diagonal().max(scene.min.abs().max(scene.max.abs()).max_element() * 1e-6);
        if !(scale > 0.0) {
            scale = 1.0;
        }
        Ok(Self {
            camera,
            light,
            bounds,
            map,
            fit: AffineFitOptions::default(),
            tolerances: Tolerances::default(),
            scale,
        })
    }

    /// Replaces the affine-fit options (margin, shear) used by every method.
    #[must_use]
    pub fn with_fit(mut self, fit: AffineFitOptions) -> Self {
        self.fit = fit;
        self
    }

    /// Replaces the tolerances.
    #[must_use]
    pub fn with_tolerances(mut self, tolerances: Tolerances) -> Self {
        self.tolerances = tolerances;
        self
    }

    /// The camera.
    #[must_use]
    pub fn camera(&self) -> &Camera {
        &self.camera
    }

    /// The light.
    #[must_use]
    pub fn light(&self) -> &Light {
        &self.light
    }

    /// The scene bounds.
    #[must_use]
    pub fn bounds(&self) -> &SceneBounds {
        &self.bounds
    }

    /// The shadow-map size.
    #[must_use]
    pub fn map_size(&self) -> ShadowMapSize {
        self.map
    }

    /// The affine-fit options.
    #[must_use]
    pub fn fit_options(&self) -> &AffineFitOptions {
        &self.fit
    }

    /// The tolerances.
    #[must_use]
    pub fn tolerances(&self) -> &Tolerances {
        &self.tolerances
    }

    /// Length scale of the problem (scene diagonal): tolerances are relative to it.
    #[must_use]
    pub fn scale(&self) -> f64 {
        self.scale
    }

    /// Absolute plane tolerance for convex-body operations.
    #[must_use]
    pub fn eps(&self) -> f64 {
        self.tolerances.plane_eps * self.scale
    }

    /// Absolute [`Tolerances::coarse_eps`]: "on the receiver plane", "at the light".
    #[must_use]
    pub fn coarse_eps(&self) -> f64 {
        self.tolerances.coarse_eps * self.scale
    }

    /// The vertices of `body` that have a direction from the light: all of
    /// them for a directional light; for a point or spot light those farther
    /// than [`Self::coarse_eps`] from it. A spot light's own apex is a vertex
    /// of every body clipped by its frustum `L` when the light sits inside the
    /// bounds; the directions to the remaining vertices span the body's
    /// directions, so the map still holds all of it.
    ///
    /// A spot light's body that lies wholly within that distance (a body
    /// below the solver's resolution, next to the light) is stood in for by
    /// points on the corner rays of the spot's pyramid: the map then holds
    /// the spot's whole frustum, which contains the body.
    #[must_use]
    pub fn mappable_vertices(&self, body: &ConvexPolyhedron) -> Vec<DVec3> {
        let mut out = Vec::new();
        with_workspace(|ws| self.mappable_vertices_into(body, &mut out, ws));
        out
    }

    /// [`Self::mappable_vertices`] into `out` (cleared first).
    pub(crate) fn mappable_vertices_into(
        &self,
        body: &ConvexPolyhedron,
        out: &mut Vec<DVec3>,
        ws: &mut SolveWorkspace,
    ) {
        out.clear();
        let Some(l) = self.light.position() else {
            out.extend_from_slice(body.vertices());
            return;
        };
        let at_light = self.coarse_eps();
        out.extend(body.vertices().iter().copied().filter(|&p| (p - l).length() > at_light));
        if let Light::Spot { direction, .. } = self.light {
            if out.is_empty() && !body.is_empty() {
                let mut planes = ws.take_planes();
                self.light_planes_into(&mut planes);
                out.extend((0..planes.len()).filter_map(|k| {
                    let ray = planes[k].normal.cross(planes[(k + 1) % planes.len()].normal).try_normalize()?;
                    let ray = if ray.dot(direction) < 0.0 { -ray } else { ray };
                    Some(l + ray * (2.0 * at_light))
                }));
                ws.put_planes(planes);
            }
        }
    }

    /// [`Self::mappable_vertices_into`] into `mapped`, and the vertices it
    /// leaves out (those within [`Self::coarse_eps`] of a positional light;
    /// none for a directional one) into `unmapped`, both cleared first, in
    /// one pass over the vertices. With the mappable ones the unmapped are
    /// every vertex, so a caller holding the mappable vertices needs only
    /// these besides for the body's depth range.
    pub(crate) fn split_vertices_into(
        &self,
        body: &ConvexPolyhedron,
        mapped: &mut Vec<DVec3>,
        unmapped: &mut Vec<DVec3>,
        ws: &mut SolveWorkspace,
    ) {
        unmapped.clear();
        let Some(l) = self.light.position() else {
            self.mappable_vertices_into(body, mapped, ws);
            return;
        };
        mapped.clear();
        let at_light = self.coarse_eps();
        for &p in body.vertices() {
            if (p - l).length() > at_light {
                mapped.push(p);
            } else {
                unmapped.push(p);
            }
        }
        if mapped.is_empty() && matches!(self.light, Light::Spot { .. }) {
            // The spot's stand-in points (`mappable_vertices_into`).
            self.mappable_vertices_into(body, mapped, ws);
        }
    }

    /// The view frustum `V` as the six half-spaces of the camera's clip volume.
    #[must_use]
    pub fn view_planes(&self) -> Vec<Plane> {
        let mut planes = Vec::new();
        view_planes_into(&self.camera, &mut planes);
        planes
    }

    /// The view frustum `V` as a polyhedron (may be huge for a far far plane;
    /// an infinite far plane is cut just beyond the scene bounds, which are
    /// always finite).
    #[must_use]
    pub fn view_body(&self) -> ConvexPolyhedron {
        with_workspace(|ws| {
            self.prepare_view_body(ws);
            ws.view.view_body.clone().unwrap_or_default()
        })
    }

    /// Makes the workspace's camera cache hold this problem's camera and
    /// bounds (its view planes are then `ws.view.planes`).
    fn prepare_view(&self, ws: &mut SolveWorkspace) {
        let camera = &self.camera;
        ws.view.prepare(camera, &self.bounds, self.eps(), |planes| view_planes_into(camera, planes));
    }

    /// [`Self::prepare_view`], and the view body computed (`ws.view.view_body`).
    fn prepare_view_body(&self, ws: &mut SolveWorkspace) {
        self.prepare_view(ws);
        self.view_body_in_prepared(ws);
    }

    /// The view body computed into the camera cache, which was prepared
    /// for this problem already.
    fn view_body_in_prepared(&self, ws: &mut SolveWorkspace) {
        if ws.view.view_body.is_none() {
            let mut body = ws.view.spare_body();
            body.set_frustum_corners(&self.camera.frustum_corners_within(&self.bounds.scene()));
            ws.view.view_body = Some(body);
        }
    }

    /// The light's own frustum `L` as half-spaces: empty (everything) for
    /// point and directional lights; a pyramid circumscribing the cone for
    /// spot lights.
    #[must_use]
    pub fn light_planes(&self) -> Vec<Plane> {
        let mut planes = Vec::new();
        self.light_planes_into(&mut planes);
        planes
    }

    /// [`Self::light_planes`] into `out` (cleared first).
    fn light_planes_into(&self, out: &mut Vec<Plane>) {
        out.clear();
        let Light::Spot { position, direction, outer_half_angle_radians } = self.light else {
            return;
        };
        let (e1, e2) = direction.any_orthonormal_pair();
        let (sin_a, cos_a) = outer_half_angle_radians.sin_cos();
        out.extend((0..SPOT_PYRAMID_SIDES).map(|k| {
            let phi = std::f64::consts::TAU * k as f64 / SPOT_PYRAMID_SIDES as f64;
            let radial = e1 * phi.cos() + e2 * phi.sin();
            // Tangent to the cone along `radial`, pointing outwards.
            Plane::from_point_normal(position, (radial * cos_a - direction * sin_a).normalize())
        }));
    }

    /// A box as a polyhedron, clipped by the light frustum `L`, into `out`.
    fn box_in_light_into(&self, aabb: &Aabb, out: &mut ConvexPolyhedron, ws: &mut SolveWorkspace) {
        out.set_aabb(aabb.min, aabb.max);
        let mut planes = ws.take_planes();
        self.light_planes_into(&mut planes);
        out.clip_all_in_place(planes.iter(), self.eps(), &mut ws.clip);
        ws.put_planes(planes);
    }

    /// All receivers the light can reach: `R ∩ L` (what a normal map covers).
    #[must_use]
    pub fn receiver_body(&self) -> ConvexPolyhedron {
        let mut body = ConvexPolyhedron::empty();
        with_workspace(|ws| self.receiver_body_into(&mut body, ws));
        body
    }

    /// [`Self::receiver_body`] into `out`.
    pub(crate) fn receiver_body_into(&self, out: &mut ConvexPolyhedron, ws: &mut SolveWorkspace) {
        self.box_in_light_into(&self.bounds.receivers, out, ws);
    }

    /// The visible receivers the light can reach: `V ∩ R ∩ L`. Every method's
    /// map must contain this body.
    #[must_use]
    pub fn visible_receiver_body(&self) -> ConvexPolyhedron {
        let mut body = ConvexPolyhedron::empty();
        with_workspace(|ws| self.visible_receiver_body_into(&mut body, ws));
        body
    }

    /// [`Self::visible_receiver_body`] into `out`. Without a light frustum
    /// (point and directional lights) this is `V ∩ R`, taken from the
    /// workspace's camera cache when it holds it; a spot light's is cached
    /// under its bits once it comes twice in a row.
    pub(crate) fn visible_receiver_body_into(&self, out: &mut ConvexPolyhedron, ws: &mut SolveWorkspace) {
        self.prepare_view(ws);
        let own_frustum = matches!(self.light, Light::Spot { .. });
        if !own_frustum {
            if let Some(visible) = &ws.view.visible {
                out.copy_from(visible);
                return;
            }
        }
        let spot = own_frustum.then(|| light_bits(&self.light));
        if let Some(spot) = &spot {
            if ws.view.spot.get_into(spot, out) {
                return;
            }
        }
        self.receiver_body_into(out, ws);
        out.clip_all_in_place(ws.view.planes.iter(), self.eps(), &mut ws.clip);
        if let Some(spot) = spot {
            ws.view.store_spot(spot, out);
        } else {
            let mut cached = ws.view.spare_body();
            cached.copy_from(out);
            ws.view.visible = Some(cached);
        }
    }

    /// Runs `f` on [`Self::visible_receiver_body`] (the same body as
    /// [`Self::visible_receiver_body_into`] gives). Without a light frustum
    /// the body is lent by the workspace's camera cache, or made there on a
    /// miss, and goes back afterwards: no copy either way. Inside `f` the
    /// cache does not hold it, so `f` must not ask for it again (it has it).
    pub(crate) fn with_visible_receiver_body<T>(
        &self,
        ws: &mut SolveWorkspace,
        f: impl FnOnce(&ConvexPolyhedron, &mut SolveWorkspace) -> T,
    ) -> T {
        if matches!(self.light, Light::Spot { .. }) {
            let mut focus = ws.take_body();
            self.visible_receiver_body_into(&mut focus, ws);
            let result = f(&focus, ws);
            ws.put_body(focus);
            return result;
        }
        self.prepare_view(ws);
        let lent = match ws.view.lend_visible() {
            Some(lent) => lent,
            None => {
                // As `visible_receiver_body_into` makes it.
                let mut body = ws.view.spare_body();
                self.receiver_body_into(&mut body, ws);
                body.clip_all_in_place(ws.view.planes.iter(), self.eps(), &mut ws.clip);
                ws.view.lent(body)
            }
        };
        let result = f(&lent.body, ws);
        ws.view.return_visible(lent);
        result
    }

    /// PSM's hull `H = conv(V ∪ l) ∩ S ∩ L` (for a directional light, `V`
    /// extruded towards the light).
    #[must_use]
    pub fn psm_hull(&self) -> ConvexPolyhedron {
        let mut body = ConvexPolyhedron::empty();
        with_workspace(|ws| self.psm_hull_into(&mut body, ws));
        body
    }

    /// [`Self::psm_hull`] into `out`, with `V` from the workspace's camera
    /// cache (and the hull itself when the same light built it last).
    pub(crate) fn psm_hull_into(&self, out: &mut ConvexPolyhedron, ws: &mut SolveWorkspace) {
        self.prepare_view(ws);
        self.psm_hull_into_prepared(out, ws);
    }

    /// [`Self::psm_hull`], where the camera cache was prepared for this
    /// problem already (inside [`Self::with_visible_receiver_body`], which
    /// prepares it and lets nothing else touch it before `f` runs: the
    /// cache's key is not compared again). A hull the cache keeps for this
    /// light is lent (no copy); give it back with
    /// [`Self::give_back_psm_hull`].
    pub(crate) fn lend_psm_hull_prepared(&self, ws: &mut SolveWorkspace) -> PsmHull {
        self.view_body_in_prepared(ws);
        let light = light_bits(&self.light);
        if let Some(lent) = ws.view.lend_psm_hull(&light) {
            return PsmHull { body: lent.body, lent: Some((light, lent.generation)) };
        }
        let mut body = ws.take_body();
        self.psm_hull_into_prepared(&mut body, ws);
        PsmHull { body, lent: None }
    }

    /// Takes back a hull [`Self::lend_psm_hull_prepared`] gave out.
    pub(crate) fn give_back_psm_hull(&self, hull: PsmHull, ws: &mut SolveWorkspace) {
        match hull.lent {
            Some((light, generation)) => ws.view.return_psm_hull(light, Lent::new(hull.body, generation)),
            None => ws.put_body(hull.body),
        }
    }

    /// [`Self::psm_hull_into`] where the camera cache was prepared for this
    /// problem already.
    fn psm_hull_into_prepared(&self, out: &mut ConvexPolyhedron, ws: &mut SolveWorkspace) {
        self.view_body_in_prepared(ws);
        let light = light_bits(&self.light);
        if ws.view.psm_hull.get_into(&light, out) {
            return;
        }
        let view = ws.view.view_body.take().unwrap_or_default();
        if view.is_empty() {
            out.clear();
        } else {
            let mut planes = ws.take_planes();
            self.towards_light_planes_into(&view, &mut planes, ws);
            self.box_in_light_into(&self.bounds.scene(), out, ws);
            out.clip_all_in_place(planes.iter(), self.eps(), &mut ws.clip);
            ws.put_planes(planes);
        }
        ws.view.view_body = Some(view);
        ws.view.store_psm_hull(light, out);
    }

    /// The casters that can shadow `focus`: `conv(focus ∪ l) ∩ C` (point and
    /// spot lights) or `focus` extruded towards the light `∩ C` (directional).
    #[must_use]
    pub fn caster_body(&self, focus: &ConvexPolyhedron) -> ConvexPolyhedron {
        let mut body = ConvexPolyhedron::empty();
        with_workspace(|ws| self.caster_body_into(focus, &mut body, ws));
        body
    }

    /// [`Self::caster_body`] into `out`.
    pub(crate) fn caster_body_into(
        &self,
        focus: &ConvexPolyhedron,
        out: &mut ConvexPolyhedron,
        ws: &mut SolveWorkspace,
    ) {
        if focus.is_empty() {
            out.clear();
            return;
        }
        let key = CasterKey::new(&self.light, &self.bounds.casters, self.eps());
        if ws.casters.get_into(&key, focus, out) {
            return;
        }
        let mut planes = ws.take_planes();
        self.towards_light_planes_into(focus, &mut planes, ws);
        out.set_aabb(self.bounds.casters.min, self.bounds.casters.max);
        out.clip_all_in_place(planes.iter(), self.eps(), &mut ws.clip);
        ws.put_planes(planes);
        ws.casters.store(key, focus, out);
    }

    /// Half-spaces of `body` grown towards the light (hull with the light's
    /// position, or extrusion along the reversed light direction), into `out`.
    ///
    /// Each is moved out by twice the plane tolerance: the bodies clipped by
    /// them must *contain* what they stand for, and a clip drops what is at
    /// most `eps` thick. A light in (or grazing) the plane of a flat receiver
    /// (a sunset over a floor) makes `conv(focus ∪ l)` exactly such a sliver,
    /// and its casters must still reach the depth row.
    fn towards_light_planes_into(&self, body: &ConvexPolyhedron, out: &mut Vec<Plane>, ws: &mut SolveWorkspace) {
        match self.light {
            Light::Directional { direction } => body.extrusion_planes_into(-direction, self.eps(), out, &mut ws.clip),
            Light::Point { position } | Light::Spot { position, .. } => {
                body.hull_with_point_planes_into(position, self.eps(), out, &mut ws.clip);
            }
        }
        for plane in out.iter_mut() {
            *plane = plane.grown(2.0 * self.eps());
        }
    }

    /// The light frame used for a body to be mapped: a spot light's own axis,
    /// towards the body for a point light.
    pub(crate) fn frame_towards(&self, focus: &ConvexPolyhedron) -> LightFrame {
        let forward = match self.light.position() {
            Some(l) if !focus.is_empty() => {
                let d = focus.centroid() - l;
                if d.length_squared() > 0.0 {
                    d
                } else {
                    DVec3::NEG_Y
                }
            }
            _ => DVec3::NEG_Y,
        };
        LightFrame::new(&self.light, forward)
    }

    /// The caster body of `focus` ([`Self::caster_body`]) as its box and
    /// half-spaces, for the depth range (no body is built).
    pub(crate) fn caster_bounds_into(&self, focus: &ConvexPolyhedron, out: &mut CasterBounds, ws: &mut SolveWorkspace) {
        out.clear();
        if focus.is_empty() {
            return;
        }
        let key = CasterKey::new(&self.light, &self.bounds.casters, self.eps());
        if ws.caster_bounds.get_into(&key, focus, out) {
            return;
        }
        self.towards_light_planes_into(focus, &mut out.planes, ws);
        let (min, max) = (self.bounds.casters.min, self.bounds.casters.max);
        out.set(min, max, focus.vertices(), self.light.position(), self.eps());
        ws.caster_bounds.store(key, focus, out);
    }

    /// Runs `place` with the casters of `focus` ([`Self::caster_bounds_into`]),
    /// then keeps them in the workspace's per-light cache when they are the
    /// kept ones, so that the answers they remembered serve the next solve
    /// of a still light and camera.
    pub(crate) fn with_casters<T>(
        &self,
        focus: &ConvexPolyhedron,
        ws: &mut SolveWorkspace,
        place: impl FnOnce(&CasterBounds, &mut SolveWorkspace) -> T,
    ) -> T {
        if !focus.is_empty() {
            // Kept for this light and body: used in place, no copy in or out.
            let key = CasterKey::new(&self.light, &self.bounds.casters, self.eps());
            if let Some(casters) = ws.caster_bounds.lend(&key, focus) {
                let result = place(&casters, ws);
                ws.caster_bounds.give_back(casters);
                return result;
            }
        }
        let mut casters = CasterBounds::new(ws.take_planes());
        self.caster_bounds_into(focus, &mut casters, ws);
        let result = place(&casters, ws);
        if !focus.is_empty() {
            let key = CasterKey::new(&self.light, &self.bounds.casters, self.eps());
            ws.caster_bounds.refresh(&key, focus, &casters);
        }
        ws.put_planes(casters.into_planes());
        result
    }

    /// Builds the matrix for axis `axis` (light coordinates of `frame`)
    /// around `focus`, with depth covering the casters of `focus`.
    pub(crate) fn place(
        &self,
        frame: LightFrame,
        axis: DVec3,
        focus: &ConvexPolyhedron,
        method: Method,
        fallback: Option<Fallback>,
        ws: &mut SolveWorkspace,
    ) -> Result<LightMatrix> {
        self.with_casters(focus, ws, |casters, ws| {
            self.place_with_casters(frame, axis, focus, casters, method, fallback, ws)
        })
    }

    /// [`Self::place`] with the casters of `focus` already bounded.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn place_with_casters(
        &self,
        frame: LightFrame,
        axis: DVec3,
        focus: &ConvexPolyhedron,
        casters: &CasterBounds,
        method: Method,
        fallback: Option<Fallback>,
        ws: &mut SolveWorkspace,
    ) -> Result<LightMatrix> {
        let mut points = ws.take_points();
        self.mappable_vertices_into(focus, &mut points, ws);
        // Depth covers the casters and all of `focus`, a vertex at the light
        // included (then near is clamped and unclipped depth requested).
        let result =
            self.placement(frame, axis, &points, focus.vertices(), Some(casters), method, fallback).build_in(ws);
        ws.put_points(points);
        result
    }

    /// The one constructor of a [`Placement`] for this problem: its light,
    /// map size, fit options and tolerances, with `focus` the world points
    /// the map must hold, and `depth_points` the further points and
    /// `casters` the caster body its depth range must hold.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn placement<'a>(
        &'a self,
        frame: LightFrame,
        axis: DVec3,
        focus: &'a [DVec3],
        depth_points: &'a [DVec3],
        casters: Option<&'a CasterBounds>,
        method: Method,
        fallback: Option<Fallback>,
    ) -> Placement<'a> {
        Placement {
            light: self.light,
            frame,
            axis,
            focus,
            depth_points,
            casters,
            map: self.map,
            fit: &self.fit,
            tolerances: &self.tolerances,
            method,
            fallback,
        }
    }
}

/// The view frustum's six half-spaces into `out` (cleared first).
fn view_planes_into(camera: &Camera, out: &mut Vec<Plane>) {
    let m = camera.clip_from_world();
    let (r0, r1, r2, r3) = (m.row(0), m.row(1), m.row(2), m.row(3));
    // Inside: h·[x; 1] >= 0 for each of these (a Plane keeps the other sign).
    out.clear();
    out.extend(
        [r3 + r0, r3 - r0, r3 + r1, r3 - r1, r2, r3 - r2].into_iter().filter_map(|h| Plane::from_homogeneous(-h)),
    );
}

/// PSM's hull for one solve ([`ShadowProblem::lend_psm_hull_prepared`]):
/// lent by the camera cache (with the light and the key generation it goes
/// back under) or made in a pooled body.
pub(crate) struct PsmHull {
    pub(crate) body: ConvexPolyhedron,
    lent: Option<([u64; 8], u64)>,
}
