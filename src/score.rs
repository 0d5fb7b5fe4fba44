//! Scoring any light matrix: the badness `b` of math.md §3.
//!
//! For a surface point seen by the camera, `J` is the 2x2 Jacobian of the map
//! from screen pixels to shadow-map texels along the surface. The badness
//! `b = ||J⁻¹||²_F = ||J||²_F / det(J)²` is the squared number of screen
//! pixels one texel covers: `b <= 1` means a texel is no larger than a pixel.
//! Lower is better.

use glam::{DMat2, DMat4, DVec2, DVec3, DVec4, UVec2};

use crate::geometry::Plane;
use crate::scene::Aabb;

use crate::camera::Camera;
use crate::matrix::LightMatrix;

/// Derivative of the projected 2D position `(p.x / p.w, p.y / p.w)`, `p = M [x; 1]`,
/// along the world direction `t`; `None` when `w <= 0`.
fn projected_derivative(m: &DMat4, x: DVec3, tangents: [DVec3; 2]) -> Option<(DVec2, DMat2)> {
    let p = *m * x.extend(1.0);
    if !(p.w > 0.0) {
        return None;
    }
    let uv = DVec2::new(p.x, p.y) / p.w;
    let column = |t: DVec3| {
        let dp: DVec4 = *m * t.extend(0.0);
        (DVec2::new(dp.x, dp.y) - uv * dp.w) / p.w
    };
    Some((uv, DMat2::from_cols(column(tangents[0]), column(tangents[1]))))
}

/// The Jacobian `J` (texels per pixel) at a world point on a surface with
/// normal `normal`, or `None` when the point is behind the camera or the
/// light, or the camera sees the surface exactly edge-on.
#[must_use]
pub fn screen_to_texel_jacobian(matrix: &LightMatrix, camera: &Camera, point: DVec3, normal: DVec3) -> Option<DMat2> {
    let n = normal.try_normalize()?;
    let (t1, t2) = n.any_orthonormal_pair();
    let (_, screen) = projected_derivative(&camera.screen_from_world(), point, [t1, t2])?;
    let (_, texel) = projected_derivative(&matrix.texel_from_world(), point, [t1, t2])?;
    let det = screen.determinant();
    if !(det.abs() > 0.0) {
        return None;
    }
    // d(texel)/d(pixel) = d(texel)/d(surface) · (d(pixel)/d(surface))⁻¹.
    Some(texel * screen.inverse())
}

/// The badness `b = ||J⁻¹||²_F` (screen pixels per texel, squared) of `matrix`
/// at a world point with surface normal `normal`.
///
/// `None` when the point is behind the camera or the light, or seen exactly
/// edge-on. `f64::INFINITY` when the light sees the surface edge-on (a texel
/// covers a whole line of pixels).
#[must_use]
pub fn badness(matrix: &LightMatrix, camera: &Camera, point: DVec3, normal: DVec3) -> Option<f64> {
    let j = screen_to_texel_jacobian(matrix, camera, point, normal)?;
    Some(badness_of_jacobian(&j))
}

/// `||J⁻¹||²_F = ||J||²_F / det(J)²`, no inversion needed.
#[must_use]
pub fn badness_of_jacobian(j: &DMat2) -> f64 {
    let det = j.determinant();
    let frob = j.x_axis.length_squared() + j.y_axis.length_squared();
    if det == 0.0 {
        f64::INFINITY
    } else {
        frob / (det * det)
    }
}

/// Summary statistics of badness over many points.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BadnessStats {
    /// Points that could be scored.
    pub count: usize,
    /// Median badness.
    pub median: f64,
    /// Mean badness.
    pub mean: f64,
    /// Largest badness.
    pub max: f64,
}

/// Scores `matrix` at every `(point, normal)` pair and summarises the ones
/// that can be scored; `None` when none can.
#[must_use]
pub fn badness_stats(
    matrix: &LightMatrix,
    camera: &Camera,
    samples: impl IntoIterator<Item = (DVec3, DVec3)>,
) -> Option<BadnessStats> {
    let mut values: Vec<f64> =
        samples.into_iter().filter_map(|(p, n)| badness(matrix, camera, p, n)).filter(|b| !b.is_nan()).collect();
    if values.is_empty() {
        return None;
    }
    values.sort_by(f64::total_cmp);
    let count = values.len();
    let median = if count % 2 == 1 { values[count / 2] } else { 0.5 * (values[count / 2 - 1] + values[count / 2]) };
    Some(BadnessStats { count, median, mean: values.iter().sum::<f64>() / count as f64, max: values[count - 1] })
}

/// The points of a plane seen through a `grid` of pixel centres spread over
/// the screen, kept when they lie within the view frustum's depth range and
/// inside `region` (a box; use a flat box for a floor). Each comes with the
/// plane's normal turned towards the camera. Statistics over these weigh
/// the plane as the screen does.
#[must_use]
pub fn plane_samples(camera: &Camera, plane: &Plane, region: &Aabb, grid: UVec2) -> Vec<(DVec3, DVec3)> {
    let world_from_screen = camera.screen_from_world().inverse();
    let size = camera.viewport().as_dvec2();
    let cells = grid.max(UVec2::ONE).as_dvec2();
    let normal = if plane.signed_distance(camera.eye()) >= 0.0 { plane.normal } else { -plane.normal };
    let slack = 1e-9 * region.diagonal().max(f64::MIN_POSITIVE);
    let inside = |p: DVec3| (p.cmpge(region.min - slack) & p.cmple(region.max + slack)).all();
    (0..grid.x * grid.y)
        .filter_map(|k| {
            let cell = DVec2::new(f64::from(k % grid.x) + 0.5, f64::from(k / grid.x) + 0.5);
            let pixel = cell * size / cells;
            let a = world_from_screen.project_point3(pixel.extend(0.0));
            let b = world_from_screen.project_point3(pixel.extend(1.0));
            let (da, db) = (plane.signed_distance(a), plane.signed_distance(b));
            if !(da * db <= 0.0 && da != db) {
                return None;
            }
            let p = a + (b - a) * (da / (da - db));
            inside(p).then_some((p, normal))
        })
        .collect()
}
