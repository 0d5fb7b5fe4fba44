//! Cascades: the splits cover the view range with no gaps and the stated
//! overlap, and every method (and the scene optimizer, per cascade from one
//! readback) holds each cascade's relevant points — checked independently
//! of the solver's bodies and of the sliced cameras: relevant points are
//! drawn in the receiver box, kept when the *full* camera sees them, and
//! given to a cascade by their view depth.

mod common;

use glam::{DVec3, UVec2};
use lixel::cascade::{CascadeOptimizer, CascadeProblems, CascadeSplits, SplitScheme, SplitTracker, Splits};
use lixel::optimize::{OptimizeOptions, SampleOptions};
use lixel::synthetic::{Sphere, SyntheticScene};
use lixel::{Aabb, Camera, Light, LightMatrix, LixelError, Parameterization, ShadowMapSize, ShadowProblem};
use proptest::prelude::*;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

const SLACK: f64 = 1e-6;

fn scheme(kind: u8, lambda: f64) -> SplitScheme {
    match kind {
        0 => SplitScheme::Uniform,
        1 => SplitScheme::Logarithmic,
        _ => SplitScheme::Practical { lambda },
    }
}

fn check_cover(splits: &Splits, overlap: f64, near: f64, far: f64, probes: &[f64]) -> Result<(), TestCaseError> {
    let b = splits.boundaries();
    let k = splits.count();
    prop_assert_eq!(b[0], near);
    prop_assert_eq!(b[k], far);
    prop_assert!(b.windows(2).all(|w| w[1] > w[0]), "not increasing: {:?}", b);
    prop_assert_eq!(splits.slice(0).0, near);
    prop_assert_eq!(splits.slice(k - 1).1, far);
    for i in 1..k {
        let (prev, this) = (splits.slice(i - 1), splits.slice(i));
        // No gap, and exactly the stated overlap.
        prop_assert!(this.0 <= prev.1, "gap between {:?} and {:?}", prev, this);
        let want = overlap * (b[i] - b[i - 1]);
        let got = prev.1 - this.0;
        prop_assert!((got - want).abs() <= 1e-9 * far.abs().max(near.abs()), "overlap {} want {}", got, want);
    }
    for &t in probes {
        let d = near + (far - near) * t;
        let c = splits.choose(d).expect("inside [near, far]");
        let (lo, hi) = splits.slice(c.index);
        prop_assert!(d >= lo && d <= hi, "depth {} chose {:?} whose slice is {:?}", d, c, (lo, hi));
        prop_assert!((0.0..1.0).contains(&c.blend));
        if c.blend > 0.0 {
            let (lo, hi) = splits.slice(c.index + 1);
            prop_assert!(d >= lo && d <= hi, "blend into {} which does not hold {}", c.index + 1, d);
        }
        // The bit owner's slice holds the depth too (the mask bit is a
        // lookup of a map that covers the pixel).
        let owner = c.bit_owner();
        prop_assert!(owner == c.index || (owner == c.index + 1 && c.blend >= 0.5));
        let (lo, hi) = splits.slice(owner);
        prop_assert!(d >= lo && d <= hi, "bit owner {} does not hold {}", owner, d);
    }
    prop_assert!(splits.choose(far + (far - near) * 1e-3).is_none());
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]
    #[test]
    fn splits_cover_the_view_range_with_the_stated_overlap(
        count in 1usize..=8,
        kind in 0u8..3,
        lambda in 0.0f64..=1.0,
        overlap in prop_oneof![Just(0.0), 0.0f64..0.99],
        near_exp in -6.0f64..12.0,
        ratio_exp in 0.3f64..9.0,
        orthographic in any::<bool>(),
        probes in prop::collection::vec(0.0f64..=1.0, 16),
    ) {
        let policy = CascadeSplits { count, scheme: scheme(kind, lambda), overlap };
        let scale = 10f64.powf(near_exp);
        // Perspective: 0 < near; orthographic: near may be at or behind the eye.
        let (near, far) = if orthographic { (-scale, scale * 10f64.powf(ratio_exp)) } else { (scale, scale * 10f64.powf(ratio_exp)) };
        let splits = policy.place(near, far).unwrap();
        prop_assert_eq!(splits.count(), count);
        check_cover(&splits, overlap, near, far, &probes)?;
    }
}

