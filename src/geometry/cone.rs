//! The smallest circular cone around a set of directions.

use glam::DVec3;

use super::accurate_cross;

/// A circular cone with its apex at the origin: the directions `u` with
/// `axis · u >= cos_half_angle` once `u` is normalized.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cone {
    /// Unit axis.
    pub axis: DVec3,
    /// Cosine of the half opening angle.
    pub cos_half_angle: f64,
}

impl Cone {
    /// Whether the direction `dir` (of any length) lies in the cone; `false`
    /// for a zero or non-finite `dir`.
    ///
    /// Normalizes exactly as [`min_enclosing_cone`] does, so every direction
    /// that function was given is contained in its result.
    #[must_use]
    pub fn contains(&self, dir: DVec3) -> bool {
        unit(dir).is_some_and(|u| self.axis.dot(u) >= self.cos_half_angle)
    }

    /// The half opening angle in radians.
    #[must_use]
    pub fn half_angle(&self) -> f64 {
        self.cos_half_angle.clamp(-1.0, 1.0).acos()
    }
}

/// The smallest circular cone (apex at the origin) containing every direction
/// in `dirs`.
///
/// The directions need not be normalized; zero and non-finite vectors are
/// skipped. Returns `None` when no usable direction is left, or when they do
/// not fit in an open hemisphere: the smallest cone would not be convex, so
/// the result is refused once its `cos_half_angle` is `1e-12` or less.
///
/// The result contains every input exactly in the sense of
/// [`Cone::contains`]: `cos_half_angle` is the least `axis · u` over the
/// normalized inputs `u`. It is minimal to within about `1e-14` radians.
///
/// # Algorithm
///
/// Welzl's randomized incremental algorithm, adapted to spherical caps
/// (which is what a cone cuts out of the unit sphere): the smallest cap with
/// one, two or three given directions on its rim is the direction itself,
/// the cap around their normalized sum, or the cap whose rim is the circle
/// through them (axis along the normal of their plane, on their side of the
/// origin). The input is shuffled by a fixed-seed generator, so the result is
/// deterministic while the expected running time stays linear. Caps are
/// compared by chord length `|u - axis|` rather than by cosine, which keeps
/// full precision for narrow cones.
#[must_use]
pub fn min_enclosing_cone(dirs: &[DVec3]) -> Option<Cone> {
    min_enclosing_cone_in(dirs, &mut Vec::new())
}

/// [`min_enclosing_cone`] with `units` as scratch for the normalized
/// directions (no allocation once it is large enough).
pub(crate) fn min_enclosing_cone_in(dirs: &[DVec3], units: &mut Vec<DVec3>) -> Option<Cone> {
    units.clear();
    units.extend(dirs.iter().filter_map(|&d| unit(d)));
    shuffle(units);
    let units = units.as_slice();
    let (&first, _) = units.split_first()?;

    // The loops run over the slices before each index (no bounds checks).
    let mut cap = Cap::point(first);
    for (i, &ui) in units.iter().enumerate().skip(1) {
        if cap.contains(ui) {
            continue;
        }
        cap = Cap::point(ui);
        for (j, &uj) in units[..i].iter().enumerate() {
            if cap.contains(uj) {
                continue;
            }
            cap = Cap::through_two(ui, uj)?;
            for &uk in &units[..j] {
                if !cap.contains(uk) {
                    cap = Cap::through_three(ui, uj, uk)?;
                }
            }
        }
    }

    // The least cosine by plain compares (`f64::min` checks for NaN each
    // time; a NaN is passed over either way, and a zero fails the bound
    // whatever its sign).
    let mut cos_half_angle = f64::INFINITY;
    for &u in units.iter() {
        let c = cap.axis.dot(u);
        if c < cos_half_angle {
            cos_half_angle = c;
        }
    }
    (cos_half_angle > 1e-12).then_some(Cone { axis: cap.axis, cos_half_angle })
}

/// `d` normalized, or `None` if zero or not finite. Scaling by the largest
/// component first keeps huge and tiny vectors from overflowing.
fn unit(d: DVec3) -> Option<DVec3> {
    (d / d.abs().max_element()).try_normalize()
}

/// A cap of the unit sphere: the unit vectors within a chord distance of
/// `axis` (the farthest of its rim, found when it is made).
#[derive(Clone, Copy, Debug)]
struct Cap {
    axis: DVec3,
    /// `chord + SLACK`, the bound [`Cap::contains`] tests against (summed
    /// once per cap rather than once per test; the same sum).
    reach: f64,
}

impl Cap {
    /// Slack on the chord when testing containment, against rounding.
    const SLACK: f64 = 1e-14;

    fn new(axis: DVec3, chord: f64) -> Cap {
        Cap { axis, reach: chord + Self::SLACK }
    }

