//! The viewer: an engine's camera, normalised to lixel's convention.

use glam::{DMat4, DVec3, DVec4, UVec2};

use crate::conventions::{analyse, CameraConventions, ClipDepth, ProjectionHints, ProjectionKind, SourceDepth};
use crate::error::{check_finite, LixelError, Result};
use crate::scene::Aabb;

/// A camera: an engine's view and projection, read once and kept in lixel's
/// convention (wgpu's): right-handed view space (the camera looks down `-z`),
/// clip depth in `[0, 1]` growing away from the eye, NDC `y` up,
/// framebuffer row 0 at the top.
///
/// [`Camera::from_matrices`] accepts the common engine conventions
/// (perspective or orthographic; symmetric, off-centre or jittered; depth
/// `[0, 1]` or `[-1, 1]`; forward or reverse Z; finite or infinite far;
/// right- or left-handed view; NDC `y` up or down) and reports what it read
/// in [`conventions`](Self::conventions). The accessors without `source_` give
/// the normalised camera; the frustum, the screen mapping and the near/far
/// distances are the engine's own.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    view_from_world: DMat4,
    clip_from_view: DMat4,
    viewport: UVec2,
    z_near: f64,
    z_far: f64,
    source_view_from_world: DMat4,
    source_clip_from_view: DMat4,
    conventions: CameraConventions,
    source_depth: SourceDepth,
}

/// Depth of the far face of [`Camera::frustum_corners`] for an infinite far
/// plane, in multiples of the near distance.
pub const INFINITE_FAR_CORNER_RATIO: f64 = 1e6;

impl Camera {
    /// A camera at `eye` looking at `target` with the given vertical field of
    /// view, viewport (full-resolution pixels) and clip distances.
    ///
    /// # Errors
    /// [`LixelError::NonFinite`] or [`LixelError::DegenerateCamera`] for
    /// non-finite input, `eye == target`, `up` parallel to the view direction,
    /// a field of view outside `(0, π)`, `0 < z_near < z_far` violated, or a
    /// zero viewport.
    pub fn look_at(
        eye: DVec3,
        target: DVec3,
        up: DVec3,
        fov_y_radians: f64,
        viewport: UVec2,
        z_near: f64,
        z_far: f64,
    ) -> Result<Self> {
        check_finite(
            &[eye.x, eye.y, eye.z, target.x, target.y, target.z, up.x, up.y, up.z, fov_y_radians, z_near, z_far],
            "camera parameters",
        )?;
        let dir = target - eye;
        if dir.length_squared() <= f64::MIN_POSITIVE {
            return Err(LixelError::DegenerateCamera { reason: "eye equals target" });
        }
        if dir.normalize().cross(up.normalize_or_zero()).length() < 1e-9 {
            return Err(LixelError::DegenerateCamera { reason: "up is parallel to the view direction" });
        }
        if !(fov_y_radians > 0.0 && fov_y_radians < std::f64::consts::PI) {
            return Err(LixelError::DegenerateCamera { reason: "vertical field of view outside (0, pi)" });
        }
        if viewport.x == 0 || viewport.y == 0 {
            return Err(LixelError::DegenerateCamera { reason: "zero viewport" });
        }
        if !(z_near > 0.0 && z_far > z_near) {
            return Err(LixelError::DegenerateCamera { reason: "need 0 < z_near < z_far" });
        }
        let aspect = f64::from(viewport.x) / f64::from(viewport.y);
        let view_from_world = glam::dcamera::rh::view::look_at_mat4(eye, target, up);
        let clip_from_view = glam::dcamera::rh::proj::directx::perspective(fov_y_radians, aspect, z_near, z_far);
        Self::from_matrices_with(
            view_from_world,
            clip_from_view,
            viewport,
            &ProjectionHints::clip_depth(ClipDepth::ZeroToOne),
        )
    }

    /// A camera from an engine's own matrices, whatever their convention.
    ///
    /// `view_from_world` must be a rotation (or reflection) plus translation;
    /// `clip_from_view` a perspective (`w = ±z_view`) or orthographic
    /// (`w = 1`) projection, any depth range, direction, far plane or centre.
    /// Near and far are read off the projection; what was read is in
    /// [`conventions`](Self::conventions). Where the matrix cannot tell the
    /// clip depth range (forward-Z perspective and orthographic projections
    /// read validly as both), the larger frustum is taken: see
    /// [`conventions`](crate::conventions) and state it with
    /// [`from_matrices_with`](Self::from_matrices_with) for an exact near plane.
    ///
    /// # Errors
    /// [`LixelError::NonFinite`] for non-finite matrices;
    /// [`LixelError::InvalidProjection`] naming the failed
    /// [`CameraProperty`](crate::conventions::CameraProperty): zero viewport,
    /// a view that is not rigid, a `w` row of neither kind, an oblique or
    /// constant depth row, no valid near/far, a mirrored `x` axis, or a
    /// singular `clip_from_world`.
    pub fn from_matrices(view_from_world: DMat4, clip_from_view: DMat4, viewport: UVec2) -> Result<Self> {
        Self::from_matrices_with(view_from_world, clip_from_view, viewport, &ProjectionHints::default())
    }

