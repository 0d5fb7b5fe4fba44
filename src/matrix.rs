//! The result type, [`LightMatrix`], and the one place where an optical axis
//! `j` plus the points a map must hold become a 4x4 matrix.

use glam::{DMat3, DMat4, DVec2, DVec3, DVec4, Mat4};

use crate::camera::viewport_matrix;
use crate::caster_bounds::CasterBounds;
use crate::error::{LixelError, Result};
use crate::fit::{AffineFitOptions, FitWorkspace};
use crate::light::{Light, LightFrame};
use crate::scene::ShadowMapSize;
use crate::tolerance::Tolerances;

/// Which parameterization produced a matrix.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum Method {
    /// Uniform map around all receivers ("normal" in the papers).
    Normal,
    /// Uniform map limited to what the view frustum can see.
    Focused,
    /// Focused with world-fixed axes and a texel-snapped grid (engines'
    /// stabilization).
    FocusedSnapped,
    /// Perspective shadow maps (Stamminger & Drettakis 2002).
    Psm,
    /// Light-space perspective shadow maps (Wimmer et al. 2004).
    LiSpsm,
    /// Perfect sampling on one receiver plane (Chong & Gortler 2004).
    PlaneOptimal,
    /// Scene-optimized: moved from read-back samples of the scene
    /// (Chong & Gortler 2006).
    Optimized,
}

impl Method {
    /// Short lowercase name, as used in reports and on the command line.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::Normal => "normal",
            Self::Focused => "focused",
            Self::FocusedSnapped => "focused-snapped",
            Self::Psm => "psm",
            Self::LiSpsm => "lispsm",
            Self::PlaneOptimal => "plane-optimal",
            Self::Optimized => "optimized",
        }
    }
}

/// Why a method returned something other than its own ideal matrix. The
/// matrix is still correct: every relevant point is in the map.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub enum Fallback {
    /// The view frustum sees no receiver; the map covers all receivers
    /// (a normal map) so that it is still usable.
    NothingVisible,
    /// LiSPSM: the light is (anti-)parallel to the view direction
    /// (`sin γ` below [`Tolerances::lispsm_min_sin_gamma`]); a uniform
    /// (focused) map was used, as the method prescribes in the limit.
    LightAlongView {
        /// `sin γ` of the configuration.
        sin_gamma: f64,
    },
    /// PSM: the light lies inside the hull `H` (so `H` spans more than a
    /// half-space seen from the light), or post-perspective space degenerated;
    /// the focused axis was used.
    PsmHullAroundLight,
    /// Plane-optimal: some relevant points lie at or beyond the vanishing line
    /// of the plane-optimal homography. The optical axis was blended towards
    /// the focused axis by the smallest amount `blend` in `(0, 1]` that brings
    /// all of them in front (`blend = 1` is the focused map).
    PlaneOptimalBlended {
        /// Weight of the focused axis in the blend.
        blend: f64,
    },
    /// Plane-optimal: the eye or the light lies in the receiver plane, so the
    /// plane's homography is singular, or the light grazes the plane so
    /// closely that the map cannot be held in `f64`; the focused map was used.
    PlaneDegenerate,
    /// Plane-optimal: the view frustum sees no part of the receiver plane
    /// inside the receiver bounds; the focused map was used.
    PlaneNotVisible,
    /// Scene-optimized: no usable samples, or no candidate map held every
    /// relevant sample (rounding at grazing axes); the focused map was used.
    /// It holds the visible receivers `V ∩ R ∩ L`; relevant samples outside
    /// them (which a correct readback does not produce) are not guaranteed.
    NoUsableSamples,
    /// PSM or LiSPSM with an orthographic camera: both methods counter the
    /// camera's perspective, and without one their warp vanishes (PSM's
    /// post-perspective space is an affine image of the world; LiSPSM's
    /// `n_opt` grows without bound as the eye recedes), so the focused
    /// (uniform) map is the method's own limit.
    OrthographicCamera,
}

/// How depth is stored, with the range it covers.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum DepthRange {
    /// Point and spot lights: `z_ndc = a + b / (j·X~)` with `z = 0` at
    /// `j·X~ = near` and `1` at `far` (distances along the optical axis).
    Perspective {
        /// Near distance along `j`.
        near: f64,
        /// Far distance along `j`.
        far: f64,
    },
    /// Directional lights: `z_ndc = α (c - c_min) / w` with `c = d·x` the
    /// distance along the light direction and `w = j·X~`; monotone along
    /// every light ray and in `[0, 1]` over the covered region.
    Orthographic {
        /// Smallest `c` of any point needing depth.
        c_min: f64,
        /// Largest `c`.
        c_max: f64,
        /// `α = w_min / (c_max - c_min)`.
        alpha: f64,
    },
}

