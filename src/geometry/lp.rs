//! Small linear programs: the largest `c·x` over a box cut by half-spaces.
//!
//! Seidel's incremental algorithm with the planes in their given order (the
//! result is deterministic): the optimum over the box is a corner; each plane
//! the current optimum violates moves the optimum onto that plane, found by
//! the same algorithm one dimension down (the box and the earlier planes
//! restricted to it), which in turn solves a one-dimensional problem on a
//! line. A few hundred operations for the ~20 half-spaces of a caster body,
//! against tens of thousands for clipping the body itself; only the optimum's
//! value is used, so ties between optimal points do not matter.
//!
//! Every comparison allows `tol` (a distance): a constraint violated by at
//! most `tol` is kept satisfied, so the returned value is never below the
//! true optimum by more than rounding, and may exceed it by about `tol`
//! times the objective's length (a *larger* maximum: callers that bound a
//! range with it only widen the range).

use glam::{DVec2, DVec3};

use super::Plane;

/// A direction below this length (a plane parallel to another, a line
/// parallel to a constraint) counts as zero.
const PARALLEL: f64 = 1e-12;

/// Restricted constraints kept on the stack (the box's six and up to 42
/// planes); more are recomputed where needed.
const MAX_RESTRICTED: usize = 48;

/// The stack array's length for the box and up to ten planes (most calls).
const FEW_RESTRICTED: usize = 16;

/// A point of the box `[min, max]` inside every plane's half-space, all of
/// them grown by `grow` (`signed_distance <= grow`, the box as much larger),
/// that maximizes `c·x`, within `tol`; `None` when that region is empty (by
/// more than `tol`).
///
/// `min <= max` and finite planes are the caller's to ensure.
pub(crate) fn maximize_in_box(
    min: DVec3,
    max: DVec3,
    planes: &[Plane],
    grow: f64,
    c: DVec3,
    tol: f64,
) -> Option<DVec3> {
    let region = Region { min: min - DVec3::splat(grow), max: max + DVec3::splat(grow), planes, grow };
    let mut x = DVec3::select(c.cmpge(DVec3::ZERO), max, min);
    for (i, plane) in planes.iter().enumerate() {
        if plane.signed_distance(x) > grow + tol {
            x = region.maximize_on_plane(i, c, tol)?;
        }
    }
    Some(x)
}

/// The box and its planes as constraints `a·x <= b`: the box's six faces
/// first, then the planes.
struct Region<'a> {
    min: DVec3,
    max: DVec3,
    planes: &'a [Plane],
    /// How far every plane is moved out.
    grow: f64,
}

impl Region<'_> {
    /// Constraint `k`: `x_k <= max_k` for `k < 3`, `-x_{k-3} <= -min_{k-3}`
    /// for `k < 6`, then plane `k - 6`.
    fn constraint(&self, k: usize) -> (DVec3, f64) {
        match k {
            0..3 => (DVec3::AXES[k], self.max[k]),
            3..6 => (-DVec3::AXES[k - 3], -self.min[k - 3]),
            _ => {
                let plane = self.planes[k - 6];
                (plane.normal, self.grow - plane.offset)
            }
        }
    }

    /// The optimum on plane `i`, subject to the box and the planes before
    /// `i`.
    fn maximize_on_plane(&self, i: usize, c: DVec3, tol: f64) -> Option<DVec3> {
        let plane = self.planes[i];
        let (e1, e2) = plane.normal.any_orthonormal_pair();
        let center = 0.5 * (self.min + self.max);
        let origin = center - plane.normal * (plane.signed_distance(center) - self.grow);
        // Every box point on the plane lies within the box's half-diagonal
        // of `origin` (the centre's projection): a square of that half-side
        // holds them all and bounds the problem.
        let half = 0.5 * (self.max - self.min).length() + tol;
        // Each with its normal's length, taken once here rather than once
        // per line it bounds.
        let restricted = |k: usize| {
            let (a, b) = self.constraint(k);
            let normal = DVec2::new(a.dot(e1), a.dot(e2));
            (normal, b - a.dot(origin), normal.length())
        };
        let goal = DVec2::new(c.dot(e1), c.dot(e2));
        let count = 6 + i;
        let y = if count <= FEW_RESTRICTED {
            maximize_in_square_kept::<FEW_RESTRICTED>(count, restricted, half, goal, tol)
        } else if count <= MAX_RESTRICTED {
            maximize_in_square_kept::<MAX_RESTRICTED>(count, restricted, half, goal, tol)
        } else {
            maximize_in_square(count, restricted, half, goal, tol)
        };
        y.map(|y| origin + e1 * y.x + e2 * y.y)
    }
}

/// [`maximize_in_square`] with the `count <= N` constraints computed once
/// into an array on the stack (of `N`: a smaller one is less to clear).
fn maximize_in_square_kept<const N: usize>(
    count: usize,
    constraint: impl Fn(usize) -> (DVec2, f64, f64),
    half: f64,
    goal: DVec2,
    tol: f64,
) -> Option<DVec2> {
    let mut kept = [(DVec2::ZERO, 0.0, 0.0); N];
    for (k, slot) in kept[..count].iter_mut().enumerate() {
        *slot = constraint(k);
    }
    maximize_in_square(count, |k| kept[k], half, goal, tol)
}

