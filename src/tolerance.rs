//! Named numeric tolerances, in one place.

/// Every tolerance the solver uses, with documented defaults.
///
/// Lengths are relative to the *problem scale*: the diagonal of the scene
/// bounds united with the part of the view frustum inside them, so the same
/// defaults serve millimetre and kilometre scenes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tolerances {
    /// Distance below which a point counts as lying on a clipping plane,
    /// relative to the problem scale. Default `1e-9`.
    pub plane_eps: f64,
    /// Boxes thinner than this (relative to their diagonal) are padded to
    /// this thickness, conservatively. Default `1e-9`.
    pub box_pad: f64,
    /// Smallest `j·X~ / |X~|` (cosine to the optical axis) a relevant point may
    /// have: points closer to the light's vanishing line than this are
    /// treated as "behind the light". Default `1e-6`.
    pub min_front_cosine: f64,
    /// Smallest ratio `near / far` of a point light's depth range. When
    /// casters come closer to the light than this, near is clamped and the
    /// matrix requests unclipped depth (casters in front of near then
    /// rasterize at depth 0 and still occlude). Default `1e-4`.
    pub min_near_far_ratio: f64,
    /// Relative padding of the depth range on both ends. Default `1e-5`.
    pub depth_pad: f64,
    /// LiSPSM falls back to a uniform map when `sin γ` (the angle between the
    /// view and light directions) is below this. Default `1e-3`.
    pub lispsm_min_sin_gamma: f64,
    /// PSM treats the light as directional in post-perspective space when
    /// `|w'| / |xyz'|` of the transformed light is below this. Default `1e-9`.
    pub psm_directional_w: f64,
}

impl Default for Tolerances {
    fn default() -> Self {
        Self {
            plane_eps: 1e-9,
            box_pad: 1e-9,
            min_front_cosine: 1e-6,
            min_near_far_ratio: 1e-4,
            depth_pad: 1e-5,
            lispsm_min_sin_gamma: 1e-3,
            psm_directional_w: 1e-9,
        }
    }
}
