//! The solve workspace's camera cache changes no bit of any result: every
//! classical method solved through one long-lived workspace (cache hits for
//! the lights sharing a camera, misses when the camera or bounds change)
//! equals the same solve through a fresh uncached workspace and through
//! `ShadowProblem::solve`, matrices and errors alike, over random cameras
//! with hard lights: inside the receivers, far away, grazing a flat floor,
//! along and against the view direction, spot lights. The same holds for the
//! per-light caches (caster bodies; a spot light's visible receivers): light
//! by light through one workspace, through one workspace per light, and with
//! the casters' bounds changed under the same light.

use glam::DVec3;
use lixel::{Aabb, Light, Parameterization, SceneBounds, ShadowProblem, SolveWorkspace};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

mod common;

/// Bit-exact comparison: `Debug` prints every `f64` so that it reads back to
/// the same bits (and `-0.0` as such); errors compare by variant and data.
fn bits<T: std::fmt::Debug>(value: &T) -> String {
    format!("{value:?}")
}

/// Hard lights for a camera and bounds.
fn lights(config: &common::Config, rng: &mut ChaCha8Rng) -> Vec<Light> {
    let r = config.bounds.receivers;
    let scale = config.bounds.scene().diagonal().max(1e-3);
    let inside = r.min + (r.max - r.min) * DVec3::new(rng.random(), rng.random(), rng.random());
    let view = (config.target - config.eye).normalize();
    let horizontal =
        DVec3::new(rng.random_range(-1.0..1.0), 0.0, rng.random_range(-1.0..1.0)).try_normalize().unwrap_or(DVec3::X);
    let far = r.center() + DVec3::new(0.3, 1.0, -0.2).normalize() * scale * 10f64.powf(rng.random_range(3.0..8.0));
    vec![
        config.light,
        Light::point(inside),
        Light::point(far),
        Light::directional(view),
        Light::directional(-view),
        Light::directional(-horizontal + DVec3::Y * -1e-9),
        Light::point(r.center().with_y(r.min.y) + horizontal * scale * 3.0),
        Light::point(config.eye - view * scale * 0.5),
        Light::spot(inside, DVec3::NEG_Y + horizontal * 0.2, 50f64.to_radians()),
        Light::spot(far, r.center() - far, 20f64.to_radians()),
    ]
}

#[test]
fn cached_solves_are_bit_identical_to_uncached() {
    let cases = (common::cases() / 20).max(20);
    let mut shared = SolveWorkspace::new();
    let mut rng = ChaCha8Rng::seed_from_u64(15);
    let (mut compared, mut errors) = (0, 0);
    for i in 0..cases {
        let config = if i % 2 == 0 { common::config(1515, i) } else { common::hard_config(1515, i).0 };
        let Some(camera) = config.camera() else { continue };
        // The same camera with the receivers flattened to their floor
        // (grazing lights; the cache must notice the bounds changed), then
        // the original bounds once more.
        let flat = SceneBounds {
            receivers: Aabb {
                max: config.bounds.receivers.max.with_y(config.bounds.receivers.min.y),
                ..config.bounds.receivers
            },
            ..config.bounds
        };
        let lights = lights(&config, &mut rng);
        let problems: Vec<ShadowProblem> = [config.bounds, flat]
            .iter()
            .flat_map(|&bounds| lights.iter().map(move |&light| (light, bounds)))
            .chain([(lights[0], config.bounds)])
            .filter_map(|(light, bounds)| ShadowProblem::new(camera, light, bounds, config.map).ok())
            .collect();
        for parameterization in Parameterization::ALL_DEFAULT {
            for problem in &problems {
                let cached = problem.solve_with(&parameterization, &mut shared);
                let uncached = problem.solve_with(&parameterization, &mut SolveWorkspace::uncached());
                assert_eq!(bits(&cached), bits(&uncached), "case {i}, {parameterization:?}, {:?}", problem.light());
                assert_eq!(bits(&problem.solve(&parameterization)), bits(&uncached), "case {i} (thread-local)");
                compared += 1;
                errors += usize::from(uncached.is_err());
            }
        }
        // Light by light, every method in turn through the shared workspace
        // (its caster cache hits between methods sharing a body), three
        // times through a workspace per light (bodies are kept from the
        // second pass on, so the third hits every cache),
        // and with the casters' bounds changed under the same light and
        // receivers (the caster cache must miss).
        let mut per_light: Vec<SolveWorkspace> = problems.iter().map(|_| SolveWorkspace::new()).collect();
        let grown = |p: &ShadowProblem| {
            let c = p.bounds().casters;
            let bounds = SceneBounds { casters: Aabb { max: c.max + DVec3::splat(0.5), ..c }, ..*p.bounds() };
            ShadowProblem::new(*p.camera(), *p.light(), bounds, p.map_size()).ok()
        };
        for _ in 0..3 {
            for (problem, own) in problems.iter().zip(&mut per_light) {
                let other = grown(problem);
                for parameterization in Parameterization::ALL_DEFAULT {
                    let uncached = bits(&problem.solve_with(&parameterization, &mut SolveWorkspace::uncached()));
                    assert_eq!(bits(&problem.solve_with(&parameterization, &mut shared)), uncached, "case {i}");
                    assert_eq!(bits(&problem.solve_with(&parameterization, own)), uncached, "case {i}, per light");
                    if let Some(other) = &other {
                        let expected = bits(&other.solve_with(&parameterization, &mut SolveWorkspace::uncached()));
                        assert_eq!(bits(&other.solve_with(&parameterization, &mut shared)), expected, "case {i}");
                    }
                    compared += 1;
                }
            }
        }
        // One method again and again through a workspace of its own (a
        // still light and camera): from the third solve on the casters'
        // linear programs answer from memory, with the same bits.
        for problem in problems.iter().take(4) {
            for parameterization in Parameterization::ALL_DEFAULT {
                let uncached = bits(&problem.solve_with(&parameterization, &mut SolveWorkspace::uncached()));
                let mut own = SolveWorkspace::new();
                for pass in 0..4 {
                    assert_eq!(
                        bits(&problem.solve_with(&parameterization, &mut own)),
                        uncached,
                        "case {i}, pass {pass}"
                    );
                    compared += 1;
                }
            }
        }
        // The public bodies agree too.
        for problem in &problems {
            let visible = problem.visible_receiver_body();
            let direct = problem.receiver_body().clip_all(problem.view_planes().iter(), problem.eps());
            assert_eq!(visible, direct, "case {i}: visible receivers");
        }
    }
    eprintln!("{compared} solves compared, {errors} of them errors");
    assert!(compared > cases * 120, "too few solves compared: {compared}");
}

