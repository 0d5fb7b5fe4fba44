//! Searching the optical axis: the paper's rotation heuristic, and argmin's
//! Nelder–Mead as a general-purpose comparison.

use std::cell::RefCell;

use argmin::core::{CostFunction, Error, Executor, State};
use argmin::solver::neldermead::NelderMead;
use glam::{DQuat, DVec3};

use super::objective::{plane_frame_gradient, texel_homography};
use super::{Candidate, GradientSource, OptimizeReport, Optimizer, Samples};

/// Algorithm 1, step 4 of the paper: take the gradient `∇_j h` (see
/// [`GradientSource`]), keep its part orthogonal to `j`, rotate `j` about
/// `j × (−∇)` by each angle, re-fit the affine part of every candidate, keep
/// the best; repeat. Never returns a candidate worse than `start`.
pub(super) fn paper(
    optimizer: &mut Optimizer,
    samples: &Samples,
    start: Candidate,
    report: &mut OptimizeReport,
) -> Candidate {
    let mut best = start;
    let map = samples.problem.map_size();
    let tries = optimizer.options.iterations.saturating_mul(optimizer.options.angles_degrees.len());
    report.angles_tried.reserve_exact(tries.min(1 << 16));
    for _ in 0..optimizer.options.iterations {
        report.iterations += 1;
        let j = best.axis;
        let gradient = match optimizer.options.gradient {
            GradientSource::Refit => refit_gradient(optimizer, samples, &best),
            GradientSource::Analytic => {
                plane_frame_gradient(&texel_homography(&best.homography, map), &samples.boundary).map(|(_, g)| g)
            }
        };
        let Some(gradient) = gradient else { break };
        let downhill = -(gradient - j * gradient.dot(j));
        let Some(rotation_axis) = j.cross(downhill).try_normalize() else { break };
        let mut improved = None::<Candidate>;
        for k in 0..optimizer.options.angles_degrees.len() {
            let degrees = optimizer.options.angles_degrees[k];
            report.angles_tried.push(degrees);
            let turned = DQuat::from_axis_angle(rotation_axis, degrees.to_radians()) * j;
            // Only a candidate below the best so far counts: its sum stops
            // once it is not (the same choice, see `candidate_below`).
            let bound = improved.map_or(best.objective, |c| c.objective);
            if let Some(candidate) = optimizer.candidate_below(samples, turned, bound) {
                improved = Some(candidate);
            }
        }
        match improved {
            Some(candidate) => best = candidate,
            None => break,
        }
    }
    best
}

/// Gradient of the re-fitted objective `j ↦ h(A*(j), j)` on `j⊥`, by central
/// differences of ±[`REFIT_STEP_DEGREES`] about two tangent axes (four
/// affine fits). A side whose candidate loses a relevant sample falls back
/// to a one-sided difference; `None` if both sides of both axes fail.
fn refit_gradient(optimizer: &mut Optimizer, samples: &Samples, at: &Candidate) -> Option<DVec3> {
    let j = at.axis;
    let step = REFIT_STEP_DEGREES.to_radians();
    let (t1, t2) = j.any_orthonormal_pair();
    let mut gradient = DVec3::ZERO;
    let mut any = false;
    for t in [t1, t2] {
        let mut h = |sign: f64| {
            let turned = j * step.cos() + t * (sign * step.sin());
            optimizer.candidate(samples, turned).map(|c| c.objective)
        };
        let slope = match (h(1.0), h(-1.0)) {
            (Some(plus), Some(minus)) => (plus - minus) / (2.0 * step),
            (Some(plus), None) => (plus - at.objective) / step,
            (None, Some(minus)) => (at.objective - minus) / step,
            (None, None) => continue,
        };
        gradient += t * slope;
        any = true;
    }
    any.then_some(gradient)
}

/// Step of the central differences in [`refit_gradient`].
const REFIT_STEP_DEGREES: f64 = 0.25;

/// The cost seen by argmin: the objective of `j(θ) = normalize(j₀ + θ₁e₁ + θ₂e₂)`
/// with the affine part re-fitted, or a large penalty where a relevant
/// sample would fall behind the light.
struct AxisCost<'a> {
    optimizer: RefCell<&'a mut Optimizer>,
    samples: &'a Samples,
    origin: DVec3,
    basis: (DVec3, DVec3),
    best: RefCell<Candidate>,
}

/// Stands in for "infeasible" without infinities (which break the simplex).
const PENALTY: f64 = 1e300;

impl AxisCost<'_> {
    fn axis(&self, theta: &[f64]) -> DVec3 {
        self.origin + self.basis.0 * theta[0] + self.basis.1 * theta[1]
    }
}

impl CostFunction for AxisCost<'_> {
    type Param = Vec<f64>;
    type Output = f64;

    fn cost(&self, theta: &Self::Param) -> Result<f64, Error> {
        let axis = self.axis(theta);
        let candidate = self.optimizer.borrow_mut().candidate(self.samples, axis);
        Ok(match candidate {
            Some(c) => {
                if c.objective < self.best.borrow().objective {
                    *self.best.borrow_mut() = c;
                }
                c.objective
            }
            None => PENALTY,
        })
    }
}

/// Nelder–Mead over two angles of `j` around the start; the best candidate
/// ever evaluated is returned (never worse than `start`).
pub(super) fn nelder_mead(
    optimizer: &mut Optimizer,
    samples: &Samples,
    start: Candidate,
    max_iterations: u64,
    report: &mut OptimizeReport,
) -> Candidate {
    let origin = start.axis.normalize();
    let cost = AxisCost {
        optimizer: RefCell::new(optimizer),
        samples,
        origin,
        basis: origin.any_orthonormal_pair(),
        best: RefCell::new(start),
    };
    // A simplex of about 6 degrees around the start.
    let step = 0.1;
    let simplex = vec![vec![0.0, 0.0], vec![step, 0.0], vec![0.0, step]];
    let solver = match NelderMead::new(simplex).with_sd_tolerance(1e-9) {
        Ok(solver) => solver,
        Err(_) => return start,
    };
    let result = Executor::new(cost, solver).configure(|state| state.max_iters(max_iterations)).run();
    match result {
        Ok(result) => {
            report.iterations += usize::try_from(result.state().get_iter()).unwrap_or(usize::MAX);
            let problem = result.problem.problem.as_ref();
            problem.map_or(start, |cost| *cost.best.borrow())
        }
        Err(_) => start,
    }
}