    /// [`from_matrices`](Self::from_matrices) with what the matrices cannot say
    /// (clip depth range, orthographic handedness) stated.
    ///
    /// # Errors
    /// As [`from_matrices`](Self::from_matrices), and
    /// [`CameraProperty::ClipDepth`](crate::conventions::CameraProperty::ClipDepth)
    /// when the stated range gives no valid camera.
    pub fn from_matrices_with(
        view_from_world: DMat4,
        clip_from_view: DMat4,
        viewport: UVec2,
        hints: &ProjectionHints,
    ) -> Result<Self> {
        let analysis = analyse(view_from_world, clip_from_view, viewport, hints)?;
        Ok(Self {
            view_from_world: analysis.view_from_world,
            clip_from_view: analysis.clip_from_view,
            viewport,
            z_near: analysis.z_near,
            z_far: analysis.z_far,
            source_view_from_world: view_from_world,
            source_clip_from_view: clip_from_view,
            conventions: analysis.conventions,
            source_depth: analysis.source_depth,
        })
    }

    /// What [`from_matrices`](Self::from_matrices) read the engine's matrices to mean.
    #[must_use]
    pub fn conventions(&self) -> CameraConventions {
        self.conventions
    }

    /// `true` for an orthographic projection.
    #[must_use]
    pub fn is_orthographic(&self) -> bool {
        self.conventions.projection == ProjectionKind::Orthographic
    }

    /// The engine's `view_from_world`, as given.
    #[must_use]
    pub fn source_view_from_world(&self) -> DMat4 {
        self.source_view_from_world
    }

    /// The engine's `clip_from_view`, as given.
    #[must_use]
    pub fn source_clip_from_view(&self) -> DMat4 {
        self.source_clip_from_view
    }

    /// Distance in front of the eye (along [`view_direction`](Self::view_direction))
    /// at NDC depth `z` of the engine's projection.
    #[must_use]
    pub fn distance_at_source_depth(&self, z: f64) -> f64 {
        self.source_depth.distance(z)
    }

    /// lixel's NDC depth (`[0, 1]`, forward) at distance `d` in front of the eye.
    #[must_use]
    pub fn depth_at_distance(&self, d: f64) -> f64 {
        let clip = self.clip_from_view * DVec4::new(0.0, 0.0, -d, 1.0);
        clip.z / clip.w
    }

    /// World to view space, normalised: camera looking down `-z` (a rigid
    /// transform, or a reflection for left-handed worlds).
    #[must_use]
    pub fn view_from_world(&self) -> DMat4 {
        self.view_from_world
    }

    /// View to clip space, normalised: `w = -z` (perspective) or `1`
    /// (orthographic), depth `[0, 1]` growing away from the eye, NDC `y` up.
    #[must_use]
    pub fn clip_from_view(&self) -> DMat4 {
        self.clip_from_view
    }

    /// World to clip space.
    #[must_use]
    pub fn clip_from_world(&self) -> DMat4 {
        self.clip_from_view * self.view_from_world
    }

    /// Full-resolution viewport size in pixels.
    #[must_use]
    pub fn viewport(&self) -> UVec2 {
        self.viewport
    }

    /// Near clip distance along the view direction (positive for a
    /// perspective camera; an orthographic one may have it at or behind the eye).
    #[must_use]
    pub fn z_near(&self) -> f64 {
        self.z_near
    }

    /// Far clip distance (`f64::INFINITY` for an infinite far plane).
    #[must_use]
    pub fn z_far(&self) -> f64 {
        self.z_far
    }

    /// Eye position in world space (for an orthographic camera: the origin
    /// of its view space).
    #[must_use]
    pub fn eye(&self) -> DVec3 {
        self.view_from_world.inverse().w_axis.truncate()
    }

    /// Unit view direction in world space.
    #[must_use]
    pub fn view_direction(&self) -> DVec3 {
        -self.view_from_world.row(2).truncate().normalize()
    }

