//! Property tests of `lixel::fit` against brute-force oracles.
//!
//! Every check runs over thousands of seeded random point sets drawn from
//! families chosen to stress the geometry: uniform boxes, tight clusters,
//! nearly and exactly collinear points, heavy duplication, tiny (`1e-9`) and
//! huge (`1e6`) coordinates, small integer grids full of collinear triples,
//! points on a circle (every point a hull vertex) and sets of one to three
//! points. A failure names the seed and family, which regenerate the set.

use glam::DVec2;
use lixel::fit::{
    convex_hull_2d, convex_hull_2d_into, fit_affine, min_area_rect, min_area_sheared, AffineFitOptions, FitError,
    FitWorkspace, Parallelogram,
};
use proptest::prelude::*;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use robust::{orient2d, Coord};

// ---------------------------------------------------------------------------
// Point-set families
// ---------------------------------------------------------------------------

#[derive(Clone, Copy, Debug)]
enum Family {
    Uniform,
    Clustered,
    NearlyCollinear,
    ExactlyCollinear,
    Duplicates,
    Tiny,
    Huge,
    HugeOffset,
    IntegerGrid,
    Circle,
    Few,
}

const FAMILIES: [Family; 11] = [
    Family::Uniform,
    Family::Clustered,
    Family::NearlyCollinear,
    Family::ExactlyCollinear,
    Family::Duplicates,
    Family::Tiny,
    Family::Huge,
    Family::HugeOffset,
    Family::IntegerGrid,
    Family::Circle,
    Family::Few,
];

fn v(x: f64, y: f64) -> DVec2 {
    DVec2::new(x, y)
}

fn unit_direction(rng: &mut ChaCha8Rng) -> DVec2 {
    DVec2::from_angle(rng.random_range(0.0..core::f64::consts::TAU))
}

/// A rotated, translated box of random aspect, scaled by `scale`.
fn boxed(rng: &mut ChaCha8Rng, n: usize, scale: f64, offset: DVec2) -> Vec<DVec2> {
    let half = v(rng.random_range(0.01..1.0), rng.random_range(0.01..1.0)) * scale;
    let axis = unit_direction(rng);
    (0..n)
        .map(|_| {
            let local = v(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0)) * half;
            offset + axis.rotate(local)
        })
        .collect()
}

fn generate(rng: &mut ChaCha8Rng, family: Family) -> Vec<DVec2> {
    let n = rng.random_range(1..=40);
    match family {
        Family::Uniform => {
            let offset = v(rng.random_range(-10.0..10.0), rng.random_range(-10.0..10.0));
            let scale = rng.random_range(0.1..10.0);
            boxed(rng, n, scale, offset)
        }
        Family::Clustered => {
            let centres: Vec<DVec2> = (0..rng.random_range(1..=3))
                .map(|_| v(rng.random_range(-5.0..5.0), rng.random_range(-5.0..5.0)))
                .collect();
            let spread = 10f64.powf(rng.random_range(-4.0..-1.0));
            (0..n)
                .map(|_| {
                    let c = centres[rng.random_range(0..centres.len())];
                    // A sum of uniforms: roughly Gaussian, bounded.
                    let noise: DVec2 =
                        (0..3).map(|_| v(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0))).sum();
                    c + spread * noise
                })
                .collect()
        }
        Family::NearlyCollinear => {
            // On a line in exact arithmetic; rounding scatters them by ulps.
            let origin = v(rng.random_range(-3.0..3.0), rng.random_range(-3.0..3.0));
            let dir = unit_direction(rng) * rng.random_range(0.1..10.0);
            (0..n).map(|_| origin + rng.random_range(-1.0..1.0) * dir).collect()
        }
        Family::ExactlyCollinear => {
            let slope = f64::from(rng.random_range(-3..=3));
            let intercept = f64::from(rng.random_range(-5..=5));
            let vertical = rng.random_bool(0.2);
            (0..n)
                .map(|_| {
                    let t = f64::from(rng.random_range(-20..=20));
                    if vertical {
                        v(intercept, t)
                    } else {
                        v(t, slope * t + intercept)
                    }
                })
                .collect()
        }
        Family::Duplicates => {
            let count = rng.random_range(1..=4);
            let distinct = boxed(rng, count, 2.0, DVec2::ZERO);
            (0..n.max(2)).map(|_| distinct[rng.random_range(0..distinct.len())]).collect()
        }
        Family::Tiny => {
            let offset = v(rng.random_range(-1e-9..1e-9), rng.random_range(-1e-9..1e-9));
            boxed(rng, n, 1e-9, offset)
        }
        Family::Huge => boxed(rng, n, 1e6, DVec2::ZERO),
        Family::HugeOffset => {
            let offset = v(1e6, -1e6) * rng.random_range(0.5..2.0);
            let scale = rng.random_range(1.0..100.0);
            boxed(rng, n, scale, offset)
        }
        Family::IntegerGrid => {
            let size = rng.random_range(1..=6);
            (0..n).map(|_| v(f64::from(rng.random_range(0..=size)), f64::from(rng.random_range(0..=size)))).collect()
        }
        Family::Circle => {
            let radius = 10f64.powf(rng.random_range(-2.0..2.0));
            let centre = v(rng.random_range(-5.0..5.0), rng.random_range(-5.0..5.0));
            let squash = rng.random_range(0.05..1.0);
            (0..n)
                .map(|_| {
                    let on = unit_direction(rng) * v(1.0, squash);
                    let inside = if rng.random_bool(0.2) { rng.random_range(0.0..1.0) } else { 1.0 };
                    centre + radius * inside * on
                })
                .collect()
        }
        Family::Few => {
            let count = rng.random_range(1..=3);
            boxed(rng, count, 3.0, v(1.0, -2.0))
        }
    }
}

