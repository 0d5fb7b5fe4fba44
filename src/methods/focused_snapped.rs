//! Focused maps stabilized the way engines ship them (Bevy, Unity's "stable
//! fit", three.js): the map's axes are fixed in world space and its texel
//! grid is snapped, so that a moving camera slides the map over a grid that
//! does not move, and shadow edges do not crawl ("shimmer").
//!
//! The plain focused map fits a minimal rectangle around the visible
//! receivers: its rotation, size and origin follow the camera continuously,
//! so every frame resamples the casters at new texel positions. Here
//!
//! - the light frame and optical axis are those of the *normal* map (all
//!   receivers the light reaches), which depend on the light and the scene
//!   only, and the image-plane axes are a fixed basis perpendicular to that
//!   axis (for a directional light: the light frame's x and y);
//! - the texel size along each image-plane axis is the focused box's size
//!   rounded *up* to a geometric ladder (`steps_per_octave` rungs per
//!   doubling), so it changes only when the visible region crosses a rung;
//! - the map's origin is snapped down to a whole number of texels, and one
//!   texel of slack makes the snapped map still hold the whole box.
//!
//! Under a camera translation that keeps the visible box's size on the same
//! rung, texel `k` of one frame is texel `k + n` of the next for an integer
//! `n` (the grid is invariant); see the tests. The price is resolution: the
//! axis-aligned box is larger than the minimal rotated one, and the ladder
//! wastes up to `2^(1/steps) - 1` of each side.

use glam::{DMat3, DVec2, DVec3};

use crate::error::{LixelError, Result};
use crate::geometry::ConvexPolyhedron;
use crate::light::LightFrame;
use crate::matrix::{Fallback, LightMatrix, Method};
use crate::problem::ShadowProblem;
use crate::scene::ShadowMapSize;
use crate::tolerance::Tolerances;
use crate::workspace::SolveWorkspace;

/// Options of [`Parameterization::FocusedSnapped`](super::Parameterization::FocusedSnapped).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub struct FocusedSnappedOptions {
    /// Rungs of the texel-size ladder per doubling; more rungs waste less
    /// resolution but change the texel size (and resample the map) more
    /// often. Values below 1 count as 1.
    pub steps_per_octave: u32,
}

impl FocusedSnappedOptions {
    /// Eight rungs per doubling: at most 9 % of each side wasted.
    pub const DEFAULT: Self = Self { steps_per_octave: 8 };

    /// Options with `steps_per_octave` rungs per doubling.
    #[must_use]
    pub fn with_steps_per_octave(steps_per_octave: u32) -> Self {
        Self { steps_per_octave }
    }
}

impl Default for FocusedSnappedOptions {
    fn default() -> Self {
        Self::DEFAULT
    }
}

pub(super) fn solve(
    problem: &ShadowProblem,
    options: &FocusedSnappedOptions,
    ws: &mut SolveWorkspace,
) -> Result<LightMatrix> {
    problem.with_visible_receiver_body(ws, |focus, ws| solve_for(problem, options, focus, ws))
}

fn solve_for(
    problem: &ShadowProblem,
    options: &FocusedSnappedOptions,
    focus: &ConvexPolyhedron,
    ws: &mut SolveWorkspace,
) -> Result<LightMatrix> {
    let method = Method::FocusedSnapped;
    if focus.is_empty() {
        return super::normal::solve_as(problem, method, Some(Fallback::NothingVisible), ws).map_err(|e| match e {
            LixelError::LightInsideFocus { .. } => LixelError::NothingVisible { method },
            other => other,
        });
    }
    // The normal map's frame and axis: independent of the camera.
    let mut receivers = ws.take_body();
    problem.receiver_body_into(&mut receivers, ws);
    let frame = problem.frame_towards(&receivers);
    let axis = super::uniform_axis(problem, &frame, &receivers, method, ws);
    ws.put_body(receivers);
    let axis = axis?.normalize();
    let basis = image_basis(&frame, axis);
    // A spot light's apex (a vertex of the body when the light is inside
    // the bounds) has no direction: left to the other vertices.
    let mut points = ws.take_points();
    problem.mappable_vertices_into(focus, &mut points, ws);
    let mut xs = ws.take_points();
    xs.extend(points.iter().map(|&p| frame.homogeneous(p)));
    let grid =
        SnapGrid { axis, basis, map: problem.map_size(), steps_per_octave: options.steps_per_octave, margin: 0.0 };
    // Depth covers the casters and all of the focus, a vertex at the light
    // included (as for the other uniform maps).
    let result = snapped_homography(&frame, problem.tolerances(), &grid, &xs)
        .ok_or(LixelError::NotInFront { method })
        .and_then(|homography| {
            problem.with_casters(focus, ws, |casters, _| {
                problem
                    .placement(frame, axis, &points, focus.vertices(), Some(casters), method, None)
                    .finish_checked(homography, &xs)
            })
        });
    ws.put_points(xs);
    ws.put_points(points);
    result
}

