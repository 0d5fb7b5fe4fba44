//! Scene-optimized matrices: gradient check, invariants over thousands of
//! seeded synthetic scenes, adversarial sample sets, and the walkthrough
//! comparison against focused and LiSPSM.

mod common;

use glam::{DMat3, DVec3, UVec2};
use lixel::optimize::{
    objective, objective_gradient, sample_badness, BoundarySample, OptimizeOptions, Optimizer, SampleOptions,
    SearchStrategy,
};
use lixel::synthetic::{Sphere, SyntheticScene};
use lixel::{
    Aabb, Camera, Fallback, Light, LightMatrix, LixelError, Method, Parameterization, Samples, ShadowMapSize,
    ShadowProblem,
};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn unit(rng: &mut impl Rng) -> DVec3 {
    loop {
        let v = DVec3::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0));
        if v.length() > 0.1 && v.length() <= 1.0 {
            return v.normalize();
        }
    }
}

#[test]
fn gradient_matches_central_differences() {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let mut checked = 0;
    for _ in 0..2000 {
        let sample = BoundarySample {
            light: unit(&mut rng) + DVec3::new(0.0, 0.0, 2.0),
            d_dx: unit(&mut rng) * rng.random_range(0.01..1.0),
            d_dy: unit(&mut rng) * rng.random_range(0.01..1.0),
        };
        let g = DMat3::from_cols(unit(&mut rng) * 100.0, unit(&mut rng) * 100.0, DVec3::Z + unit(&mut rng) * 0.3)
            .transpose();
        let Some((b, grad)) = objective_gradient(&g, &[sample]) else { continue };
        if !(b.is_finite() && b < 1e8) {
            continue;
        }
        let j = g.row(2);
        let h = 1e-6;
        let numeric = DVec3::from_array(std::array::from_fn(|k| {
            let mut dj = DVec3::ZERO;
            dj[k] = h;
            let at = |j: DVec3| sample_badness(&DMat3::from_cols(g.row(0), g.row(1), j).transpose(), &sample);
            (at(j + dj) - at(j - dj)) / (2.0 * h)
        }));
        let scale = grad.length().max(numeric.length()).max(1e-12);
        assert!((grad - numeric).length() <= 1e-4 * scale, "analytic {grad} vs numeric {numeric} (b = {b})");
        checked += 1;
    }
    assert!(checked > 1000, "only {checked} samples were checkable");
}

/// A walkthrough-like synthetic scene: floor, spheres and boxes on it.
fn scene(rng: &mut impl Rng) -> SyntheticScene {
    let half = 20.0;
    let mut s = SyntheticScene { floor: Some((0.0, half)), ..Default::default() };
    for _ in 0..rng.random_range(1..5) {
        let at = DVec3::new(rng.random_range(-15.0..15.0), 0.0, rng.random_range(-15.0..15.0));
        if rng.random_bool(0.5) {
            let r = rng.random_range(0.3..3.0);
            s.spheres.push(Sphere { center: at + DVec3::Y * rng.random_range(r..r + 3.0), radius: r });
        } else {
            let size = DVec3::new(rng.random_range(0.3..4.0), rng.random_range(0.3..6.0), rng.random_range(0.3..4.0));
            s.boxes
                .push(Aabb::from_corners(at - size * DVec3::new(0.5, 0.0, 0.5), at + size * DVec3::new(0.5, 1.0, 0.5)));
        }
    }
    s
}

fn random_light(rng: &mut impl Rng, index: usize, view: DVec3, eye: DVec3) -> Light {
    match index % 8 {
        0 => Light::directional(view),
        1 => Light::directional((view + DVec3::NEG_Y * 1e-9).normalize()),
        2 => Light::point(eye - view * 30.0 + DVec3::Y * 20.0),
        3 => Light::point(DVec3::new(
            rng.random_range(-30.0..30.0),
            rng.random_range(8.0..40.0),
            rng.random_range(-30.0..30.0),
        )),
        _ => {
            let mut d = unit(rng);
            d.y = -d.y.abs() - 0.05;
            Light::directional(d.normalize())
        }
    }
}

