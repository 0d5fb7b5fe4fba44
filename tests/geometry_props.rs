//! Randomized property tests of `lixel::geometry` against brute force.
//!
//! Every loop is seeded, so failures reproduce; the case index is in each
//! message. Set `LIXEL_STRESS=<factor>` to run that many times more cases.

use glam::{DMat3, DMat4, DVec3};
use lixel::geometry::{default_eps, min_enclosing_cone, ConvexPolyhedron, Plane};
use proptest::prelude::*;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// `n` times the factor in the `LIXEL_STRESS` environment variable (default 1),
/// e.g. `LIXEL_STRESS=100 cargo test --release --test geometry_props`.
fn cases(n: usize) -> usize {
    n * std::env::var("LIXEL_STRESS").ok().and_then(|f| f.parse().ok()).unwrap_or(1)
}

fn rng(seed: u64) -> ChaCha8Rng {
    ChaCha8Rng::seed_from_u64(seed)
}

fn unit_vector(rng: &mut impl Rng) -> DVec3 {
    loop {
        let v = DVec3::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0));
        let len = v.length();
        if len > 0.1 && len <= 1.0 {
            return v / len;
        }
    }
}

fn log_uniform(rng: &mut impl Rng, lo: f64, hi: f64) -> f64 {
    rng.random_range(lo.ln()..hi.ln()).exp()
}

fn in_box(rng: &mut impl Rng, min: DVec3, max: DVec3) -> DVec3 {
    min + (max - min) * DVec3::new(rng.random(), rng.random(), rng.random())
}

fn box_planes(min: DVec3, max: DVec3) -> Vec<Plane> {
    [DVec3::X, DVec3::Y, DVec3::Z]
        .into_iter()
        .flat_map(|n| [Plane::from_point_normal(max, n), Plane::from_point_normal(min, -n)])
        .collect()
}

/// A random box of size about `s` around a random centre up to `10 s` away,
/// sometimes flat in one axis.
fn random_box(rng: &mut impl Rng, s: f64) -> (DVec3, DVec3) {
    let center = unit_vector(rng) * rng.random_range(0.0..10.0 * s);
    let mut half = DVec3::new(rng.random_range(0.1..1.0), rng.random_range(0.1..1.0), rng.random_range(0.1..1.0)) * s;
    if rng.random_bool(0.1) {
        half[rng.random_range(0..3)] = 0.0;
    }
    (center - half, center + half)
}

/// Planes through random points of the middle of `[min, max]`.
fn random_planes(rng: &mut impl Rng, min: DVec3, max: DVec3, count: usize) -> Vec<Plane> {
    let (lo, hi) = (min.lerp(max, 0.2), min.lerp(max, 0.8));
    (0..count).map(|_| Plane::from_point_normal(in_box(rng, lo, hi), unit_vector(rng))).collect()
}

/// A random non-empty convex body of size about `s`, with its eps.
fn random_body(rng: &mut impl Rng, s: f64) -> (ConvexPolyhedron, f64) {
    loop {
        let (min, max) = random_box(rng, s);
        let eps = default_eps((max - min).length().max(1e-3 * min.abs().max(max.abs()).max_element()));
        let count = rng.random_range(0..6);
        let planes = random_planes(rng, min, max, count);
        let body = ConvexPolyhedron::from_aabb(min, max).clip_all(&planes, eps);
        if !body.is_empty() {
            return (body, eps);
        }
    }
}

/// Structural invariants ([`ConvexPolyhedron::sanity_check`], shared with the
/// unit tests) of a non-empty body.
fn assert_closed(body: &ConvexPolyhedron, tol: f64, context: &str) {
    assert!(!body.is_empty(), "{context}: empty");
    if let Err(e) = body.sanity_check(tol) {
        panic!("{context}: {e}");
    }
}

/// Intersection points of well-conditioned plane triples that lie inside all
/// planes (within `tol`): the vertices of the body the planes bound.
fn brute_force_vertices(planes: &[Plane], tol: f64) -> Vec<DVec3> {
    let mut vertices = Vec::new();
    for i in 0..planes.len() {
        for j in i + 1..planes.len() {
            for k in j + 1..planes.len() {
                let (a, b, c) = (planes[i], planes[j], planes[k]);
                let m = DMat3::from_cols(a.normal, b.normal, c.normal).transpose();
                if m.determinant().abs() < 1e-3 {
                    continue;
                }
                let x = m.inverse() * -DVec3::new(a.offset, b.offset, c.offset);
                if planes.iter().all(|p| p.signed_distance(x) <= tol) {
                    vertices.push(x);
                }
            }
        }
    }
    vertices
}

