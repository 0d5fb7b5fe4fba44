//! Reading an engine's view and projection matrices: which convention they
//! follow, and the same camera in lixel's own convention.
//!
//! # Algorithm
//! 1. `view_from_world` must be a rotation or reflection plus translation.
//! 2. The projection's `w` row decides the kind: `(0, 0, ∓c, 0)` is a
//!    perspective looking down `∓z` (right- or left-handed view), `(0, 0, 0, c)`
//!    orthographic. Dividing by `c` and flipping view `z` for a left-handed
//!    view gives a right-handed projection `P` with `w = -z` (or `1`).
//! 3. A negative `y` scale is a `y`-down clip space (flipped back); a
//!    negative `x` scale is a mirror (rejected).
//! 4. The depth row gives NDC depth as a function of the distance `d` in
//!    front of the eye: `z(d) = α + β/d` (perspective) or `s·d + t`
//!    (orthographic). Its monotonicity is the depth direction; solving
//!    `z(d) = lo` and `z(d) = hi` for each candidate range `[lo, hi]` gives
//!    near and far (far is infinite where the limit `α` reaches the range's
//!    far end); a reading is valid when `0 < near < far` (orthographic:
//!    `near < far`).
//! 5. The canonical camera keeps the `x`/`y` rows and gets a fresh
//!    `[0, 1]` forward depth row for the same near and far.
//!
//! Cost: constant (a few 4x4 products).

use glam::{DMat3, DMat4, DVec2, DVec4, UVec2};

use super::{
    CameraConventions, CameraProperty, Centring, ClipDepth, ClipY, DepthDirection, Handedness, Inferred,
    ProjectionHints, ProjectionKind,
};
use crate::error::{check_finite, LixelError, Result};

/// NDC depth of the engine's projection as a function of the distance `d`
/// in front of the eye.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum SourceDepth {
    /// `z = alpha + beta / d`.
    Perspective { alpha: f64, beta: f64 },
    /// `z = slope · d + offset`.
    Orthographic { slope: f64, offset: f64 },
}

impl SourceDepth {
    /// Distance in front of the eye at engine NDC depth `z`.
    pub(crate) fn distance(self, z: f64) -> f64 {
        match self {
            Self::Perspective { alpha, beta } => beta / (z - alpha),
            Self::Orthographic { slope, offset } => (z - offset) / slope,
        }
    }
}

/// The result of reading a camera's matrices.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Analysis {
    /// Canonical: right-handed view (looking down `-z`).
    pub view_from_world: DMat4,
    /// Canonical: `w = -z` or `1`, clip depth `[0, 1]` forward, NDC `y` up.
    pub clip_from_view: DMat4,
    pub z_near: f64,
    pub z_far: f64,
    pub conventions: CameraConventions,
    pub source_depth: SourceDepth,
}

fn invalid(property: CameraProperty, reason: &'static str) -> LixelError {
    LixelError::InvalidProjection { property, reason }
}

/// Near and far distances of one reading `[lo, hi]`, or `None` when it is not
/// a valid camera. `depth` is the engine's `z(d)`.
fn reading(
    depth: SourceDepth,
    direction: DepthDirection,
    (lo, hi): (f64, f64),
    infinite_tol: f64,
) -> Option<(f64, f64)> {
    let (z_near, z_far) = match direction {
        DepthDirection::Forward => (lo, hi),
        DepthDirection::Reverse => (hi, lo),
    };
    let near = depth.distance(z_near);
    let far = match depth {
        SourceDepth::Perspective { alpha, .. } => {
            // z(d) tends to alpha as d grows: far is infinite when the range
            // end is at (or beyond) alpha.
            let beyond = match direction {
                DepthDirection::Forward => z_far - alpha,
                DepthDirection::Reverse => alpha - z_far,
            };
            if beyond >= -infinite_tol {
                f64::INFINITY
            } else {
                depth.distance(z_far)
            }
        }
        SourceDepth::Orthographic { .. } => depth.distance(z_far),
    };
    let valid = match depth {
        SourceDepth::Perspective { .. } => near.is_finite() && near > 0.0 && far > near,
        SourceDepth::Orthographic { .. } => near.is_finite() && far.is_finite() && far > near,
    };
    valid.then_some((near, far))
}