/// Distance from the light along its rays, over every point whose depth the
/// map must hold (receivers and their casters): radial `|x - l|` for point and
/// spot lights, `d·x` for directional ones. A renderer that stores *linear*
/// light depth (lixel's does: warped maps spend the projective depth range
/// across the map instead of along the rays) normalizes with it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightDistance {
    /// Smallest distance (padded).
    pub min: f64,
    /// Largest distance (padded).
    pub max: f64,
}

impl LightDistance {
    /// `(distance - min) / (max - min)` of a world point, in `[0, 1]` over the range.
    #[must_use]
    pub fn normalized(&self, frame: &LightFrame, world: DVec3) -> f64 {
        (light_distance(frame, world) - self.min) / (self.max - self.min)
    }
}

/// Radial distance from a point light, or `d·x` for a directional one.
#[must_use]
pub fn light_distance(frame: &LightFrame, world: DVec3) -> f64 {
    match *frame {
        LightFrame::Perspective { position, .. } => (world - position).length(),
        LightFrame::Orthographic { rotation } => rotation.row(2).dot(world),
    }
}

/// A shadow map's light matrix and how it was made.
///
/// `clip_from_world` is in wgpu conventions (depth `[0, 1]`, NDC y up). Its
/// rows 1, 2 and 4, restricted to the light coordinates `X~` of
/// [`LightFrame::homogeneous`], form the homography `G = [g1; g2; j]` (NDC
/// units, `|j| = 1`); row 3 is the depth row of [`DepthRange`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightMatrix {
    /// World to light clip space.
    pub clip_from_world: DMat4,
    /// The light the map was made for (a renderer applies a spot light's
    /// cone with it: outside the cone the light does not reach).
    pub light: Light,
    /// The light frame the homography acts in.
    pub frame: LightFrame,
    /// `G`: rows `g1`, `g2` (NDC x and y), `j` (the optical axis, unit length).
    pub homography: DMat3,
    /// The depth row's parameters.
    pub depth: DepthRange,
    /// The range of distances along the light's rays the map must hold.
    pub light_distance: LightDistance,
    /// The shadow map's size in texels.
    pub map_size: ShadowMapSize,
    /// Casters closer to the light than the near plane exist: render with
    /// unclipped depth (`wgpu::Features::DEPTH_CLIP_CONTROL`,
    /// `unclipped_depth: true`) so that they rasterize, clamped to depth 0.
    pub needs_unclipped_depth: bool,
    /// The method that produced the matrix.
    pub method: Method,
    /// Set when the method could not use its own ideal parameters.
    pub fallback: Option<Fallback>,
}

impl LightMatrix {
    /// The optical axis `j` in light coordinates (unit length).
    #[must_use]
    pub fn optical_axis(&self) -> DVec3 {
        self.homography.row(2)
    }

    /// `clip_from_world` in single precision, for uploading to a GPU.
    #[must_use]
    pub fn clip_from_world_f32(&self) -> Mat4 {
        self.clip_from_world.as_mat4()
    }

    /// Texel coordinates (x right, y down, as stored in the texture; texel
    /// centres at half-integers) plus depth, from world space, homogeneous.
    #[must_use]
    pub fn texel_from_world(&self) -> DMat4 {
        viewport_matrix(f64::from(self.map_size.width), f64::from(self.map_size.height)) * self.clip_from_world
    }

    /// NDC position `(x, y, depth)` of a world point, or `None` when it lies
    /// on or behind the light's vanishing plane (`w <= 0`).
    #[must_use]
    pub fn project(&self, world: DVec3) -> Option<DVec3> {
        let clip = self.clip_from_world * world.extend(1.0);
        (clip.w > 0.0).then(|| clip.truncate() / clip.w)
    }

    /// Whether a world point lands inside the map (`|x|, |y| <= 1 + slack`,
    /// in front of the light).
    #[must_use]
    pub fn covers(&self, world: DVec3, slack: f64) -> bool {
        self.project(world).is_some_and(|ndc| ndc.x.abs() <= 1.0 + slack && ndc.y.abs() <= 1.0 + slack)
    }
}

