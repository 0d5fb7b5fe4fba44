//! Light-space perspective shadow maps (Wimmer, Scherzer & Purgathofer 2004).
//!
//! A perspective frustum in light space whose axis is orthogonal to the light
//! direction and aligned with the view direction projected onto the light's
//! image plane; its one free parameter is the distance `n` from the
//! projection centre to the near face of the body. In lixel's terms the
//! frustum's `w` row is `w = τ - τ_c`, with `τ` the coordinate along that
//! axis on the uniform map's image plane and `τ_c = τ_min - n`, so
//! `j = a₁ e₁ + a₂ e₂ - τ_c j₀` (uniform axis `j₀`, image-plane basis `e₁, e₂`,
//! projected view direction `a`).
//!
//! * Simple `n_opt = (z_n + sqrt(z_n z_f)) / sin γ` with `z_n`, `z_f` the
//!   view depths of the nearest and farthest visible receivers.
//! * General `n_opt = d / (sqrt(z₁ / z₀) - 1)` with `d` the body's extent
//!   along the axis, `z₀ = z_n` and `z₁ = z₀ + d sin γ`.
//!
//! As the light approaches the view direction (`γ → 0`) both grow without
//! bound and the map tends to uniform; below
//! [`Tolerances::lispsm_min_sin_gamma`](crate::Tolerances) lixel returns the
//! focused (uniform) map with [`Fallback::LightAlongView`], as OGRE, Filament
//! and OpenSceneGraph fall back to uniform. So that the switch is not a visible
//! jump, `n` is additionally faded to infinity over
//! `sin γ ∈ [s₀, fade_sin_gamma]` ([`LiSpsmOptions::fade_sin_gamma`]).
//!
//! Point and spot lights: the construction runs on the image plane of the
//! light's uniform (focused) map, where the light is directional; the view
//! direction is taken at the centre of the visible receivers, and `n` is
//! converted from world units by the ratio of the body's extents.

use glam::{DVec2, DVec3};

use crate::error::Result;
use crate::geometry::ConvexPolyhedron;
use crate::light::LightFrame;
use crate::matrix::{Fallback, LightMatrix, Method};
use crate::problem::ShadowProblem;
use crate::workspace::SolveWorkspace;

/// Which formula for the frustum's near distance `n_opt`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NOpt {
    /// `(z_n + sqrt(z_n z_f)) / sin γ`.
    Simple,
    /// `d / (sqrt(z₁ / z₀) - 1)`, `z₁ = z₀ + d sin γ`.
    General,
}

/// Options of [`Parameterization::LiSpsm`](crate::Parameterization::LiSpsm).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LiSpsmOptions {
    /// The `n_opt` formula. Default [`NOpt::General`].
    pub n_opt: NOpt,
    /// Multiplies `n_opt` (1 = the paper's optimum; larger is more uniform).
    pub n_scale: f64,
    /// Below this `sin γ`, `n` is divided by `(sin γ - s₀) / (fade - s₀)`
    /// (`s₀` = [`Tolerances::lispsm_min_sin_gamma`](crate::Tolerances)), so
    /// the map reaches uniform continuously where the fallback takes over
    /// instead of jumping to it. Default `0.02` (about 1.1°); `0` disables.
    pub fade_sin_gamma: f64,
}

impl LiSpsmOptions {
    /// General `n_opt`, unscaled.
    pub const DEFAULT: Self = Self { n_opt: NOpt::General, n_scale: 1.0, fade_sin_gamma: 0.02 };
}

impl Default for LiSpsmOptions {
    fn default() -> Self {
        Self::DEFAULT
    }
}

pub(super) fn solve(problem: &ShadowProblem, options: &LiSpsmOptions, ws: &mut SolveWorkspace) -> Result<LightMatrix> {
    problem.with_visible_receiver_body(ws, |focus, ws| solve_for(problem, options, focus, ws))
}