/// Runs `check` on `cases` seeded point sets, cycling through the families.
fn for_each_case(cases: u64, seed_base: u64, mut check: impl FnMut(&[DVec2], &str)) {
    for seed in seed_base..seed_base + cases {
        let family = FAMILIES[(seed % FAMILIES.len() as u64) as usize];
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let points = generate(&mut rng, family);
        check(&points, &format!("seed {seed}, {family:?}, {} points", points.len()));
    }
}

// ---------------------------------------------------------------------------
// Oracles
// ---------------------------------------------------------------------------

fn orient(a: DVec2, b: DVec2, c: DVec2) -> f64 {
    orient2d(Coord { x: a.x, y: a.y }, Coord { x: b.x, y: b.y }, Coord { x: c.x, y: c.y })
}

fn sorted_unique(points: &[DVec2]) -> Vec<DVec2> {
    let mut sorted = points.to_vec();
    sorted.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    sorted.dedup_by(|a, b| a == b);
    sorted
}

/// The hull vertices by definition, in `O(n³)`: `a → b` is a hull edge iff no
/// point lies to its right and every point on its line lies within `[a, b]`;
/// the hull's vertices are the ends of its edges.
fn brute_force_hull_vertices(points: &[DVec2]) -> Vec<DVec2> {
    let mut vertices = Vec::new();
    for &a in points {
        for &b in points {
            if a == b {
                continue;
            }
            let is_edge = points.iter().all(|&q| {
                let side = orient(a, b, q);
                side > 0.0 || (side == 0.0 && (q - a).dot(b - a) >= 0.0 && (q - b).dot(a - b) >= 0.0)
            });
            if is_edge {
                vertices.extend([a, b]);
            }
        }
    }
    if vertices.is_empty() {
        vertices.extend(points.first());
    }
    sorted_unique(&vertices)
}

/// Largest coordinate magnitude: the scale of rounding errors.
fn magnitude(points: &[DVec2]) -> f64 {
    points.iter().fold(0.0, |m: f64, p| m.max(p.abs().max_element()))
}

/// Largest distance between two points.
fn diameter(points: &[DVec2]) -> f64 {
    let mut d: f64 = 0.0;
    for &a in points {
        for &b in points {
            d = d.max(a.distance(b));
        }
    }
    d
}

/// Area of the bounding rectangle of `points` with a side along `dir`.
fn rect_area_along(points: &[DVec2], dir: DVec2) -> f64 {
    let dir = dir.normalize();
    let normal = dir.perp();
    let (mut lo, mut hi) = (DVec2::INFINITY, DVec2::NEG_INFINITY);
    for &p in points {
        let d = p - points[0];
        let c = v(d.dot(dir), d.dot(normal));
        lo = lo.min(c);
        hi = hi.max(c);
    }
    let extent = hi - lo;
    extent.x * extent.y
}

