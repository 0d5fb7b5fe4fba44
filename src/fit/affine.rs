//! The affine fit: map a fitted rectangle (or parallelogram) onto the shadow
//! map's NDC square.

use glam::{DMat2, DMat3, DVec2};

use super::hull::{convex_hull_of_finite_into, convex_hull_of_polygon_into};
use super::rect::{bounding_rect_along, min_area_rect, min_area_sheared, Parallelogram};

/// Padding floor relative to the larger extent: a fit is never thinner than
/// this fraction of its width, which bounds the aspect ratio of the map.
const MIN_EXTENT_PER_LARGER_EXTENT: f64 = 1e-6;

/// Padding floor relative to the largest coordinate magnitude of the input.
///
/// Applying `ndc_from_plane` to a point at magnitude `r` rounds by about
/// `4ε·r / extent` in NDC; with extents of at least `1e-9·r` that stays below
/// `1e-6` NDC, a small fraction of a texel for maps up to `2²⁰` texels.
const MIN_EXTENT_PER_MAGNITUDE: f64 = 1e-9;

/// Absolute padding floor, whatever the options: keeps `1 / extent` finite
/// for any input, including a single point at the origin.
const MIN_EXTENT_ABSOLUTE: f64 = 1e-150;

/// Why [`fit_affine`] could not fit.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum FitError {
    /// There were no points to fit.
    #[error("no points to fit")]
    NoPoints,
    /// The point at `index` has a NaN or infinite coordinate.
    #[error("point {index} has a non-finite coordinate")]
    NonFinite {
        /// Index of the first offending point in the input slice.
        index: usize,
    },
    /// The shadow map has zero width or height.
    #[error("shadow map width and height must be non-zero")]
    ZeroMapSize,
}

/// Options for [`fit_affine`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AffineFitOptions {
    /// Empty border, in texels, between the fitted frame and each edge of the
    /// map; the points are sub-sampled, so the frame is grown a little to keep
    /// their neighbourhood on the map. Clamped per axis to `[0, (n − 1) / 2]`
    /// for an axis of `n` texels, so that at least one texel of interior
    /// remains; NaN counts as `0`. Default `1.0`.
    pub margin_texels: f64,
    /// Fit the minimum-area parallelogram ([`min_area_sheared`]) instead of
    /// the minimum-area rectangle ([`min_area_rect`]): a sheared frame wastes
    /// fewer texels at the cost of skewed texels. The shear is unbounded; the
    /// minimum-area parallelogram of an irregular hull can be strongly skewed.
    /// Falls back to the rectangle when the parallelogram is thin enough to
    /// need padding (see [`min_extent`](Self::min_extent)), where its skew
    /// would be arbitrary. Default `false`.
    pub shear: bool,
    /// Least width of the frame, in the units of the input points. A thinner
    /// extent (from a single point, collinear points or a sliver of a hull) is
    /// padded symmetrically to `max(min_extent, 1e-6 × larger extent)`; see
    /// [`fit_affine`] for the full rule. Default `1e-9`.
    pub min_extent: f64,
}

impl Default for AffineFitOptions {
    fn default() -> Self {
        Self { margin_texels: 1.0, shear: false, min_extent: 1e-9 }
    }
}

/// The result of [`fit_affine`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AffineFit {
    /// Affine map from the plane to NDC (x right, y up, both in `[-1, 1]`):
    /// multiplies the homogeneous point `(s.x, s.y, 1)` to
    /// `(ndc_x, ndc_y, 1)`. Its last row is `(0, 0, 1)` and its linear part
    /// has a positive determinant (no mirroring).
    pub ndc_from_plane: DMat3,
    /// The fitted parallelogram in the plane, padded where it was too thin,
    /// and oriented for the map: `origin` maps to the inner lower-left corner
    /// `(−1 + 2m_x/W, −1 + 2m_y/H)`, `edge_u` runs along NDC `+x` and
    /// `edge_v` along NDC `+y`, where `m_x`, `m_y` are the clamped margins.
    /// So `frame.to_unit(s)` is the position of `s` across the map's
    /// interior, as fractions along NDC `x` and `y` (y up).
    pub frame: Parallelogram,
}