fn surface_area(body: &ConvexPolyhedron) -> f64 {
    let v = body.vertices();
    body.faces()
        .map(|f| {
            let i = f.indices();
            (2..i.len()).map(|k| 0.5 * (v[i[k - 1]] - v[i[0]]).cross(v[i[k]] - v[i[0]]).length()).sum::<f64>()
        })
        .sum()
}

fn nearest(points: &[DVec3], x: DVec3) -> f64 {
    points.iter().map(|&p| (p - x).length()).fold(f64::INFINITY, f64::min)
}

/// Fraction of `n` uniform samples of `[min, max]` inside every plane.
fn monte_carlo_fraction(rng: &mut impl Rng, planes: &[Plane], min: DVec3, max: DVec3, n: usize) -> f64 {
    let hits = (0..n).filter(|_| {
        let x = in_box(rng, min, max);
        planes.iter().all(|p| p.signed_distance(x) <= 0.0)
    });
    hits.count() as f64 / n as f64
}

#[test]
fn clipped_boxes_match_brute_force() {
    let mut rng = rng(1);
    let (mut non_empty, mut volume_checks) = (0, 0);
    for case in 0..cases(10000) {
        let s = log_uniform(&mut rng, 1e-6, 1e5);
        let (min, max) = random_box(&mut rng, s);
        let count = rng.random_range(1..7);
        let cuts = random_planes(&mut rng, min, max, count);
        let input = ConvexPolyhedron::from_aabb(min, max);
        let (pmin, pmax) = input.aabb().unwrap();
        let eps = input.default_eps();
        let body = input.clip_all(&cuts, eps);

        let mut planes = box_planes(pmin, pmax);
        planes.extend_from_slice(&cuts);
        let brute = brute_force_vertices(&planes, 2.0 * eps);
        let context = format!("case {case} (scale {s:e})");
        if body.is_empty() {
            // Only a sliver thinner than eps may vanish: all true vertices
            // then lie within eps of one of the planes.
            let sliver = planes.iter().any(|p| brute.iter().all(|&x| p.signed_distance(x).abs() <= 2.0 * eps));
            assert!(sliver, "{context}: empty, but brute force finds {} vertices", brute.len());
            continue;
        }
        non_empty += 1;
        let tol = 2.0 * eps;
        assert_closed(&body, tol, &context);
        for &x in body.vertices() {
            assert!(planes.iter().all(|p| p.signed_distance(x) <= tol), "{context}: vertex outside");
            let touching = planes.iter().filter(|p| p.signed_distance(x).abs() <= tol).count();
            assert!(touching >= 3, "{context}: vertex {x} on {touching} planes");
        }
        for &x in &brute {
            let d = nearest(body.vertices(), x);
            assert!(d <= 1e-6 * s, "{context}: true vertex {x} missing ({d:e} away)");
        }
        // Every face plane is one of the inputs.
        for plane in body.planes() {
            assert!(planes.contains(&plane), "{context}: invented plane");
        }
        if case % 10 == 0 {
            volume_checks += 1;
            let n = 4000;
            let fraction = monte_carlo_fraction(&mut rng, &planes, pmin, pmax, n);
            let box_volume = (pmax - pmin).element_product();
            let expected = body.volume() / box_volume;
            let sigma = (expected * (1.0 - expected) / n as f64).sqrt().max(1.0 / n as f64);
            let error = (expected - fraction).abs();
            assert!(error <= 6.0 * sigma + 1e-6, "{context}: volume fraction {expected} vs Monte Carlo {fraction}");
        }
    }
    assert!(non_empty > 7000, "{non_empty}");
    assert!(volume_checks > 700);
}

#[test]
fn clipping_is_idempotent_and_monotone() {
    let mut rng = rng(2);
    for case in 0..cases(3000) {
        let s = log_uniform(&mut rng, 1e-6, 1e5);
        let (body, eps) = random_body(&mut rng, s);
        let (min, max) = body.aabb().unwrap();
        let plane = random_planes(&mut rng, min, max, 1)[0];
        let once = body.clip(&plane, eps);
        assert_eq!(once.clip(&plane, eps), once, "case {case}: not idempotent");
        assert!(once.volume() <= body.volume() * (1.0 + 1e-12), "case {case}: grew");
        let other = body.clip(&plane.flipped(), eps);
        // The halves may overlap or miss slivers up to eps thick.
        let total = once.volume() + other.volume();
        let slack = 1e-12 * body.volume() + 2.0 * eps * surface_area(&body);
        assert!((total - body.volume()).abs() <= slack, "case {case}: halves {total} vs {}", body.volume());
    }
}