fn check_covers(matrix: &LightMatrix, points: &[DVec3], what: &str) -> Result<(), String> {
    if !matrix.clip_from_world.is_finite() {
        return Err(format!("{what}: non-finite matrix"));
    }
    for &p in points {
        let c = matrix.clip_from_world * p.extend(1.0);
        if !(c.w > 0.0) {
            return Err(format!("{what}: relevant {p} behind the light"));
        }
        let ndc = c.truncate() / c.w;
        if !(ndc.x.abs() <= 1.0 + 1e-6 && ndc.y.abs() <= 1.0 + 1e-6) {
            return Err(format!("{what}: relevant {p} outside the map, ndc {ndc}"));
        }
        if !(ndc.z <= 1.0 + 1e-6 && (ndc.z >= -1e-6 || matrix.needs_unclipped_depth)) {
            return Err(format!("{what}: relevant {p} outside the depth range, z {}", ndc.z));
        }
    }
    Ok(())
}

/// World positions of the relevant pixels of a readback (shadowed or next to
/// a shadow boundary), recomputed independently of `Samples`.
fn relevant_world(camera: &Camera, rb: &lixel::synthetic::SyntheticReadback, bit: u32) -> Vec<DVec3> {
    let (w, h) = (rb.width as usize, rb.height as usize);
    let world_from_screen = camera.screen_from_world().inverse();
    let step = camera.viewport().as_dvec2() / glam::DVec2::new(w as f64, h as f64);
    let mut out = Vec::new();
    for y in 0..h {
        for x in 0..w {
            let i = y * w + x;
            if rb.depth[i] >= 1.0 {
                continue;
            }
            let shadowed = rb.shadow_bits[i] & bit != 0;
            let mixed = (-1i64..=1).any(|dy| {
                (-1i64..=1).any(|dx| {
                    let (nx, ny) = (x as i64 + dx, y as i64 + dy);
                    nx >= 0
                        && ny >= 0
                        && (nx as usize) < w
                        && (ny as usize) < h
                        && rb.depth[ny as usize * w + nx as usize] < 1.0
                        && (rb.shadow_bits[ny as usize * w + nx as usize] & bit != 0) != shadowed
                })
            });
            if shadowed || mixed {
                let pixel = (glam::DVec2::new(x as f64, y as f64) + 0.5) * step;
                out.push(world_from_screen.project_point3(pixel.extend(f64::from(rb.depth[i]))));
            }
        }
    }
    out
}

/// Every stability option on (issue 19): the contract holds for them too.
fn stability_options() -> OptimizeOptions {
    OptimizeOptions {
        accept_measure: lixel::optimize::AcceptMeasure::Objective,
        snap: Some(lixel::optimize::TexelSnap::DEFAULT),
        max_turn_degrees: Some(5.0),
        ..OptimizeOptions::default()
    }
}

