//! Perspective shadow maps (Stamminger & Drettakis 2002).
//!
//! The map is built in the camera's post-perspective space (PPS), where the
//! view frustum is a cube and distant receivers shrink, so a map uniform in
//! PPS spends more texels near the viewer. Steps:
//!
//! 1. `H = conv(V ∪ l) ∩ S ∩ L`, the points that must be in the map.
//! 2. Virtual camera shift: if part of `H` lies behind the camera's near
//!    plane, the shadow camera (only it) moves back along the view axis by
//!    `δ = max(0, max_v (z_v + near))` so all of `H` maps to `w > 0` in PPS.
//!    `near` stays (or is pushed out to a read-back minimum view depth),
//!    `far` grows by `δ`. As `δ → ∞` PSM tends to a uniform map.
//! 3. The light moves to PPS as a homogeneous point `L' = M [l; 1]` (or
//!    `M [-d; 0]`). Its `w'` tells the case: `> 0` an ordinary point light,
//!    `≈ 0` a directional light in PPS (the ideal case: light parallel to
//!    the image plane), `< 0` the *inverted* case (light behind the viewer).
//! 4. The light frustum's axis in PPS is the axis of the narrowest cone
//!    around the directions `D(p) = L'_w p' - p'_w L'_xyz` to the points of
//!    `H`; this formula covers all three cases (for `w' < 0` it reverses the
//!    directions, which is the inverted case's frustum).
//! 5. The frustum's `w` row, pulled back to world space, is the optical axis
//!    `j`; the shared affine fit and depth row finish the matrix.
//!
//! The inverted case is classically rendered with a reversed depth test,
//! because PPS depth runs backwards there. lixel rebuilds the depth row from
//! light-space distance (see [`DepthRange`](crate::DepthRange)), which is
//! monotone away from the light in every case, so the ordinary test works.

use glam::{DMat4, DVec3, DVec4};

use crate::error::{LixelError, Result};
use crate::geometry::{min_enclosing_cone_in, ConvexPolyhedron};
use crate::light::LightFrame;
use crate::matrix::{Fallback, LightMatrix, Method};
use crate::problem::ShadowProblem;
use crate::workspace::{light_bits, PsmAxisKey, SolveWorkspace};

/// Options of [`Parameterization::Psm`](crate::Parameterization::Psm).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PsmOptions {
    /// A known lower bound of the view depth of every visible receiver (for
    /// example the minimum of a read-back depth buffer). PSM's near plane is
    /// pushed out to it (never in): the further, the better PSM distributes
    /// texels. `None` keeps the camera's near plane.
    pub min_view_depth: Option<f64>,
}

impl PsmOptions {
    /// The defaults: the camera's near plane.
    pub const DEFAULT: Self = Self { min_view_depth: None };
}

impl Default for PsmOptions {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// Where the light lands in PSM's post-perspective space.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PsmLightCase {
    /// In front of the camera plane: an ordinary point light in PPS.
    Regular,
    /// On the camera plane (`w' ≈ 0`): a directional light in PPS.
    Directional,
    /// Behind the camera plane: the inverted case.
    Inverted,
}

/// The post-perspective transform PSM works in, with the shift it applied.
struct PostPerspective {
    /// World to (shifted, near-adjusted) camera clip space.
    clip_from_world: DMat4,
    /// The light as a homogeneous point in that space.
    light: DVec4,
}

fn post_perspective(problem: &ShadowProblem, options: &PsmOptions, hull: &ConvexPolyhedron) -> PostPerspective {
    let camera = problem.camera();
    let near = options.min_view_depth.filter(|d| d.is_finite()).map_or(camera.z_near(), |d| d.max(camera.z_near()));
    let view = camera.view_from_world();
    // Virtual shift: every vertex of H must be at least `near` in front.
    let delta = hull.vertices().iter().map(|&p| (view * p.extend(1.0)).z + near).fold(0.0_f64, f64::max);
    // An infinite far plane: the hull (clipped by the finite scene) ends first.
    let far = match camera.z_far() {
        f if f.is_finite() => f,
        _ => hull.vertices().iter().map(|&p| camera.view_depth(p)).fold(near, f64::max) * 2.0,
    };
    let far = far.max(near * (1.0 + problem.tolerances().min_relative_span)) + delta;
    let shifted_view = DMat4::from_translation(DVec3::new(0.0, 0.0, -delta)) * view;
    // Keep the camera's x/y rows (asymmetric or jittered frusta included) and
    // replace the depth row by one for [near, far]: z_ndc = (a z + b) / (-z).
    let mut proj = camera.clip_from_view();
    let a = far / (near - far);
    proj.z_axis.z = a;
    proj.w_axis.z = a * near;
    let clip_from_world = proj * shifted_view;
    PostPerspective { clip_from_world, light: clip_from_world * problem.light().homogeneous_position() }
}