impl AffineFit {
    /// The NDC position of the plane point `s`: `ndc_from_plane · (s, 1)`.
    #[must_use]
    pub fn to_ndc(&self, s: DVec2) -> DVec2 {
        (self.ndc_from_plane * s.extend(1.0)).truncate()
    }
}

/// Reusable buffers for [`fit_affine`], for callers that fit many point sets.
///
/// Once its buffers have grown to the largest input, [`FitWorkspace::fit`]
/// does not allocate.
#[derive(Clone, Debug, Default)]
pub struct FitWorkspace {
    sorted: Vec<DVec2>,
    hull: Vec<DVec2>,
}

impl FitWorkspace {
    /// An empty workspace; buffers grow on first use.
    #[must_use]
    pub fn new() -> Self {
        Self::default()
    }

    /// The convex hull of the points of the last successful [`fit`](Self::fit),
    /// counter-clockwise (see [`convex_hull_2d`](super::convex_hull_2d)); empty
    /// before the first fit and after a failed one.
    #[must_use]
    pub fn hull(&self) -> &[DVec2] {
        &self.hull
    }

    /// [`fit_affine`], reusing this workspace's buffers.
    ///
    /// # Errors
    ///
    /// As [`fit_affine`].
    pub fn fit(
        &mut self,
        points: &[DVec2],
        map_width: u32,
        map_height: u32,
        options: &AffineFitOptions,
    ) -> Result<AffineFit, FitError> {
        self.fit_hull_of(points, map_width, map_height, options, false)
    }

    /// [`fit`](Self::fit) of points that are expected to be a strictly
    /// convex polygon's vertices in order (an earlier hull's, projected
    /// onto another plane): their hull is then taken without a sort, and
    /// the fit is `fit`'s bit for bit whether they are or not (see
    /// `hull::convex_hull_of_polygon_into`).
    pub(crate) fn fit_polygon(
        &mut self,
        points: &[DVec2],
        map_width: u32,
        map_height: u32,
        options: &AffineFitOptions,
    ) -> Result<AffineFit, FitError> {
        self.fit_hull_of(points, map_width, map_height, options, true)
    }

    fn fit_hull_of(
        &mut self,
        points: &[DVec2],
        map_width: u32,
        map_height: u32,
        options: &AffineFitOptions,
        polygon: bool,
    ) -> Result<AffineFit, FitError> {
        self.hull.clear();
        if map_width == 0 || map_height == 0 {
            return Err(FitError::ZeroMapSize);
        }
        if points.is_empty() {
            return Err(FitError::NoPoints);
        }
        if let Some(index) = points.iter().position(|p| !p.is_finite()) {
            return Err(FitError::NonFinite { index });
        }

        if polygon {
            convex_hull_of_polygon_into(points, &mut self.sorted, &mut self.hull);
        } else {
            // Every point is finite (checked above).
            convex_hull_of_finite_into(points, &mut self.sorted, &mut self.hull);
        }
        let hull = self.hull.as_slice();
        let magnitude = hull.iter().fold(0.0, |max: f64, p| max.max(p.abs().max_element()));
        let rect = min_area_rect(hull).ok_or(FitError::NoPoints)?;
        let sheared = if options.shear { min_area_sheared(hull) } else { None };
        let padded = match sheared.map(|frame| pad_thin_extents(frame, options.min_extent, magnitude)) {
            Some(Padded::Unchanged(frame)) => frame,
            // A parallelogram thin enough to need padding has an arbitrary
            // skew, which padding would only magnify: pad the rectangle.
            _ => pad_thin_extents(rect, options.min_extent, magnitude).frame(),
        };
        let frame = orient_for_map(padded, map_width, map_height);
        let ndc_from_plane = ndc_from_frame(&frame, map_width, map_height, options.margin_texels);
        Ok(AffineFit { ndc_from_plane, frame })
    }
}