/// Least bounding-rectangle area over the directions of all point pairs: the
/// true minimum, since the optimum is flush with a hull edge.
fn brute_force_rect_area(points: &[DVec2]) -> f64 {
    let mut best = f64::INFINITY;
    for (i, &a) in points.iter().enumerate() {
        for &b in &points[i + 1..] {
            if a != b {
                best = best.min(rect_area_along(points, b - a));
            }
        }
    }
    best
}

/// Least bounding-rectangle area over `steps` uniform directions.
fn sampled_rect_area(points: &[DVec2], steps: u32) -> f64 {
    (0..steps)
        .map(|i| rect_area_along(points, DVec2::from_angle(core::f64::consts::PI * f64::from(i) / f64::from(steps))))
        .fold(f64::INFINITY, f64::min)
}

/// Area of the least parallelogram enclosing `points` with a side pair along
/// `base` and the other along `side` (non-parallel).
fn parallelogram_area(points: &[DVec2], base: DVec2, side: DVec2) -> f64 {
    let e = base.normalize();
    let n = e.perp();
    let side = v(side.dot(e), side.dot(n));
    let k = side.x / side.y;
    let (mut y_lo, mut y_hi, mut w_lo, mut w_hi) = (f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY);
    for &p in points {
        let d = p - points[0];
        let (x, y) = (d.dot(e), d.dot(n));
        y_lo = y_lo.min(y);
        y_hi = y_hi.max(y);
        w_lo = w_lo.min(x - k * y);
        w_hi = w_hi.max(x - k * y);
    }
    (y_hi - y_lo) * (w_hi - w_lo)
}

/// The exact minimum-area enclosing parallelogram, in `O(h³)`: one side pair
/// flush with a hull edge, the other parallel to another hull edge.
fn brute_force_parallelogram_area(hull: &[DVec2]) -> f64 {
    let h = hull.len();
    let edge = |i: usize| hull[(i + 1) % h] - hull[i];
    let mut best = f64::INFINITY;
    for i in 0..h {
        for j in 0..h {
            if edge(i).perp_dot(edge(j)) != 0.0 {
                best = best.min(parallelogram_area(hull, edge(i), edge(j)));
            }
        }
    }
    best
}

/// Least parallelogram area with a side pair on a hull edge and the shear
/// `k = tan θ` sampled on a grid of angles.
fn sampled_parallelogram_area(hull: &[DVec2], steps: u32) -> f64 {
    let h = hull.len();
    let mut best = f64::INFINITY;
    for i in 0..h {
        let base = hull[(i + 1) % h] - hull[i];
        let e = base.normalize();
        for s in 1..steps {
            let theta = core::f64::consts::PI * f64::from(s) / f64::from(steps);
            let side = DVec2::from_angle(theta);
            best = best.min(parallelogram_area(hull, base, side.x * e + side.y * e.perp()));
        }
    }
    best
}

fn assert_encloses(frame: &Parallelogram, points: &[DVec2], tol: f64, context: &str) {
    for &p in points {
        assert!(frame.contains(p, tol), "{context}: {p} outside {frame:?} (tolerance {tol})");
    }
}

// ---------------------------------------------------------------------------
// Hull
// ---------------------------------------------------------------------------

fn check_hull(points: &[DVec2], context: &str) {
    let hull = convex_hull_2d(points);
    assert_eq!(
        sorted_unique(&hull),
        brute_force_hull_vertices(points),
        "{context}: vertex set differs from the brute-force hull"
    );
    assert_eq!(sorted_unique(&hull).len(), hull.len(), "{context}: repeated vertex");
    for q in &hull {
        assert!(points.contains(q), "{context}: {q} is not an input point");
    }
    let h = hull.len();
    match h {
        0 => assert!(points.is_empty(), "{context}"),
        1 => assert!(points.iter().all(|&p| p == hull[0]), "{context}"),
        _ => {
            if h >= 3 {
                for i in 0..h {
                    let turn = orient(hull[i], hull[(i + 1) % h], hull[(i + 2) % h]);
                    assert!(turn > 0.0, "{context}: not a strict left turn at {i}: {hull:?}");
                }
            }
            for i in 0..h {
                let (a, b) = (hull[i], hull[(i + 1) % h]);
                for &p in points {
                    assert!(orient(a, b, p) >= 0.0, "{context}: {p} right of edge {a} → {b}");
                }
            }
        }
    }
}

