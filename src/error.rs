//! The error type shared by every solver entry point.

use crate::Method;

/// Why a light matrix could not be computed.
///
/// Every variant describes input that no single shadow map can serve (or input
/// that is malformed); recoverable situations produce a matrix with a
/// [`Fallback`](crate::Fallback) instead.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum LixelError {
    /// An input value was NaN or infinite.
    #[error("non-finite input: {what}")]
    NonFinite {
        /// Which input held the bad value.
        what: &'static str,
    },
    /// The camera cannot be used (singular matrices, near >= far, zero viewport, ...).
    #[error("degenerate camera: {reason}")]
    DegenerateCamera {
        /// What is wrong with it.
        reason: &'static str,
    },
    /// An engine's camera matrices cannot be one camera: `property` says
    /// which property failed ([`Camera::from_matrices`](crate::Camera::from_matrices)).
    #[error("invalid camera matrices ({property}): {reason}")]
    InvalidProjection {
        /// The property that failed.
        property: crate::conventions::CameraProperty,
        /// What is wrong with it.
        reason: &'static str,
    },
    /// The light cannot be used (zero direction, spot cone of 90 degrees or more, ...).
    #[error("invalid light: {reason}")]
    InvalidLight {
        /// What is wrong with it.
        reason: &'static str,
    },
    /// A finite input coordinate lies beyond the supported range
    /// `|x| <= MAX_COORDINATE` ([`crate::MAX_COORDINATE`], `1e15`): squares
    /// of such values overflow or swamp the scene in rounding error.
    #[error("{what} has a coordinate of magnitude {magnitude:e}, beyond the supported {limit:e}")]
    OutOfRange {
        /// Which input held the value.
        what: &'static str,
        /// Its largest absolute coordinate.
        magnitude: f64,
        /// The supported limit.
        limit: f64,
    },
    /// Scene bounds are empty or inverted.
    #[error("invalid scene bounds: {reason}")]
    InvalidBounds {
        /// What is wrong with them.
        reason: &'static str,
    },
    /// A shadow map with zero width or height.
    #[error("shadow map size must be non-zero, got {width}x{height}")]
    ZeroMapSize {
        /// Requested width in texels.
        width: u32,
        /// Requested height in texels.
        height: u32,
    },
    /// A point or spot light lies inside the region its map must cover, so the
    /// directions towards that region span more than a half-space: no single
    /// planar shadow map can hold them (a cube map is needed).
    #[error("{method:?}: the light lies inside the region its shadow map must cover")]
    LightInsideFocus {
        /// The method that was asked for.
        method: Method,
    },
    /// The light reaches no receiver (a spot light pointing away from the
    /// scene): there is nothing to map and no shadow to draw.
    #[error("{method:?}: the light reaches no receiver")]
    NothingLit {
        /// The method that was asked for.
        method: Method,
    },
    /// The camera sees no receiver the light reaches, and the fallback (a
    /// normal map of all receivers) is impossible because the point light
    /// sits inside the receiver bounds. No shadow is visible; no map is needed.
    #[error("{method:?}: nothing visible to shadow, and a normal map is impossible")]
    NothingVisible {
        /// The method that was asked for.
        method: Method,
    },
    /// No optical axis puts every relevant point safely in front of the
    /// light, or the finished matrix (checked in world coordinates) would not
    /// hold them: an internal invariant of the method failed; please report it.
    #[error("{method:?}: relevant points lie behind the light's image plane")]
    NotInFront {
        /// The method that was asked for.
        method: Method,
    },
    /// The receiver plane given to the plane-optimal method is invalid
    /// (non-finite, zero normal) or its options are (`min_relative_w` outside
    /// `(0, 1)`). An eye in the plane is not an error: the method falls back
    /// with [`Fallback::PlaneDegenerate`](crate::Fallback::PlaneDegenerate).
    #[error("invalid receiver plane: {reason}")]
    InvalidPlane {
        /// What is wrong with it.
        reason: &'static str,
    },
    /// The sample set handed to the scene optimizer cannot be used at all.
    #[error("unusable samples: {reason}")]
    UnusableSamples {
        /// What is wrong with them.
        reason: &'static str,
    },
}

/// Result alias used throughout the crate.
pub type Result<T, E = LixelError> = std::result::Result<T, E>;

/// Returns `Err(OutOfRange)` when a coordinate's magnitude exceeds
/// [`crate::MAX_COORDINATE`] (after [`check_finite`]).
pub(crate) fn check_range(values: &[f64], what: &'static str) -> Result<()> {
    let magnitude = values.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    if magnitude <= crate::tolerance::MAX_COORDINATE {
        Ok(())
    } else {
        Err(LixelError::OutOfRange { what, magnitude, limit: crate::tolerance::MAX_COORDINATE })
    }
}

/// Returns `Err(NonFinite)` unless every component is finite.
pub(crate) fn check_finite(values: &[f64], what: &'static str) -> Result<()> {
    if values.iter().all(|v| v.is_finite()) {
        Ok(())
    } else {
        Err(LixelError::NonFinite { what })
    }
}