/// Fits the affine part of a light matrix to 2D points on the light's image
/// plane.
///
/// Encloses `points` in the minimum-area rectangle (or, with
/// [`shear`](AffineFitOptions::shear), parallelogram) and maps it onto a
/// `map_width × map_height` shadow map, filling it up to a border of
/// [`margin_texels`](AffineFitOptions::margin_texels): every point lands in
/// `[−1 + 2m/W, 1 − 2m/W] × [−1 + 2m/H, 1 − 2m/H]` in NDC (up to rounding).
///
/// * The frame's longer side goes along the map's larger dimension: along
///   `x` when `map_width ≥ map_height` (so for square maps too), along `y`
///   otherwise. For parallelograms, "longer" compares side lengths.
/// * The map is never mirrored: the linear part of
///   [`ndc_from_plane`](AffineFit::ndc_from_plane) has a positive
///   determinant, so counter-clockwise in the plane stays counter-clockwise
///   in (y-up) NDC. Which of the two non-mirrored orientations (a half turn
///   apart) is chosen is deterministic but otherwise unspecified.
/// * An extent thinner than
///   `max(min_extent, 1e-6 × larger extent, 1e-9 × largest |coordinate|)` is
///   padded symmetrically to that width ("extent" is the frame's width across
///   a pair of sides). The last term, beyond the documented option, keeps the
///   map's rounding error at the input's magnitude small; an absolute floor of
///   `1e-150` keeps it finite even with `min_extent = 0`. So one point, two
///   points, collinear or coincident points all give a finite, invertible map.
///   With `shear`, a parallelogram that would need padding is replaced by the
///   (padded) rectangle.
///
/// Inputs are assumed to be well inside the range of `f64`
/// (`|coordinate| < 1e150`); beyond that the fit may overflow.
///
/// This allocates; use a [`FitWorkspace`] to fit many point sets.
///
/// # Errors
///
/// Checked in this order: [`FitError::ZeroMapSize`] if either map dimension
/// is zero, [`FitError::NoPoints`] if `points` is empty,
/// [`FitError::NonFinite`] for the first point with a NaN or infinite
/// coordinate.
///
/// # Algorithm
///
/// Convex hull ([`convex_hull_2d`](super::convex_hull_2d), `O(n log n)`),
/// then [`min_area_rect`] (`O(h)`) or [`min_area_sheared`] (`O(h²)`) on its
/// `h` vertices, padding, orientation and a 2×2 inverse. `O(n log n + h²)`
/// time with shear, `O(n log n)` without.
pub fn fit_affine(
    points: &[DVec2],
    map_width: u32,
    map_height: u32,
    options: &AffineFitOptions,
) -> Result<AffineFit, FitError> {
    FitWorkspace::new().fit(points, map_width, map_height, options)
}

/// Unit vectors along the frame's edges. A zero-length edge takes the
/// direction a quarter turn from the other (counter-clockwise from `edge_u`
/// to `edge_v`), or the coordinate axes if both are zero.
fn edge_directions(frame: &Parallelogram) -> (DVec2, DVec2) {
    let (len_u, len_v) = (frame.edge_u.length(), frame.edge_v.length());
    match (len_u > 0.0, len_v > 0.0) {
        (true, true) => (frame.edge_u / len_u, frame.edge_v / len_v),
        (true, false) => {
            let u = frame.edge_u / len_u;
            (u, u.perp())
        }
        (false, true) => {
            let v = frame.edge_v / len_v;
            (-v.perp(), v)
        }
        (false, false) => (DVec2::X, DVec2::Y),
    }
}

/// The outcome of [`pad_thin_extents`].
enum Padded {
    /// No extent was below the floor; the frame is returned as it was.
    Unchanged(Parallelogram),
    /// At least one extent was grown to the floor.
    Grown(Parallelogram),
}

impl Padded {
    fn frame(self) -> Parallelogram {
        match self {
            Self::Unchanged(frame) | Self::Grown(frame) => frame,
        }
    }
}