#[test]
fn hull_matches_brute_force() {
    for_each_case(3300, 0, check_hull);
}

#[test]
fn hull_into_reuses_buffers_and_agrees() {
    let (mut scratch, mut hull) = (Vec::new(), Vec::new());
    for_each_case(1100, 10_000, |points, context| {
        convex_hull_2d_into(points, &mut scratch, &mut hull);
        assert_eq!(hull, convex_hull_2d(points), "{context}");
    });
}

#[test]
fn hull_is_invariant_under_permutation() {
    for_each_case(1100, 20_000, |points, context| {
        let mut reversed = points.to_vec();
        reversed.reverse();
        assert_eq!(convex_hull_2d(&reversed), convex_hull_2d(points), "{context}");
    });
}

// ---------------------------------------------------------------------------
// Minimum-area rectangle
// ---------------------------------------------------------------------------

#[test]
fn min_area_rect_matches_brute_force() {
    for_each_case(2200, 30_000, |points, context| {
        let hull = convex_hull_2d(points);
        let rect = min_area_rect(&hull).expect("non-empty hull");
        let scale = magnitude(points);
        let diam = diameter(points);
        assert_encloses(&rect, points, 1e-12 * scale, context);

        let (u, v) = (rect.edge_u, rect.edge_v);
        assert!(u.dot(v).abs() <= 1e-12 * u.length() * v.length(), "{context}: not a rectangle: {rect:?}");
        assert!(u.perp_dot(v) >= 0.0, "{context}: edge_v is clockwise of edge_u");

        let area = rect.area();
        let area_tol = 1e-12 * scale * diam;
        // With all points equal, no pair has a direction: the area is zero.
        let exact = match brute_force_rect_area(points) {
            a if a.is_finite() => a,
            _ => 0.0,
        };
        let sampled = sampled_rect_area(points, 3600).min(exact);
        assert!(area <= sampled * (1.0 + 1e-9) + area_tol, "{context}: area {area} > brute force {sampled}");
        assert!(area >= exact * (1.0 - 1e-9) - area_tol, "{context}: area {area} < true optimum {exact}");
    });
}

// ---------------------------------------------------------------------------
// Minimum-area parallelogram (shear heuristic)
// ---------------------------------------------------------------------------

#[test]
fn min_area_sheared_matches_brute_force() {
    for_each_case(2200, 40_000, |points, context| {
        let hull = convex_hull_2d(points);
        let rect = min_area_rect(&hull).expect("non-empty hull");
        let sheared = min_area_sheared(&hull).expect("non-empty hull");
        let scale = magnitude(points);
        let diam = diameter(points);
        assert_encloses(&sheared, points, 1e-12 * scale, context);
        assert!(sheared.edge_u.perp_dot(sheared.edge_v) >= 0.0, "{context}: edge_v is clockwise of edge_u");

        let area = sheared.area();
        assert!(area <= rect.area(), "{context}: sheared {area} > rectangle {}", rect.area());
        if hull.len() < 3 {
            assert_eq!(sheared, rect, "{context}");
            return;
        }
        let area_tol = 1e-12 * scale * diam;
        let sampled = sampled_parallelogram_area(&hull, 720);
        assert!(area <= sampled * (1.0 + 1e-9) + area_tol, "{context}: area {area} > sampled shears {sampled}");
        let exact = brute_force_parallelogram_area(&hull);
        assert!((area - exact).abs() <= 1e-9 * exact + area_tol, "{context}: area {area} != exact optimum {exact}");
    });
}

// ---------------------------------------------------------------------------
// Affine fit
// ---------------------------------------------------------------------------

const MAP_SIZES: [(u32, u32); 6] = [(1024, 256), (256, 1024), (512, 512), (2048, 2048), (1, 1), (3, 7)];