/// Shadow-map contract for one point of one cascade, with the casters
/// between it and the light (method_props' checker, restated).
fn check_point(problem: &ShadowProblem, m: &LightMatrix, p: DVec3) -> Result<(), String> {
    let depth_ok = |z: f64| z <= 1.0 + SLACK && (z >= -SLACK || m.needs_unclipped_depth);
    let c = m.clip_from_world * p.extend(1.0);
    if !(c.w > 0.0) {
        return Err(format!("{p} behind the light"));
    }
    let ndc = c.truncate() / c.w;
    if !(ndc.x.abs() <= 1.0 + SLACK && ndc.y.abs() <= 1.0 + SLACK && depth_ok(ndc.z)) {
        return Err(format!("{p} outside the map: ndc {ndc}"));
    }
    let Light::Directional { direction } = *problem.light() else { unreachable!("suns only") };
    for t in [1e-4, 1e-3, 0.01, 0.1, 0.3, 0.6, 0.9, 1.5, 3.0] {
        let q = p - direction * (t * problem.scale());
        if !problem.bounds().casters.contains(q) {
            continue;
        }
        let c = m.clip_from_world * q.extend(1.0);
        let z = c.z / c.w;
        if !(c.w > 0.0) || !depth_ok(z) || z.max(0.0) > ndc.z.max(0.0) + 1e-9 {
            return Err(format!("caster {q} of {p}: depth {z} vs {}", ndc.z));
        }
    }
    Ok(())
}

/// Points the full camera sees in the receiver box, with their view depths.
fn visible_points(problem: &ShadowProblem, rng: &mut ChaCha8Rng) -> Vec<(DVec3, f64)> {
    let camera = problem.camera();
    let r = problem.bounds().receivers;
    let in_view = |p: DVec3| {
        let c = camera.clip_from_world() * p.extend(1.0);
        c.w > 0.0 && c.x.abs() <= c.w && c.y.abs() <= c.w && c.z >= 0.0 && c.z <= c.w
    };
    let mut out: Vec<DVec3> = Vec::new();
    for _ in 0..800 {
        let t = DVec3::new(rng.random_range(0.0..=1.0), rng.random_range(0.0..=1.0), rng.random_range(0.0..=1.0));
        let p = r.min + (r.max - r.min) * t;
        if in_view(p) {
            out.push(p);
            if out.len() == 48 {
                break;
            }
        }
    }
    out.extend(r.corners().into_iter().filter(|&p| in_view(p)));
    out.into_iter().map(|p| (p, camera.view_depth(p))).collect()
}

/// A sun for configuration `i`: along the view both ways, parallel to the
/// image plane, grazing the floor, or anywhere.
fn sun(i: usize, view: DVec3, rng: &mut ChaCha8Rng) -> Light {
    let (right, _) = view.any_orthonormal_pair();
    let horizontal = DVec3::new(rng.random_range(-1.0..1.0), 0.0, rng.random_range(-1.0..1.0)).normalize_or(DVec3::X);
    match i % 6 {
        0 => Light::directional(view),
        1 => Light::directional(-view),
        2 => Light::directional(right),
        3 => Light::directional(horizontal + DVec3::NEG_Y * 10f64.powf(rng.random_range(-9.0..-2.0))),
        4 => Light::directional(horizontal),
        _ => Light::directional(DVec3::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..0.2),
            rng.random_range(-1.0..1.0),
        )),
    }
}