/// PSM's axis, kept in the camera cache with its hull, is found again only
/// for the same near-plane option and tolerances: one workspace solving a
/// still light and camera with the options and tolerances alternating gives
/// every uncached result, and each alternative differs from the default in
/// enough cases that a stale axis would show.
#[test]
fn psm_axis_kept_per_option_and_tolerance() {
    use lixel::{PsmOptions, Tolerances};
    let cases = (common::cases() / 20).max(40);
    let mut compared = 0;
    // How often each alternative's result differs from the default's: the
    // option, then the three tolerances, then the light.
    let mut differing = [0usize; 5];
    for i in 0..cases {
        let config = if i % 2 == 0 { common::config(1516, i) } else { common::hard_config(1516, i).0 };
        let Some(problem) = config.problem() else { continue };
        let t = *problem.tolerances();
        // The light moved along x alone (the key's light bits).
        let x = problem.bounds().scene().diagonal() * 0.05;
        let moved = match *problem.light() {
            Light::Point { position } => Light::point(position + DVec3::X * x),
            Light::Spot { position, direction, outer_half_angle_radians } => {
                Light::spot(position + DVec3::X * x, direction, outer_half_angle_radians)
            }
            Light::Directional { direction } => Light::directional(direction + DVec3::X * 0.05),
        };
        let Ok(moved) = ShadowProblem::new(*problem.camera(), moved, *problem.bounds(), problem.map_size()) else {
            continue;
        };
        let variants = [
            problem.clone(),
            problem.clone().with_tolerances(Tolerances { min_front_cosine: 0.9999, ..t }),
            problem.clone().with_tolerances(Tolerances { coarse_eps: 0.3, ..t }),
            problem.clone().with_tolerances(Tolerances { min_relative_span: 1e4, ..t }),
            moved,
        ];
        let near = problem.camera().z_near();
        let options = [0.0, 3.0, 6.0].map(|k| PsmOptions { min_view_depth: (k > 0.0).then_some(near * k) });
        let uncached = |v: usize, o: usize| {
            bits(&variants[v].solve_with(&Parameterization::Psm(options[o]), &mut SolveWorkspace::uncached()))
        };
        let default = uncached(0, 0);
        differing[0] += usize::from(uncached(0, 1) != default);
        for (v, count) in differing.iter_mut().enumerate().skip(1) {
            *count += usize::from(uncached(v, 0) != default);
        }
        // Each alternative right after the default, differing from it in
        // one key field only: a key missing that field hits a stale axis.
        let mut order = Vec::new();
        for o in 0..options.len() {
            for v in 1..variants.len() {
                order.extend([(0, o), (v, o)]);
            }
        }
        for v in 0..variants.len() {
            order.extend([(v, 0), (v, 1), (v, 2)]);
        }
        let mut own = SolveWorkspace::new();
        for _ in 0..2 {
            for &(v, o) in &order {
                let expected = uncached(v, o);
                for _ in 0..2 {
                    let cached = variants[v].solve_with(&Parameterization::Psm(options[o]), &mut own);
                    assert_eq!(bits(&cached), expected, "case {i}, variant {v}, option {o}");
                    compared += 1;
                }
            }
        }
    }
    eprintln!(
        "{compared} PSM solves compared; differing from the default (option, three tolerances, light): {differing:?}"
    );
    assert!(compared > cases * 20, "{compared} compared");
    assert!(differing.iter().all(|&d| d > cases / 20), "{differing:?} differing of {cases}");
}