/// The largest `goal·y` over the square `|y| <= half` and the half-planes
/// `constraint(k) = (a, b, |a|)` (`a·y <= b`) for `k < count`.
fn maximize_in_square(
    count: usize,
    constraint: impl Fn(usize) -> (DVec2, f64, f64),
    half: f64,
    goal: DVec2,
    tol: f64,
) -> Option<DVec2> {
    let mut y = DVec2::select(goal.cmpge(DVec2::ZERO), DVec2::splat(half), DVec2::splat(-half));
    for k in 0..count {
        let (a, b, length) = constraint(k);
        if a.dot(y) > b + tol {
            y = maximize_on_line(a, b, length, (0..k).map(&constraint), half, goal, tol)?;
        }
    }
    Some(y)
}

/// The optimum of `goal·y` on the line `a·y = b` (`length = |a|`) inside
/// the square `|y| <= half` and the half-planes `earlier` (`(g, h, |g|)`:
/// `g·y <= h` each).
fn maximize_on_line(
    a: DVec2,
    b: f64,
    length: f64,
    earlier: impl Iterator<Item = (DVec2, f64, f64)>,
    half: f64,
    goal: DVec2,
    tol: f64,
) -> Option<DVec2> {
    if !(length > PARALLEL) {
        // Parallel to the plane and violated by more than `tol`.
        return None;
    }
    let along = a.perp() / length;
    let foot = a * (b / (length * length));
    let square = [(DVec2::X, half, 1.0), (DVec2::NEG_X, half, 1.0), (DVec2::Y, half, 1.0), (DVec2::NEG_Y, half, 1.0)];
    let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::INFINITY);
    for (g, h, g_length) in square.into_iter().chain(earlier) {
        let slope = g.dot(along);
        let room = h - g.dot(foot);
        if slope.abs() <= PARALLEL * g_length {
            if room < -tol {
                return None;
            }
        } else if slope > 0.0 {
            hi = hi.min(room / slope);
        } else {
            lo = lo.max(room / slope);
        }
    }
    let t = if lo <= hi {
        if goal.dot(along) >= 0.0 {
            hi
        } else {
            lo
        }
    } else if lo - hi <= tol {
        0.5 * (lo + hi)
    } else {
        return None;
    };
    Some(foot + along * t)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The largest `c·v` over a list of vertices.
    fn best(vertices: &[DVec3], c: DVec3) -> f64 {
        vertices.iter().map(|v| c.dot(*v)).fold(f64::NEG_INFINITY, f64::max)
    }

    #[test]
    fn the_box_alone_gives_its_corner() {
        let x = maximize_in_box(DVec3::ZERO, DVec3::ONE, &[], 0.0, DVec3::new(1.0, -2.0, 0.5), 0.0).unwrap();
        assert_eq!(x, DVec3::new(1.0, 0.0, 1.0));
    }

    #[test]
    fn a_cut_corner_moves_the_optimum_onto_the_plane() {
        // x + y + z <= 1 cuts the unit box to a tetrahedron; the largest
        // x + 2y + 3z is 3 at (0, 0, 1).
        let plane = Plane::from_point_normal(DVec3::new(1.0, 0.0, 0.0), DVec3::ONE);
        let c = DVec3::new(1.0, 2.0, 3.0);
        let x = maximize_in_box(DVec3::ZERO, DVec3::ONE, &[plane], 0.0, c, 1e-12).unwrap();
        assert!((c.dot(x) - 3.0).abs() < 1e-12, "{x}");
    }

    #[test]
    fn disjoint_half_spaces_are_empty() {
        let planes = [
            Plane::from_point_normal(DVec3::splat(0.2), DVec3::X),
            Plane::from_point_normal(DVec3::splat(0.6), DVec3::NEG_X),
        ];
        assert!(maximize_in_box(DVec3::ZERO, DVec3::ONE, &planes, 0.0, DVec3::Y, 1e-9).is_none());
        assert!(maximize_in_box(DVec3::ZERO, DVec3::ONE, &planes[..1], 0.0, DVec3::Y, 1e-9).is_some());
    }

    #[test]
    fn matches_the_clipped_box_on_random_cuts() {
        use crate::geometry::ConvexPolyhedron;
        use rand::{Rng, SeedableRng};
        let mut rng = rand::rngs::StdRng::seed_from_u64(15);
        let unit = |rng: &mut rand::rngs::StdRng| {
            DVec3::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0))
        };
        let (min, max) = (DVec3::new(-1.0, -2.0, -0.5), DVec3::new(2.0, 1.0, 0.5));
        let (mut empty, mut full) = (0, 0);
        for _ in 0..2000 {
            let count = rng.random_range(1..24);
            let planes: Vec<Plane> = (0..count)
                .map(|_| Plane::from_point_normal(unit(&mut rng) * 0.8, unit(&mut rng)))
                .filter(Plane::is_finite)
                .collect();
            let body = ConvexPolyhedron::from_aabb(min, max).clip_all(&planes, 1e-12);
            for _ in 0..4 {
                let c = unit(&mut rng);
                match maximize_in_box(min, max, &planes, 0.0, c, 1e-12) {
                    Some(x) => {
                        full += 1;
                        let want = best(body.vertices(), c);
                        assert!(body.is_empty() || (c.dot(x) - want).abs() < 1e-9, "{} vs {want}", c.dot(x));
                        assert!(planes.iter().all(|p| p.signed_distance(x) < 1e-9));
                    }
                    None => {
                        empty += 1;
                        assert!(body.is_empty() || body.volume() < 1e-9, "{}", body.volume());
                    }
                }
            }
        }
        assert!(empty > 100 && full > 100, "{empty} empty, {full} not");
    }
}