    fn point(u: DVec3) -> Cap {
        Cap::new(u, 0.0)
    }

    /// The cap around `axis` reaching just the farthest of `rim`.
    fn around(axis: DVec3, rim: &[DVec3]) -> Cap {
        let chord = rim.iter().map(|&u| (u - axis).length()).fold(0.0, f64::max);
        Cap::new(axis, chord)
    }

    /// The smallest cap with `u` and `v` on its rim; `None` when they are
    /// opposite (no cap smaller than a hemisphere contains both).
    fn through_two(u: DVec3, v: DVec3) -> Option<Cap> {
        Some(Cap::around((u + v).try_normalize()?, &[u, v]))
    }

    /// The cap whose rim passes through `u`, `v` and `w`. When they are
    /// collinear on the sphere to within rounding (a great circle can pass
    /// through any three such points), the cap through the farthest pair.
    fn through_three(u: DVec3, v: DVec3, w: DVec3) -> Option<Cap> {
        let (uv, uw) = (v - u, w - u);
        let normal = accurate_cross(uv, uw);
        if normal.length() > 8.0 * f64::EPSILON * uv.length() * uw.length() {
            let axis = normal.normalize();
            let axis = if axis.dot(u + v + w) < 0.0 { -axis } else { axis };
            return Some(Cap::around(axis, &[u, v, w]));
        }
        let vw = w - v;
        let (a, b) = if uv.length() >= uw.length().max(vw.length()) {
            (u, v)
        } else if uw.length() >= vw.length() {
            (u, w)
        } else {
            (v, w)
        };
        Cap::through_two(a, b)
    }

    fn contains(&self, u: DVec3) -> bool {
        (u - self.axis).length() <= self.reach
    }
}

/// Fisher–Yates shuffle driven by SplitMix64 from a fixed seed. The swaps
/// depend only on the length: up to [`SWAPS_UP_TO`] items they are read
/// from a table made at compile time by the same generator ([`swaps`]), so
/// no 64-bit division is left at run time.
fn shuffle<T>(items: &mut [T]) {
    let n = items.len();
    if let Some(row) = SWAPS.get(n) {
        for i in (1..n).rev() {
            items.swap(i, usize::from(row[i]));
        }
    } else {
        shuffle_by_generator(items);
    }
}

/// The shuffle's generator: SplitMix64 from the fixed seed, one draw per
/// position from the last down, each reduced modulo the position plus one.
const fn splitmix_swap(state: &mut u64, i: usize) -> usize {
    *state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    (z % (i as u64 + 1)) as usize
}

const SEED: u64 = 0x853C_49E6_748F_EA9B;

/// [`shuffle`] without the table (any length).
fn shuffle_by_generator<T>(items: &mut [T]) {
    let mut state = SEED;
    for i in (1..items.len()).rev() {
        let j = splitmix_swap(&mut state, i);
        items.swap(i, j);
    }
}

/// Longest input whose swaps are tabled.
const SWAPS_UP_TO: usize = 64;

/// `SWAPS[n][i]`: the index position `i` swaps with when `n` items are
/// shuffled (`i` from `n - 1` down to 1, as [`shuffle_by_generator`] draws).
static SWAPS: [[u8; SWAPS_UP_TO]; SWAPS_UP_TO + 1] = swaps();

const fn swaps() -> [[u8; SWAPS_UP_TO]; SWAPS_UP_TO + 1] {
    let mut table = [[0u8; SWAPS_UP_TO]; SWAPS_UP_TO + 1];
    let mut n = 2;
    while n <= SWAPS_UP_TO {
        let mut state = SEED;
        let mut i = n - 1;
        while i >= 1 {
            // `j <= i < 64`: fits in a byte.
            table[n][i] = splitmix_swap(&mut state, i) as u8;
            i -= 1;
        }
        n += 1;
    }
    table
}

#[cfg(test)]
mod tests {
    use super::*;

    fn assert_contains_all(cone: &Cone, dirs: &[DVec3]) {
        for &d in dirs {
            if unit(d).is_some() {
                assert!(cone.contains(d), "{d} outside {cone:?}");
            }
        }
    }

    #[test]
    fn one_and_two_directions() {
        let cone = min_enclosing_cone(&[DVec3::new(0.0, 0.0, 3.0)]).unwrap();
        assert_eq!(cone.axis, DVec3::Z);
        assert_eq!(cone.cos_half_angle, 1.0);

        let dirs = [DVec3::X, DVec3::new(0.0, 2.0, 0.0)];
        let cone = min_enclosing_cone(&dirs).unwrap();
        assert!((cone.axis - DVec3::new(1.0, 1.0, 0.0).normalize()).length() < 1e-15);
        assert!((cone.half_angle() - std::f64::consts::FRAC_PI_4).abs() < 1e-14);
        assert_contains_all(&cone, &dirs);
    }

