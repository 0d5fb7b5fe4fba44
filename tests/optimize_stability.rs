//! The optimizer's stability options (issue 19) on CPU-rendered readbacks:
//! texel snapping keeps the map's texel grid fixed in the world while the
//! axis is kept and the camera walks; bounded rotation limits how far an
//! accepted axis turns per update.

use glam::{DVec2, DVec3, UVec2};
use lixel::optimize::{OptimizeOptions, Optimizer, SampleOptions, TexelSnap};
use lixel::synthetic::{Sphere, SyntheticScene};
use lixel::{Aabb, Camera, Light, LightMatrix, Parameterization, Samples, ShadowMapSize, ShadowProblem};

const MAP: u32 = 512;

fn scene() -> SyntheticScene {
    SyntheticScene {
        floor: Some((0.0, 20.0)),
        spheres: vec![
            Sphere { center: DVec3::new(0.0, 1.0, -5.0), radius: 1.0 },
            Sphere { center: DVec3::new(3.0, 2.0, -9.0), radius: 1.5 },
        ],
        boxes: vec![Aabb::from_corners(DVec3::new(-4.0, 0.0, -8.0), DVec3::new(-2.0, 3.0, -6.0))],
    }
}

/// The problem of a camera walked `step` steps sideways and forward (not
/// texel-aligned amounts).
fn problem_at(light: Light, step: u32) -> ShadowProblem {
    let d = DVec3::new(0.0137, 0.0, -0.0291) * f64::from(step);
    let camera = Camera::look_at(
        DVec3::new(0.0, 1.7, 4.0) + d,
        DVec3::new(0.0, 0.5, -6.0) + d,
        DVec3::Y,
        60f64.to_radians(),
        UVec2::new(800, 800),
        0.1,
        60.0,
    )
    .unwrap();
    ShadowProblem::new(camera, light, scene().bounds().unwrap(), ShadowMapSize::square(MAP)).unwrap()
}

/// The samples of [`problem_at`] from a CPU-rendered 96² readback.
fn samples_at(light: Light, step: u32) -> Samples {
    let problem = problem_at(light, step);
    let readback = scene().render(problem.camera(), &[light], 96, 96);
    Samples::from_readback(&problem, &readback.as_readback(true), 0, &SampleOptions::default()).unwrap()
}

fn texel(m: &LightMatrix, p: DVec3) -> DVec2 {
    let c = m.clip_from_world * p.extend(1.0);
    (DVec2::new(c.x, c.y) / c.w * 0.5 + 0.5) * f64::from(MAP)
}

fn probes() -> Vec<DVec3> {
    (0..7).map(|i| DVec3::new(-3.1 + 1.3 * f64::from(i), 0.2 * f64::from(i % 3), -4.3 - 0.8 * f64::from(i))).collect()
}

/// Walks the camera with the axis always kept (a ratio of 0 accepts
/// nothing after the first optimization); per step: whether the texel size
/// stayed, and whether the probes moved by one whole-texel offset.
fn walk(light: Light, options: OptimizeOptions) -> Vec<(bool, bool)> {
    let mut optimizer = Optimizer::new(OptimizeOptions { accept_ratio: 0.0, ..options });
    let first = optimizer.optimize(&samples_at(light, 0), None).unwrap();
    assert!(first.report.accepted && first.report.fallback.is_none());
    let mut prev = first.matrix;
    let mut steps = Vec::new();
    for step in 1..10 {
        let samples = samples_at(light, step);
        let next = optimizer.optimize(&samples, Some(&prev)).unwrap();
        assert!(!next.report.accepted, "step {step}: a ratio of 0 accepts nothing");
        assert_eq!(next.report.snapped, options.snap.is_some(), "step {step}");
        assert_eq!(next.matrix.fallback, None);
        let scale = |m: &LightMatrix| texel(m, DVec3::X) - texel(m, DVec3::ZERO);
        let same_size = (scale(&next.matrix) - scale(&prev)).length() < 1e-7;
        let offsets: Vec<DVec2> = probes().iter().map(|&p| texel(&next.matrix, p) - texel(&prev, p)).collect();
        let whole = offsets.iter().all(|o| (*o - o.round()).length() < 1e-5 && (*o - offsets[0]).length() < 1e-5);
        steps.push((same_size, whole));
        prev = next.matrix;
    }
    steps
}

#[test]
fn snapping_keeps_the_texel_grid_while_the_axis_is_kept() {
    for light in [Light::directional(DVec3::new(0.5, -1.0, -0.2)), Light::point(DVec3::new(-6.0, 12.0, -2.0))] {
        let snapped = walk(light, OptimizeOptions { snap: Some(TexelSnap::DEFAULT), ..OptimizeOptions::paper() });
        let same_size = snapped.iter().filter(|s| s.0).count();
        assert!(same_size >= 5, "{light:?}: the texel size changed in {} of 9 steps", 9 - same_size);
        for (k, &(same, whole)) in snapped.iter().enumerate() {
            assert!(!same || whole, "{light:?}, step {}: same texel size but not a whole-texel shift", k + 1);
        }
        // The paper's re-fit moves the grid by fractions of a texel.
        let paper = walk(light, OptimizeOptions::paper());
        assert!(paper.iter().any(|&(_, whole)| !whole), "{light:?}: the unsnapped map is expected to shimmer");
    }
}

#[test]
fn an_accepted_axis_turns_at_most_the_bound() {
    let light = Light::point(DVec3::new(-6.0, 12.0, -2.0));
    let samples = samples_at(light, 0);
    // A poor previous matrix: the normal map's axis.
    let problem = problem_at(light, 0);
    let normal = problem.solve(&Parameterization::Normal).unwrap();
    let direction = |m: &LightMatrix| m.clip_from_world.row(3).truncate().normalize();
    let free = Optimizer::new(OptimizeOptions { accept_ratio: 1.0, ..OptimizeOptions::paper() })
        .optimize(&samples, Some(&normal))
        .unwrap();
    assert!(free.report.accepted && !free.report.turn_limited);
    let turned = direction(&free.matrix).angle_between(direction(&normal)).to_degrees();
    assert!(turned > 2.0, "the test needs a search that turns the axis more than the bound ({turned}°)");
    let bounded =
        Optimizer::new(OptimizeOptions { accept_ratio: 1.0, max_turn_degrees: Some(1.0), ..OptimizeOptions::paper() })
            .optimize(&samples, Some(&normal))
            .unwrap();
    assert!(bounded.report.accepted && bounded.report.turn_limited);
    let angle = direction(&bounded.matrix).angle_between(direction(&normal)).to_degrees();
    assert!((angle - 1.0).abs() < 1e-6, "turned {angle}° with a bound of 1°");
}
