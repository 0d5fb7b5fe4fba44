//! The depth range of a focused map is bounded from the caster body's
//! half-spaces (small linear programs), not from its vertices: it must hold
//! every vertex of the body [`ShadowProblem::caster_body`] builds, and stay
//! within a small tolerance of their range for the linear functions (the
//! projective `w`, a directional light's `d·x` and its light distance).
//! The lower bound of a positional light's distance may be looser (it is a
//! bound, not the minimum); its gap is measured and bounded here.
//!
//! Configurations: the seeded general ones and the hard regions (light inside
//! the scene box, grazing a floor, far and huge, along the view direction,
//! empty caster bodies) of `tests/common`.

mod common;

use glam::DVec3;
use lixel::{light_distance, DepthRange, LightFrame, LightMatrix, Parameterization, ShadowProblem};

/// The solver's relative depth padding (`Tolerances::depth_pad`).
const PAD: f64 = 1e-5;

/// `(min, max)` of `f` over `points`.
fn range(points: &[DVec3], f: impl Fn(DVec3) -> f64) -> (f64, f64) {
    points.iter().map(|&p| f(p)).fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| (lo.min(v), hi.max(v)))
}

#[derive(Default)]
struct Tally {
    checked: usize,
    empty_casters: usize,
    positional: usize,
    /// Linear ranges wider than the vertices' by more than the slack.
    loose: usize,
    /// Largest excess of a linear range over the vertices', relative to
    /// the vertices' span.
    worst_excess: f64,
    /// Largest `(vertex min - bound) / vertex max` of a positional light's
    /// distance.
    worst_distance_gap: f64,
}

impl Tally {
    fn report(&self) -> String {
        format!(
            "{} checked, {} with empty casters, {} positional; {} linear ranges looser than the slack, \
             worst excess {:.3e} of the span; worst distance gap {:.3e} of the largest distance",
            self.checked, self.empty_casters, self.positional, self.loose, self.worst_excess, self.worst_distance_gap
        )
    }

    /// Notes how much wider than the vertices' `(lo, hi)` the range
    /// `(min, max)` is (beyond `slack`; the minimum only if `tight_min`).
    fn excess(&mut self, (lo, hi): (f64, f64), (min, max): (f64, f64), slack: f64, tight_min: bool) {
        let over = (max - hi).max(if tight_min { lo - min } else { 0.0 });
        if over > slack {
            self.loose += 1;
            self.worst_excess = self.worst_excess.max(over / (hi - lo).max(f64::MIN_POSITIVE));
        }
    }
}

/// `Err` unless the range `(min, max)` holds the vertices' `(lo, hi)`.
fn contains(what: &str, (lo, hi): (f64, f64), (min, max): (f64, f64)) -> Result<(), String> {
    if min <= lo && max >= hi {
        Ok(())
    } else {
        Err(format!("{what}: range [{min}, {max}] does not hold the vertices' [{lo}, {hi}]"))
    }
}

/// Checks one focused matrix against the vertices of its focus and caster
/// bodies; `Err` describes a violation.
fn check(problem: &ShadowProblem, matrix: &LightMatrix, tally: &mut Tally) -> Result<(), String> {
    let focus = problem.visible_receiver_body();
    let casters = problem.caster_body(&focus);
    tally.empty_casters += usize::from(casters.is_empty());
    let points: Vec<DVec3> = focus.vertices().iter().chain(casters.vertices()).copied().collect();
    // The padding, and a thousand plane tolerances: the widening (64), the
    // vertices' own rounding.
    let slack = |(lo, hi): (f64, f64)| 2.0 * PAD * lo.abs().max(hi.abs()).max(hi - lo) + 1e3 * problem.eps();
    let w_row = matrix.clip_from_world.row(3);
    match matrix.depth {
        DepthRange::Perspective { near, far } => {
            let w = range(&points, |p| w_row.dot(p.extend(1.0)));
            // Near is clamped (and unclipped depth requested) when the
            // vertices reach the light.
            let near = if matrix.needs_unclipped_depth { near.min(w.0) } else { near };
            contains("w", w, (near, far))?;
            tally.excess(w, (near, far), slack(w), !matrix.needs_unclipped_depth);
        }
        DepthRange::Orthographic { c_min, c_max, .. } => {
            let LightFrame::Orthographic { rotation } = matrix.frame else { unreachable!() };
            let d = rotation.row(2);
            let c = range(&points, |p| d.dot(p));
            contains("d·x", c, (c_min, c_max))?;
            tally.excess(c, (c_min, c_max), slack(c), true);
        }
    }
    let distance = range(&points, |p| light_distance(&matrix.frame, p));
    let bound = (matrix.light_distance.min, matrix.light_distance.max);
    contains("light distance", distance, bound)?;
    match matrix.frame {
        LightFrame::Perspective { .. } => {
            tally.positional += 1;
            tally.excess(distance, bound, slack(distance), false);
            let gap = (distance.0 - bound.0) / distance.1.max(f64::MIN_POSITIVE);
            tally.worst_distance_gap = tally.worst_distance_gap.max(gap);
        }
        LightFrame::Orthographic { .. } => tally.excess(distance, bound, slack(distance), true),
    }
    tally.checked += 1;
    Ok(())
}

fn run(configs: impl Iterator<Item = common::Config>) -> Tally {
    let mut tally = Tally::default();
    for config in configs {
        let Some(problem) = config.problem() else { continue };
        let Ok(matrix) = problem.solve(&Parameterization::Focused) else { continue };
        if matrix.fallback.is_some() {
            continue;
        }
        if let Err(message) = check(&problem, &matrix, &mut tally) {
            panic!("{message}\n{config:?}");
        }
    }
    tally
}

#[test]
fn depth_range_holds_the_caster_vertices_and_stays_close() {
    let tally = run((0..common::cases()).map(|i| common::config(0x15, i)));
    println!("{}", tally.report());
    assert!(tally.checked > common::cases() / 2 && tally.positional > 100, "too few checked");
    assert!(tally.loose * 100 <= tally.checked, "{}", tally.report());
}

#[test]
fn depth_range_holds_the_caster_vertices_in_the_hard_regions() {
    let tally = run((0..common::cases()).map(|i| common::hard_config(0x15, i).0));
    println!("{}", tally.report());
    assert!(tally.checked > common::cases() / 2 && tally.empty_casters > 0, "too few checked");
}