/// `conv(body ∪ {p})` built directly agrees with a big box clipped by the
/// hull planes, whose vertices must all be input points.
#[test]
fn hull_with_point_matches_clipped_box() {
    let mut rng = rng(3);
    let mut outside = 0;
    for case in 0..cases(5000) {
        let s = log_uniform(&mut rng, 1e-6, 1e5);
        let (body, eps) = random_body(&mut rng, s);
        let (min, max) = body.aabb().unwrap();
        let center = body.centroid();
        let p = match case % 4 {
            0 => in_box(&mut rng, min, max),
            1 => center + unit_vector(&mut rng) * log_uniform(&mut rng, 1e-3, 1e3) * s,
            // Close to a vertex or a face: near-degenerate silhouettes.
            2 => body.vertices()[rng.random_range(0..body.vertices().len())] + unit_vector(&mut rng) * 1e-7 * s,
            _ => {
                let face = body.face(rng.random_range(0..body.face_count())).expect("a face");
                let x = body.vertices()[face.indices()[0]].lerp(body.vertices()[face.indices()[1]], rng.random());
                x + face.plane().normal * rng.random_range(-2.0..2.0) * eps
            }
        };
        let context = format!("case {case} (scale {s:e})");
        let tol = 4.0 * eps;
        let planes = body.hull_with_point_planes(p, eps);
        for plane in &planes {
            assert!(plane.signed_distance(p) <= tol, "{context}: p outside a hull plane");
            for &v in body.vertices() {
                assert!(plane.signed_distance(v) <= tol, "{context}: vertex outside a hull plane");
            }
        }
        let hull = body.hull_with_point(p, eps);
        assert_closed(&hull, tol, &context);
        if !body.contains(p, eps) {
            outside += 1;
            assert!(hull.vertices().contains(&p), "{context}: p is not a hull vertex");
        }

        // Independent construction: a big box cut by the planes. Its vertices
        // must all be input points (no plane missing or wrong).
        let (lo, hi) = (min.min(p), max.max(p));
        let margin = DVec3::splat(0.5 * (hi - lo).length());
        let clipped = ConvexPolyhedron::from_aabb(lo - margin, hi + margin).clip_all(&planes, eps);
        assert_closed(&clipped, tol, &context);
        let mut points = body.vertices().to_vec();
        points.push(p);
        for &x in clipped.vertices() {
            assert!(hull.contains(x, tol), "{context}: clipped hull vertex {x} outside the hull");
        }
        for &x in hull.vertices() {
            assert!(clipped.contains(x, tol), "{context}: hull vertex {x} outside the clipped hull");
        }
        // With p well away from the features of a body that is not flat
        // (cases 0 and 1), planes meet at healthy angles and the vertex sets
        // agree. (Otherwise nearly parallel planes let the clipped vertices
        // wander along them by up to eps / angle, within eps of all planes.)
        let fat = body.volume() > 1e-3 * body.scale().powi(3);
        if case % 4 < 2 && fat {
            let match_tol = 1e-6 * (s + (p - center).length());
            for &x in clipped.vertices() {
                assert!(nearest(&points, x) <= match_tol, "{context}: clipped hull has foreign vertex {x}");
            }
            for &x in hull.vertices() {
                assert!(nearest(clipped.vertices(), x) <= match_tol, "{context}: hull vertex {x} not in clipped hull");
            }
        }
        let (vh, vc) = (hull.volume(), clipped.volume());
        let slack = 1e-9 * vc + 4.0 * eps * surface_area(&hull);
        assert!((vh - vc).abs() <= slack, "{context}: volumes {vh} vs {vc}");
        assert!(vh >= body.volume() - slack, "{context}: hull smaller than body");
        // Every hull face is a supporting plane touching at least 3 points.
        for plane in hull.planes() {
            let touching = points.iter().filter(|&&x| plane.signed_distance(x).abs() <= tol).count();
            assert!(touching >= 3, "{context}: hull face touches {touching} points");
        }
    }
    assert!(outside > 2000, "{outside}");
}

/// A random camera's view frustum; glam's `rh` and `lh` conventions give
/// mirror images.
struct Frustum {
    clip_from_world: DMat4,
    corners: [DVec3; 8],
    volume: f64,
    far: f64,
    tan_y: f64,
    aspect: f64,
    world_from_view: DMat4,
    forward: f64,
}

impl Frustum {
    /// World position of NDC `(x, y)` at view depth `depth`.
    fn point(&self, x: f64, y: f64, depth: f64) -> DVec3 {
        let view = DVec3::new(x * self.tan_y * self.aspect * depth, y * self.tan_y * depth, self.forward * depth);
        self.world_from_view.transform_point3(view)
    }
}