#[test]
fn optimized_matrices_keep_every_relevant_sample_over_synthetic_scenes() {
    let n = common::cases();
    let mut failures = Vec::new();
    let (mut optimized, mut fallbacks, mut errors, mut accepted, mut snapped) = (0, 0, 0, 0, 0);
    let mut paper = Optimizer::new(OptimizeOptions::default());
    let mut stable = Optimizer::new(stability_options());
    for i in 0..n {
        // Every other pair of scenes with the stability options on.
        let optimizer = if i % 4 >= 2 { &mut stable } else { &mut paper };
        let mut rng = ChaCha8Rng::seed_from_u64(1000 + i as u64);
        let synthetic = scene(&mut rng);
        let eye = DVec3::new(rng.random_range(-18.0..18.0), rng.random_range(0.3..4.0), rng.random_range(-18.0..18.0));
        // Mostly towards an object, sometimes anywhere.
        let object = synthetic.spheres.first().map_or_else(|| synthetic.boxes[0].center(), |s| s.center);
        let look = if i % 5 == 4 {
            DVec3::new(rng.random_range(-1.0..1.0), rng.random_range(-0.6..0.05), rng.random_range(-1.0..1.0))
        } else {
            (object - eye).normalize_or(DVec3::NEG_Z) + unit(&mut rng) * 0.2
        };
        let Ok(camera) =
            Camera::look_at(eye, eye + look, DVec3::Y, 70f64.to_radians(), UVec2::new(640, 480), 0.1, 100.0)
        else {
            continue;
        };
        let light = random_light(&mut rng, i, look.normalize(), eye);
        let map = if i % 3 == 0 { ShadowMapSize::new(1024, 256) } else { ShadowMapSize::square(512) };
        let bounds = synthetic.bounds().unwrap();
        let problem = ShadowProblem::new(camera, light, bounds, map).unwrap();
        let rb = synthetic.render(&camera, &[light], 32, 24);
        let samples = match Samples::from_readback(&problem, &rb.as_readback(i % 2 == 0), 0, &SampleOptions::default())
        {
            Ok(s) => s,
            Err(e) => {
                failures.push(format!("#{i}: samples {e}"));
                continue;
            }
        };
        let prev = match i % 3 {
            0 => None,
            1 => problem.solve(&Parameterization::Focused).ok(),
            _ => problem.solve(&Parameterization::LiSpsm(Default::default())).ok(),
        };
        match optimizer.optimize(&samples, prev.as_ref()) {
            Ok(result) => {
                let r = &result.report;
                let usable = !samples.boundary().is_empty() && samples.relevant_count() > 0;
                if usable == r.fallback.is_some() {
                    failures.push(format!("#{i}: usable samples {usable} but fallback {:?}", r.fallback));
                }
                if r.fallback.is_some() {
                    fallbacks += 1;
                } else {
                    optimized += 1;
                }
                accepted += usize::from(r.accepted);
                snapped += usize::from(r.snapped);
                if r.fallback.is_none() && !(r.objective_new <= r.objective_start) {
                    failures
                        .push(format!("#{i}: objective {} worse than start {}", r.objective_new, r.objective_start));
                }
                if let Err(e) = check_covers(&result.matrix, &relevant_world(&camera, &rb, 1), &format!("#{i}")) {
                    failures.push(format!("{e}\n  {light:?} eye {eye} look {look} report {r:?}"));
                }
                if result.matrix.method != Method::Optimized && prev.is_none() {
                    failures.push(format!("#{i}: method {:?}", result.matrix.method));
                }
            }
            Err(LixelError::LightInsideFocus { .. }) => errors += 1,
            Err(e) => failures.push(format!("#{i}: error {e}")),
        }
    }
    eprintln!(
        "{n} synthetic scenes: {optimized} optimized ({accepted} accepted, {snapped} snapped), {fallbacks} fallbacks, \
         {errors} errors"
    );
    assert!(failures.is_empty(), "{} failures:\n{}", failures.len(), failures[..failures.len().min(5)].join("\n"));
    assert!(optimized > n / 2, "only {optimized} of {n} scenes had shadow boundaries in view");
    assert!(snapped > optimized / 4, "only {snapped} of the {optimized} optimized matrices were snapped");
}

fn walkthrough_problem(light: Light) -> (ShadowProblem, SyntheticScene) {
    let mut synthetic = SyntheticScene { floor: Some((0.0, 30.0)), ..Default::default() };
    for k in 0..12 {
        let a = f64::from(k) * 0.9;
        let at = DVec3::new(12.0 * a.cos(), 0.0, -6.0 - 1.5 * f64::from(k));
        if k % 2 == 0 {
            synthetic.spheres.push(Sphere { center: at + DVec3::Y * 1.2, radius: 1.0 });
        } else {
            synthetic.boxes.push(Aabb::from_corners(at - DVec3::new(0.8, 0.0, 0.8), at + DVec3::new(0.8, 3.0, 0.8)));
        }
    }
    let camera = Camera::look_at(
        DVec3::new(0.0, 1.7, 8.0),
        DVec3::new(0.0, 1.0, -10.0),
        DVec3::Y,
        60f64.to_radians(),
        UVec2::new(1150, 1150),
        0.1,
        100.0,
    )
    .unwrap();
    let problem = ShadowProblem::new(camera, light, synthetic.bounds().unwrap(), ShadowMapSize::square(400)).unwrap();
    (problem, synthetic)
}