/// Which PSM case a configuration falls in (for reports and tests).
#[must_use]
pub fn psm_light_case(problem: &ShadowProblem, options: &PsmOptions) -> PsmLightCase {
    let pps = post_perspective(problem, options, &problem.psm_hull());
    classify(problem, pps.light)
}

fn classify(problem: &ShadowProblem, light: DVec4) -> PsmLightCase {
    let tol = problem.tolerances().psm_directional_w * light.truncate().length();
    if light.w.abs() <= tol {
        PsmLightCase::Directional
    } else if light.w > 0.0 {
        PsmLightCase::Regular
    } else {
        PsmLightCase::Inverted
    }
}

pub(super) fn solve(problem: &ShadowProblem, options: &PsmOptions, ws: &mut SolveWorkspace) -> Result<LightMatrix> {
    problem.with_visible_receiver_body(ws, |focus, ws| solve_for(problem, options, focus, ws))
}

fn solve_for(
    problem: &ShadowProblem,
    options: &PsmOptions,
    focus: &ConvexPolyhedron,
    ws: &mut SolveWorkspace,
) -> Result<LightMatrix> {
    if focus.is_empty() {
        return super::focused::around(problem, focus, Method::Psm, None, ws);
    }
    if problem.camera().is_orthographic() {
        return super::focused::around(problem, focus, Method::Psm, Some(Fallback::OrthographicCamera), ws);
    }
    let frame = problem.frame_towards(focus);
    // First choice: the whole hull H. If H wraps around the light, PSM's own
    // light frustum does not exist; fit PPS around the visible receivers
    // alone, and failing that use the focused map.
    // (Each result is returned as it came, not unwrapped and wrapped again:
    // a matrix is moved once fewer.) The camera cache was prepared by
    // `with_visible_receiver_body`.
    let hull = problem.lend_psm_hull_prepared(ws);
    let key = Some(axis_key(problem, options));
    let first = attempt(problem, options, frame, &hull.body, focus, None, key, ws);
    problem.give_back_psm_hull(hull, ws);
    if first.is_ok() {
        return first;
    }
    let fallback = Some(Fallback::PsmHullAroundLight);
    let second = attempt(problem, options, frame, focus, focus, fallback, None, ws);
    if second.is_ok() {
        return second;
    }
    super::focused::around(problem, focus, Method::Psm, fallback, ws)
}

/// The key of PSM's axis around its hull `H` under the camera cache's key
/// ([`crate::workspace::ViewCache::psm_axis`]): what [`psm_axis`] reads
/// besides the camera, the bounds and the plane tolerance (the cache's key)
/// and `H`, the frame and the mappable vertices (functions of those and the
/// light): the light, the near plane's option, the coarse tolerance (the
/// mappable vertices), the relative span (the far plane) and the least
/// front cosine.
fn axis_key(problem: &ShadowProblem, options: &PsmOptions) -> PsmAxisKey {
    let l = light_bits(problem.light());
    let (has_depth, depth) = options.min_view_depth.map_or((0, 0), |d| (1, d.to_bits()));
    let t = problem.tolerances();
    [
        l[0],
        l[1],
        l[2],
        l[3],
        l[4],
        l[5],
        l[6],
        l[7],
        has_depth,
        depth,
        problem.coarse_eps().to_bits(),
        t.min_relative_span.to_bits(),
        t.min_front_cosine.to_bits(),
    ]
}