fn check_fit(points: &[DVec2], width: u32, height: u32, options: &AffineFitOptions, context: &str) {
    let fit = fit_affine(points, width, height, options).unwrap_or_else(|e| panic!("{context}: {e}"));
    let m = fit.ndc_from_plane;
    assert!(m.is_finite(), "{context}: {fit:?}");
    assert_eq!((m.x_axis.z, m.y_axis.z, m.z_axis.z), (0.0, 0.0, 1.0), "{context}");
    let det = m.x_axis.x * m.y_axis.y - m.x_axis.y * m.y_axis.x;
    assert!(det > 0.0, "{context}: mirrored map, det {det}");

    // The interior the points must land in.
    let half = |n: u32| {
        let margin = options.margin_texels.clamp(0.0, 0.5 * (f64::from(n) - 1.0));
        1.0 - 2.0 * margin / f64::from(n)
    };
    let half = v(half(width), half(height));

    // Rounding in applying the map grows with |s| / extent.
    let gain = m.x_axis.truncate().abs().max(m.y_axis.truncate().abs()).max_element();
    let tol = 1e-9 + 1e-14 * magnitude(points) * gain;
    for &p in points {
        let q = fit.to_ndc(p);
        assert!(
            q.x.abs() <= half.x + tol && q.y.abs() <= half.y + tol,
            "{context}, {width}x{height}: {p} -> {q}, interior ±{half}"
        );
    }

    // The frame fills the interior exactly, edge_u along +x, edge_v along +y.
    let frame = fit.frame;
    let corners = frame.corners().map(|c| fit.to_ndc(c));
    let expected = [v(-half.x, -half.y), v(half.x, -half.y), v(half.x, half.y), v(-half.x, half.y)];
    for (got, want) in corners.iter().zip(expected) {
        assert!(
            (*got - want).abs().max_element() <= tol,
            "{context}, {width}x{height}, {options:?}: corner {got} != {want}, {fit:?}"
        );
    }

    // The longer side runs along the larger map dimension.
    let (len_x, len_y) = (frame.edge_u.length(), frame.edge_v.length());
    if width > height {
        assert!(len_x >= len_y, "{context}, {width}x{height}: {frame:?}");
    } else if width < height {
        assert!(len_x <= len_y, "{context}, {width}x{height}: {frame:?}");
    } else {
        assert!(len_x >= len_y, "{context}, square map: {frame:?}");
    }
}

#[test]
fn fit_affine_maps_every_point_inside_the_margin() {
    let margins = [0.0, 1.0, 2.5];
    for_each_case(1100, 50_000, |points, context| {
        for (i, &(w, h)) in MAP_SIZES.iter().enumerate() {
            for shear in [false, true] {
                let options = AffineFitOptions {
                    margin_texels: margins[i % margins.len()],
                    shear,
                    ..AffineFitOptions::default()
                };
                check_fit(points, w, h, &options, context);
            }
        }
    });
}

#[test]
fn fit_affine_uses_the_whole_interior_when_nothing_is_padded() {
    // Unpadded, the fitted frame is flush with the points on all four sides,
    // so their NDC bounding box is the interior.
    let options = AffineFitOptions { margin_texels: 0.0, min_extent: 0.0, ..AffineFitOptions::default() };
    for_each_case(1100, 60_000, |points, context| {
        let hull = convex_hull_2d(points);
        let rect = min_area_rect(&hull).expect("non-empty hull");
        let (a, b) = (rect.edge_u.length(), rect.edge_v.length());
        if a.min(b) < 1e-3 * a.max(b) || a.min(b) < 1e-6 * magnitude(points) {
            return; // padded or too ill-conditioned to compare tightly
        }
        let fit = fit_affine(points, 256, 1024, &options).expect("valid input");
        let (lo, hi) = points.iter().fold((DVec2::INFINITY, DVec2::NEG_INFINITY), |(lo, hi), &p| {
            let q = fit.to_ndc(p);
            (lo.min(q), hi.max(q))
        });
        let tol = 1e-6;
        assert!((lo + DVec2::ONE).abs().max_element() < tol, "{context}: {lo}");
        assert!((hi - DVec2::ONE).abs().max_element() < tol, "{context}: {hi}");
    });
}