/// Points `X~` in front of the light for axis `j`, projected onto the plane
/// `j·v = 1` and expressed in an orthonormal basis `(e1, e2)` of `j⊥`.
///
/// Returns the basis. Points with `j·X~ <= 0` are reported through `Err`.
pub(crate) fn project_to_image_plane(
    j: DVec3,
    points: impl IntoIterator<Item = DVec3>,
    out: &mut Vec<DVec2>,
) -> std::result::Result<(DVec3, DVec3), usize> {
    let (e1, e2) = j.any_orthonormal_pair();
    out.clear();
    for (i, x) in points.into_iter().enumerate() {
        let w = j.dot(x);
        if !(w > 0.0) {
            return Err(i);
        }
        out.push(DVec2::new(e1.dot(x), e2.dot(x)) / w);
    }
    Ok((e1, e2))
}

/// What an affine fit for a candidate axis needs besides the axis and points.
pub(crate) struct AxisFit<'a> {
    pub frame: &'a LightFrame,
    pub map: ShadowMapSize,
    pub fit: &'a AffineFitOptions,
    pub tolerances: &'a Tolerances,
    /// The points are a convex cone's edges in order around it (the
    /// optimizer's extreme rays): the fit takes their hull without a sort
    /// ([`FitWorkspace::fit_polygon`]; the same fit either way).
    pub polygon: bool,
}

/// The homography `G` (NDC units, unit `j`) for optical axis `axis` that fits
/// the map around the light-coordinate points `xs`, or `None` when a point is
/// not safely in front of the light (see [`Tolerances::min_front_cosine`]),
/// the fit fails, or the fitted map does not hold every point to within
/// [`Tolerances::coverage_slack`] (rounding, for axes that see a point at a
/// grazing angle). `scratch` is reused for the projected points.
pub(crate) fn fit_homography(
    setup: &AxisFit<'_>,
    axis: DVec3,
    xs: &[DVec3],
    workspace: &mut FitWorkspace,
    scratch: &mut Vec<DVec2>,
) -> Option<DMat3> {
    let j = axis.normalize();
    if !j.is_finite() || xs.is_empty() || !in_front(setup.frame, setup.tolerances, j, xs) {
        return None;
    }
    let (e1, e2) = project_to_image_plane(j, xs.iter().copied(), scratch).ok()?;
    let fit = if setup.polygon {
        workspace.fit_polygon(scratch, setup.map.width, setup.map.height, setup.fit)
    } else {
        workspace.fit(scratch, setup.map.width, setup.map.height, setup.fit)
    }
    .ok()?;
    let homography = fit.ndc_from_plane * DMat3::from_cols(e1, e2, j).transpose();
    holds_all(&homography, xs, setup.tolerances.coverage_slack).then_some(homography)
}

/// Whether every point `x` (light coordinates) has `w = j·x̂` above
/// [`Tolerances::min_front_cosine`] times the largest `w`, with `x̂ = x / |x|`
/// for a point light (a cosine to the axis) and `x̂ = x` for a directional
/// one (whose `X~` all have third coordinate 1). Relative, so a far point
/// light, whose points all sit within a tiny angle, is judged as the
/// directional light it approaches.
pub(crate) fn in_front(frame: &LightFrame, tolerances: &Tolerances, j: DVec3, xs: &[DVec3]) -> bool {
    let w = |x: &DVec3| if frame.is_orthographic() { j.dot(*x) } else { j.dot(*x) / x.length() };
    // One pass: every `w` above the bound is the least one above it. A NaN
    // `w` fails the test (as it fails `w > bound`); `f64::max` skips it in
    // the largest, as before.
    let (mut min_w, mut max_w, mut nan) = (f64::INFINITY, 0.0_f64, false);
    for x in xs {
        let w = w(x);
        nan |= w.is_nan();
        min_w = min_w.min(w);
        max_w = max_w.max(w);
    }
    max_w > 0.0 && !nan && min_w > tolerances.min_front_cosine * max_w
}

/// Whether `homography` puts every light-coordinate point in front of the
/// light and inside the map (`|ndc| <= 1 + slack`).
pub(crate) fn holds_all(homography: &DMat3, xs: &[DVec3], slack: f64) -> bool {
    homography.is_finite()
        && xs.iter().all(|&x| {
            let c = *homography * x;
            c.z > 0.0 && c.x.abs() <= (1.0 + slack) * c.z && c.y.abs() <= (1.0 + slack) * c.z
        })
}

/// `(min, max)` of `values`; `None` when there are none.
fn fold_range(values: impl Iterator<Item = f64>) -> Option<(f64, f64)> {
    values.fold(None, |range, v| match range {
        None => Some((v, v)),
        Some((lo, hi)) => Some((v.min(lo), v.max(hi))),
    })
}