/// Grows each extent of `frame` thinner than the padding floor symmetrically
/// to that floor (see [`fit_affine`]). The result has non-parallel edges and
/// contains `frame`.
fn pad_thin_extents(frame: Parallelogram, min_extent: f64, magnitude: f64) -> Padded {
    let parallel =
        frame.edge_u.perp_dot(frame.edge_v) == 0.0 && frame.edge_u != DVec2::ZERO && frame.edge_v != DVec2::ZERO;
    let mut frame = if parallel {
        // Parallel non-zero edges span a segment (the fits never produce
        // them, short of underflow): re-express it as a rectangle along the
        // segment, of zero height, for the padding below to grow.
        bounding_rect_along(&frame.corners(), frame.edge_u.normalize())
    } else {
        frame
    };
    let (dir_u, dir_v) = edge_directions(&frame);
    let sin = dir_u.perp_dot(dir_v).abs();
    let (len_u, len_v) = (frame.edge_u.length(), frame.edge_v.length());

    // Widths across the pair of sides each edge spans.
    let (width_u, width_v) = (len_u * sin, len_v * sin);
    let floor = min_extent
        .max(MIN_EXTENT_PER_LARGER_EXTENT * width_u.max(width_v))
        .max(MIN_EXTENT_PER_MAGNITUDE * magnitude)
        .max(MIN_EXTENT_ABSOLUTE);
    if !parallel && width_u >= floor && width_v >= floor {
        return Padded::Unchanged(frame);
    }
    if width_u < floor {
        let len = floor / sin;
        frame.origin -= 0.5 * (len - len_u) * dir_u;
        frame.edge_u = len * dir_u;
    }
    if width_v < floor {
        let len = floor / sin;
        frame.origin -= 0.5 * (len - len_v) * dir_v;
        frame.edge_v = len * dir_v;
    }
    Padded::Grown(frame)
}

/// Re-expresses `frame` so that `edge_u` is the edge to lay along NDC `x`
/// (the longer one on a wide or square map, the shorter on a tall one) and
/// `edge_u × edge_v > 0`, flipping `edge_v` if needed.
fn orient_for_map(frame: Parallelogram, map_width: u32, map_height: u32) -> Parallelogram {
    let u_is_longer = frame.edge_u.length_squared() >= frame.edge_v.length_squared();
    let map_is_wide = map_width >= map_height;
    let (edge_x, edge_y) =
        if u_is_longer == map_is_wide { (frame.edge_u, frame.edge_v) } else { (frame.edge_v, frame.edge_u) };
    if edge_x.perp_dot(edge_y) >= 0.0 {
        Parallelogram { origin: frame.origin, edge_u: edge_x, edge_v: edge_y }
    } else {
        Parallelogram { origin: frame.origin + edge_y, edge_u: edge_x, edge_v: -edge_y }
    }
}

/// Half-size in NDC of the interior of an axis of `texels` texels, after a
/// margin of `margin_texels` clamped to leave at least one texel.
fn interior_half_extent(texels: u32, margin_texels: f64) -> f64 {
    let n = f64::from(texels);
    let margin = margin_texels.max(0.0).min(0.5 * (n - 1.0));
    1.0 - 2.0 * margin / n
}

