//! The affine part of a shadow map's light matrix.
//!
//! Points that need shadow-map samples (visible surface points, or a
//! conservative sample of them) are projected to the light's image plane.
//! This module chooses the 2D affine map from that plane to the shadow map's
//! NDC square: it encloses the points in the smallest rectangle it can and
//! stretches that rectangle over the map, so that no texels are spent on the
//! plane outside it.
//!
//! Following Chong & Gortler 2006, *Scene Optimized Shadow Mapping*,
//! section 2.3:
//!
//! 1. [`convex_hull_2d`] takes the convex hull of the projected points;
//! 2. [`min_area_rect`] finds the minimum-area rectangle enclosing the hull,
//!    which has a side flush with a hull edge (Freeman & Shapira 1975,
//!    \[FS75\]), so only the hull's edges need to be tried;
//! 3. optionally, [`min_area_sheared`] applies the paper's affine skew
//!    heuristic: for each hull edge, the rectangle's other pair of sides is
//!    sheared to line up with the hull, which gives the minimum-area enclosing
//!    parallelogram and wastes fewer samples;
//! 4. [`fit_affine`] maps the longer side of the result to the map's larger
//!    dimension and grows it by a small margin of texels, as the points are
//!    only a sub-sample of what the map must cover.
//!
//! Everything is in `f64`; the hull uses exact orientation predicates, so its
//! combinatorics are never wrong. [`FitWorkspace`] and
//! [`convex_hull_2d_into`] reuse their buffers for callers that fit many
//! point sets per frame.

mod affine;
mod hull;
mod rect;

pub use affine::{fit_affine, AffineFit, AffineFitOptions, FitError, FitWorkspace};
pub use hull::{convex_hull_2d, convex_hull_2d_into};
pub use rect::{min_area_rect, min_area_sheared, Parallelogram};
