//! The classical parameterizations, one module each. They differ only in how
//! they choose the optical axis `j` and the region the map must hold; the
//! affine fit and the depth row are shared (see [`crate::matrix`]).

pub(crate) mod focused;
mod focused_snapped;
mod lispsm;
mod normal;
mod plane_optimal;
mod psm;

use glam::DVec3;

use crate::error::{LixelError, Result};
use crate::geometry::{min_enclosing_cone_in, ConvexPolyhedron};
use crate::light::{Light, LightFrame};
use crate::matrix::{LightMatrix, Method};
use crate::problem::ShadowProblem;
use crate::workspace::{with_workspace, SolveWorkspace};

pub use focused_snapped::FocusedSnappedOptions;
pub(crate) use focused_snapped::{snapped_homography, SnapGrid};
pub use lispsm::{LiSpsmOptions, NOpt};
pub use plane_optimal::PlaneOptimalOptions;
pub use psm::{psm_light_case, PsmLightCase, PsmOptions};

/// A classical parameterization and its options.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub enum Parameterization {
    /// Uniform map around all receivers the light reaches.
    Normal,
    /// Uniform map around the receivers the view frustum can see.
    Focused,
    /// The focused map with world-fixed axes and a snapped texel grid (what
    /// engines ship against shimmering).
    FocusedSnapped(FocusedSnappedOptions),
    /// Perspective shadow maps.
    Psm(PsmOptions),
    /// Light-space perspective shadow maps.
    LiSpsm(LiSpsmOptions),
    /// Perfect sampling on one receiver plane.
    PlaneOptimal(PlaneOptimalOptions),
}

impl Parameterization {
    /// Every classical method with default options, in the papers' order.
    pub const ALL_DEFAULT: [Self; 6] = [
        Self::Normal,
        Self::Focused,
        Self::FocusedSnapped(FocusedSnappedOptions::DEFAULT),
        Self::Psm(PsmOptions::DEFAULT),
        Self::LiSpsm(LiSpsmOptions::DEFAULT),
        Self::PlaneOptimal(PlaneOptimalOptions::DEFAULT),
    ];

    /// The [`Method`] this produces.
    #[must_use]
    pub fn method(&self) -> Method {
        match self {
            Self::Normal => Method::Normal,
            Self::Focused => Method::Focused,
            Self::FocusedSnapped(_) => Method::FocusedSnapped,
            Self::Psm(_) => Method::Psm,
            Self::LiSpsm(_) => Method::LiSpsm,
            Self::PlaneOptimal(_) => Method::PlaneOptimal,
        }
    }
}

// `solve` lives here, not in `problem.rs`, so that `problem` does not import
// the methods that import it.
impl ShadowProblem {
    /// Computes the light matrix of one parameterization.
    ///
    /// # Errors
    /// See [`LixelError`]; chiefly [`LightInsideFocus`](LixelError::LightInsideFocus)
    /// when a point light (not a spot light: a spot under 89° always fits its
    /// own frustum) sits inside the region its single map must cover.
    pub fn solve(&self, parameterization: &Parameterization) -> Result<LightMatrix> {
        with_workspace(|ws| self.solve_with(parameterization, ws))
    }

    /// [`solve`](Self::solve) with the buffers and the camera cache of
    /// `workspace` (`solve` uses one per thread). The result is the same
    /// whatever the workspace held before.
    ///
    /// # Errors
    /// As [`solve`](Self::solve).
    pub fn solve_with(
        &self,
        parameterization: &Parameterization,
        workspace: &mut SolveWorkspace,
    ) -> Result<LightMatrix> {
        let ws = workspace;
        match parameterization {
            Parameterization::Normal => normal::solve(self, ws),
            Parameterization::Focused => focused::solve(self, ws),
            Parameterization::FocusedSnapped(options) => focused_snapped::solve(self, options, ws),
            Parameterization::Psm(options) => psm::solve(self, options, ws),
            Parameterization::LiSpsm(options) => lispsm::solve(self, options, ws),
            Parameterization::PlaneOptimal(options) => plane_optimal::solve(self, options, ws),
        }
    }
}

/// The uniform optical axis for a body: the orthographic axis for a
/// directional light, the axis of the narrowest cone around the body seen from
/// a point light (its map has the smallest field of view).
///
/// A point light inside the body (boundary included) is
/// [`LixelError::LightInsideFocus`]. A spot light's body lies inside its
/// frustum `L`, so the light is at most the apex of the body; the apex has no
/// direction and is left out ([`ShadowProblem::mappable_vertices`]).
pub(crate) fn uniform_axis(
    problem: &ShadowProblem,
    frame: &LightFrame,
    body: &ConvexPolyhedron,
    method: Method,
    ws: &mut SolveWorkspace,
) -> Result<DVec3> {
    match frame {
        LightFrame::Orthographic { .. } => Ok(DVec3::Z),
        LightFrame::Perspective { position, .. } => {
            let spot = matches!(problem.light(), Light::Spot { .. });
            if !spot && body.contains(*position, problem.eps()) {
                return Err(LixelError::LightInsideFocus { method });
            }
            let mut dirs = ws.take_points();
            problem.mappable_vertices_into(body, &mut dirs, ws);
            for p in &mut dirs {
                *p = frame.homogeneous(*p);
            }
            let cone = min_enclosing_cone_in(&dirs, &mut ws.units);
            ws.put_points(dirs);
            cone.filter(|cone| cone.cos_half_angle > problem.tolerances().min_front_cosine)
                .map(|cone| cone.axis)
                .ok_or(LixelError::LightInsideFocus { method })
        }
    }
}