fn random_frustum(rng: &mut impl Rng, near: f64, far: f64, right_handed: bool) -> Frustum {
    let fov = rng.random_range(0.1..2.8);
    let aspect = log_uniform(rng, 0.25, 4.0);
    let eye = unit_vector(rng) * rng.random_range(0.0..10.0) * far.sqrt();
    let forward_dir = unit_vector(rng);
    let up = loop {
        let up = unit_vector(rng);
        if up.cross(forward_dir).length() > 0.1 {
            break up;
        }
    };
    let (view, proj, forward) = if right_handed {
        (
            glam::dcamera::rh::view::look_to_mat4(eye, forward_dir, up),
            glam::dcamera::rh::proj::directx::perspective(fov, aspect, near, far),
            -1.0,
        )
    } else {
        (
            glam::dcamera::lh::view::look_to_mat4(eye, forward_dir, up),
            glam::dcamera::lh::proj::directx::perspective(fov, aspect, near, far),
            1.0,
        )
    };
    let tan_y = (0.5 * fov).tan();
    let mut f = Frustum {
        clip_from_world: proj * view,
        corners: [DVec3::ZERO; 8],
        volume: 4.0 / 3.0 * tan_y * tan_y * aspect * (far.powi(3) - near.powi(3)),
        far,
        tan_y,
        aspect,
        world_from_view: view.inverse(),
        forward,
    };
    f.corners = std::array::from_fn(|i| {
        let x = if i & 1 == 0 { -1.0 } else { 1.0 };
        let y = if i & 2 == 0 { -1.0 } else { 1.0 };
        f.point(x, y, if i & 4 == 0 { near } else { far })
    });
    f
}

#[test]
fn frusta_from_random_cameras() {
    let mut rng = rng(4);
    for case in 0..cases(3000) {
        let extreme = case % 3 == 0;
        let (near, far) = if extreme {
            (1e-4, 1e6)
        } else {
            let near = log_uniform(&mut rng, 1e-3, 10.0);
            (near, near * log_uniform(&mut rng, 1.5, 1e4))
        };
        let right_handed = case % 2 == 0;
        let f = random_frustum(&mut rng, near, far, right_handed);
        let context = format!("case {case} (near {near:e}, far {far:e}, rh {right_handed})");
        let body = ConvexPolyhedron::from_frustum_corners(&f.corners).unwrap_or_else(|| panic!("{context}: None"));
        let eps = body.default_eps();
        assert_closed(&body, 4.0 * eps, &context);
        assert!(
            (body.volume() - f.volume).abs() <= 1e-9 * f.volume,
            "{context}: volume {} vs {}",
            body.volume(),
            f.volume
        );

        for _ in 0..20 {
            let depth = log_uniform(&mut rng, near, far);
            let (x, y) = (rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0));
            assert!(body.contains(f.point(x, y, depth), 0.5 * eps), "{context}: inside point rejected");
            // Push outside in x by a margin well above eps.
            let half_width = f.tan_y * f.aspect * depth;
            if 0.05 * half_width > 20.0 * eps {
                let outside = f.point(x.signum() * 1.1, y, depth);
                assert!(!body.contains(outside, eps), "{context}: outside point accepted");
            }
        }
        assert!(!body.contains(f.point(0.0, 0.0, 0.5 * near), eps) || 0.5 * near < 2.0 * eps);

        if !extreme {
            // The planes of the clip matrix agree with the faces.
            let m = f.clip_from_world;
            let (r0, r1, r2, r3) = (m.row(0), m.row(1), m.row(2), m.row(3));
            for h in [r0 - r3, -r0 - r3, r1 - r3, -r1 - r3, -r2, r2 - r3] {
                let plane = Plane::from_homogeneous(h).unwrap();
                let matched = body.planes().any(|q| {
                    (q.normal - plane.normal).length() < 1e-9 && (q.offset - plane.offset).abs() < 1e-9 * (1.0 + f.far)
                });
                assert!(matched, "{context}: clip plane {plane:?} not a face");
            }
        }
        // Corners from the inverse clip matrix (as a camera computes them;
        // ill-conditioned for extreme near/far) give the same body.
        let inverse = f.clip_from_world.inverse();
        let corners: [DVec3; 8] = std::array::from_fn(|i| {
            let x = if i & 1 == 0 { -1.0 } else { 1.0 };
            let y = if i & 2 == 0 { -1.0 } else { 1.0 };
            inverse.project_point3(DVec3::new(x, y, if i & 4 == 0 { 0.0 } else { 1.0 }))
        });
        let again = ConvexPolyhedron::from_frustum_corners(&corners)
            .unwrap_or_else(|| panic!("{context}: None from the inverse matrix's corners"));
        // (The inverse loses about `f64::EPSILON * far / near` relative
        // accuracy: up to ~1e-5 for near 1e-4, far 1e6.)
        let accuracy = if extreme { 1e-4 } else { 1e-9 };
        let error = (again.volume() - body.volume()).abs() / body.volume();
        assert!(error <= accuracy, "{context}: volume from the inverse matrix off by {error:e}");
    }
}

