//! Plane-optimal shadow maps (Chong & Gortler 2004, "A lixel for every pixel").
//!
//! For a receiver plane `π` the map from a screen pixel to the plane point it
//! shows is projective, and so is the map from that point to light
//! coordinates. Composing the two gives `X~ = H x̂` for the homogeneous pixel
//! `x̂ = (x₁ w, x₂ w, w)` (`w` the point's view depth). Choosing `G = A H⁻¹`
//! with `A` affine makes the shadow-map position an affine function of the
//! pixel on the plane: every visible pixel of the plane gets the same number
//! of texels. The optical axis is the third row of `H⁻¹` (so `j·X~` equals
//! the view depth of the plane point: positive in front of the camera).
//!
//! Relevant points off the plane may land at or beyond this map's vanishing
//! line. Then no single map keeps both perfect sampling and full coverage:
//! lixel blends the axis towards the focused axis by the smallest weight that
//! keeps every relevant point's `w` at least
//! [`PlaneOptimalOptions::min_relative_w`] times the smallest `w` of the
//! visible plane, and reports [`Fallback::PlaneOptimalBlended`].

use glam::{DMat3, DVec3};

use crate::error::{check_finite, LixelError, Result};
use crate::geometry::{ConvexPolyhedron, Plane};
use crate::matrix::{Fallback, LightMatrix, Method};
use crate::problem::ShadowProblem;
use crate::workspace::SolveWorkspace;

/// Options of [`Parameterization::PlaneOptimal`](crate::Parameterization::PlaneOptimal).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlaneOptimalOptions {
    /// The receiver plane. `None`: the horizontal plane at the bottom of the
    /// receiver bounds (the floor), `y = receivers.min.y`.
    pub plane: Option<Plane>,
    /// Every relevant point must keep at least this fraction of the smallest
    /// `w = j·X~` over the visible part of the plane (`X~` normalized for
    /// point lights); otherwise points near the vanishing line would stretch
    /// the map, and the axis is blended towards the focused one. In `(0, 1)`;
    /// default `0.5`.
    pub min_relative_w: f64,
}

impl PlaneOptimalOptions {
    /// The floor of the receiver bounds, `min_relative_w = 0.5`.
    pub const DEFAULT: Self = Self { plane: None, min_relative_w: 0.5 };

    /// Optimal on `plane`.
    #[must_use]
    pub fn on_plane(plane: Plane) -> Self {
        Self { plane: Some(plane), ..Self::DEFAULT }
    }
}

impl Default for PlaneOptimalOptions {
    fn default() -> Self {
        Self::DEFAULT
    }
}

pub(super) fn solve(
    problem: &ShadowProblem,
    options: &PlaneOptimalOptions,
    ws: &mut SolveWorkspace,
) -> Result<LightMatrix> {
    let plane = match options.plane {
        Some(p) => {
            check_finite(&[p.normal.x, p.normal.y, p.normal.z, p.offset], "receiver plane")?;
            let len = p.normal.length();
            if !(len > 0.0) {
                return Err(LixelError::InvalidPlane { reason: "zero normal" });
            }
            Plane { normal: p.normal / len, offset: p.offset / len }
        }
        None => Plane::from_point_normal(problem.bounds().receivers.min, DVec3::Y),
    };
    if !(options.min_relative_w > 0.0 && options.min_relative_w < 1.0) {
        return Err(LixelError::InvalidPlane { reason: "min_relative_w must lie in (0, 1)" });
    }
    problem.with_visible_receiver_body(ws, |focus, ws| solve_on(problem, options, &plane, focus, ws))
}

