//! Oriented planes, each bounding a half-space.

use glam::{DVec3, DVec4};

use super::accurate_cross;

/// The plane `normal · x + offset = 0`, bounding the half-space
/// `normal · x + offset <= 0`: its *inside*, the side that clipping keeps.
///
/// Every constructor here returns a unit `normal`, which points outwards (away
/// from the inside), so [`Plane::signed_distance`] is a Euclidean distance:
/// negative inside, positive outside. The fields are public; a plane built by
/// hand with a non-unit normal still classifies points correctly, but its
/// distances, and the tolerances compared with them, scale by `|normal|`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Plane {
    /// Unit outward normal.
    pub normal: DVec3,
    /// `-normal · p` for any point `p` on the plane.
    pub offset: f64,
}

impl Plane {
    /// The plane through `point` with outward normal `normal`, which is
    /// normalized here.
    ///
    /// A zero or non-finite `normal` gives a non-finite plane (see
    /// [`Plane::is_finite`]); clipping by one yields an empty body.
    #[must_use]
    pub fn from_point_normal(point: DVec3, normal: DVec3) -> Plane {
        let normal = normal / normal.length();
        Plane { normal, offset: -normal.dot(point) }
    }

    /// The plane through `a`, `b` and `c`, with outward normal along
    /// `(b - a) × (c - a)`: the points run counter-clockwise seen from
    /// outside.
    ///
    /// Returns `None` when the points are collinear to within rounding
    /// (the sine of the angle at `a` is below `8 * f64::EPSILON`) or not
    /// finite.
    ///
    /// # Algorithm
    ///
    /// The cross product is evaluated with Kahan's fused multiply-add
    /// difference of products, so the plane passes within rounding of all
    /// three points even when they are nearly collinear; the offset is taken
    /// at their centroid.
    #[must_use]
    pub fn through_points(a: DVec3, b: DVec3, c: DVec3) -> Option<Plane> {
        let (ab, ac) = (b - a, c - a);
        let n = accurate_cross(ab, ac);
        let len = n.length();
        let floor = 8.0 * f64::EPSILON * ab.length() * ac.length();
        if !(len > floor) || !len.is_finite() {
            return None;
        }
        let normal = n / len;
        let offset = -normal.dot((a + b + c) / 3.0);
        offset.is_finite().then_some(Plane { normal, offset })
    }

    /// The plane `h.x * x + h.y * y + h.z * z + h.w = 0` with inside
    /// `h · (x, 1) <= 0`, normalized so that the normal is unit length.
    ///
    /// This is the form in which planes come out of a clip matrix: with
    /// `r0 .. r3` the rows of `clip_from_world`, the clip-space condition
    /// `x <= w` reads `(r0 - r3) · (x, 1) <= 0`. (Gribb–Hartmann's planes,
    /// `h · (x, 1) >= 0` inside, need negating: `from_homogeneous(-h)`.)
    ///
    /// Returns `None` when `h` is not finite or its normal part is zero.
    ///
    /// ```
    /// use glam::{DMat4, DVec3};
    /// use lixel::geometry::Plane;
    ///
    /// let clip_from_world = DMat4::IDENTITY;
    /// let right = Plane::from_homogeneous(clip_from_world.row(0) - clip_from_world.row(3)).unwrap();
    /// assert_eq!(right.signed_distance(DVec3::new(3.0, 0.0, 0.0)), 2.0);
    /// ```
    #[must_use]
    pub fn from_homogeneous(h: DVec4) -> Option<Plane> {
        let len = h.truncate().length();
        if !(len > 0.0) || !h.is_finite() {
            return None;
        }
        let plane = Plane { normal: h.truncate() / len, offset: h.w / len };
        plane.is_finite().then_some(plane)
    }

    /// The homogeneous vector `(normal, offset)`: `h · (x, 1)` is the signed
    /// distance of `x`.
    #[must_use]
    pub fn to_homogeneous(self) -> DVec4 {
        self.normal.extend(self.offset)
    }

    /// Signed distance of `x` from the plane: negative inside, positive
    /// outside.
    #[must_use]
    pub fn signed_distance(&self, x: DVec3) -> f64 {
        self.normal.dot(x) + self.offset
    }