    /// Depth along the view direction of a world point (positive in front).
    #[must_use]
    pub fn view_depth(&self, world: DVec3) -> f64 {
        -(self.view_from_world * world.extend(1.0)).z
    }

    /// Full-resolution pixel coordinates from clip space: `x` right, `y` down
    /// (row 0 at the top), `z` the depth-buffer value: `S = Viewport · Proj · View`
    /// is `screen_from_clip() * clip_from_world()`.
    #[must_use]
    pub fn screen_from_clip(&self) -> DMat4 {
        viewport_matrix(f64::from(self.viewport.x), f64::from(self.viewport.y))
    }

    /// `S = Viewport · Proj · View`: world to (pixel x, pixel y, depth), homogeneous.
    #[must_use]
    pub fn screen_from_world(&self) -> DMat4 {
        self.screen_from_clip() * self.clip_from_world()
    }

    /// The eight corners of the view frustum in world space. Index bits:
    /// bit 0 selects NDC `x = +1`, bit 1 `y = +1`, bit 2 the far plane. For
    /// an infinite far plane the far face is put at
    /// [`INFINITE_FAR_CORNER_RATIO`]` · z_near`; [`frustum_corners_to`](Self::frustum_corners_to)
    /// chooses it.
    #[must_use]
    pub fn frustum_corners(&self) -> [DVec3; 8] {
        self.frustum_corners_to(self.z_near.abs().max(f64::MIN_POSITIVE) * INFINITE_FAR_CORNER_RATIO)
    }

    /// [`frustum_corners`](Self::frustum_corners) with the far face at depth
    /// `min(z_far, max_depth)` (never nearer than just beyond the near plane).
    #[must_use]
    pub fn frustum_corners_to(&self, max_depth: f64) -> [DVec3; 8] {
        let far = if max_depth < self.z_far { max_depth } else { self.z_far };
        let far = far.max(self.z_near + 1e-9 * far.abs().max(self.z_near.abs()).max(f64::MIN_POSITIVE));
        let far_ndc = self.depth_at_distance(far);
        // Unproject in view space first, then apply the rigid inverse: going
        // through the inverse of the full clip_from_world loses about
        // ε·far/near of accuracy at extreme depth ranges.
        let view_from_clip = self.clip_from_view.inverse();
        let world_from_view = self.view_from_world.inverse();
        std::array::from_fn(|i| {
            let x = if i & 1 == 0 { -1.0 } else { 1.0 };
            let y = if i & 2 == 0 { -1.0 } else { 1.0 };
            let z = if i & 4 == 0 { 0.0 } else { far_ndc };
            world_from_view.transform_point3(view_from_clip.project_point3(DVec3::new(x, y, z)))
        })
    }

    /// The view frustum's corners with the far face no further than the
    /// farthest corner of `bounds` (so an infinite far plane gives a finite
    /// body that still holds everything the camera sees inside `bounds`).
    #[must_use]
    pub fn frustum_corners_within(&self, bounds: &Aabb) -> [DVec3; 8] {
        if self.z_far.is_finite() {
            return self.frustum_corners();
        }
        let deepest = (0..8)
            .map(|i| {
                let pick = |bit: usize, lo: f64, hi: f64| if i & bit == 0 { lo } else { hi };
                let p = DVec3::new(
                    pick(1, bounds.min.x, bounds.max.x),
                    pick(2, bounds.min.y, bounds.max.y),
                    pick(4, bounds.min.z, bounds.max.z),
                );
                self.view_depth(p)
            })
            .fold(f64::NEG_INFINITY, f64::max);
        // A little beyond, so that the far face never touches the bounds.
        self.frustum_corners_to(deepest + 1e-6 * deepest.abs().max(self.z_near) + self.z_near)
    }

    /// Direction from `world` towards the viewer: to the eye for a
    /// perspective camera, against the view direction for an orthographic one.
    #[must_use]
    pub fn towards_viewer(&self, world: DVec3) -> DVec3 {
        if self.is_orthographic() {
            -self.view_direction()
        } else {
            self.eye() - world
        }
    }
}

/// NDC to pixel coordinates for a `width x height` target: `x` right, `y`
/// down, depth unchanged.
#[must_use]
pub(crate) fn viewport_matrix(width: f64, height: f64) -> DMat4 {
    DMat4::from_cols(
        DVec4::new(0.5 * width, 0.0, 0.0, 0.0),
        DVec4::new(0.0, -0.5 * height, 0.0, 0.0),
        DVec4::new(0.0, 0.0, 1.0, 0.0),
        DVec4::new(0.5 * width, 0.5 * height, 0.0, 1.0),
    )
}