#[test]
fn fit_affine_orients_long_side_along_long_map_axis() {
    // A long thin strip at an arbitrary angle. (Only for rectangles: the
    // minimum-area parallelogram of a jagged strip may be a skewed rhombus
    // whose sides are both close to the strip's axis.)
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    for _ in 0..200 {
        let axis = unit_direction(&mut rng);
        let points: Vec<DVec2> =
            (0..20).map(|_| axis.rotate(v(rng.random_range(-8.0..8.0), rng.random_range(-1.0..1.0)))).collect();
        for (w, h) in [(1024, 256), (256, 1024)] {
            let fit = fit_affine(&points, w, h, &AffineFitOptions::default()).expect("valid input");
            // The frame side along NDC x on the wide map (y on the tall one)
            // follows the strip's axis.
            let long_side = if w > h { fit.frame.edge_u } else { fit.frame.edge_v };
            let cos = long_side.normalize().dot(axis).abs();
            assert!(cos > 0.9, "{w}x{h}: long side {long_side} vs axis {axis}");
        }
    }
}

#[test]
fn fit_affine_handles_degenerate_input() {
    let cases: [&[DVec2]; 6] = [
        &[v(1.0, 2.0)],
        &[v(1.0, 2.0); 5],
        &[v(1.0, 2.0), v(-3.0, 0.5)],
        &[v(0.0, 0.0), v(1.0, 1.0), v(2.0, 2.0), v(3.0, 3.0), v(1.5, 1.5)],
        &[v(1e6, 1e6), v(1e6, 1e6)],
        &[v(1e-9, -1e-9), v(2e-9, -1e-9)],
    ];
    for points in cases {
        for min_extent in [0.0, 1e-9, 1.0] {
            for shear in [false, true] {
                let options = AffineFitOptions { min_extent, shear, ..AffineFitOptions::default() };
                for &(w, h) in &MAP_SIZES {
                    check_fit(points, w, h, &options, &format!("{points:?}, {options:?}"));
                }
            }
        }
    }
}

#[test]
fn fit_affine_errors() {
    let options = AffineFitOptions::default();
    assert_eq!(fit_affine(&[], 16, 16, &options), Err(FitError::NoPoints));
    assert_eq!(fit_affine(&[v(0.0, 0.0)], 0, 16, &options), Err(FitError::ZeroMapSize));
    assert_eq!(fit_affine(&[v(0.0, 0.0)], 16, 0, &options), Err(FitError::ZeroMapSize));
    let mut rng = ChaCha8Rng::seed_from_u64(99);
    for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        for _ in 0..20 {
            let mut points = generate(&mut rng, Family::Uniform);
            let index = rng.random_range(0..points.len());
            if rng.random_bool(0.5) {
                points[index].x = bad;
            } else {
                points[index].y = bad;
            }
            assert_eq!(fit_affine(&points, 64, 64, &options), Err(FitError::NonFinite { index }));
        }
    }
}

#[test]
fn workspace_agrees_with_fit_affine() {
    let mut workspace = FitWorkspace::new();
    for_each_case(550, 70_000, |points, context| {
        for shear in [false, true] {
            let options = AffineFitOptions { shear, ..AffineFitOptions::default() };
            assert_eq!(workspace.fit(points, 640, 480, &options), fit_affine(points, 640, 480, &options), "{context}");
            assert_eq!(workspace.hull(), convex_hull_2d(points).as_slice(), "{context}");
        }
    });
}

// ---------------------------------------------------------------------------
// proptest: arbitrary (shrinkable) inputs
// ---------------------------------------------------------------------------

fn point_strategy() -> impl Strategy<Value = DVec2> {
    prop_oneof![
        (-4i32..=4, -4i32..=4).prop_map(|(x, y)| v(f64::from(x), f64::from(y))),
        (-1e3..1e3f64, -1e3..1e3f64).prop_map(|(x, y)| v(x, y)),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    #[test]
    fn prop_hull_matches_brute_force(points in prop::collection::vec(point_strategy(), 0..24)) {
        check_hull(&points, "proptest");
    }

    #[test]
    fn prop_fits_enclose_and_order(points in prop::collection::vec(point_strategy(), 1..24)) {
        let hull = convex_hull_2d(&points);
        let rect = min_area_rect(&hull).unwrap();
        let sheared = min_area_sheared(&hull).unwrap();
        let tol = 1e-9 * magnitude(&points).max(1.0);
        assert_encloses(&rect, &points, tol, "proptest rect");
        assert_encloses(&sheared, &points, tol, "proptest sheared");
        prop_assert!(sheared.area() <= rect.area());
        for shear in [false, true] {
            let options = AffineFitOptions { shear, ..AffineFitOptions::default() };
            check_fit(&points, 1024, 256, &options, "proptest");
        }
    }
}