#[test]
fn frusta_survive_clipping_at_all_scales() {
    let mut rng = rng(5);
    for case in 0..cases(2000) {
        let s = log_uniform(&mut rng, 1e-6, 1e5);
        let near = s * log_uniform(&mut rng, 1e-4, 1.0);
        let f = random_frustum(&mut rng, near, s, case % 2 == 0);
        let body = ConvexPolyhedron::from_frustum_corners(&f.corners).unwrap();
        let eps = body.default_eps();
        let (min, max) = body.aabb().unwrap();
        // A flat scene box through the middle, and random planes.
        let mut box_max = max;
        box_max.y = min.y + 0.5 * (max.y - min.y);
        let mut box_min = min;
        box_min.y = box_max.y;
        let widen = DVec3::new(s, 0.0, s);
        let flat = body.intersect_aabb(box_min - widen, box_max + widen, eps);
        let context = format!("case {case}");
        if !flat.is_empty() {
            assert_closed(&flat, 4.0 * eps, &context);
            let (fmin, fmax) = flat.aabb().unwrap();
            let thickness = fmax.y - fmin.y;
            assert!(thickness <= 1e-8 * (s + (max - min).length()) + 1e-12, "{context}: flat box {thickness} thick");
        }
        let cut = body.clip_all(&random_planes(&mut rng, min, max, 4), eps);
        if !cut.is_empty() {
            assert_closed(&cut, 4.0 * eps, &context);
        }
    }
}

/// A plane tilted from `plane` by about `angle` and moved by `shift`, pivoting
/// around `pivot`.
fn perturbed(rng: &mut impl Rng, plane: Plane, pivot: DVec3, angle: f64, shift: f64) -> Plane {
    let normal = (plane.normal + unit_vector(rng) * angle).normalize();
    let on_plane = pivot - plane.normal * plane.signed_distance(pivot);
    let mut q = Plane::from_point_normal(on_plane, normal);
    q.offset -= shift;
    q
}

#[test]
fn nearly_parallel_cuts_stay_closed() {
    let mut rng = rng(9);
    for case in 0..cases(3000) {
        let s = log_uniform(&mut rng, 1e-6, 1e5);
        let (mut body, eps) = random_body(&mut rng, s);
        let context = format!("case {case} (scale {s:e})");
        // A cascade of planes within a few eps and tiny angles of one face,
        // as PSM's hull planes are when the light is near a face's plane.
        let face = body.face(rng.random_range(0..body.face_count())).expect("a face").plane();
        let pivot = body.centroid();
        for _ in 0..rng.random_range(1..8) {
            let angle = log_uniform(&mut rng, 1e-12, 1e-5);
            let shift = rng.random_range(-3.0..3.0) * eps;
            let plane = perturbed(&mut rng, face, pivot, angle, shift);
            let next = body.clip(&plane, eps);
            if next.is_empty() {
                break;
            }
            body = next;
            assert_closed(&body, 4.0 * eps, &context);
        }
        // And the light just off that face.
        let p = pivot + face.normal * (face.signed_distance(pivot).abs() + rng.random_range(-3.0..3.0) * eps);
        let hull = body.hull_with_point(p, eps);
        assert_closed(&hull, 4.0 * eps, &context);
        for plane in body.hull_with_point_planes(p, eps) {
            assert!(plane.signed_distance(p) <= 4.0 * eps, "{context}");
            assert!(body.vertices().iter().all(|&v| plane.signed_distance(v) <= 4.0 * eps), "{context}");
        }
    }
}

/// Whether `q` lies in `body` swept along `dir`: the ray `q - t dir`, `t >= 0`,
/// meets `body` (within `tol`).
fn in_extrusion(body: &ConvexPolyhedron, dir: DVec3, q: DVec3, tol: f64) -> bool {
    let (mut lo, mut hi) = (0.0f64, f64::INFINITY);
    for plane in body.planes() {
        // d(q - t dir) = d(q) - t (n · dir) <= tol
        let (d, rate) = (plane.signed_distance(q) - tol, plane.normal.dot(dir));
        if rate > 0.0 {
            lo = lo.max(d / rate);
        } else if rate < 0.0 {
            hi = hi.min(d / rate);
        } else if d > 0.0 {
            return false;
        }
    }
    lo <= hi * (1.0 + 1e-12)
}

