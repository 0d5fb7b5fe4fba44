//! Lights and the light frames their shadow maps are built in.

use glam::{DMat3, DMat4, DVec3, DVec4};

use crate::error::{check_finite, LixelError, Result};

/// A light that casts shadows.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Light {
    /// Parallel rays (the sun).
    Directional {
        /// Unit direction in which the light travels (from the light into the scene).
        direction: DVec3,
    },
    /// Rays from a point in every direction.
    Point {
        /// World position.
        position: DVec3,
    },
    /// A point light restricted to a cone.
    Spot {
        /// World position.
        position: DVec3,
        /// Unit axis of the cone (from the light into the scene).
        direction: DVec3,
        /// Half the cone's opening angle, in `(0, π/2)`.
        outer_half_angle_radians: f64,
    },
}

impl Light {
    /// A directional light travelling along `direction` (normalized here).
    #[must_use]
    pub fn directional(direction: DVec3) -> Self {
        Self::Directional { direction: direction.normalize_or_zero() }
    }

    /// A point light at `position`.
    #[must_use]
    pub fn point(position: DVec3) -> Self {
        Self::Point { position }
    }

    /// A spot light at `position` pointing along `direction` (normalized here).
    #[must_use]
    pub fn spot(position: DVec3, direction: DVec3, outer_half_angle_radians: f64) -> Self {
        Self::Spot { position, direction: direction.normalize_or_zero(), outer_half_angle_radians }
    }

    /// World position of a point or spot light; `None` for a directional light.
    #[must_use]
    pub fn position(&self) -> Option<DVec3> {
        match *self {
            Self::Directional { .. } => None,
            Self::Point { position } | Self::Spot { position, .. } => Some(position),
        }
    }

    /// The light as a homogeneous world point: `(p, 1)` for a positional
    /// light, `(-d, 0)` (the point at infinity the light comes from) for a
    /// directional one.
    #[must_use]
    pub fn homogeneous_position(&self) -> DVec4 {
        match *self {
            Self::Directional { direction } => (-direction).extend(0.0),
            Self::Point { position } | Self::Spot { position, .. } => position.extend(1.0),
        }
    }

    /// Whether the light can reach `point` at all, occluders aside: inside a
    /// spot light's cone (its boundary included); always for point and
    /// directional lights.
    #[must_use]
    pub fn reaches(&self, point: DVec3) -> bool {
        match *self {
            Self::Spot { position, direction, outer_half_angle_radians } => {
                let to_point = point - position;
                direction.dot(to_point) >= outer_half_angle_radians.cos() * to_point.length()
            }
            Self::Directional { .. } | Self::Point { .. } => true,
        }
    }

    /// The cone of a spot light as (unit axis, cosine of the half-angle).
    #[must_use]
    pub fn cone(&self) -> Option<(DVec3, f64)> {
        match *self {
            Self::Spot { direction, outer_half_angle_radians, .. } => Some((direction, outer_half_angle_radians.cos())),
            Self::Directional { .. } | Self::Point { .. } => None,
        }
    }

    /// Checks that every value is finite and the light is well formed.
    ///
    /// # Errors
    /// [`LixelError::NonFinite`] or [`LixelError::InvalidLight`].
    pub fn validate(&self) -> Result<()> {
        match *self {
            Self::Directional { direction } => {
                check_finite(&direction.to_array(), "light direction")?;
                unit(direction, "directional light needs a unit direction")
            }
            Self::Point { position } => check_finite(&position.to_array(), "light position"),
            Self::Spot { position, direction, outer_half_angle_radians } => {
                check_finite(&position.to_array(), "light position")?;
                check_finite(&direction.to_array(), "light direction")?;
                check_finite(&[outer_half_angle_radians], "spot angle")?;
                unit(direction, "spot light needs a unit direction")?;
                // The circumscribed pyramid (see `Spot`) must stay inside a half-space.
                if !(outer_half_angle_radians > 0.0 && outer_half_angle_radians < 89.0_f64.to_radians()) {
                    return Err(LixelError::InvalidLight {
                        reason: "spot half-angle must lie in (0, 89) degrees for a single map",
                    });
                }
                Ok(())
            }
        }
    }
}

fn unit(v: DVec3, reason: &'static str) -> Result<()> {
    if (v.length() - 1.0).abs() < 1e-6 {
        Ok(())
    } else {
        Err(LixelError::InvalidLight { reason })
    }
}

