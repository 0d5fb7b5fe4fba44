//! Named numeric tolerances and limits, in one place.

/// The largest coordinate magnitude the solver accepts (`|x| <= 1e15`), in
/// every input position: camera eye, light position, scene bounds, receiver
/// plane, samples. Beyond it squared lengths approach overflow and the rounding
/// of a single coordinate (`1e15 · 2⁻⁵²` ≈ 0.2) swamps any scene of ordinary
/// size; inputs beyond it are [`LixelError::OutOfRange`](crate::LixelError)
/// (samples beyond it are dropped as invalid).
pub const MAX_COORDINATE: f64 = 1e15;

/// The most lights one shadow bitmask (a `u32` per pixel) can carry: the
/// analysis readback, the scheduler and the renderer's light slots share it.
pub const MAX_LIGHTS: usize = 32;

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
    /// Coarser distance, relative to the problem scale, within which a point
    /// counts as lying *on* a receiver plane (plane-optimal's visible slab)
    /// or *at* the light (a body vertex at a spot light's apex, PSM's hull
    /// touching the light): such points have no direction from the light and
    /// are left to the neighbouring ones. Default `1e-6`.
    pub coarse_eps: f64,
    /// Boxes thinner than this (relative to their diagonal) are padded to
    /// this thickness, conservatively. Default `1e-9`.
    pub box_pad: f64,
    /// Smallest `j·X~ / |X~|` (cosine to the optical axis) a relevant point may
    /// have, relative to the largest one over the points the map holds:
    /// points closer to the light's vanishing line than this are treated as
    /// "behind the light". Relative, so that a far point light (whose map's
    /// field of view is tiny) is judged like the directional light it
    /// approaches. Default `1e-6`.
    pub min_front_cosine: f64,
    /// Smallest ratio `near / far` of a point light's depth range. When
    /// casters come closer to the light than this, near is clamped and the
    /// matrix requests unclipped depth (casters in front of near then
    /// rasterize at depth 0 and still occlude). Default `1e-4`.
    pub min_near_far_ratio: f64,
    /// Relative padding of the depth range on both ends. Default `1e-5`.
    pub depth_pad: f64,
    /// Smallest extent of a depth or distance range relative to its
    /// magnitude: thinner ranges (every point at one depth) are widened to
    /// it, so no depth row divides by zero. Default `1e-9`.
    pub min_relative_span: f64,
    /// A 3x3 matrix counts as singular when `|det|` is below this times the
    /// product of its column lengths (Hadamard's bound), a scale-free test.
    /// Default `1e-12`.
    pub singular_det: f64,
    /// A boundary sample whose surface is seen this close to edge-on (sine of
    /// the angle between its two screen-space tangent images) has no usable
    /// derivative and is dropped. Default `1e-6`.
    pub min_view_sine: f64,
    /// LiSPSM falls back to a uniform map when `sin γ` (the angle between the
    /// view and light directions) is below this. Default `1e-3`.
    pub lispsm_min_sin_gamma: f64,
    /// PSM treats the light as directional in post-perspective space when
    /// `|w'| / |xyz'|` of the transformed light is below this. Default `1e-9`.
    pub psm_directional_w: f64,
    /// Bisection steps of plane-optimal's blend towards the focused axis
    /// (`2⁻⁴⁰` of the blend range). Default `40`.
    pub blend_bisection_steps: u32,
    /// Slack, in NDC units, of the final coverage check every matrix passes
    /// (each point it must hold lands within `1 + slack` of the centre).
    /// Default `1e-6`.
    pub coverage_slack: f64,
}

impl Default for Tolerances {
    fn default() -> Self {
        Self {
            plane_eps: 1e-9,
            coarse_eps: 1e-6,
            box_pad: 1e-9,
            min_front_cosine: 1e-6,
            min_near_far_ratio: 1e-4,
            depth_pad: 1e-5,
            min_relative_span: 1e-9,
            singular_det: 1e-12,
            min_view_sine: 1e-6,
            lispsm_min_sin_gamma: 1e-3,
            psm_directional_w: 1e-9,
            blend_bisection_steps: 40,
            coverage_slack: 1e-6,
        }
    }
}