#[test]
fn extrusion_clipped_by_box_is_the_sweep() {
    let mut rng = rng(6);
    for case in 0..cases(5000) {
        let s = log_uniform(&mut rng, 1e-6, 1e5);
        let (body, eps) = if case % 2 == 0 {
            random_body(&mut rng, s)
        } else {
            let near = s * log_uniform(&mut rng, 1e-3, 0.5);
            let f = random_frustum(&mut rng, near, s, case % 4 == 1);
            let body = ConvexPolyhedron::from_frustum_corners(&f.corners).unwrap();
            let eps = body.default_eps();
            (body, eps)
        };
        let dir = match case % 5 {
            // Parallel to a face.
            0 => {
                let n = body.face(rng.random_range(0..body.face_count())).expect("a face").plane().normal;
                n.any_orthonormal_vector()
            }
            1 => [DVec3::X, DVec3::NEG_Y, DVec3::Z][rng.random_range(0..3)],
            _ => unit_vector(&mut rng),
        } * log_uniform(&mut rng, 1e-3, 1e3);
        let context = format!("case {case} (scale {s:e})");
        let planes = body.extrusion_planes(dir, eps);
        let tol = 4.0 * eps;
        for plane in &planes {
            assert!(plane.normal.dot(dir.normalize()) <= 1e-12, "{context}: plane facing along dir");
            for &v in body.vertices() {
                assert!(plane.signed_distance(v) <= tol, "{context}: body outside an extrusion plane");
            }
        }
        let (min, max) = body.aabb().unwrap();
        let grow = DVec3::new(rng.random_range(0.5..3.0), rng.random_range(0.5..3.0), rng.random_range(0.5..3.0)) * s;
        let (bmin, bmax) = (min - grow, max + grow);
        let swept = ConvexPolyhedron::from_aabb(bmin, bmax).clip_all(&planes, eps);
        assert_closed(&swept, tol, &context);

        let d = dir.normalize();
        let inner = (bmin + DVec3::splat(tol), bmax - DVec3::splat(tol));
        for _ in 0..30 {
            let x = body.vertices()[rng.random_range(0..body.vertices().len())];
            let q = x + d * rng.random_range(0.0..6.0) * s;
            if q.cmpge(inner.0).all() && q.cmple(inner.1).all() {
                assert!(swept.contains(q, tol), "{context}: swept point missing");
            }
        }
        let vertices = swept.vertices();
        for _ in 0..30 {
            let weights: Vec<f64> = (0..vertices.len()).map(|_| -rng.random::<f64>().max(1e-300).ln()).collect();
            let total: f64 = weights.iter().sum();
            let q = vertices.iter().zip(&weights).map(|(&v, &w)| v * (w / total)).sum::<DVec3>();
            assert!(in_extrusion(&body, d, q, tol), "{context}: point {q} not in the sweep");
        }
        for &v in vertices {
            assert!(in_extrusion(&body, d, v, tol), "{context}: vertex {v} not in the sweep");
        }
    }
}

/// The largest `cos_half_angle` among the caps through one, two or three of
/// `units` that contain all of them (the optimum is one of these).
fn brute_force_cone_cos(units: &[DVec3]) -> f64 {
    let valid = |axis: DVec3| units.iter().map(|&u| axis.dot(u)).fold(f64::INFINITY, f64::min);
    let mut best = f64::NEG_INFINITY;
    let n = units.len();
    for i in 0..n {
        best = best.max(valid(units[i]));
        for j in i + 1..n {
            if let Some(axis) = (units[i] + units[j]).try_normalize() {
                best = best.max(valid(axis));
            }
            for k in j + 1..n {
                if let Some(axis) = (units[j] - units[i]).cross(units[k] - units[i]).try_normalize() {
                    let axis = if axis.dot(units[i]) < 0.0 { -axis } else { axis };
                    best = best.max(valid(axis));
                }
            }
        }
    }
    best
}

#[test]
fn cones_are_minimal_and_contain_everything() {
    let mut rng = rng(7);
    let (mut some, mut none) = (0, 0);
    for case in 0..cases(10000) {
        let n = rng.random_range(1..12);
        let axis = unit_vector(&mut rng);
        let (u, v) = axis.any_orthonormal_pair();
        let spread = if case % 3 == 0 { rng.random_range(0.0..3.2) } else { log_uniform(&mut rng, 1e-6, 1.55) };
        let mut dirs: Vec<DVec3> = (0..n)
            .map(|_| {
                let theta = rng.random_range(0.0..spread);
                let phi = rng.random_range(0.0..std::f64::consts::TAU);
                (axis * theta.cos() + (u * phi.cos() + v * phi.sin()) * theta.sin()) * log_uniform(&mut rng, 1e-3, 1e3)
            })
            .collect();
        if case % 7 == 0 {
            dirs.push(DVec3::ZERO);
        }
        let units: Vec<DVec3> = dirs.iter().filter_map(|d| d.try_normalize()).collect();
        let best = brute_force_cone_cos(&units);
        let context = format!("case {case}: n {n}, spread {spread}, brute force cos {best}");
        match min_enclosing_cone(&dirs) {
            Some(cone) => {
                some += 1;
                assert!((cone.axis.length() - 1.0).abs() < 1e-12, "{context}");
                for &d in &dirs {
                    if d != DVec3::ZERO {
                        assert!(cone.contains(d), "{context}: {d} outside");
                        assert!(cone.axis.dot(d.normalize()) >= cone.cos_half_angle - 1e-12, "{context}");
                    }
                }
                assert!(cone.cos_half_angle > 1e-12, "{context}");
                assert!(cone.cos_half_angle >= best - 1e-9, "{context}: cone cos {} not minimal", cone.cos_half_angle);
                assert!(cone.cos_half_angle <= best + 1e-9, "{context}: beats brute force: {}", cone.cos_half_angle);
            }
            None => {
                none += 1;
                assert!(best <= 1e-9, "{context}: None, but a cone exists");
            }
        }
    }
    assert!(some > 5000 && none > 300, "{some} / {none}");
}