/// PSM's map around `region` (with the visible receivers `focus`): its
/// axis, then the placement; an error where either fails (no axis:
/// [`LixelError::NotInFront`]). `region`'s mappable vertices are taken once
/// for both. With `key` (`region` is the hull `H`), the axis is taken from
/// the camera cache when it was found for the same key, and kept there
/// otherwise.
#[allow(clippy::too_many_arguments)]
fn attempt(
    problem: &ShadowProblem,
    options: &PsmOptions,
    frame: LightFrame,
    region: &ConvexPolyhedron,
    focus: &ConvexPolyhedron,
    fallback: Option<Fallback>,
    key: Option<PsmAxisKey>,
    ws: &mut SolveWorkspace,
) -> Result<LightMatrix> {
    let (mut mapped, mut unmapped) = (ws.take_points(), ws.take_points());
    problem.split_vertices_into(region, &mut mapped, &mut unmapped, ws);
    let axis = match key {
        Some(key) => match ws.view.psm_axis(&key) {
            Some(axis) => axis,
            None => {
                let axis = psm_axis(problem, options, region, &mapped, &frame, ws);
                ws.view.store_psm_axis(key, axis);
                axis
            }
        },
        None => psm_axis(problem, options, region, &mapped, &frame, ws),
    };
    let result = match axis {
        Some(axis) => place(problem, frame, axis, &mapped, &unmapped, focus, fallback, ws),
        None => Err(LixelError::NotInFront { method: Method::Psm }),
    };
    ws.put_points(unmapped);
    ws.put_points(mapped);
    result
}

/// Map around a region (with the visible receivers), depth over their
/// casters; `mapped` are the region's mappable vertices, `unmapped` the
/// rest of them (next to the light).
#[allow(clippy::too_many_arguments)]
fn place(
    problem: &ShadowProblem,
    frame: LightFrame,
    axis: DVec3,
    mapped: &[DVec3],
    unmapped: &[DVec3],
    focus: &ConvexPolyhedron,
    fallback: Option<Fallback>,
    ws: &mut SolveWorkspace,
) -> Result<LightMatrix> {
    let mut points = ws.take_points();
    points.extend_from_slice(mapped);
    let mut more = ws.take_points();
    problem.mappable_vertices_into(focus, &mut more, ws);
    points.extend_from_slice(&more);
    // Depth covers the casters of the visible receivers and all of the
    // region (for `H`, which holds casters itself, the light included when
    // it lies in `S`: such a map needs unclipped depth). The depth points
    // add to the mapped ones, which hold the region's mappable vertices
    // already: only the rest of its vertices (`unmapped`) are passed again.
    let result = problem.with_casters(focus, ws, |casters, ws| {
        problem.placement(frame, axis, &points, unmapped, Some(casters), Method::Psm, fallback).build_in(ws)
    });
    ws.put_points(more);
    ws.put_points(points);
    result
}

/// PSM's optical axis for `region` (`mapped`: its mappable vertices), in
/// light coordinates of `frame`; `None` when the directions from the light
/// to `region` do not fit in a cone.
fn psm_axis(
    problem: &ShadowProblem,
    options: &PsmOptions,
    region: &ConvexPolyhedron,
    mapped: &[DVec3],
    frame: &LightFrame,
    ws: &mut SolveWorkspace,
) -> Option<DVec3> {
    if region.is_empty() {
        return None;
    }
    let pps = post_perspective(problem, options, region);
    let l = pps.light;
    let mut dirs = ws.take_points();
    dirs.extend_from_slice(mapped);
    for p in &mut dirs {
        let q = pps.clip_from_world * p.extend(1.0);
        *p = q.truncate() * l.w - l.truncate() * q.w;
    }
    let cone = min_enclosing_cone_in(&dirs, &mut ws.units);
    ws.put_points(dirs);
    let cone = cone?;
    if cone.cos_half_angle <= problem.tolerances().min_front_cosine {
        return None;
    }
    // The light frustum's w row in PPS, `(L'_w a, -a·L'_xyz)`, pulled back.
    let a = cone.axis;
    let row_pps = (a * l.w).extend(-a.dot(l.truncate()));
    let row_world = pps.clip_from_world.transpose() * row_pps;
    let axis = frame.axis_from_world_row(row_world);
    (axis.is_finite() && axis.length_squared() > 0.0).then_some(axis)
}