fn solve_for(
    problem: &ShadowProblem,
    options: &LiSpsmOptions,
    focus: &ConvexPolyhedron,
    ws: &mut SolveWorkspace,
) -> Result<LightMatrix> {
    if focus.is_empty() {
        return super::focused::around(problem, focus, Method::LiSpsm, None, ws);
    }
    if problem.camera().is_orthographic() {
        return super::focused::around(problem, focus, Method::LiSpsm, Some(Fallback::OrthographicCamera), ws);
    }
    let frame = problem.frame_towards(focus);
    let j0 = super::uniform_axis(problem, &frame, focus, Method::LiSpsm, ws)?;
    let (e1, e2) = j0.any_orthonormal_pair();
    let camera = problem.camera();
    let view = camera.view_direction();
    let center = focus.centroid();
    let ray = match problem.light().position() {
        None => frame_light_direction(&frame),
        Some(l) => (center - l).normalize(),
    };
    let sin_gamma = view.cross(ray).length();
    let uniform = |sin_gamma, ws: &mut SolveWorkspace| {
        super::focused::around(problem, focus, Method::LiSpsm, Some(Fallback::LightAlongView { sin_gamma }), ws)
    };
    if !(sin_gamma >= problem.tolerances().lispsm_min_sin_gamma) {
        return uniform(sin_gamma, ws);
    }
    let axis_world = (view - ray * view.dot(ray)).normalize();

    // Image-plane coordinates of the uniform map and the view direction there.
    let image = |x: DVec3| DVec2::new(e1.dot(x), e2.dot(x)) / j0.dot(x);
    let xc = frame.homogeneous(center);
    let dx = frame.homogeneous(center + view) - xc;
    let q_center = image(xc);
    let dq = (DVec2::new(e1.dot(dx), e2.dot(dx)) - q_center * j0.dot(dx)) / j0.dot(xc);
    let Some(a) = dq.try_normalize() else {
        return uniform(sin_gamma, ws);
    };

    let vertices = focus.vertices();
    let (tau_min, tau_max) = min_max(vertices.iter().map(|&p| a.dot(image(frame.homogeneous(p)))));
    let (along_min, along_max) = min_max(vertices.iter().map(|&p| axis_world.dot(p)));
    let (depth_min, depth_max) = min_max(vertices.iter().map(|&p| camera.view_depth(p)));
    let d_image = tau_max - tau_min;
    let d_world = along_max - along_min;
    if !(d_image > 0.0 && d_world > 0.0) {
        return uniform(sin_gamma, ws);
    }
    let z_n = depth_min.max(camera.z_near());
    let z_f = depth_max.max(z_n * (1.0 + problem.tolerances().min_relative_span));
    let n_world = match options.n_opt {
        NOpt::Simple => (z_n + (z_n * z_f).sqrt()) / sin_gamma,
        NOpt::General => {
            let z1 = z_n + d_world * sin_gamma;
            d_world / ((z1 / z_n).sqrt() - 1.0)
        }
    } * options.n_scale.max(f64::MIN_POSITIVE);
    let s0 = problem.tolerances().lispsm_min_sin_gamma;
    let n_world = if sin_gamma < options.fade_sin_gamma && options.fade_sin_gamma > s0 {
        n_world / ((sin_gamma - s0) / (options.fade_sin_gamma - s0))
    } else {
        n_world
    };
    let n_image = n_world * d_image / d_world;
    if !n_image.is_finite() {
        return uniform(sin_gamma, ws);
    }
    let tau_c = tau_min - n_image;
    let axis = e1 * a.x + e2 * a.y - j0 * tau_c;
    problem.place(frame, axis, focus, Method::LiSpsm, None, ws)
}

/// The light direction of an orthographic frame (its third axis).
fn frame_light_direction(frame: &LightFrame) -> DVec3 {
    match frame {
        LightFrame::Orthographic { rotation } | LightFrame::Perspective { rotation, .. } => rotation.row(2),
    }
}

fn min_max(values: impl Iterator<Item = f64>) -> (f64, f64) {
    values.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| (lo.min(v), hi.max(v)))
}