#[test]
fn every_method_holds_each_cascades_relevant_points() {
    let n = (common::cases() / 16).max(20);
    let mut failures = Vec::new();
    let (mut solved, mut checked, mut thin) = (0usize, 0usize, 0usize);
    for i in 0..n {
        let mut config = if i % 4 == 3 { common::hard_config(20, 5 * i + 4).0 } else { common::config(20, i) };
        let mut rng = ChaCha8Rng::seed_from_u64(i as u64);
        config.light = sun(i, (config.target - config.eye).normalize(), &mut rng);
        let Some(problem) = config.problem() else { continue };
        let policy =
            CascadeSplits { count: 1 + i % 8, scheme: scheme((i % 3) as u8, 0.75), overlap: [0.0, 0.1, 0.5][i % 3] };
        let cascades = match policy.for_problem(&problem).and_then(|s| CascadeProblems::new(&problem, s)) {
            Ok(c) => c,
            Err(LixelError::InvalidCascades { .. }) => {
                thin += 1;
                continue;
            }
            Err(e) => {
                failures.push(format!("#{i}: cascades {e}\n  {config:?}"));
                continue;
            }
        };
        let points = visible_points(&problem, &mut rng);
        let splits = cascades.splits();
        for param in Parameterization::ALL_DEFAULT {
            let matrices = cascades.solve(&param);
            for (k, result) in matrices.iter().enumerate() {
                let m = match result {
                    Ok(m) => m,
                    Err(e) => {
                        failures.push(format!("#{i} cascade {k} {:?}: error {e}\n  {config:?}", param.method()));
                        continue;
                    }
                };
                solved += 1;
                let (lo, hi) = splits.slice(k);
                let slice_problem = &cascades.problems()[k];
                let mine = points.iter().filter(|(_, d)| *d >= lo && *d <= hi).map(|(p, _)| *p);
                let body = slice_problem.visible_receiver_body().vertices().to_vec();
                for p in mine.chain(body) {
                    checked += 1;
                    if let Err(e) = check_point(slice_problem, m, p) {
                        failures.push(format!(
                            "#{i} cascade {k} of {} {:?} slice [{lo}, {hi}]: {e}\n  fallback {:?}\n  {config:?}",
                            splits.count(),
                            param.method(),
                            m.fallback
                        ));
                        break;
                    }
                }
            }
            // Every point the camera sees within the splits has a cascade
            // whose matrix holds it (the per-pixel choice).
            for &(p, d) in &points {
                let Some(choice) = splits.choose(d) else {
                    if d >= splits.near() && d <= splits.far() {
                        failures.push(format!("#{i}: depth {d} inside the splits but no cascade"));
                    }
                    continue;
                };
                if let Ok(m) = &matrices[choice.index] {
                    if let Err(e) = check_point(&cascades.problems()[choice.index], m, p) {
                        failures.push(format!("#{i} chosen cascade {}: {e}", choice.index));
                    }
                }
            }
        }
    }
    eprintln!("{n} configurations: {solved} cascade matrices, {checked} points checked, {thin} ranges too thin");
    assert!(
        failures.is_empty(),
        "{} failures; first:\n{}",
        failures.len(),
        failures[..failures.len().min(5)].join("\n")
    );
    assert!(thin * 20 < n, "{thin} of {n} split ranges were too thin");
    assert!(checked > 1000, "only {checked} points checked");
}

fn walkthrough() -> SyntheticScene {
    let mut s = SyntheticScene { floor: Some((0.0, 200.0)), ..Default::default() };
    for k in 0..12 {
        let z = -3.0 - 12.0 * k as f64;
        let x = if k % 2 == 0 { -3.0 } else { 4.0 };
        s.spheres.push(Sphere { center: DVec3::new(x, 1.0, z), radius: 1.0 });
        s.boxes.push(Aabb::from_corners(DVec3::new(x + 2.0, 0.0, z - 4.0), DVec3::new(x + 3.5, 3.0, z - 2.5)));
    }
    s
}