#[test]
fn cones_refuse_more_than_a_hemisphere() {
    let mut rng = rng(8);
    for case in 0..cases(1000) {
        let mut dirs: Vec<DVec3> = (0..rng.random_range(1..10)).map(|_| unit_vector(&mut rng)).collect();
        let u = dirs[0];
        dirs.push(-u * 3.0);
        assert!(min_enclosing_cone(&dirs).is_none(), "case {case}");
    }
    let tetrahedron = [
        DVec3::new(1.0, 1.0, 1.0),
        DVec3::new(1.0, -1.0, -1.0),
        DVec3::new(-1.0, 1.0, -1.0),
        DVec3::new(-1.0, -1.0, 1.0),
    ];
    assert!(min_enclosing_cone(&tetrahedron).is_none());
    // The tetrahedron minus one vertex fits.
    let cone = min_enclosing_cone(&tetrahedron[..3]).unwrap();
    assert!((cone.axis + tetrahedron[3].normalize()).length() < 1e-12);
}

fn any_vec3() -> impl Strategy<Value = DVec3> {
    let coordinate = prop_oneof![
        4 => -10.0..10.0f64,
        1 => any::<f64>(),
        1 => Just(0.0),
    ];
    (coordinate.clone(), coordinate.clone(), coordinate).prop_map(|(x, y, z)| DVec3::new(x, y, z))
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 1000, failure_persistence: None, ..ProptestConfig::default() })]

    /// Arbitrary (also non-finite and huge) input never panics, and whatever
    /// comes out non-empty is a closed polyhedron.
    #[test]
    fn arbitrary_input_never_panics(
        a in any_vec3(), b in any_vec3(), n in any_vec3(), p in any_vec3(), offset in any::<f64>(),
        corners in proptest::array::uniform8(any_vec3()),
    ) {
        let body = ConvexPolyhedron::from_aabb(a.min(b), a.max(b));
        let plane = Plane { normal: n.normalize_or_zero(), offset: offset.clamp(-20.0, 20.0) };
        let eps = body.default_eps();
        for result in [
            body.clip(&plane, eps),
            body.hull_with_point(p, eps),
            body.clip_all(&body.extrusion_planes(n, eps), eps),
            body.clip_all(&body.hull_with_point_planes(p, eps), eps),
            body.intersect_aabb(b, a, eps),
        ] {
            if !result.is_empty() {
                prop_assert!(result.vertices().iter().all(|v| v.is_finite()));
                prop_assert!(result.faces().len() >= 4);
            }
        }
        if let Some(frustum) = ConvexPolyhedron::from_frustum_corners(&corners) {
            prop_assert!(frustum.volume() > 0.0);
        }
        if let Some(cone) = min_enclosing_cone(&[a, b, n, p]) {
            prop_assert!(cone.cos_half_angle > 0.0);
            for d in [a, b, n, p] {
                prop_assert!(!d.is_finite() || d == DVec3::ZERO || cone.contains(d));
            }
        }
    }

    /// Clipping a box by a plane splits its volume exactly.
    #[test]
    fn clip_splits_volume(
        half in (0.1..10.0f64, 0.1..10.0f64, 0.1..10.0f64),
        n in (-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64),
        t in -1.5..1.5f64,
    ) {
        let half = DVec3::new(half.0, half.1, half.2);
        let Some(n) = DVec3::new(n.0, n.1, n.2).try_normalize() else { return Ok(()) };
        let body = ConvexPolyhedron::from_aabb(-half, half);
        let plane = Plane::from_point_normal(half * t, n);
        let eps = body.default_eps();
        let (a, b) = (body.clip(&plane, eps), body.clip(&plane.flipped(), eps));
        prop_assert!((a.volume() + b.volume() - body.volume()).abs() <= 1e-9 * body.volume());
    }
}

// ---------------------------------------------------------------------------
// Planar hull: the thinned hull against a plain monotone chain
// ---------------------------------------------------------------------------