fn solve_on(
    problem: &ShadowProblem,
    options: &PlaneOptimalOptions,
    plane: &Plane,
    focus: &ConvexPolyhedron,
    ws: &mut SolveWorkspace,
) -> Result<LightMatrix> {
    if focus.is_empty() {
        return super::focused::around(problem, focus, Method::PlaneOptimal, None, ws);
    }
    let frame = problem.frame_towards(focus);
    let focused_axis = super::uniform_axis(problem, &frame, focus, Method::PlaneOptimal, ws)?.normalize();
    let Some(plane_axis) = plane_optimal_axis(problem, &frame, plane) else {
        return super::focused::around(problem, focus, Method::PlaneOptimal, Some(Fallback::PlaneDegenerate), ws);
    };

    // The visible part of the plane (a thin slab of the focus body).
    let slab = problem.coarse_eps();
    let mut on_plane = ws.take_body();
    focus.clip_all_into(
        [plane.grown(slab), plane.flipped().grown(slab)].iter(),
        problem.eps(),
        &mut on_plane,
        &mut ws.clip,
    );
    if on_plane.is_empty() {
        ws.put_body(on_plane);
        return super::focused::around(problem, focus, Method::PlaneOptimal, Some(Fallback::PlaneNotVisible), ws);
    }
    let beta = options.min_relative_w;
    let directions = |body: &ConvexPolyhedron, ws: &mut SolveWorkspace| -> Vec<DVec3> {
        let mut dirs = ws.take_points();
        problem.mappable_vertices_into(body, &mut dirs, ws);
        for p in &mut dirs {
            *p = cosine_frame(&frame, frame.homogeneous(*p));
        }
        dirs
    };
    let (plane_dirs, focus_dirs) = (directions(&on_plane, ws), directions(focus, ws));
    ws.put_body(on_plane);
    // Every relevant point must keep at least β times the smallest w of the
    // visible plane: points near the vanishing line would blow the map up.
    // Never closer to the vanishing line than the matrix builder accepts.
    let front = 2.0 * problem.tolerances().min_front_cosine;
    let acceptable = |axis: DVec3| {
        // The least and the largest `w` by plain compares: a NaN is passed
        // over as `f64::min` and `f64::max` pass it over, and the sign of a
        // zero does not matter below (a zero `floor_w` fails, a zero
        // `max_w` bounds nothing).
        let mut floor_w = f64::INFINITY;
        for u in &plane_dirs {
            let w = axis.dot(*u);
            if w < floor_w {
                floor_w = w;
            }
        }
        // With the relevant points' least `w`: all are at least `least`
        // exactly when it is and none is NaN.
        let (mut max_w, mut min_w, mut nan) = (0.0, f64::INFINITY, false);
        for u in &focus_dirs {
            let w = axis.dot(*u);
            if w > max_w {
                max_w = w;
            }
            if w < min_w {
                min_w = w;
            }
            nan |= w.is_nan();
        }
        let least = (beta * floor_w).max(front * max_w);
        floor_w > 0.0 && (focus_dirs.is_empty() || (!nan && min_w >= least))
    };
    let blended = |t: f64| plane_axis * (1.0 - t) + focused_axis * t;
    let (axis, fallback) = if acceptable(plane_axis) {
        (plane_axis, None)
    } else {
        // Bisection for the least blend towards the focused axis that is acceptable.
        let (mut lo, mut hi) = (0.0, 1.0);
        for _ in 0..problem.tolerances().blend_bisection_steps {
            let mid = 0.5 * (lo + hi);
            if acceptable(blended(mid)) {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        (blended(hi), Some(Fallback::PlaneOptimalBlended { blend: hi }))
    };
    ws.put_points(focus_dirs);
    ws.put_points(plane_dirs);
    // So near the plane's vanishing line that f64 cannot hold the map (a
    // light grazing the plane): the plane is degenerate for this light.
    problem
        .place(frame, axis, focus, Method::PlaneOptimal, fallback, ws)
        .or_else(|_| super::focused::around(problem, focus, Method::PlaneOptimal, Some(Fallback::PlaneDegenerate), ws))
}

/// The unit plane-optimal axis in light coordinates of `frame`, or `None`
/// when the eye or the light lies in the plane.
fn plane_optimal_axis(problem: &ShadowProblem, frame: &crate::LightFrame, plane: &Plane) -> Option<DVec3> {
    // Homogeneous coordinates y on the plane: [x; 1] = P y, columns
    // (p0, 1), (u, 0), (v, 0).
    let p0 = plane.normal * -plane.offset;
    let (u, v) = plane.normal.any_orthonormal_pair();
    let columns = [p0.extend(1.0), u.extend(0.0), v.extend(0.0)];
    // Screen rows x, y, w of `S` (pixels, homogeneous) and the light rows `T`.
    let screen = problem.camera().screen_from_world();
    let s_rows = [screen.row(0), screen.row(1), screen.row(3)];
    let t_rows = frame.light_from_world_3x4_rows();
    let restrict = |rows: [glam::DVec4; 3]| {
        DMat3::from_cols_array_2d(&std::array::from_fn(|c| std::array::from_fn(|r| rows[r].dot(columns[c]))))
    };
    let pixel_from_plane = restrict(s_rows);
    let light_from_plane = restrict(t_rows);
    // x̂ = (S P) y and X~ = (T P) y, so x̂ = (S P)(T P)⁻¹ X~ and j is row 3.
    // Singular relative to Hadamard's bound (the product of the column
    // lengths): scale-free, so a light 1e9 away (huge translation column) is
    // judged like the directional light it approaches.
    let singular = |m: &DMat3| {
        let bound = m.x_axis.length() * m.y_axis.length() * m.z_axis.length();
        !(m.determinant().abs() > problem.tolerances().singular_det * bound)
    };
    if singular(&light_from_plane) || singular(&pixel_from_plane) {
        return None;
    }
    let pixel_from_light = pixel_from_plane * light_from_plane.inverse();
    let axis = pixel_from_light.row(2);
    // The eye in the plane makes the w row of S P vanish on the plane's frame
    // (an orthographic camera's w row is constant: no such eye).
    let eye_distance = plane.signed_distance(problem.camera().eye()).abs();
    if !problem.camera().is_orthographic() && !(eye_distance > problem.eps()) {
        return None;
    }
    axis.try_normalize()
}

/// `X~` scaled for comparing `w` across points: unit length for point lights
/// (a cosine to the axis), unchanged for directional lights (whose `X~` all
/// have third coordinate 1).
fn cosine_frame(frame: &crate::LightFrame, x: DVec3) -> DVec3 {
    if frame.is_orthographic() {
        x
    } else {
        x.normalize_or_zero()
    }
}