/// Image-plane axes perpendicular to the unit `axis`, a function of the
/// axis alone (for the orthographic axis `z`: the frame's `x` and `y`).
fn image_basis(frame: &LightFrame, axis: DVec3) -> (DVec3, DVec3) {
    match frame {
        LightFrame::Orthographic { .. } => (DVec3::X, DVec3::Y),
        LightFrame::Perspective { .. } => {
            let (a, b) = axis.any_orthonormal_pair();
            // Right-handed (a, b, axis), so the map is not mirrored.
            if a.cross(b).dot(axis) > 0.0 {
                (a, b)
            } else {
                (b, a)
            }
        }
    }
}

/// A texel grid fixed by an optical axis and two image-plane directions:
/// what [`snapped_homography`] snaps to.
pub(crate) struct SnapGrid {
    /// The optical axis (unit).
    pub axis: DVec3,
    /// Image-plane directions (perpendicular to `axis`, not necessarily to
    /// each other): the map's `x` and `y` are `e·X / axis·X`, scaled and
    /// shifted.
    pub basis: (DVec3, DVec3),
    /// Texels along `x` and `y`.
    pub map: ShadowMapSize,
    /// Rungs of the texel-size ladder per doubling (at least 1).
    pub steps_per_octave: u32,
    /// Extra room on each side, as a fraction of the points' extent.
    pub margin: f64,
}

/// The homography (rows: x, y, unit axis) whose map holds every point of
/// `xs` (light coordinates of `frame`) on the snapped texel grid of `grid`:
/// texel size on the ladder, origin on a whole texel, one texel of slack.
/// `None` when a point is not safely in front of the light along the axis
/// (relative to the map's own field of view, as for every fit).
pub(crate) fn snapped_homography(
    frame: &LightFrame,
    tolerances: &Tolerances,
    grid: &SnapGrid,
    xs: &[DVec3],
) -> Option<DMat3> {
    let axis = grid.axis;
    let (e1, e2) = grid.basis;
    if xs.is_empty() || !crate::matrix::in_front(frame, tolerances, axis, xs) {
        return None;
    }
    let mut lo = DVec2::splat(f64::INFINITY);
    let mut hi = DVec2::splat(f64::NEG_INFINITY);
    for x in xs {
        let uv = DVec2::new(e1.dot(*x), e2.dot(*x)) / axis.dot(*x);
        lo = lo.min(uv);
        hi = hi.max(uv);
    }
    let pad = (hi - lo) * grid.margin.max(0.0);
    let (lo, hi) = (lo - pad, hi + pad);
    // A floor on the extent keeps a degenerate (point or segment) focus
    // from giving a zero texel.
    let floor = 1e-9 * hi.abs().max(lo.abs()).max_element().max(1e-9);
    let map = grid.map;
    let x = snap_interval(lo.x, hi.x, map.width, grid.steps_per_octave, floor);
    let y = snap_interval(lo.y, hi.y, map.height, grid.steps_per_octave, floor);
    // NDC = 2 (u - origin) / (texels · texel) - 1 along each axis.
    let row = |e: DVec3, (origin, texel): (f64, f64), texels: u32| {
        let s = 2.0 / (f64::from(texels) * texel);
        e * s + axis * (-origin * s - 1.0)
    };
    let h = DMat3::from_cols(row(e1, x, map.width), row(e2, y, map.height), axis).transpose();
    h.is_finite().then_some(h)
}

/// `(origin, texel)` of a grid of `texels` texels holding `[lo, hi]`: the
/// texel size is `(hi - lo) / (texels - 1)` rounded up to the ladder
/// `2^(k / steps)`, the origin the largest multiple of it not above `lo`
/// (one texel of slack). A one-texel axis has no room for slack: it holds
/// `[lo, hi]` exactly, unsnapped.
pub(crate) fn snap_interval(lo: f64, hi: f64, texels: u32, steps: u32, floor: f64) -> (f64, f64) {
    if texels < 2 {
        return (lo, (hi - lo).max(floor));
    }
    let steps = f64::from(steps.max(1));
    let raw = ((hi - lo) / f64::from(texels - 1)).max(floor);
    let mut texel = (raw.log2() * steps).ceil() / steps;
    texel = texel.exp2();
    // exp2 of the rounded exponent may land a hair below `raw`.
    if texel < raw {
        texel = raw;
    }
    let origin = (lo / texel).floor() * texel;
    (origin, texel)
}

/// Every world point of `body` lies in the map of `m` (NDC within `[-1, 1]`
/// up to `tol`).
#[cfg(test)]
fn holds(m: &LightMatrix, body: &crate::geometry::ConvexPolyhedron, tol: f64) -> bool {
    body.vertices().iter().all(|&p| {
        let c = m.clip_from_world * p.extend(1.0);
        c.w > 0.0 && (c.x / c.w).abs() <= 1.0 + tol && (c.y / c.w).abs() <= 1.0 + tol
    })
}

#[cfg(test)]
mod tests {
    use glam::{DVec3, UVec2};

    use super::*;
    use crate::{Aabb, Camera, Light, Parameterization, SceneBounds, ShadowMapSize};

    const MAP: u32 = 256;