/// Andrew's monotone chain with Shewchuk's exact orientation and no
/// thinning: the oracle of `convex_hull_2d` (which thins inputs of more than
/// 64 points before its chain).
fn plain_hull(points: &[glam::DVec2]) -> Vec<glam::DVec2> {
    use glam::DVec2;
    let orient = |a: DVec2, b: DVec2, c: DVec2| {
        robust::orient2d(
            robust::Coord { x: a.x, y: a.y },
            robust::Coord { x: b.x, y: b.y },
            robust::Coord { x: c.x, y: c.y },
        )
    };
    let mut sorted: Vec<DVec2> = points.iter().copied().filter(|p| p.is_finite()).collect();
    sorted.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    sorted.dedup();
    if sorted.len() <= 2 {
        return sorted;
    }
    let mut hull: Vec<DVec2> = Vec::new();
    for &p in &sorted {
        while hull.len() >= 2 && !(orient(hull[hull.len() - 2], hull[hull.len() - 1], p) > 0.0) {
            hull.pop();
        }
        hull.push(p);
    }
    let lower = hull.len();
    for &p in sorted.iter().rev().skip(1) {
        while hull.len() > lower && !(orient(hull[hull.len() - 2], hull[hull.len() - 1], p) > 0.0) {
            hull.pop();
        }
        hull.push(p);
    }
    hull.pop();
    hull
}

/// Large point sets of the shapes that reach the thinning's edges: a
/// readback's pixels (in row order) through random perspective maps,
/// integer grids (collinear runs on the thinning polygons' edges), points
/// exactly on the edges of a polygon, repeated points, one line, a circle
/// with points an ulp inside; at scales from 1e-300 (products underflow)
/// to 1e300 (products overflow) and far from the origin. The hull is the
/// plain chain's, bit for bit, through both entry points.
#[test]
fn planar_hull_thinning_keeps_the_hull() {
    use glam::DVec2;
    use lixel::fit::{convex_hull_2d, convex_hull_2d_into};
    let mut rng = rng(0x48_1516_2342);
    let (mut scratch, mut reused) = (Vec::new(), Vec::new());
    for case in 0..cases(600) {
        let n = rng.random_range(65..4000usize);
        let w = rng.random_range(5..120usize);
        let shape = case % 8;
        let (h1, h2, h3) = (rng.random_range(-0.02..0.02), rng.random_range(-0.02..0.02), rng.random_range(-1.0..1.0));
        let mut points: Vec<DVec2> = (0..n)
            .map(|k| {
                let (px, py) = ((k % w) as f64, (k / w) as f64);
                match shape {
                    0 | 1 => {
                        let q = 1.0 + h1 * px + h2 * py;
                        DVec2::new((px + h3 * py) / q, (py - 0.2 * px) / q)
                    }
                    2 => DVec2::new(px, py),
                    3 => {
                        // On the edges of an octagon with integer corners.
                        let corners = [(0, -8), (6, -6), (8, 0), (6, 6), (0, 8), (-6, 6), (-8, 0), (-6, -6)];
                        let (i, t) = (k % 8, (k / 8 % 32) as f64 / 32.0);
                        let (a, b) = (corners[i], corners[(i + 1) % 8]);
                        let (a, b) = (DVec2::new(a.0 as f64, a.1 as f64), DVec2::new(b.0 as f64, b.1 as f64));
                        if k % 5 == 0 {
                            (a + (b - a) * t) * 0.5
                        } else {
                            a + (b - a) * t
                        }
                    }
                    4 => DVec2::new((k % 13) as f64 * 0.5, (k % 7) as f64 * 0.25),
                    5 => DVec2::new(k as f64 * 0.75, k as f64 * -1.5 + 2.0),
                    6 => {
                        let a = rng.random_range(0.0..core::f64::consts::TAU);
                        DVec2::from_angle(a) * (1.0 - f64::EPSILON * (k % 3) as f64)
                    }
                    _ => DVec2::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0)),
                }
            })
            .collect();
        let scale = [1.0, 1e-300, 1e-160, 1e-20, 1e20, 1e150, 1e300, 7.0][rng.random_range(0..8)];
        let offset = if rng.random_bool(0.2) { DVec2::new(3e8, -1e9) } else { DVec2::ZERO };
        for p in &mut points {
            // `+ 0.0` turns −0.0 into 0.0: the two tie in the sort, and
            // which one a hull keeps is unspecified.
            *p = *p * scale + offset + DVec2::ZERO;
        }
        if case % 3 == 2 {
            for i in (1..points.len()).rev() {
                points.swap(i, rng.random_range(0..=i));
            }
        }
        let expected = plain_hull(&points);
        let bits = |h: &[DVec2]| h.iter().map(|p| (p.x.to_bits(), p.y.to_bits())).collect::<Vec<_>>();
        let context = format!("case {case}: shape {shape}, {n} points, scale {scale:e}");
        assert_eq!(bits(&convex_hull_2d(&points)), bits(&expected), "{context}");
        convex_hull_2d_into(&points, &mut scratch, &mut reused);
        assert_eq!(bits(&reused), bits(&expected), "{context}");
    }
}