/// The coordinates a shadow map's homography acts on (`X~` of math.md §1).
///
/// * Perspective (point and spot lights): `X~ = R (x - l)`, the direction
///   from the light in the light's rotated frame.
/// * Orthographic (directional lights): `X~ = (r1·x, r2·x, 1)`, the
///   coordinates on a plane orthogonal to the light, homogenised; the third
///   light axis `d` (the light direction) measures depth `c = d·x`.
///
/// Rotation rows are the light axes. Any light frame works (the homography
/// absorbs the choice); lixel picks one whose third axis points along the
/// light (the spot axis, or towards the scene for a point light).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LightFrame {
    /// Frame of a point or spot light.
    Perspective {
        /// Light position.
        position: DVec3,
        /// Rotation whose rows are the light axes.
        rotation: DMat3,
    },
    /// Frame of a directional light.
    Orthographic {
        /// Rotation whose rows are `r1`, `r2` and the light direction `d`.
        rotation: DMat3,
    },
}

impl LightFrame {
    /// A frame for `light` whose third axis is `forward` (used when the light
    /// itself does not fix one: point lights).
    #[must_use]
    pub(crate) fn new(light: &Light, forward: DVec3) -> Self {
        match *light {
            Light::Directional { direction } => Self::Orthographic { rotation: rotation_with_z(direction) },
            Light::Spot { position, direction, .. } => {
                Self::Perspective { position, rotation: rotation_with_z(direction) }
            }
            Light::Point { position } => Self::Perspective { position, rotation: rotation_with_z(forward) },
        }
    }

    /// `X~` of a world point.
    #[must_use]
    #[inline]
    pub fn homogeneous(&self, world: DVec3) -> DVec3 {
        match *self {
            Self::Perspective { position, rotation } => rotation * (world - position),
            Self::Orthographic { rotation } => {
                let p = rotation * world;
                DVec3::new(p.x, p.y, 1.0)
            }
        }
    }

    /// `X~` of a homogeneous world point `(x, w)` (`w = 0`: a direction).
    #[must_use]
    pub fn homogeneous4(&self, world: DVec4) -> DVec3 {
        self.light_from_world_3x4_rows().map(|row| row.dot(world)).into()
    }

    /// The 3x4 matrix `T` with `X~ = T [x; 1]`, as its three rows.
    #[must_use]
    pub fn light_from_world_3x4_rows(&self) -> [DVec4; 3] {
        match *self {
            Self::Perspective { position, rotation } => {
                let t = -(rotation * position);
                [rotation.row(0).extend(t.x), rotation.row(1).extend(t.y), rotation.row(2).extend(t.z)]
            }
            Self::Orthographic { rotation } => [rotation.row(0).extend(0.0), rotation.row(1).extend(0.0), DVec4::W],
        }
    }

    /// The rigid world-to-light transform (light axes as rows, light at the
    /// origin for positional lights).
    #[must_use]
    pub fn light_from_world(&self) -> DMat4 {
        match *self {
            Self::Perspective { position, rotation } => DMat4::from_mat3(rotation) * DMat4::from_translation(-position),
            Self::Orthographic { rotation } => DMat4::from_mat3(rotation),
        }
    }

    /// The `j` with `j · X~(x) = ρ · [x; 1]` for a world-space row `ρ` that
    /// vanishes at the light (for example the `w` row of any light matrix of
    /// this light): how an optical axis moves between frames.
    #[must_use]
    pub fn axis_from_world_row(&self, row: DVec4) -> DVec3 {
        match *self {
            // X~ = R (x - l): j·X~ = (Rᵀj)·x - (Rᵀj)·l, so Rᵀ j = ρ_xyz.
            Self::Perspective { rotation, .. } => rotation * row.truncate(),
            // X~ = (r1·x, r2·x, 1): j = (ρ_xyz·r1, ρ_xyz·r2, ρ_w).
            Self::Orthographic { rotation } => {
                let r = row.truncate();
                DVec3::new(r.dot(rotation.row(0)), r.dot(rotation.row(1)), row.w)
            }
        }
    }

    /// Whether this is a directional light's frame.
    #[must_use]
    pub fn is_orthographic(&self) -> bool {
        matches!(self, Self::Orthographic { .. })
    }
}

/// A rotation (rows = axes) whose third row is `z` (normalized).
#[must_use]
pub(crate) fn rotation_with_z(z: DVec3) -> DMat3 {
    let z = z.normalize();
    let (x, y) = z.any_orthonormal_pair();
    // Rows x, y, z; right-handed since x × y = z for glam's pair.
    DMat3::from_cols(x, y, z).transpose()
}
