//! [`ShadowProblem`]: one validated camera, light, scene and map size, and the
//! convex bodies every method builds on.

use glam::DVec3;

use crate::camera::Camera;
use crate::error::{check_range, Result};
use crate::fit::{AffineFitOptions, FitWorkspace};
use crate::geometry::{ConvexPolyhedron, Plane};
use crate::light::{Light, LightFrame};
use crate::matrix::{Fallback, LightMatrix, Method, Placement};
use crate::scene::{Aabb, SceneBounds, ShadowMapSize};
use crate::tolerance::Tolerances;

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
        let Some(l) = self.light.position() else {
            return body.vertices().to_vec();
        };
        let at_light = self.coarse_eps();
        let far: Vec<DVec3> = body.vertices().iter().copied().filter(|&p| (p - l).length() > at_light).collect();
        match self.light {
            Light::Spot { direction, .. } if far.is_empty() && !body.is_empty() => {
                let planes = self.light_planes();
                (0..planes.len())
                    .filter_map(|k| {
                        let ray = planes[k].normal.cross(planes[(k + 1) % planes.len()].normal).try_normalize()?;
                        let ray = if ray.dot(direction) < 0.0 { -ray } else { ray };
                        Some(l + ray * (2.0 * at_light))
                    })
                    .collect()
            }
            _ => far,
        }
    }

    /// The view frustum `V` as the six half-spaces of the camera's clip volume.
    #[must_use]
    pub fn view_planes(&self) -> Vec<Plane> {
        let m = self.camera.clip_from_world();
        let (r0, r1, r2, r3) = (m.row(0), m.row(1), m.row(2), m.row(3));
        // Inside: h·[x; 1] >= 0 for each of these (a Plane keeps the other sign).
        [r3 + r0, r3 - r0, r3 + r1, r3 - r1, r2, r3 - r2]
            .into_iter()
            .filter_map(|h| Plane::from_homogeneous(-h))
            .collect()
    }

    /// The view frustum `V` as a polyhedron (may be huge for a far far plane;
    /// an infinite far plane is cut just beyond the scene bounds, which are
    /// always finite).
    #[must_use]
    pub fn view_body(&self) -> ConvexPolyhedron {
        let corners = self.camera.frustum_corners_within(&self.bounds.scene());
        ConvexPolyhedron::from_frustum_corners(&corners).unwrap_or_else(ConvexPolyhedron::empty)
    }

    /// The light's own frustum `L` as half-spaces: empty (everything) for
    /// point and directional lights; a pyramid circumscribing the cone for
    /// spot lights.
    #[must_use]
    pub fn light_planes(&self) -> Vec<Plane> {
        let Light::Spot { position, direction, outer_half_angle_radians } = self.light else {
            return Vec::new();
        };
        let (e1, e2) = direction.any_orthonormal_pair();
        let (sin_a, cos_a) = outer_half_angle_radians.sin_cos();
        (0..SPOT_PYRAMID_SIDES)
            .map(|k| {
                let phi = std::f64::consts::TAU * k as f64 / SPOT_PYRAMID_SIDES as f64;
                let radial = e1 * phi.cos() + e2 * phi.sin();
                // Tangent to the cone along `radial`, pointing outwards.
                Plane::from_point_normal(position, (radial * cos_a - direction * sin_a).normalize())
            })
            .collect()
    }

    /// A box as a polyhedron, clipped by the light frustum `L`.
    fn box_in_light(&self, aabb: &Aabb) -> ConvexPolyhedron {
        ConvexPolyhedron::from_aabb(aabb.min, aabb.max).clip_all(self.light_planes().iter(), self.eps())
    }

    /// All receivers the light can reach: `R ∩ L` (what a normal map covers).
    #[must_use]
    pub fn receiver_body(&self) -> ConvexPolyhedron {
        self.box_in_light(&self.bounds.receivers)
    }

    /// The visible receivers the light can reach: `V ∩ R ∩ L`. Every method's
    /// map must contain this body.
    #[must_use]
    pub fn visible_receiver_body(&self) -> ConvexPolyhedron {
        self.receiver_body().clip_all(self.view_planes().iter(), self.eps())
    }

    /// PSM's hull `H = conv(V ∪ l) ∩ S ∩ L` (for a directional light, `V`
    /// extruded towards the light).
    #[must_use]
    pub fn psm_hull(&self) -> ConvexPolyhedron {
        let view = self.view_body();
        if view.is_empty() {
            return ConvexPolyhedron::empty();
        }
        let planes = self.towards_light_planes(&view);
        self.box_in_light(&self.bounds.scene()).clip_all(planes.iter(), self.eps())
    }

    /// The casters that can shadow `focus`: `conv(focus ∪ l) ∩ C` (point and
    /// spot lights) or `focus` extruded towards the light `∩ C` (directional).
    #[must_use]
    pub fn caster_body(&self, focus: &ConvexPolyhedron) -> ConvexPolyhedron {
        if focus.is_empty() {
            return ConvexPolyhedron::empty();
        }
        let planes = self.towards_light_planes(focus);
        ConvexPolyhedron::from_aabb(self.bounds.casters.min, self.bounds.casters.max)
            .clip_all(planes.iter(), self.eps())
    }

    /// Half-spaces of `body` grown towards the light (hull with the light's
    /// position, or extrusion along the reversed light direction).
    ///
    /// Each is moved out by twice the plane tolerance: the bodies clipped by
    /// them must *contain* what they stand for, and a clip drops what is at
    /// most `eps` thick. A light in (or grazing) the plane of a flat receiver
    /// (a sunset over a floor) makes `conv(focus ∪ l)` exactly such a sliver,
    /// and its casters must still reach the depth row.
    fn towards_light_planes(&self, body: &ConvexPolyhedron) -> Vec<Plane> {
        let planes = match self.light {
            Light::Directional { direction } => body.extrusion_planes(-direction, self.eps()),
            Light::Point { position } | Light::Spot { position, .. } => {
                body.hull_with_point_planes(position, self.eps())
            }
        };
        planes.into_iter().map(|p| p.grown(2.0 * self.eps())).collect()
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

    /// Builds the matrix for axis `axis` (light coordinates of `frame`)
    /// around `focus`, with depth covering the casters of `focus`.
    pub(crate) fn place(
        &self,
        frame: LightFrame,
        axis: DVec3,
        focus: &ConvexPolyhedron,
        method: Method,
        fallback: Option<Fallback>,
    ) -> Result<LightMatrix> {
        self.place_with_casters(frame, axis, focus, &self.caster_body(focus), method, fallback)
    }

    /// [`Self::place`] with the caster body of `focus` already computed.
    pub(crate) fn place_with_casters(
        &self,
        frame: LightFrame,
        axis: DVec3,
        focus: &ConvexPolyhedron,
        casters: &ConvexPolyhedron,
        method: Method,
        fallback: Option<Fallback>,
    ) -> Result<LightMatrix> {
        let points = self.mappable_vertices(focus);
        // Depth covers the casters and all of `focus`, a vertex at the light
        // included (then near is clamped and unclipped depth requested).
        let mut depth_points = casters.vertices().to_vec();
        depth_points.extend_from_slice(focus.vertices());
        self.placement(frame, axis, &points, &depth_points, method, fallback).build(&mut FitWorkspace::default())
    }

    /// The one constructor of a [`Placement`] for this problem: its light,
    /// map size, fit options and tolerances, with `focus` the world points
    /// the map must hold and `depth_points` the further points (casters)
    /// its depth range must hold.
    pub(crate) fn placement<'a>(
        &'a self,
        frame: LightFrame,
        axis: DVec3,
        focus: &'a [DVec3],
        depth_points: &'a [DVec3],
        method: Method,
        fallback: Option<Fallback>,
    ) -> Placement<'a> {
        Placement {
            light: self.light,
            frame,
            axis,
            focus,
            depth_points,
            map: self.map,
            fit: &self.fit,
            tolerances: &self.tolerances,
            method,
            fallback,
        }
    }
}