const ZERO_TO_ONE: (f64, f64) = (0.0, 1.0);
const NEGATIVE_ONE_TO_ONE: (f64, f64) = (-1.0, 1.0);

/// Reads `view_from_world`, `clip_from_view` and the viewport.
pub(crate) fn analyse(
    view_from_world: DMat4,
    clip_from_view: DMat4,
    viewport: UVec2,
    hints: &ProjectionHints,
) -> Result<Analysis> {
    let tol = hints.tolerances;
    check_finite(&view_from_world.to_cols_array(), "view_from_world")?;
    check_finite(&clip_from_view.to_cols_array(), "clip_from_view")?;
    if viewport.x == 0 || viewport.y == 0 {
        return Err(invalid(CameraProperty::Viewport, "zero viewport"));
    }
    // 1. Rigid view (a reflection is a valid view of a left-handed world).
    let rot = DMat3::from_mat4(view_from_world);
    let orthonormal = (rot.transpose() * rot - DMat3::IDENTITY).to_cols_array().iter().all(|v| v.abs() < tol.rigid);
    let last = view_from_world.row(3) - DVec4::W;
    let translation = view_from_world.w_axis.truncate().abs().max_element().max(1.0);
    if !orthonormal || last.abs().max_element() > tol.rigid * translation {
        return Err(invalid(CameraProperty::RigidView, "view_from_world is not a rotation plus translation"));
    }
    // 2. Kind and handedness from the w row.
    let w_row = clip_from_view.row(3);
    let scale = w_row.abs().max_element();
    let small = |v: f64| v.abs() <= tol.structure * scale;
    let (kind, view, c) = if small(w_row.x) && small(w_row.y) && small(w_row.w) && w_row.z != 0.0 {
        let handedness = if w_row.z < 0.0 { Handedness::Right } else { Handedness::Left };
        (ProjectionKind::Perspective, handedness, w_row.z.abs())
    } else if small(w_row.x) && small(w_row.y) && small(w_row.z) && w_row.w > 0.0 {
        (ProjectionKind::Orthographic, hints.orthographic_view.unwrap_or(Handedness::Right), w_row.w)
    } else {
        return Err(invalid(
            CameraProperty::ProjectionKind,
            "the w row is neither ±z (perspective) nor a positive constant (orthographic)",
        ));
    };
    let flip_z = DMat4::from_diagonal(DVec4::new(1.0, 1.0, -1.0, 1.0));
    let (mut proj, view_from_world) = match view {
        Handedness::Right => (clip_from_view * (1.0 / c), view_from_world),
        Handedness::Left => (clip_from_view * (1.0 / c) * flip_z, flip_z * view_from_world),
    };
    // Exact w row, so that w is the distance (perspective) or 1.
    let w_exact = match kind {
        ProjectionKind::Perspective => DVec4::new(0.0, 0.0, -1.0, 0.0),
        ProjectionKind::Orthographic => DVec4::W,
    };
    set_row(&mut proj, 3, w_exact);
    // 3. Screen axes.
    let clip_y = if proj.y_axis.y < 0.0 { ClipY::Down } else { ClipY::Up };
    if clip_y == ClipY::Down {
        let flipped = -proj.row(1);
        set_row(&mut proj, 1, flipped);
    }
    if !(proj.x_axis.x > 0.0) || !(proj.y_axis.y > 0.0) {
        return Err(invalid(CameraProperty::Mirrored, "NDC x must grow with view x and NDC y with view y (or -y)"));
    }
    // 4. Depth.
    let z_row = proj.row(2);
    let z_scale = z_row.abs().max_element();
    if z_row.x.abs() > tol.structure * z_scale || z_row.y.abs() > tol.structure * z_scale {
        return Err(invalid(CameraProperty::DepthRow, "depth depends on view x or y (an oblique near plane)"));
    }
    let (a, b) = (z_row.z, z_row.w);
    let source_depth = match kind {
        ProjectionKind::Perspective => SourceDepth::Perspective { alpha: -a, beta: b },
        ProjectionKind::Orthographic => SourceDepth::Orthographic { slope: -a, offset: b },
    };
    let rate = match source_depth {
        // dz/dd = -beta / d²: forward when beta < 0.
        SourceDepth::Perspective { beta, .. } => -beta,
        SourceDepth::Orthographic { slope, .. } => slope,
    };
    if !(rate != 0.0) || !rate.is_finite() {
        return Err(invalid(CameraProperty::DepthRow, "depth does not change with distance"));
    }
    let depth = if rate > 0.0 { DepthDirection::Forward } else { DepthDirection::Reverse };
    let read = |range| reading(source_depth, depth, range, tol.infinite_far);
    let (clip_depth, inferred, (z_near, z_far)) = match hints.clip_depth {
        Some(stated) => {
            let range = if stated == ClipDepth::ZeroToOne { ZERO_TO_ONE } else { NEGATIVE_ONE_TO_ONE };
            let near_far = read(range).ok_or_else(|| {
                invalid(CameraProperty::ClipDepth, "the stated clip depth range gives no valid near and far")
            })?;
            (stated, Inferred::Stated, near_far)
        }
        None => match (read(ZERO_TO_ONE), read(NEGATIVE_ONE_TO_ONE), depth) {
            (Some(zo), Some(_), DepthDirection::Reverse) => (ClipDepth::ZeroToOne, Inferred::Assumed, zo),
            (Some(_), Some(no), DepthDirection::Forward) => (ClipDepth::NegativeOneToOne, Inferred::Assumed, no),
            (Some(zo), None, _) => (ClipDepth::ZeroToOne, Inferred::FromMatrix, zo),
            (None, Some(no), _) => (ClipDepth::NegativeOneToOne, Inferred::FromMatrix, no),
            (None, None, _) => {
                return Err(invalid(
                    CameraProperty::DepthRow,
                    "no clip depth range gives 0 < near < far (near plane behind the eye?)",
                ))
            }
        },
    };
    // 5. Canonical depth row: [0, 1] forward over [near, far].
    let canonical_z = match kind {
        ProjectionKind::Perspective if z_far.is_infinite() => DVec4::new(0.0, 0.0, -1.0, -z_near),
        ProjectionKind::Perspective => {
            let k = z_far / (z_far - z_near);
            DVec4::new(0.0, 0.0, -k, -k * z_near)
        }
        ProjectionKind::Orthographic => {
            let k = 1.0 / (z_far - z_near);
            DVec4::new(0.0, 0.0, -k, -k * z_near)
        }
    };
    set_row(&mut proj, 2, canonical_z);
    let det = (proj * view_from_world).determinant();
    if !det.is_finite() || det.abs() < 1e-300 {
        return Err(invalid(CameraProperty::Singular, "clip_from_world is singular"));
    }
    // Centre: where the view axis lands in NDC (y up).
    let centre = match kind {
        ProjectionKind::Perspective => DVec2::new(-proj.z_axis.x, -proj.z_axis.y),
        ProjectionKind::Orthographic => DVec2::new(proj.w_axis.x, proj.w_axis.y),
    };
    let pixels = centre * viewport.as_dvec2() * 0.5;
    let centring = if centre == DVec2::ZERO {
        Centring::Symmetric
    } else if pixels.abs().max_element() < tol.jitter_pixels {
        Centring::Jittered
    } else {
        Centring::OffCentre
    };
    let conventions = CameraConventions {
        projection: kind,
        clip_depth,
        clip_depth_inferred: inferred,
        depth,
        infinite_far: z_far.is_infinite(),
        centring,
        centre_offset_ndc: centre,
        view,
        clip_y,
    };
    Ok(Analysis { view_from_world, clip_from_view: proj, z_near, z_far, conventions, source_depth })
}

fn set_row(m: &mut DMat4, row: usize, v: DVec4) {
    let mut t = m.transpose();
    *t.col_mut(row) = v;
    *m = t.transpose();
}