#[test]
fn optimized_beats_focused_and_lispsm_on_a_walkthrough() {
    let mut rng = ChaCha8Rng::seed_from_u64(2006);
    let (mut total, mut beats_focused, mut beats_lispsm, mut beats_both) = (0, 0, 0, 0);
    for _ in 0..60 {
        let mut d = unit(&mut rng);
        d.y = -d.y.abs() - 0.1;
        let light = Light::directional(d.normalize());
        let (problem, synthetic) = walkthrough_problem(light);
        let rb = synthetic.render(problem.camera(), &[light], 180, 180);
        let samples = Samples::from_readback(&problem, &rb.as_readback(false), 0, &SampleOptions::default()).unwrap();
        if samples.boundary().len() < 20 {
            continue;
        }
        let result = lixel::optimize_light_matrix(&samples, None).unwrap();
        if result.report.fallback.is_some() {
            continue;
        }
        let median = |m: &LightMatrix| {
            // Express the matrix in the samples' frame through its world-space rows.
            let frame = samples.frame();
            let rows = [m.clip_from_world.row(0), m.clip_from_world.row(1), m.clip_from_world.row(3)];
            let in_frame = rows.map(|r| frame.axis_from_world_row(r));
            let texel_frame = DMat3::from_cols(in_frame[0] * 200.0, in_frame[1] * 200.0, in_frame[2]).transpose();
            let mut b: Vec<f64> = samples.boundary().iter().map(|s| sample_badness(&texel_frame, s)).collect();
            b.sort_by(f64::total_cmp);
            b[b.len() / 2]
        };
        let ours = median(&result.matrix);
        let focused = median(&problem.solve(&Parameterization::Focused).unwrap());
        let lispsm = median(&problem.solve(&Parameterization::LiSpsm(Default::default())).unwrap());
        total += 1;
        beats_focused += usize::from(ours < focused);
        beats_lispsm += usize::from(ours < lispsm);
        beats_both += usize::from(ours < focused && ours < lispsm);
    }
    eprintln!(
        "walkthrough: {total} light directions; optimized beats focused in {beats_focused}, LiSPSM in {beats_lispsm}, both in {beats_both}"
    );
    assert!(total >= 30);
    assert!(beats_both * 2 > total, "optimized beat both in only {beats_both} of {total}");
}