/// [`fold_range`] of `value` over `a` then `b`, four values at a time: the
/// lanes' smallest and largest by plain compares (`minpd`), which are
/// `fold_range`'s bits whenever no value is NaN and neither end is a zero
/// (the one value whose bits `f64::min` may pick either way, `±0`);
/// otherwise `fold_range` itself. Compiled for AVX where the CPU has it
/// (the same Rust, so the same compares and the same bits).
fn range_of(a: &[DVec3], b: &[DVec3], value: impl Fn(&DVec3) -> f64 + Copy) -> Option<(f64, f64)> {
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx")]
    fn range_of_avx(a: &[DVec3], b: &[DVec3], value: impl Fn(&DVec3) -> f64 + Copy) -> Option<(f64, f64)> {
        range_of_lanes(a, b, value)
    }
    avx_or_portable!(range_of_avx(a, b, value), range_of_lanes(a, b, value))
}

/// The body of [`range_of`], for any target features.
#[inline(always)]
fn range_of_lanes(a: &[DVec3], b: &[DVec3], value: impl Fn(&DVec3) -> f64 + Copy) -> Option<(f64, f64)> {
    const LANES: usize = 4;
    let mut lo = [f64::INFINITY; LANES];
    let mut hi = [f64::NEG_INFINITY; LANES];
    let mut nan = [false; LANES];
    let mut fold = |v: f64, k: usize| {
        lo[k] = if v < lo[k] { v } else { lo[k] };
        hi[k] = if v > hi[k] { v } else { hi[k] };
        nan[k] |= v.is_nan();
    };
    for points in [a, b] {
        let mut chunks = points.chunks_exact(LANES);
        for chunk in &mut chunks {
            for (k, p) in chunk.iter().enumerate() {
                fold(value(p), k);
            }
        }
        for p in chunks.remainder() {
            fold(value(p), 0);
        }
    }
    let lo = lo.into_iter().fold(f64::INFINITY, |m, v| if v < m { v } else { m });
    let hi = hi.into_iter().fold(f64::NEG_INFINITY, |m, v| if v > m { v } else { m });
    if a.is_empty() && b.is_empty() {
        None
    } else if nan.contains(&true) || lo == 0.0 || hi == 0.0 {
        fold_range(a.iter().chain(b).map(value))
    } else {
        Some((lo, hi))
    }
}

/// The smallest range holding both ranges (either may be absent).
fn union(a: Option<(f64, f64)>, b: Option<(f64, f64)>) -> Option<(f64, f64)> {
    match (a, b) {
        (Some((a0, a1)), Some((b0, b1))) => Some((a0.min(b0), a1.max(b1))),
        (range, None) | (None, range) => range,
    }
}

/// Everything needed to turn an optical axis into a [`LightMatrix`].
pub(crate) struct Placement<'a> {
    pub light: Light,
    pub frame: LightFrame,
    /// Optical axis, any positive scale.
    pub axis: DVec3,
    /// World points that must land inside the map.
    pub focus: &'a [DVec3],
    /// Further world points that must lie inside the depth range.
    pub depth_points: &'a [DVec3],
    /// The casters that must lie inside the depth range, as half-spaces
    /// (their extremes bound the range; [`CasterBounds`]).
    pub casters: Option<&'a CasterBounds>,
    pub map: ShadowMapSize,
    pub fit: &'a AffineFitOptions,
    pub tolerances: &'a Tolerances,
    pub method: Method,
    pub fallback: Option<Fallback>,
}

