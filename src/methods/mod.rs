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
use crate::geometry::{min_enclosing_cone, ConvexPolyhedron};
use crate::light::LightFrame;
use crate::matrix::{LightMatrix, Method};
use crate::problem::ShadowProblem;

pub use focused_snapped::FocusedSnappedOptions;
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

pub(crate) fn solve(problem: &ShadowProblem, parameterization: &Parameterization) -> Result<LightMatrix> {
    match parameterization {
        Parameterization::Normal => normal::solve(problem),
        Parameterization::Focused => focused::solve(problem),
        Parameterization::FocusedSnapped(options) => focused_snapped::solve(problem, options),
        Parameterization::Psm(options) => psm::solve(problem, options),
        Parameterization::LiSpsm(options) => lispsm::solve(problem, options),
        Parameterization::PlaneOptimal(options) => plane_optimal::solve(problem, options),
    }
}

/// The uniform optical axis for a body: the orthographic axis for a
/// directional light, the axis of the narrowest cone around the body seen from
/// a point light (its map has the smallest field of view).
pub(crate) fn uniform_axis(
    problem: &ShadowProblem,
    frame: &LightFrame,
    body: &ConvexPolyhedron,
    method: Method,
) -> Result<DVec3> {
    match frame {
        LightFrame::Orthographic { .. } => Ok(DVec3::Z),
        LightFrame::Perspective { position, .. } => {
            if body.contains(*position, problem.eps()) {
                return Err(LixelError::LightInsideFocus { method });
            }
            let dirs: Vec<DVec3> = body.vertices().iter().map(|&p| frame.homogeneous(p)).collect();
            min_enclosing_cone(&dirs)
                .filter(|cone| cone.cos_half_angle > problem.tolerances().min_front_cosine)
                .map(|cone| cone.axis)
                .ok_or(LixelError::LightInsideFocus { method })
        }
    }
}
