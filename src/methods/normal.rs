//! Normal (uniform) shadow maps: the light's frustum around every receiver it
//! reaches, whatever the camera sees.

use crate::error::{LixelError, Result};
use crate::matrix::{LightMatrix, Method};
use crate::problem::ShadowProblem;

/// The normal map: the receivers `R ∩ L`, uniform axis.
pub(super) fn solve(problem: &ShadowProblem) -> Result<LightMatrix> {
    solve_as(problem, Method::Normal, None)
}

/// The normal map reported as `method` (the focused method's fallback).
pub(super) fn solve_as(
    problem: &ShadowProblem,
    method: Method,
    fallback: Option<crate::Fallback>,
) -> Result<LightMatrix> {
    let focus = problem.receiver_body();
    if focus.is_empty() {
        return Err(LixelError::NothingLit { method });
    }
    let frame = problem.frame_towards(&focus);
    let axis = super::uniform_axis(problem, &frame, &focus, method)?;
    problem.place(frame, axis, &focus, method, fallback)
}
