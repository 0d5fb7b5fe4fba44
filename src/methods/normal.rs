//! Normal (uniform) shadow maps: the light's frustum around every receiver it
//! reaches, whatever the camera sees.

use crate::error::{LixelError, Result};
use crate::geometry::ConvexPolyhedron;
use crate::matrix::{LightMatrix, Method};
use crate::problem::ShadowProblem;
use crate::workspace::SolveWorkspace;

/// The normal map: the receivers `R ∩ L`, uniform axis.
pub(super) fn solve(problem: &ShadowProblem, ws: &mut SolveWorkspace) -> Result<LightMatrix> {
    solve_as(problem, Method::Normal, None, ws)
}

/// The normal map reported as `method` (the focused method's fallback).
pub(super) fn solve_as(
    problem: &ShadowProblem,
    method: Method,
    fallback: Option<crate::Fallback>,
    ws: &mut SolveWorkspace,
) -> Result<LightMatrix> {
    let mut focus = ws.take_body();
    problem.receiver_body_into(&mut focus, ws);
    let result = around(problem, &focus, method, fallback, ws);
    ws.put_body(focus);
    result
}

fn around(
    problem: &ShadowProblem,
    focus: &ConvexPolyhedron,
    method: Method,
    fallback: Option<crate::Fallback>,
    ws: &mut SolveWorkspace,
) -> Result<LightMatrix> {
    if focus.is_empty() {
        return Err(LixelError::NothingLit { method });
    }
    let frame = problem.frame_towards(focus);
    let axis = super::uniform_axis(problem, &frame, focus, method, ws)?;
    problem.place(frame, axis, focus, method, fallback, ws)
}