impl Placement<'_> {
    /// Fits the affine part around `focus` for the axis and adds the depth row.
    ///
    /// # Errors
    /// [`LixelError::NotInFront`] when a focus point is not safely in front of
    /// the light for this axis, or the finished matrix does not hold it in
    /// the map and the depth range (to [`Tolerances::coverage_slack`]) in
    /// world coordinates; [`LixelError::UnusableSamples`] when there
    /// are no focus points.
    pub(crate) fn build_in(&self, ws: &mut crate::workspace::SolveWorkspace) -> Result<LightMatrix> {
        let crate::workspace::SolveWorkspace { fit, xs, image, .. } = ws;
        xs.clear();
        xs.extend(self.focus.iter().map(|&p| self.frame.homogeneous(p)));
        if xs.is_empty() {
            return Err(LixelError::UnusableSamples { reason: "no points to fit the map around" });
        }
        let homography = fit_homography(
            &AxisFit { frame: &self.frame, map: self.map, fit: self.fit, tolerances: self.tolerances, polygon: false },
            self.axis,
            xs,
            fit,
            image,
        )
        .ok_or(LixelError::NotInFront { method: self.method })?;
        self.finish_checked(homography, xs)
    }

    /// [`finish`](Self::finish), then checked: every focus and depth point
    /// in the map and the depth range in world coordinates.
    ///
    /// # Errors
    /// [`LixelError::NotInFront`] when the matrix does not hold them.
    pub(crate) fn finish_checked(&self, homography: DMat3, xs: &[DVec3]) -> Result<LightMatrix> {
        let matrix = self.finish(homography, xs);
        // Checked again as a renderer will evaluate it, in world coordinates:
        // composing `G` with a far light's translation can round differently.
        let slack = self.tolerances.coverage_slack;
        // `covers` and the depth test on one projection.
        let held = |p: &DVec3| {
            matrix.project(*p).is_some_and(|ndc| {
                ndc.x.abs() <= 1.0 + slack
                    && ndc.y.abs() <= 1.0 + slack
                    && ndc.z <= 1.0 + slack
                    && (ndc.z >= -slack || matrix.needs_unclipped_depth)
            })
        };
        if !(matrix.clip_from_world.is_finite() && self.focus.iter().all(held)) {
            return Err(LixelError::NotInFront { method: self.method });
        }
        Ok(matrix)
    }

    /// Adds the depth row to a homography whose third row is the unit axis;
    /// `focus_light` are the focus points (or their extreme rays) in light
    /// coordinates. Here `focus` and `depth_points` are read only as one
    /// sequence of depth points, `focus` first (the optimizer passes its
    /// bodies' vertices and its relevant samples so).
    pub(crate) fn finish(&self, homography: DMat3, focus_light: &[DVec3]) -> LightMatrix {
        let j = homography.row(2);
        let t_rows = self.frame.light_from_world_3x4_rows();
        let g_row = |r: usize| -> DVec4 {
            let g = homography.row(r);
            t_rows[0] * g.x + t_rows[1] * g.y + t_rows[2] * g.z
        };
        let (x_row, y_row, w_row) = (g_row(0), g_row(1), g_row(2));
        let pad = self.tolerances.depth_pad;
        // The casters' range of the depth function: `w` or `d·x`.
        let depth_function = match self.frame {
            LightFrame::Perspective { .. } => w_row,
            LightFrame::Orthographic { rotation } => rotation.row(2).extend(0.0),
        };
        // The depth points' range of it. They hold the casters' focus
        // vertices, so (with the light's own value for a positional light)
        // they bound the casters' maximum (`CasterBounds::linear_range`),
        // except where a directional light's function grows towards the
        // light (then the casters' maximum is solved for).
        let depth_points = match self.frame {
            LightFrame::Perspective { .. } => {
                range_of(self.focus, self.depth_points, |p: &DVec3| w_row.dot(p.extend(1.0)))
            }
            LightFrame::Orthographic { rotation } => {
                let d = rotation.row(2);
                range_of(self.focus, self.depth_points, |p: &DVec3| d.dot(*p))
            }
        };
        let hull_max = depth_points.and_then(|(_, top)| match (self.frame, self.light) {
            (LightFrame::Perspective { position, .. }, _) => Some(top.max(w_row.dot(position.extend(1.0)))),
            (LightFrame::Orthographic { rotation }, Light::Directional { direction }) => {
                (rotation.row(2).dot(direction) >= 0.0).then_some(top)
            }
            _ => None,
        });
        let casters = self.casters.and_then(|c| c.linear_range(depth_function, hull_max));
        let caster_depth = casters.map(|(lo, hi, _)| (lo, hi));
        let mut needs_unclipped_depth = false;
        let (z_row, depth) = match self.frame {
            LightFrame::Perspective { .. } => {
                let points = depth_points;
                // `w` is positive in front of the light: the range starts at 0.
                let (lo, hi) = union(points, caster_depth).map_or((f64::INFINITY, 0.0), |(lo, hi)| (lo, hi.max(0.0)));
                let far = hi * (1.0 + pad);
                let mut near = lo * (1.0 - pad);
                if !(near >= far * self.tolerances.min_near_far_ratio) {
                    near = far * self.tolerances.min_near_far_ratio;
                    needs_unclipped_depth = true;
                }
                let a = far / (far - near);
                let b = -near * far / (far - near);
                (w_row * a + DVec4::W * b, DepthRange::Perspective { near, far })
            }
            LightFrame::Orthographic { rotation } => {
                let d = rotation.row(2);
                let points = depth_points;
                let (lo, hi) = union(points, caster_depth).unwrap_or((f64::INFINITY, f64::NEG_INFINITY));
                let span = (hi - lo)
                    .max(f64::MIN_POSITIVE.sqrt())
                    .max(self.tolerances.min_relative_span * lo.abs().max(hi.abs()));
                let (c_min, c_max) = (lo - pad * span, hi + pad * span);
                let w_min = focus_light.iter().map(|x| j.dot(*x)).fold(f64::INFINITY, f64::min);
                let alpha = w_min / (c_max - c_min);
                (d.extend(-c_min) * alpha, DepthRange::Orthographic { c_min, c_max, alpha })
            }
        };
        let clip_from_world = DMat4::from_cols(x_row, y_row, z_row, w_row).transpose();
        let points = match self.frame {
            LightFrame::Perspective { .. } => {
                range_of(self.focus, self.depth_points, |p: &DVec3| light_distance(&self.frame, *p))
            }
            // The same values as the depth function's (`light_distance`).
            LightFrame::Orthographic { .. } => depth_points,
        };
        // A directional light's distance is the depth function itself.
        let caster_distance = match (self.frame, self.casters, casters) {
            (LightFrame::Perspective { position, .. }, Some(c), Some((_, _, nearest))) => {
                c.distance_range(position, w_row.truncate(), nearest)
            }
            _ => caster_depth,
        };
        let (lo, hi) = union(points, caster_distance).unwrap_or((f64::INFINITY, f64::NEG_INFINITY));
        let span = (hi - lo).max(self.tolerances.min_relative_span * lo.abs().max(hi.abs()).max(f64::MIN_POSITIVE));
        let light_distance = LightDistance { min: lo - pad * span, max: hi + pad * span };
        LightMatrix {
            clip_from_world,
            light: self.light,
            frame: self.frame,
            homography,
            depth,
            light_distance,
            map_size: self.map,
            needs_unclipped_depth,
            method: self.method,
            fallback: self.fallback,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `range_of` is `fold_range` bit for bit: on plain values (the lanes),
    /// and with NaN, signed zeros at either end, infinities, short and
    /// empty inputs (the fallback).
    #[test]
    fn range_of_is_fold_range() {
        let mut unit = crate::test_rng::unit(0x0DDB_1A5E_5BAD_5EED_u64);
        let mut next = move || unit() * 2.0 - 1.0;
        let mut fallbacks = 0;
        for case in 0..4000 {
            let (na, nb) = (case % 13, (case / 13) % 11);
            let mut point = || DVec3::new(next(), next(), next()) * 10.0;
            let mut a: Vec<DVec3> = (0..na).map(|_| point()).collect();
            let mut b: Vec<DVec3> = (0..nb).map(|_| point()).collect();
            let all = a.len() + b.len();
            if all > 0 {
                let k = case % all;
                let p = if k < a.len() { &mut a[k] } else { &mut b[k - a.len()] };
                match case % 7 {
                    1 => p.x = f64::NAN,
                    4 => p.x = f64::INFINITY,
                    _ => {}
                }
            }
            if case % 7 == 2 && all >= 2 {
                // The smallest value along `X` a zero, both signs present
                // (`f64::min` may keep either).
                for p in a.iter_mut().chain(&mut b) {
                    *p = p.abs();
                }
                let (k0, k1) = (case % all, (case + 1) % all);
                for (k, zero) in [(k0, DVec3::ZERO), (k1, DVec3::splat(-0.0))] {
                    if k < a.len() {
                        a[k] = zero;
                    } else {
                        b[k - a.len()] = zero;
                    }
                }
            }
            for d in [DVec3::X, DVec3::new(0.3, -0.5, 0.8)] {
                let value = |p: &DVec3| d.dot(*p);
                let fast = range_of(&a, &b, value);
                let plain = fold_range(a.iter().chain(&b).map(value));
                let bits = |r: Option<(f64, f64)>| r.map(|(lo, hi)| (lo.to_bits(), hi.to_bits()));
                assert_eq!(bits(fast), bits(plain), "case {case}: {a:?} {b:?}");
                fallbacks += usize::from(plain.is_some_and(|(lo, hi)| lo == 0.0 || hi == 0.0));
            }
        }
        assert!(fallbacks > 100, "{fallbacks}");
    }
}
