//! Focused shadow maps: the normal map limited to the receivers the view
//! frustum can see (the papers' "frustum-limiting" step).
//!
//! The papers project `V` onto the light's image plane and intersect it with
//! the projection of the scene; lixel fits the map around `V ∩ R ∩ L`, whose
//! projection lies inside that intersection, so the map is never larger.

use crate::caster_bounds::CasterBounds;
use crate::error::{LixelError, Result};
use crate::geometry::ConvexPolyhedron;
use crate::matrix::{Fallback, LightMatrix, Method};
use crate::problem::ShadowProblem;
use crate::workspace::SolveWorkspace;

pub(super) fn solve(problem: &ShadowProblem, ws: &mut SolveWorkspace) -> Result<LightMatrix> {
    solve_as(problem, Method::Focused, None, ws)
}

/// The focused map reported as `method` with `fallback` (other methods fall
/// back to it).
pub(super) fn solve_as(
    problem: &ShadowProblem,
    method: Method,
    fallback: Option<Fallback>,
    ws: &mut SolveWorkspace,
) -> Result<LightMatrix> {
    problem.with_visible_receiver_body(ws, |focus, ws| around(problem, focus, method, fallback, ws))
}

/// The focused map around `focus`, the visible receiver body: what
/// [`solve_as`] gives, for callers already holding that body.
pub(super) fn around(
    problem: &ShadowProblem,
    focus: &ConvexPolyhedron,
    method: Method,
    fallback: Option<Fallback>,
    ws: &mut SolveWorkspace,
) -> Result<LightMatrix> {
    if focus.is_empty() {
        return super::normal::solve_as(problem, method, Some(Fallback::NothingVisible), ws).map_err(|e| match e {
            LixelError::LightInsideFocus { .. } => LixelError::NothingVisible { method },
            other => other,
        });
    }
    let frame = problem.frame_towards(focus);
    let axis = super::uniform_axis(problem, &frame, focus, method, ws)?;
    problem.place(frame, axis, focus, method, fallback, ws)
}

/// The focused matrix from the visible receiver body and its casters,
/// already computed (the scene optimizer shares them).
pub(crate) fn from_bodies(
    problem: &ShadowProblem,
    focus: &ConvexPolyhedron,
    casters: &CasterBounds,
    ws: &mut SolveWorkspace,
) -> Result<LightMatrix> {
    if focus.is_empty() {
        return solve(problem, ws);
    }
    let frame = problem.frame_towards(focus);
    let axis = super::uniform_axis(problem, &frame, focus, Method::Focused, ws)?;
    problem.place_with_casters(frame, axis, focus, casters, Method::Focused, None, ws)
}
