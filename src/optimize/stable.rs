//! Temporal stability of scene-optimized matrices (issue 19).
//!
//! The optimizer re-fits a light's matrix every few frames. Even when it
//! keeps the optical axis `j`, the affine part is the minimum-area rectangle
//! around the current samples, whose rotation, size and origin follow the
//! camera continuously: every update resamples the casters at new texel
//! positions and shadow edges crawl ("shimmer"), as they do for a plain
//! focused map; and the samples come from an analysis pass rendered with
//! that very matrix, so on a still camera a re-fit can chase its own
//! samples for ever. When a new `j` is accepted, the whole map jumps. Four
//! options of [`OptimizeOptions`](super::OptimizeOptions) act on this, each
//! off in [`OptimizeOptions::paper`](super::OptimizeOptions::paper):
//!
//! - **hold** (on by default): while `j` is kept, the previous matrix is
//!   kept as it is, as long as it holds every sample and its re-fit would
//!   not replace it under the hysteresis;
//! - **hysteresis** ([`AcceptMeasure`] with `accept_ratio`): which figure a
//!   new matrix must beat the previous one by (the paper: the median
//!   badness, by 20 %);
//! - **texel snapping** ([`TexelSnap`]): the map's image-plane directions are
//!   kept from the matrix they came from while `j` is kept, its texel size is
//!   rounded up to a geometric ladder and its origin snapped to whole
//!   texels, as engines stabilize uniform maps (`focused-snapped`), so a
//!   moving camera slides the samples over a grid that stays put;
//! - **bounded rotation** (`max_turn_degrees`): an accepted `j` turns at most
//!   this far from the previous one per update, so the map glides to a new
//!   axis instead of jumping.
//!
//! `lixel experiment --stability` measures each (README, "Temporal
//! stability"); the defaults are chosen from it.

use glam::{DMat3, DQuat, DVec3};

use super::Samples;
use crate::methods::{snapped_homography, SnapGrid};

/// What the hysteresis compares: a new matrix replaces the previous one
/// only if this figure of the new one is below `accept_ratio` times the
/// previous one's (both fitted to the current samples).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[non_exhaustive]
pub enum AcceptMeasure {
    /// The median badness of the boundary samples (the paper).
    #[default]
    Median,
    /// The objective `h`, the summed badness the search minimizes.
    Objective,
}

/// Texel snapping of the optimized map's affine part
/// (see the `optimize::stable` module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub struct TexelSnap {
    /// Rungs of the texel-size ladder per doubling (values below 1 count as
    /// 1): more rungs waste less resolution but change the texel size, and
    /// so resample the map, more often.
    pub steps_per_octave: u32,
}

impl TexelSnap {
    /// Eight rungs per doubling (at most 9 % of each side wasted), as
    /// `focused-snapped`.
    pub const DEFAULT: Self = Self { steps_per_octave: 8 };

    /// Snapping with `steps_per_octave` rungs per doubling.
    #[must_use]
    pub fn with_steps_per_octave(steps_per_octave: u32) -> Self {
        Self { steps_per_octave }
    }
}

impl Default for TexelSnap {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// The homography of `m` (rows `x`, `y`, unit axis) in the light
/// coordinates of `frame`; `None` if it is not finite or has no axis.
pub(super) fn homography_in(frame: &crate::LightFrame, m: &crate::LightMatrix) -> Option<DMat3> {
    let row = |r: usize| frame.axis_from_world_row(m.clip_from_world.row(r));
    let (x, y, w) = (row(0), row(1), row(3));
    let scale = w.length();
    let h = DMat3::from_cols(x / scale, y / scale, w / scale).transpose();
    (scale > 0.0 && h.is_finite()).then_some(h)
}

/// `from` turned towards `to` by at most `max_radians` (both unit or not;
/// the result is unit); `to` itself when the angle is within the bound, the
/// bound is not positive and finite, or the two are (anti-)parallel.
pub(super) fn turn_towards(from: DVec3, to: DVec3, max_radians: f64) -> DVec3 {
    let (a, b) = (from.normalize(), to.normalize());
    let angle = a.angle_between(b);
    if !(max_radians > 0.0 && max_radians.is_finite() && angle > max_radians) {
        return b;
    }
    match a.cross(b).try_normalize() {
        Some(axis) => DQuat::from_axis_angle(axis, max_radians) * a,
        None => b,
    }
}

/// The snapped homography for axis `j` with the image-plane directions of
/// `reference` (a homography whose rows are `x`, `y` and an axis, in the
/// light coordinates of `samples`), holding the points `xs`; `None` when snapping
/// is impossible (a reference row along `j`, a point not in front).
pub(super) fn snap(
    samples: &Samples,
    reference: &DMat3,
    axis: DVec3,
    xs: &[DVec3],
    options: TexelSnap,
    margin: f64,
) -> Option<DMat3> {
    let j = axis.try_normalize()?;
    let in_plane = |g: DVec3| (g - j * g.dot(j)).try_normalize();
    let basis = (in_plane(reference.row(0))?, in_plane(reference.row(1))?);
    // Nearly parallel directions would make a sliver of a map.
    if basis.0.cross(basis.1).length() < 1e-6 {
        return None;
    }
    let map = samples.problem.map_size();
    let grid = SnapGrid { axis: j, basis, map, steps_per_octave: options.steps_per_octave, margin };
    snapped_homography(&samples.frame, samples.problem.tolerances(), &grid, xs)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn turning_is_bounded_and_reaches_close_targets() {
        let from = DVec3::Z;
        let to = DVec3::new(1.0, 0.0, 1.0); // 45 degrees away
        let turned = turn_towards(from, to, 10f64.to_radians());
        assert!((turned.angle_between(from).to_degrees() - 10.0).abs() < 1e-9);
        // In the plane of the two, towards the target.
        assert!(turned.y.abs() < 1e-12 && turned.x > 0.0);
        assert!(turn_towards(from, to, 50f64.to_radians()).abs_diff_eq(to.normalize(), 1e-12));
        assert!(turn_towards(from, to, f64::NAN).abs_diff_eq(to.normalize(), 1e-12));
        assert!(turn_towards(from, to, 0.0).abs_diff_eq(to.normalize(), 1e-12));
    }
}