/// The affine map taking `frame`'s unit square onto the map's interior.
fn ndc_from_frame(frame: &Parallelogram, map_width: u32, map_height: u32, margin_texels: f64) -> DMat3 {
    let half =
        DVec2::new(interior_half_extent(map_width, margin_texels), interior_half_extent(map_height, margin_texels));
    let unit_from_plane = DMat2::from_cols(frame.edge_u, frame.edge_v).inverse();
    // ndc = 2·half·(a, b) − half, with (a, b) = unit_from_plane · (s − origin);
    // anchoring at the centre keeps the translation's rounding symmetric.
    let linear = DMat2::from_diagonal(2.0 * half) * unit_from_plane;
    let centre = frame.origin + 0.5 * (frame.edge_u + frame.edge_v);
    let translation = -(linear * centre);
    DMat3::from_cols(linear.x_axis.extend(0.0), linear.y_axis.extend(0.0), translation.extend(1.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn v(x: f64, y: f64) -> DVec2 {
        DVec2::new(x, y)
    }

    fn linear_det(fit: &AffineFit) -> f64 {
        let m = fit.ndc_from_plane;
        m.x_axis.x * m.y_axis.y - m.x_axis.y * m.y_axis.x
    }

    fn assert_affine(fit: &AffineFit) {
        assert!(fit.ndc_from_plane.is_finite(), "{fit:?}");
        let m = fit.ndc_from_plane;
        assert_eq!((m.x_axis.z, m.y_axis.z, m.z_axis.z), (0.0, 0.0, 1.0));
        assert!(linear_det(fit) > 0.0, "mirrored: {fit:?}");
    }

    #[test]
    fn axis_aligned_box_fills_the_interior() {
        let points = [v(0.0, 0.0), v(4.0, 0.0), v(4.0, 2.0), v(0.0, 2.0), v(1.0, 1.0)];
        let fit = fit_affine(&points, 8, 4, &AffineFitOptions::default()).unwrap();
        assert_affine(&fit);
        // One texel of margin: x in [-0.75, 0.75], y in [-0.5, 0.5].
        let ndc: Vec<_> = points[..4].iter().map(|&p| fit.to_ndc(p)).collect();
        for corner in [v(-0.75, -0.5), v(0.75, -0.5), v(0.75, 0.5), v(-0.75, 0.5)] {
            assert!(ndc.iter().any(|q| q.distance(corner) < 1e-12), "{corner} not hit: {ndc:?}");
        }
        assert!(fit.to_ndc(v(2.0, 1.0)).length() < 1e-12);
    }

    #[test]
    fn longer_side_follows_the_larger_map_dimension() {
        let points = [v(0.0, 0.0), v(0.0, 10.0), v(1.0, 10.0), v(1.0, 0.0)];
        let options = AffineFitOptions { margin_texels: 0.0, ..AffineFitOptions::default() };
        for (w, h, long_along_x) in [(1024, 256, true), (256, 1024, false), (512, 512, true)] {
            let fit = fit_affine(&points, w, h, &options).unwrap();
            assert_affine(&fit);
            let span = fit.to_ndc(v(0.0, 10.0)) - fit.to_ndc(v(0.0, 0.0));
            let (long, short) = if long_along_x { (span.x, span.y) } else { (span.y, span.x) };
            assert!((long.abs() - 2.0).abs() < 1e-12, "{w}x{h}: {span}");
            assert!(short.abs() < 1e-12, "{w}x{h}: {span}");
        }
    }

    #[test]
    fn degenerate_inputs_give_finite_maps() {
        let options = AffineFitOptions::default();
        let cases: [&[DVec2]; 4] = [
            &[v(3.0, -2.0)],
            &[v(3.0, -2.0), v(3.0, -2.0), v(3.0, -2.0)],
            &[v(0.0, 0.0), v(2.0, 1.0)],
            &[v(0.0, 0.0), v(1.0, 1.0), v(2.0, 2.0), v(0.5, 0.5)],
        ];
        for points in cases {
            for shear in [false, true] {
                let fit = fit_affine(points, 64, 32, &AffineFitOptions { shear, ..options }).unwrap();
                assert_affine(&fit);
                for &p in points {
                    let q = fit.to_ndc(p);
                    assert!(q.abs().max_element() <= 1.0 - 2.0 / 64.0 + 1e-9, "{p} -> {q}");
                }
            }
        }
        // A single point at the origin with no padding requested still gets
        // the absolute floor.
        let zero = AffineFitOptions { min_extent: 0.0, ..options };
        let fit = fit_affine(&[DVec2::ZERO], 1, 1, &zero).unwrap();
        assert_affine(&fit);
        assert_eq!(fit.to_ndc(DVec2::ZERO), DVec2::ZERO);
    }

    #[test]
    fn segment_is_padded_to_min_extent() {
        let options = AffineFitOptions { min_extent: 0.5, ..AffineFitOptions::default() };
        let fit = fit_affine(&[v(0.0, 0.0), v(4.0, 0.0)], 16, 16, &options).unwrap();
        let frame = fit.frame;
        assert!((frame.edge_u.length() - 4.0).abs() < 1e-12);
        assert!((frame.edge_v.length() - 0.5).abs() < 1e-12);
        assert!((frame.from_unit(v(0.5, 0.5)) - v(2.0, 0.0)).length() < 1e-12);
    }

    #[test]
    fn errors() {
        let options = AffineFitOptions::default();
        assert_eq!(fit_affine(&[], 16, 16, &options), Err(FitError::NoPoints));
        assert_eq!(
            fit_affine(&[v(0.0, 0.0), v(f64::NAN, 1.0)], 16, 16, &options),
            Err(FitError::NonFinite { index: 1 })
        );
        assert_eq!(fit_affine(&[v(f64::NEG_INFINITY, 0.0)], 16, 16, &options), Err(FitError::NonFinite { index: 0 }));
        assert_eq!(fit_affine(&[v(0.0, 0.0)], 0, 16, &options), Err(FitError::ZeroMapSize));
        assert_eq!(fit_affine(&[], 16, 0, &options), Err(FitError::ZeroMapSize));
    }

    #[test]
    fn margin_is_clamped_to_leave_a_texel() {
        let points = [v(0.0, 0.0), v(1.0, 1.0), v(1.0, 0.0)];
        let options = AffineFitOptions { margin_texels: 100.0, ..AffineFitOptions::default() };
        let fit = fit_affine(&points, 4, 1, &options).unwrap();
        assert_affine(&fit);
        let corners = fit.frame.corners().map(|c| fit.to_ndc(c));
        // x: 4 texels, margin 1.5 -> interior [-0.25, 0.25]; y: no margin.
        assert!((corners[2] - v(0.25, 1.0)).length() < 1e-12, "{corners:?}");
        assert!((corners[0] - v(-0.25, -1.0)).length() < 1e-12, "{corners:?}");
        let nan_margin = AffineFitOptions { margin_texels: f64::NAN, ..AffineFitOptions::default() };
        let fit = fit_affine(&points, 4, 4, &nan_margin).unwrap();
        assert!((fit.to_ndc(fit.frame.origin) - v(-1.0, -1.0)).length() < 1e-12);
    }

    #[test]
    fn shear_maps_a_parallelogram_onto_the_square() {
        let frame = Parallelogram { origin: v(1.0, 0.0), edge_u: v(4.0, 0.0), edge_v: v(2.0, 2.0) };
        let points = frame.corners();
        let options = AffineFitOptions { margin_texels: 0.0, shear: true, ..AffineFitOptions::default() };
        let fit = fit_affine(&points, 32, 32, &options).unwrap();
        assert_affine(&fit);
        let mut ndc = points.map(|p| fit.to_ndc(p));
        ndc.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
        let expected = [v(-1.0, -1.0), v(-1.0, 1.0), v(1.0, -1.0), v(1.0, 1.0)];
        for (got, want) in ndc.iter().zip(expected) {
            assert!((*got - want).length() < 1e-12, "{ndc:?}");
        }
    }

    #[test]
    fn workspace_matches_the_plain_function() {
        let mut workspace = FitWorkspace::new();
        let options = AffineFitOptions::default();
        let a = [v(0.0, 0.0), v(3.0, 1.0), v(1.0, 2.0), v(1.0, 1.0)];
        let b = [v(-5.0, 0.5), v(2.0, 7.0)];
        for points in [&a[..], &b[..], &a[..]] {
            assert_eq!(workspace.fit(points, 128, 64, &options), fit_affine(points, 128, 64, &options));
        }
        assert_eq!(workspace.hull().len(), 3);
        assert!(workspace.fit(&[], 128, 64, &options).is_err());
        assert!(workspace.hull().is_empty());
    }
}
