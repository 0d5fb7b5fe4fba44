//! Whether a fitted matrix holds every relevant sample, four samples at a
//! time: each lane does the same operations in the same order as
//! [`holds_all`] and [`LightMatrix::covers`] (glam's `DMat3 * DVec3` and
//! `DMat4 * DVec4`, column by column), so each answer is theirs, and the
//! compiler packs the lanes into vector instructions (with AVX where the
//! CPU has it: the same operations per lane, so the same answers).

use glam::{DMat3, DMat4, DVec3};

use crate::matrix::holds_all;
use crate::LightMatrix;

/// Points per step.
const LANES: usize = 4;

/// [`holds_all`]: `homography` puts every light-coordinate point in front of
/// the light and inside the map (`|ndc| <= 1 + slack`).
pub(super) fn holds_all_points(homography: &DMat3, xs: &[DVec3], slack: f64) -> bool {
    avx_or_portable!(avx::holds_all_points(homography, xs, slack), holds_all_points_lanes(homography, xs, slack),)
}

/// The body of [`holds_all_points`], for any target features.
#[inline(always)]
fn holds_all_points_lanes(homography: &DMat3, xs: &[DVec3], slack: f64) -> bool {
    if !homography.is_finite() {
        return false;
    }
    let (cx, cy, cz) = (homography.x_axis, homography.y_axis, homography.z_axis);
    let mut lanes = xs.chunks_exact(LANES);
    for chunk in &mut lanes {
        let mut all = true;
        for x in chunk {
            // `DMat3::mul_vec3`: x_axis·x + y_axis·y, then + z_axis·z.
            let c = DVec3::new(
                cx.x * x.x + cy.x * x.y + cz.x * x.z,
                cx.y * x.x + cy.y * x.y + cz.y * x.z,
                cx.z * x.x + cy.z * x.y + cz.z * x.z,
            );
            let limit = (1.0 + slack) * c.z;
            all &= (c.z > 0.0) & (c.x.abs() <= limit) & (c.y.abs() <= limit);
        }
        if !all {
            return false;
        }
    }
    holds_all(homography, lanes.remainder(), slack)
}

/// Every world point `p` has [`LightMatrix::covers`]`(p, slack)`.
pub(super) fn covers_all(matrix: &LightMatrix, points: &[DVec3], slack: f64) -> bool {
    avx_or_portable!(avx::covers_all(matrix, points, slack), covers_all_lanes(matrix, points, slack))
}

/// The body of [`covers_all`], for any target features.
#[inline(always)]
fn covers_all_lanes(matrix: &LightMatrix, points: &[DVec3], slack: f64) -> bool {
    let m: &DMat4 = &matrix.clip_from_world;
    let (cx, cy, cz, cw) = (m.x_axis, m.y_axis, m.z_axis, m.w_axis);
    let bound = 1.0 + slack;
    let mut lanes = points.chunks_exact(LANES);
    for chunk in &mut lanes {
        let mut all = true;
        for p in chunk {
            // `DMat4::mul_vec4` of `(p, 1)` (the last column times 1 is
            // itself), then `project`'s division by `w`.
            let x = cx.x * p.x + cy.x * p.y + cz.x * p.z + cw.x;
            let y = cx.y * p.x + cy.y * p.y + cz.y * p.z + cw.y;
            let w = cx.w * p.x + cy.w * p.y + cz.w * p.z + cw.w;
            all &= (w > 0.0) & ((x / w).abs() <= bound) & ((y / w).abs() <= bound);
        }
        if !all {
            return false;
        }
    }
    lanes.remainder().iter().all(|&p| matrix.covers(p, slack))
}

/// The two tests compiled for AVX (called only where the CPU has it).
#[cfg(target_arch = "x86_64")]
mod avx {
    use glam::{DMat3, DVec3};

    use crate::LightMatrix;

    #[target_feature(enable = "avx")]
    pub(super) fn holds_all_points(homography: &DMat3, xs: &[DVec3], slack: f64) -> bool {
        super::holds_all_points_lanes(homography, xs, slack)
    }

    #[target_feature(enable = "avx")]
    pub(super) fn covers_all(matrix: &LightMatrix, points: &[DVec3], slack: f64) -> bool {
        super::covers_all_lanes(matrix, points, slack)
    }
}

#[cfg(test)]
mod tests {
    use glam::{DVec4, UVec2};

    use super::*;
    use crate::{Aabb, Camera, Light, Parameterization, SceneBounds, ShadowMapSize, ShadowProblem};

    /// Both tests give the scalar answer on every window of random points
    /// spread around the map's edges (about half of them outside), and on
    /// points a rounding away from an edge.
    #[test]
    fn lanes_answer_as_the_scalar_tests() {
        let mut unit = crate::test_rng::unit(0x1234_5678_9ABC_DEF1_u64);
        let mut next = move || unit() * 2.0 - 1.0;
        let h = DMat3::from_cols_array(&[0.9, 0.1, 0.05, -0.2, 1.1, -0.03, 0.01, 0.02, 1.0]);
        let m = DMat4::from_cols(
            DVec4::new(0.9, 0.1, 0.3, 0.05),
            DVec4::new(-0.2, 1.1, 0.1, -0.03),
            DVec4::new(0.01, 0.02, 0.5, 0.2),
            DVec4::new(0.1, -0.1, 0.2, 1.0),
        );
        let slack = 1e-9;
        let mut points: Vec<DVec3> =
            (0..600).map(|_| DVec3::new(next() * 1.4, next() * 1.4, 1.0 + 0.3 * next())).collect();
        // On the edge of `h`'s map: |c.x| = (1 + slack)·c.z, give or take an ulp.
        for k in 0..40 {
            let z = DVec3::new(0.0, 0.0, 1.0 + 0.01 * f64::from(k));
            let c = h * z;
            let edge = (1.0 + slack) * c.z;
            let target = DVec3::new(edge, c.y, c.z);
            let p = h.inverse() * target;
            points.push(p);
            points.push(p + DVec3::X * f64::EPSILON * f64::from(k % 3));
        }
        let camera =
            Camera::look_at(DVec3::new(0.0, 2.0, 5.0), DVec3::ZERO, DVec3::Y, 1.0, UVec2::new(64, 64), 0.1, 50.0)
                .expect("camera");
        let bounds = SceneBounds::uniform(Aabb::from_corners(DVec3::splat(-3.0), DVec3::splat(3.0)));
        let problem = ShadowProblem::new(
            camera,
            Light::directional(DVec3::new(0.3, -1.0, 0.2)),
            bounds,
            ShadowMapSize::square(256),
        )
        .expect("problem");
        let solved = problem.solve(&Parameterization::Normal).expect("normal");
        let matrix = LightMatrix { clip_from_world: m, homography: h, ..solved };
        let (mut inside, mut outside) = (0, 0);
        for start in 0..points.len() {
            for len in 0..=9.min(points.len() - start) {
                let window = &points[start..start + len];
                let scalar = holds_all(&h, window, slack);
                assert_eq!(holds_all_points(&h, window, slack), scalar, "{window:?}");
                let covers = window.iter().all(|&p| matrix.covers(p, slack));
                assert_eq!(covers_all(&matrix, window, slack), covers, "{window:?}");
                if len == 1 {
                    if scalar {
                        inside += 1
                    } else {
                        outside += 1
                    }
                }
            }
        }
        assert!(inside > 100 && outside > 100, "{inside} {outside}");
    }
}
