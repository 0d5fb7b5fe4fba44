//! Convex geometry for fitting light matrices.
//!
//! Every body a method needs — the view frustum `V`, scene boxes, PSM's hull
//! `conv(V ∪ {l}) ∩ S ∩ L`, `V` extruded towards a directional light — is a
//! [`ConvexPolyhedron`] cut by [`Plane`]s (half-spaces). The directions from a
//! light to a body are bounded by a [`Cone`] ([`min_enclosing_cone`]).
//!
//! # Conventions
//!
//! * A [`Plane`] keeps the half-space `normal · x + offset <= 0` (the
//!   *inside*); its normal is unit length and points outwards.
//! * Face loops of a [`ConvexPolyhedron`] are counter-clockwise seen from
//!   outside, and adjacent faces share vertex indices.
//!
//! # Tolerances
//!
//! Bodies span roughly `1e-3 .. 1e5` units, so every tolerance is a distance
//! relative to the size of the body: [`default_eps`] gives `1e-9 * scale`
//! and [`ConvexPolyhedron::default_eps`] applies it to a body. Points within
//! `eps` of a plane count as lying on it. Results are conservative where a
//! choice exists: near-degenerate input grows a body by at most about `eps`
//! rather than dropping part of it.

mod clip;
mod cone;
mod lp;
mod plane;
mod polyhedron;
mod validation;

pub use clip::ClipWorkspace;
pub(crate) use cone::min_enclosing_cone_in;
pub use cone::{min_enclosing_cone, Cone};
pub(crate) use lp::maximize_in_box;
pub use plane::Plane;
pub(crate) use polyhedron::padded_box;
pub use polyhedron::{ConvexPolyhedron, Face};

use glam::DVec3;

/// The default distance tolerance for geometry of size `scale` (for example a
/// bounding-box diagonal): `1e-9 * scale`.
///
/// `1e-9` sits about seven orders of magnitude above the rounding error of an
/// `f64` signed distance (`~1e-16 * scale`), so rounding never flips a
/// classification, yet far below any distance that matters for a shadow map.
/// A zero, negative or NaN `scale` is treated as `1e-300`, so the result is
/// always positive and finite for finite input.
#[must_use]
pub fn default_eps(scale: f64) -> f64 {
    1e-9 * scale.max(1e-300)
}

/// `u × v` with every component correctly rounded up to one extra rounding.
///
/// # Algorithm
///
/// Each component `a*b - c*d` uses Kahan's fused-multiply-add difference of
/// products, so cancellation between the two products loses no accuracy. This
/// makes planes through nearly collinear points backward stable: the plane
/// passes within rounding of all three points even when its normal is
/// ill-conditioned.
#[must_use]
pub(crate) fn accurate_cross(u: DVec3, v: DVec3) -> DVec3 {
    DVec3::new(
        diff_of_products(u.y, v.z, u.z, v.y),
        diff_of_products(u.z, v.x, u.x, v.z),
        diff_of_products(u.x, v.y, u.y, v.x),
    )
}

/// `a*b - c*d` with a single rounding (Kahan).
fn diff_of_products(a: f64, b: f64, c: f64, d: f64) -> f64 {
    let cd = c * d;
    // Exact rounding error of `cd`: `cd - c*d`.
    let err = (-c).mul_add(d, cd);
    a.mul_add(b, -cd) + err
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_eps_is_relative_and_positive() {
        assert_eq!(default_eps(2.0), 2e-9);
        assert!(default_eps(0.0) > 0.0);
        assert!(default_eps(f64::NAN) > 0.0);
        assert!(default_eps(-1.0) > 0.0);
    }

    #[test]
    fn accurate_cross_matches_cross_and_resolves_cancellation() {
        let u = DVec3::new(1.0, 2.0, 3.0);
        let v = DVec3::new(-4.0, 0.5, 2.0);
        assert!((accurate_cross(u, v) - u.cross(v)).length() < 1e-14);
        // Nearly parallel vectors: the naive cross product cancels badly.
        let u = DVec3::new(1.0, 1.0 + 2f64.powi(-40), 1.0);
        let v = DVec3::new(1.0 + 2f64.powi(-52), 1.0, 1.0);
        let (a, b) = (2f64.powi(-40), 2f64.powi(-52));
        let exact = DVec3::new(a, b, -(a + b + a * b));
        let c = accurate_cross(u, v);
        assert!((c - exact).length() <= 1e-15 * exact.length(), "{c} vs {exact}");
    }
}