    fn problem(eye: DVec3, target: DVec3, light: Light) -> ShadowProblem {
        // A large floor with a few casters: a small camera translation keeps
        // the visible floor the same shape.
        let floor = Aabb::from_corners(DVec3::new(-500.0, -0.1, -500.0), DVec3::new(500.0, 0.0, 500.0));
        let casters = Aabb::from_corners(DVec3::new(-400.0, 0.0, -400.0), DVec3::new(400.0, 5.0, 400.0));
        let camera = Camera::look_at(eye, target, DVec3::Y, 0.9, UVec2::new(320, 240), 0.5, 40.0).unwrap();
        ShadowProblem::new(camera, light, SceneBounds { casters, receivers: floor }, ShadowMapSize::square(MAP))
            .unwrap()
    }

    /// Texel coordinates (x, y) of a world point in the map of `m`.
    fn texel(m: &LightMatrix, p: DVec3) -> DVec2 {
        let c = m.clip_from_world * p.extend(1.0);
        let ndc = DVec2::new(c.x / c.w, c.y / c.w);
        DVec2::new((ndc.x * 0.5 + 0.5) * f64::from(MAP), (0.5 - ndc.y * 0.5) * f64::from(MAP))
    }

    fn sun() -> Light {
        Light::directional(DVec3::new(0.3, -1.0, 0.45))
    }

    #[test]
    fn texel_grid_is_invariant_under_camera_translation() {
        let a = problem(DVec3::new(0.0, 6.0, 0.0), DVec3::new(0.0, 0.0, -20.0), sun());
        let probes: Vec<DVec3> = (0..9)
            .map(|i| DVec3::new(-7.3 + 1.7 * f64::from(i), 0.4 * f64::from(i % 3), -9.1 - 0.9 * f64::from(i)))
            .collect();
        let snapped = Parameterization::FocusedSnapped(FocusedSnappedOptions::DEFAULT);
        let base = a.solve(&snapped).unwrap();
        let mut same_rung = 0;
        for step in 1..12 {
            // Arbitrary, non-texel-aligned translations.
            let d = DVec3::new(0.137 * f64::from(step), 0.0, -0.291 * f64::from(step));
            let b = problem(DVec3::new(0.0, 6.0, 0.0) + d, DVec3::new(0.0, 0.0, -20.0) + d, sun());
            let moved = b.solve(&snapped).unwrap();
            assert!(holds(&moved, &b.visible_receiver_body(), 1e-9));
            let scale = |m: &LightMatrix| texel(m, DVec3::X) - texel(m, DVec3::ZERO);
            if (scale(&moved) - scale(&base)).length() > 1e-9 {
                continue; // the visible box crossed a rung: a new grid
            }
            same_rung += 1;
            let offsets: Vec<DVec2> = probes.iter().map(|&p| texel(&moved, p) - texel(&base, p)).collect();
            for o in &offsets {
                assert!((*o - o.round()).length() < 1e-6, "offset {o} is not whole texels");
                assert!((*o - offsets[0]).length() < 1e-6, "the grid is warped, not shifted");
            }
            // The unsnapped focused map's grid does move by fractions.
            let f0 = a.solve(&Parameterization::Focused).unwrap();
            let f1 = b.solve(&Parameterization::Focused).unwrap();
            let fractional = probes.iter().any(|&p| {
                let o = texel(&f1, p) - texel(&f0, p);
                (o - o.round()).length() > 1e-3
            });
            assert!(fractional, "the focused map is expected to shimmer here");
        }
        assert!(same_rung >= 6, "too few translations kept the texel size ({same_rung})");
    }

    #[test]
    fn holds_the_visible_receivers_for_point_lights_too() {
        let light = Light::point(DVec3::new(30.0, 60.0, 10.0));
        for step in 0..5 {
            let d = DVec3::new(0.31 * f64::from(step), 0.0, -0.17 * f64::from(step));
            let p = problem(DVec3::new(0.0, 6.0, 0.0) + d, DVec3::new(3.0, 0.0, -20.0) + d, light);
            let m = p.solve(&Parameterization::FocusedSnapped(FocusedSnappedOptions::DEFAULT)).unwrap();
            assert_eq!(m.method, Method::FocusedSnapped);
            assert!(holds(&m, &p.visible_receiver_body(), 1e-9));
        }
    }

    #[test]
    fn ladder_rounds_up_and_snaps_down() {
        for (lo, hi) in [(-3.7, 12.2), (0.0, 1e-12), (1e6, 1e6 + 3.0), (-5.0, -4.9)] {
            let (origin, texel) = snap_interval(lo, hi, 100, 8, 1e-15);
            assert!(origin <= lo && origin + 100.0 * texel >= hi, "[{lo}, {hi}] -> {origin} + 100 x {texel}");
            let rung = texel.log2() * 8.0;
            assert!((rung - rung.round()).abs() < 1e-9 || texel == (hi - lo) / 99.0);
            assert!(((origin / texel) - (origin / texel).round()).abs() < 1e-6);
        }
        // One texel: no slack, the interval exactly.
        assert_eq!(snap_interval(-1.0, 3.0, 1, 8, 1e-15), (-1.0, 4.0));
    }
}