    #[test]
    fn three_axes() {
        let dirs = [DVec3::X, DVec3::Y, DVec3::Z];
        let cone = min_enclosing_cone(&dirs).unwrap();
        assert!((cone.axis - DVec3::ONE.normalize()).length() < 1e-15);
        assert!((cone.cos_half_angle - 1.0 / 3f64.sqrt()).abs() < 1e-15);
        assert_contains_all(&cone, &dirs);
        // An interior direction changes nothing.
        let more = [DVec3::X, DVec3::ONE, DVec3::Y, DVec3::Z, DVec3::new(1.0, 2.0, 1.0)];
        let cone2 = min_enclosing_cone(&more).unwrap();
        assert!((cone2.cos_half_angle - cone.cos_half_angle).abs() < 1e-14);
    }

    #[test]
    fn obtuse_triangle_uses_two_points() {
        // The middle direction lies inside the cap of the outer two.
        let dirs = [DVec3::new(1.0, 0.0, 1.0), DVec3::new(-1.0, 0.0, 1.0), DVec3::new(0.0, 0.1, 1.0)];
        let cone = min_enclosing_cone(&dirs).unwrap();
        assert!((cone.axis - DVec3::Z).length() < 1e-15);
        assert!((cone.half_angle() - std::f64::consts::FRAC_PI_4).abs() < 1e-14);
    }

    #[test]
    fn not_in_a_hemisphere() {
        assert!(min_enclosing_cone(&[DVec3::X, DVec3::NEG_X]).is_none());
        assert!(min_enclosing_cone(&[DVec3::X, DVec3::Y, DVec3::NEG_X]).is_none());
        let tetrahedron = [
            DVec3::new(1.0, 1.0, 1.0),
            DVec3::new(1.0, -1.0, -1.0),
            DVec3::new(-1.0, 1.0, -1.0),
            DVec3::new(-1.0, -1.0, 1.0),
        ];
        assert!(min_enclosing_cone(&tetrahedron).is_none());
        let axes = [DVec3::X, DVec3::Y, DVec3::Z, DVec3::NEG_X, DVec3::NEG_Y, DVec3::NEG_Z];
        assert!(min_enclosing_cone(&axes).is_none());
        // Exactly a hemisphere's rim is refused too.
        assert!(min_enclosing_cone(&[DVec3::X, DVec3::Y, DVec3::NEG_X, DVec3::Z]).is_none());
    }

    #[test]
    fn unusable_input() {
        assert!(min_enclosing_cone(&[]).is_none());
        assert!(min_enclosing_cone(&[DVec3::ZERO, DVec3::NAN, DVec3::INFINITY]).is_none());
        let cone = min_enclosing_cone(&[DVec3::ZERO, DVec3::Y, DVec3::NAN]).unwrap();
        assert_eq!(cone.axis, DVec3::Y);
        // Huge and tiny vectors are still directions.
        let cone = min_enclosing_cone(&[DVec3::new(1e300, 1e300, 0.0), DVec3::new(1e-320, 0.0, 0.0)]).unwrap();
        assert!((cone.half_angle() - std::f64::consts::FRAC_PI_8).abs() < 1e-14);
        assert!(!cone.contains(DVec3::ZERO));
    }

    /// The tabled swaps are the generator's: every length up to the table's
    /// and one past it give the generator's permutation.
    #[test]
    fn tabled_shuffle_equals_the_generator() {
        for n in 0..=SWAPS_UP_TO + 1 {
            let mut tabled: Vec<usize> = (0..n).collect();
            let mut drawn = tabled.clone();
            shuffle(&mut tabled);
            shuffle_by_generator(&mut drawn);
            assert_eq!(tabled, drawn, "{n} items");
            if n >= 8 {
                assert_ne!(drawn, (0..n).collect::<Vec<_>>(), "{n} items left in order");
            }
        }
    }

    #[test]
    fn narrow_cone_keeps_precision() {
        let spread = 1e-9;
        let dirs: Vec<DVec3> = (0..7)
            .map(|k| {
                let a = k as f64;
                DVec3::new(spread * a.cos(), spread * a.sin(), 1.0) + DVec3::new(3.0, -2.0, 5.0)
            })
            .collect();
        let cone = min_enclosing_cone(&dirs).unwrap();
        assert_contains_all(&cone, &dirs);
        // Half angle about spread / |offset|, certainly well below 1e-8.
        let angle = dirs.iter().map(|d| unit(*d).unwrap().cross(cone.axis).length()).fold(0.0, f64::max);
        assert!(angle < 1e-9, "{angle}");
    }
}