    /// The same plane bounding the opposite half-space.
    #[must_use]
    pub fn flipped(self) -> Plane {
        Plane { normal: -self.normal, offset: -self.offset }
    }

    /// The plane moved `distance` outwards (along its normal): its kept
    /// half-space grows by `distance` (shrinks for a negative one).
    #[must_use]
    pub fn grown(self, distance: f64) -> Plane {
        Plane { normal: self.normal, offset: self.offset - distance }
    }

    /// Whether the normal and offset are finite.
    #[must_use]
    pub fn is_finite(&self) -> bool {
        self.normal.is_finite() && self.offset.is_finite()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn from_point_normal_normalizes() {
        let p = Plane::from_point_normal(DVec3::new(0.0, 0.0, 2.0), DVec3::new(0.0, 0.0, 5.0));
        assert_eq!(p.normal, DVec3::Z);
        assert_eq!(p.offset, -2.0);
        assert_eq!(p.signed_distance(DVec3::new(7.0, -3.0, 5.0)), 3.0);
        assert!(p.signed_distance(DVec3::ZERO) < 0.0);
        assert!(!Plane::from_point_normal(DVec3::ONE, DVec3::ZERO).is_finite());
    }

    #[test]
    fn through_points_orientation_and_degeneracy() {
        let p = Plane::through_points(DVec3::X, DVec3::Y, DVec3::Z).unwrap();
        let expected = DVec3::ONE.normalize();
        assert!((p.normal - expected).length() < 1e-15);
        assert!((p.offset + 1.0 / 3f64.sqrt()).abs() < 1e-15);
        assert!(p.signed_distance(DVec3::ZERO) < 0.0);

        // Clockwise from +n: flipped.
        let q = Plane::through_points(DVec3::X, DVec3::Z, DVec3::Y).unwrap();
        assert!((q.normal + expected).length() < 1e-15);

        assert!(Plane::through_points(DVec3::ZERO, DVec3::X, 2.0 * DVec3::X).is_none());
        assert!(Plane::through_points(DVec3::ONE, DVec3::ONE, DVec3::X).is_none());
        assert!(Plane::through_points(DVec3::NAN, DVec3::X, DVec3::Y).is_none());
        assert!(Plane::through_points(DVec3::INFINITY, DVec3::X, DVec3::Y).is_none());
    }

    #[test]
    fn through_nearly_collinear_points_stays_on_them() {
        // Far-away third point barely off the line through the first two.
        let a = DVec3::new(1.0, 2.0, 3.0);
        let b = DVec3::new(1.5, 2.0, 3.0);
        let c = DVec3::new(1e4, 2.0 + 1e-7, 3.0 - 3e-8);
        let p = Plane::through_points(a, b, c).unwrap();
        for x in [a, b, c] {
            assert!(p.signed_distance(x).abs() < 1e-11, "{}", p.signed_distance(x));
        }
    }

    #[test]
    fn flipped_and_homogeneous() {
        let p = Plane::from_point_normal(DVec3::new(1.0, 2.0, 3.0), DVec3::new(1.0, -1.0, 0.5));
        let x = DVec3::new(-0.3, 4.0, 9.0);
        assert_eq!(p.flipped().signed_distance(x), -p.signed_distance(x));
        assert_eq!(p.flipped().flipped(), p);
        let h = p.to_homogeneous();
        assert!((h.dot(x.extend(1.0)) - p.signed_distance(x)).abs() < 1e-14);
        let q = Plane::from_homogeneous(h * 7.0).unwrap();
        assert!((q.normal - p.normal).length() < 1e-15 && (q.offset - p.offset).abs() < 1e-14);
        assert!(Plane::from_homogeneous(DVec4::new(0.0, 0.0, 0.0, 1.0)).is_none());
        assert!(Plane::from_homogeneous(DVec4::new(1.0, 0.0, f64::NAN, 1.0)).is_none());
        assert!(Plane::from_homogeneous(DVec4::new(1.0, 0.0, 0.0, f64::INFINITY)).is_none());
    }
}