/// A named adversarial input: relevant points and (point, normal) boundary points.
type Case = (&'static str, Vec<DVec3>, Vec<(DVec3, DVec3)>);

#[test]
fn adversarial_sample_sets_fall_back_or_stay_correct() {
    let (problem, _) = walkthrough_problem(Light::directional(DVec3::new(0.3, -1.0, 0.2)));
    let ahead = DVec3::new(0.0, 0.0, -5.0);
    let up = DVec3::Y;
    let behind_light = DVec3::new(-300.0, 1000.0, -200.0);
    let cases: Vec<Case> = vec![
        ("empty", vec![], vec![]),
        ("one point", vec![ahead], vec![(ahead, up)]),
        (
            "collinear",
            (0..20).map(|k| DVec3::new(f64::from(k), 0.0, -5.0)).collect(),
            (0..20).map(|k| (DVec3::new(f64::from(k), 0.0, -5.0), up)).collect(),
        ),
        (
            "same depth",
            (0..20).map(|k| DVec3::new(f64::from(k) * 0.3 - 3.0, 0.0, -5.0)).collect(),
            vec![(ahead, up), (ahead + DVec3::X, up)],
        ),
        (
            "nan and inf",
            vec![DVec3::NAN, DVec3::INFINITY, ahead],
            vec![(DVec3::NAN, up), (ahead, DVec3::NAN), (ahead, up)],
        ),
        ("duplicates", vec![ahead; 50], vec![(ahead, up); 50]),
        ("behind the camera", vec![DVec3::new(0.0, 0.0, 50.0)], vec![(DVec3::new(0.0, 0.0, 50.0), up)]),
        ("far beyond the light", vec![behind_light, ahead], vec![(ahead, up), (behind_light, up)]),
        ("boundary only, back-facing", vec![], vec![(ahead, DVec3::NEG_Y)]),
    ];
    for (name, relevant, boundary) in cases {
        let samples = Samples::from_points(&problem, &relevant, &boundary);
        for strategy in [SearchStrategy::Paper, SearchStrategy::NelderMead { max_iterations: 40 }] {
            let mut optimizer = Optimizer::new(OptimizeOptions { strategy, ..Default::default() });
            let result = optimizer.optimize(&samples, None).unwrap_or_else(|e| panic!("{name}: {e}"));
            assert!(result.matrix.clip_from_world.is_finite(), "{name}");
            let finite: Vec<DVec3> = relevant
                .iter()
                .chain(boundary.iter().map(|(p, _)| p))
                .copied()
                .filter(|p| p.is_finite() && problem.camera().view_depth(*p) > 0.0)
                .collect();
            if samples.boundary().is_empty() {
                assert_eq!(result.report.fallback, Some(Fallback::NoUsableSamples), "{name}");
            }
            check_covers(&result.matrix, &finite, name).unwrap();
        }
    }
}

#[test]
fn nelder_mead_is_never_worse_than_its_start_and_close_to_the_heuristic() {
    let (mut total, mut heuristic_within_10_percent) = (0, 0);
    for k in 0..12 {
        let a = f64::from(k) * 0.5;
        let light = Light::directional(DVec3::new(a.cos(), -1.2, a.sin()).normalize());
        let (problem, synthetic) = walkthrough_problem(light);
        let rb = synthetic.render(problem.camera(), &[light], 120, 120);
        let samples = Samples::from_readback(&problem, &rb.as_readback(true), 0, &SampleOptions::default()).unwrap();
        if samples.boundary().len() < 20 {
            continue;
        }
        let paper = Optimizer::new(OptimizeOptions::default()).optimize(&samples, None).unwrap().report;
        let nm = Optimizer::new(OptimizeOptions {
            strategy: SearchStrategy::NelderMead { max_iterations: 200 },
            ..Default::default()
        })
        .optimize(&samples, None)
        .unwrap()
        .report;
        assert!(nm.objective_new <= nm.objective_start);
        eprintln!(
            "start {:.4e} paper {:.4e} ({} iterations) nelder-mead {:.4e} ({} iterations)",
            paper.objective_start, paper.objective_new, paper.iterations, nm.objective_new, nm.iterations
        );
        total += 1;
        heuristic_within_10_percent += usize::from(paper.objective_new <= 1.1 * nm.objective_new);
    }
    eprintln!("heuristic within 10% of Nelder-Mead in {heuristic_within_10_percent} of {total}");
    assert!(total > 6);
}

#[test]
fn objective_is_the_sum_of_the_scorer_badness() {
    // Samples from points: the objective per sample equals score::badness.
    let (problem, _) = walkthrough_problem(Light::point(DVec3::new(5.0, 20.0, -10.0)));
    let m = problem.solve(&Parameterization::Focused).unwrap();
    let points: Vec<(DVec3, DVec3)> =
        (0..50).map(|k| (DVec3::new(f64::from(k % 10) - 5.0, 0.0, -2.0 - f64::from(k / 10) * 2.0), DVec3::Y)).collect();
    let samples = Samples::from_points(&problem, &[], &points);
    let frame = samples.frame();
    let rows = [m.clip_from_world.row(0), m.clip_from_world.row(1), m.clip_from_world.row(3)];
    let in_frame = rows.map(|r| frame.axis_from_world_row(r));
    let map = m.map_size;
    let texel = DMat3::from_cols(
        in_frame[0] * (0.5 * f64::from(map.width)),
        in_frame[1] * (0.5 * f64::from(map.height)),
        in_frame[2],
    )
    .transpose();
    let expected: f64 = points.iter().map(|&(p, n)| lixel::score::badness(&m, problem.camera(), p, n).unwrap()).sum();
    let got = objective(&texel, samples.boundary());
    assert!((got - expected).abs() <= 1e-8 * expected, "objective {got} vs scorer {expected}");
}

/// Degenerate sample sets over the method property tests' configurations
/// (general and the hard regions): one or a few boundary samples inside the
/// visible receivers, some seen edge-on, with the previous matrix of another
/// method. The answer holds every sample, or is a typed error the focused
/// method itself reports.
#[test]
fn degenerate_sample_sets_with_prev_keep_every_sample() {
    let n = common::cases() / 4;
    let mut failures = Vec::new();
    let mut outcomes: std::collections::BTreeMap<String, usize> = Default::default();
    let mut paper = Optimizer::new(OptimizeOptions::default());
    let mut stable = Optimizer::new(stability_options());
    for i in 0..2 * n {
        let optimizer = if (i / 4) % 2 == 1 { &mut stable } else { &mut paper };
        let (config, region) = if i < n {
            (common::config(11, i), "general".to_string())
        } else {
            let (c, r) = common::hard_config(11, i - n);
            (c, format!("{r:?}"))
        };
        let Some(problem) = config.problem() else { continue };
        let body = problem.visible_receiver_body();
        let mut rng = ChaCha8Rng::seed_from_u64(i as u64);
        let vertices = body.vertices();
        if vertices.is_empty() {
            continue;
        }
        let pick = |rng: &mut ChaCha8Rng| -> DVec3 {
            let w: Vec<f64> = vertices.iter().map(|_| rng.random_range(0.0..1.0f64).powi(4)).collect();
            let total: f64 = w.iter().sum::<f64>().max(1e-300);
            vertices.iter().zip(&w).map(|(&v, &k)| v * (k / total)).sum()
        };
        let count = 1 + i % 3;
        let camera = problem.camera();
        let boundary: Vec<(DVec3, DVec3)> = (0..count)
            .map(|k| {
                let p = pick(&mut rng);
                let ray = (p - camera.eye()).normalize_or(DVec3::Z);
                let n = if k == 1 {
                    // Edge-on: orthogonal to the ray, up to rounding.
                    let (a, _) = ray.any_orthonormal_pair();
                    a
                } else {
                    unit(&mut rng)
                };
                (p, n)
            })
            .collect();
        let samples = Samples::from_points(&problem, &[], &boundary);
        if std::env::var("LIXEL_DUMP").is_ok_and(|d| d == i.to_string()) {
            eprintln!("DUMP {config:?}\n{boundary:?}");
        }
        let prev = match i % 4 {
            0 => None,
            1 => problem.solve(&Parameterization::Focused).ok(),
            2 => problem.solve(&Parameterization::LiSpsm(Default::default())).ok(),
            _ => problem.solve(&Parameterization::Psm(Default::default())).ok(),
        };
        match optimizer.optimize(&samples, prev.as_ref()) {
            Ok(result) => {
                *outcomes.entry(format!("{region}: {:?}", result.report.fallback)).or_default() += 1;
                let points: Vec<DVec3> = boundary
                    .iter()
                    .map(|b| b.0)
                    .filter(|&p| {
                        camera.view_depth(p) > 0.0
                            && problem.light().position().is_none_or(|l| (p - l).length() > 1e-6 * problem.scale())
                    })
                    .collect();
                if let Err(e) = check_covers(&result.matrix, &points, &format!("#{i} ({region})")) {
                    failures.push(format!(
                        "{e}\n  fallback {:?}, prev {:?}\n  {config:?}",
                        result.report.fallback,
                        prev.map(|m| m.method)
                    ));
                }
            }
            Err(e) => {
                *outcomes
                    .entry(format!("{region}: error {e:?}").split([' ', '{']).take(3).collect::<Vec<_>>().join(" "))
                    .or_default() += 1;
                let focused_err = problem.solve(&Parameterization::Focused).err();
                let justified = focused_err.as_ref() == Some(&e)
                    || (matches!(e, LixelError::UnusableSamples { .. })
                        && matches!(problem.light(), Light::Point { .. }));
                if !justified {
                    failures.push(format!("#{i} ({region}): unjustified {e}\n  {config:?}"));
                }
            }
        }
    }
    eprintln!("degenerate sample sets, {} configurations: {outcomes:#?}", 2 * n);
    assert!(
        failures.is_empty(),
        "{} failed; first ones:\n{}",
        failures.len(),
        failures[..failures.len().min(5)].join("\n")
    );
}