/// Relevant pixels (shadowed, or next to a shadow boundary) of a readback
/// cut to the view depths `[near, far]` (pixels outside count as empty),
/// recomputed independently, with their view depths.
fn relevant_pixels(
    camera: &Camera,
    rb: &lixel::synthetic::SyntheticReadback,
    (near, far): (f64, f64),
) -> Vec<(DVec3, f64)> {
    let (w, h) = (rb.width as usize, rb.height as usize);
    let world_from_screen = camera.screen_from_world().inverse();
    let step = camera.viewport().as_dvec2() / glam::DVec2::new(w as f64, h as f64);
    let point = |x: usize, y: usize| {
        let pixel = (glam::DVec2::new(x as f64, y as f64) + 0.5) * step;
        world_from_screen.project_point3(pixel.extend(f64::from(rb.depth[y * w + x])))
    };
    let lit = |x: i64, y: i64| -> Option<bool> {
        let (x, y) = (usize::try_from(x).ok()?, usize::try_from(y).ok()?);
        let inside = x < w && y < h && rb.depth[y * w + x] < 1.0 && {
            let d = camera.view_depth(point(x, y));
            d >= near && d <= far
        };
        inside.then(|| rb.shadow_bits[y * w + x] & 1 == 0)
    };
    let mut out = Vec::new();
    for y in 0..h as i64 {
        for x in 0..w as i64 {
            let Some(here) = lit(x, y) else { continue };
            let mixed = (-1..=1).any(|dy| (-1..=1).any(|dx| lit(x + dx, y + dy).is_some_and(|l| l != here)));
            if !here || mixed {
                let p = point(x as usize, y as usize);
                out.push((p, camera.view_depth(p)));
            }
        }
    }
    out
}

#[test]
fn optimized_cascades_hold_their_slices_samples_along_a_walk() {
    let scene = walkthrough();
    let bounds = scene.bounds().unwrap();
    let sun = Light::directional(DVec3::new(0.4, -0.8, -0.45));
    let policy = CascadeSplits { count: 4, scheme: SplitScheme::Logarithmic, overlap: 0.1 };
    let mut tracker = SplitTracker::new(policy, 0.1).unwrap();
    let mut optimizer = CascadeOptimizer::new(4, &OptimizeOptions::default());
    let (mut optimized, mut checked) = (0, 0);
    for step in 0..6 {
        let eye = DVec3::new(0.3 * step as f64, 1.7, 6.0 - 2.0 * step as f64);
        let camera =
            Camera::look_at(eye, eye + DVec3::new(0.1, -0.15, -1.0), DVec3::Y, 1.1, UVec2::new(640, 480), 0.1, 400.0)
                .unwrap();
        let problem = ShadowProblem::new(camera, sun, bounds, ShadowMapSize::square(256)).unwrap();
        let rb = scene.render(&camera, &[sun], 64, 48);
        let readback = rb.as_readback(step % 2 == 0);
        let visible = lixel::cascade::visible_depth_range(&camera, &readback).unwrap();
        let (lo, hi) = visible.expect("the floor is in view");
        let splits = tracker.update(&problem, visible).unwrap().clone();
        assert!(splits.near() <= lo && splits.far() >= hi, "splits {splits:?} miss the visible range [{lo}, {hi}]");
        let cascades = CascadeProblems::new(&problem, splits.clone()).unwrap();
        let samples = CascadeOptimizer::samples(&cascades, &readback, 0, &SampleOptions::default()).unwrap();
        let results = optimizer.optimize(&samples).unwrap();
        for (k, result) in results.iter().enumerate() {
            let m = &result.as_ref().unwrap().matrix;
            optimized += usize::from(result.as_ref().unwrap().report.fallback.is_none());
            // Away from the slice ends by more than f32 rounding of depth.
            let (a, b) = splits.slice(k);
            let (a, b) = (a * (1.0 + 1e-5), b * (1.0 - 1e-5));
            for (p, _) in relevant_pixels(&camera, &rb, splits.slice(k)).into_iter().filter(|(_, d)| *d >= a && *d <= b)
            {
                checked += 1;
                check_point(&cascades.problems()[k], m, p).unwrap_or_else(|e| panic!("step {step} cascade {k}: {e}"));
            }
        }
    }
    assert!(optimized >= 8, "only {optimized} cascade optimizations had samples");
    assert!(checked > 500, "only {checked} pixels checked");
}
