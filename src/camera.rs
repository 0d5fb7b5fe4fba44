//! The viewer: a perspective camera in wgpu conventions.

use glam::{DMat4, DVec3, DVec4, UVec2};

use crate::error::{check_finite, LixelError, Result};

/// A perspective camera in wgpu conventions: right-handed world and view
/// space (the camera looks down `-z`), clip depth in `[0, 1]`, NDC `y` up,
/// framebuffer row 0 at the top.
///
/// Any perspective `clip_from_view` whose `w` row is `-z_view` is accepted
/// (asymmetric and jittered frusta included); orthographic cameras are not,
/// because PSM and LiSPSM are defined by the camera's perspective.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    view_from_world: DMat4,
    clip_from_view: DMat4,
    viewport: UVec2,
    z_near: f64,
    z_far: f64,
}

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
        Self::from_matrices(view_from_world, clip_from_view, viewport)
    }

    /// A camera from an engine's own matrices.
    ///
    /// `view_from_world` must be rigid (rotation and translation);
    /// `clip_from_view` a perspective projection with depth in `[0, 1]` whose
    /// `w` row is `(0, 0, -1, 0)`. Near and far are read off the projection.
    ///
    /// # Errors
    /// [`LixelError::NonFinite`] or [`LixelError::DegenerateCamera`] when the
    /// matrices are non-finite, not of that form, singular, or the viewport is
    /// zero.
    pub fn from_matrices(view_from_world: DMat4, clip_from_view: DMat4, viewport: UVec2) -> Result<Self> {
        check_finite(&view_from_world.to_cols_array(), "view_from_world")?;
        check_finite(&clip_from_view.to_cols_array(), "clip_from_view")?;
        if viewport.x == 0 || viewport.y == 0 {
            return Err(LixelError::DegenerateCamera { reason: "zero viewport" });
        }
        let rot = glam::DMat3::from_mat4(view_from_world);
        let orthonormal =
            (rot.transpose() * rot - glam::DMat3::IDENTITY).to_cols_array().iter().all(|v| v.abs() < 1e-6);
        if !orthonormal || rot.determinant() <= 0.0 || view_from_world.row(3) != DVec4::W {
            return Err(LixelError::DegenerateCamera { reason: "view_from_world is not a rigid transform" });
        }
        if (clip_from_view.row(3) - DVec4::new(0.0, 0.0, -1.0, 0.0)).abs().max_element() > 1e-12 {
            return Err(LixelError::DegenerateCamera {
                reason: "clip_from_view is not a perspective projection with w = -z_view",
            });
        }
        // Depth row: z_clip = a z_view + b, so z_ndc = (a z + b) / (-z).
        // z_ndc = 0 at z = -near and 1 at z = -far: near = b / a, far = b / (1 + a).
        let a = clip_from_view.z_axis.z;
        let b = clip_from_view.w_axis.z;
        let (z_near, z_far) = (b / a, b / (1.0 + a));
        if !(z_near.is_finite() && z_far.is_finite() && z_near > 0.0 && z_far > z_near) {
            return Err(LixelError::DegenerateCamera {
                reason: "projection does not map a finite 0 < near < far to depth [0, 1]",
            });
        }
        let clip_from_world = clip_from_view * view_from_world;
        let det = clip_from_world.determinant();
        if !det.is_finite() || det.abs() < 1e-300 {
            return Err(LixelError::DegenerateCamera { reason: "singular clip_from_world" });
        }
        Ok(Self { view_from_world, clip_from_view, viewport, z_near, z_far })
    }

    /// World to view space (rigid, camera looking down `-z`).
    #[must_use]
    pub fn view_from_world(&self) -> DMat4 {
        self.view_from_world
    }

    /// View to clip space (perspective, depth `[0, 1]`).
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

    /// Near clip distance (positive, along the view direction).
    #[must_use]
    pub fn z_near(&self) -> f64 {
        self.z_near
    }

    /// Far clip distance.
    #[must_use]
    pub fn z_far(&self) -> f64 {
        self.z_far
    }

    /// Eye position in world space.
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
    /// bit 0 selects NDC `x = +1`, bit 1 `y = +1`, bit 2 the far plane.
    #[must_use]
    pub fn frustum_corners(&self) -> [DVec3; 8] {
        // Unproject in view space first, then apply the rigid inverse: going
        // through the inverse of the full clip_from_world loses about
        // ε·far/near of accuracy at extreme depth ranges.
        let view_from_clip = self.clip_from_view.inverse();
        let world_from_view = self.view_from_world.inverse();
        std::array::from_fn(|i| {
            let x = if i & 1 == 0 { -1.0 } else { 1.0 };
            let y = if i & 2 == 0 { -1.0 } else { 1.0 };
            let z = if i & 4 == 0 { 0.0 } else { 1.0 };
            world_from_view.transform_point3(view_from_clip.project_point3(DVec3::new(x, y, z)))
        })
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
