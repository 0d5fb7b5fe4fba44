//! Each method's claim, shown with the scorer (badness `b`, lower is better).

use glam::{DVec3, UVec2};
use lixel::geometry::Plane;
use lixel::score::{badness, badness_stats, plane_samples};
use lixel::{
    psm_light_case, Aabb, Camera, Fallback, Light, Parameterization, PsmLightCase, PsmOptions, SceneBounds,
    ShadowMapSize, ShadowProblem,
};

const HALF: f64 = 40.0;

fn walker(eye: DVec3, look: DVec3) -> Camera {
    Camera::look_at(eye, eye + look, DVec3::Y, 60f64.to_radians(), UVec2::new(800, 600), 0.1, 200.0).unwrap()
}

fn floor() -> Aabb {
    Aabb::from_corners(DVec3::new(-HALF, 0.0, -HALF), DVec3::new(HALF, 0.0, HALF))
}

/// The floor seen through a 160x120 grid of pixels (normal +y).
fn visible_floor(camera: &Camera) -> Vec<(DVec3, DVec3)> {
    plane_samples(camera, &Plane::from_point_normal(DVec3::ZERO, DVec3::Y), &floor(), UVec2::new(160, 120))
}

fn median(problem: &ShadowProblem, p: &Parameterization, samples: &[(DVec3, DVec3)]) -> f64 {
    let m = problem.solve(p).unwrap();
    badness_stats(&m, problem.camera(), samples.iter().copied()).unwrap().median
}

#[test]
fn plane_optimal_samples_its_plane_uniformly() {
    // Receivers: the floor only, so nothing relevant leaves the plane.
    for (eye, look, light) in [
        (DVec3::new(0.0, 1.7, 20.0), DVec3::new(0.0, -0.3, -1.0), Light::directional(DVec3::new(0.4, -1.0, 0.2))),
        (DVec3::new(5.0, 3.0, 0.0), DVec3::new(-1.0, -0.5, 0.2), Light::point(DVec3::new(10.0, 30.0, -5.0))),
        (DVec3::new(-10.0, 2.0, 10.0), DVec3::new(1.0, -0.2, -1.0), Light::directional(DVec3::new(-1.0, -0.3, 0.0))),
    ] {
        let camera = walker(eye, look);
        let bounds = SceneBounds { casters: floor(), receivers: floor() };
        let problem = ShadowProblem::new(camera, light, bounds, ShadowMapSize::square(512)).unwrap();
        let m = problem.solve(&Parameterization::PlaneOptimal(Default::default())).unwrap();
        assert_eq!(m.fallback, None, "{light:?}");
        let samples = visible_floor(&camera);
        let b: Vec<f64> = samples.iter().filter_map(|&(p, n)| badness(&m, &camera, p, n)).collect();
        assert!(b.len() > 1000);
        let (lo, hi) = b.iter().fold((f64::INFINITY, 0.0_f64), |(lo, hi), &v| (lo.min(v), hi.max(v)));
        assert!(hi / lo < 1.0 + 1e-6, "plane-optimal badness varies on its plane: {lo} .. {hi}");
        // The focused map, by contrast, varies by orders of magnitude.
        let f = problem.solve(&Parameterization::Focused).unwrap();
        let fb: Vec<f64> = samples.iter().filter_map(|&(p, n)| badness(&f, &camera, p, n)).collect();
        let (flo, fhi) = fb.iter().fold((f64::INFINITY, 0.0_f64), |(lo, hi), &v| (lo.min(v), hi.max(v)));
        assert!(fhi / flo > 10.0, "focused {flo} .. {fhi}");
    }
}

#[test]
fn plane_optimal_blends_when_points_leave_the_plane() {
    // Tall receivers behind the viewer's floor reach the vanishing line.
    let camera = walker(DVec3::new(0.0, 1.7, 20.0), DVec3::new(0.0, -0.2, -1.0));
    let tall = Aabb::from_corners(DVec3::new(-HALF, 0.0, -HALF), DVec3::new(HALF, 30.0, HALF));
    let bounds = SceneBounds { casters: tall, receivers: tall };
    let light = Light::directional(DVec3::new(0.0, -0.3, 1.0));
    let problem = ShadowProblem::new(camera, light, bounds, ShadowMapSize::square(512)).unwrap();
    let m = problem.solve(&Parameterization::PlaneOptimal(Default::default())).unwrap();
    assert!(matches!(m.fallback, Some(Fallback::PlaneOptimalBlended { blend }) if blend > 0.0 && blend <= 1.0));
}

#[test]
fn psm_beats_normal_for_a_walking_viewer_under_an_orthogonal_light() {
    // Light straight down, viewer looking horizontally: orthogonal, the
    // directional-in-post-perspective case that PSM handles best.
    let light = Light::directional(DVec3::NEG_Y);
    let objects = Aabb::from_corners(DVec3::new(-30.0, 0.0, -30.0), DVec3::new(30.0, 4.0, 30.0));
    let bounds = SceneBounds { casters: objects, receivers: objects.union(&floor()) };
    for step in 0..8 {
        let t = f64::from(step) / 8.0;
        let eye = DVec3::new(-25.0 + 50.0 * t, 1.7, 25.0 - 10.0 * t);
        let look = DVec3::new((t * 6.0).sin(), 0.0, -(t * 6.0).cos());
        let camera = walker(eye, look);
        let problem = ShadowProblem::new(camera, light, bounds, ShadowMapSize::square(1024)).unwrap();
        assert_eq!(psm_light_case(&problem, &PsmOptions::default()), PsmLightCase::Directional);
        let samples = visible_floor(&camera);
        // A readback would supply the nearest visible depth; the floor samples do here.
        let nearest = samples.iter().map(|(p, _)| camera.view_depth(*p)).fold(f64::INFINITY, f64::min);
        let psm = Parameterization::Psm(PsmOptions { min_view_depth: Some(nearest) });
        let (psm, normal) = (median(&problem, &psm, &samples), median(&problem, &Parameterization::Normal, &samples));
        assert!(psm < normal, "step {step}: PSM median {psm} vs normal {normal}");
    }
}

#[test]
fn psm_classifies_the_light() {
    let camera = walker(DVec3::new(0.0, 1.7, 20.0), DVec3::new(0.0, 0.0, -1.0));
    let bounds = SceneBounds::uniform(Aabb::from_corners(DVec3::new(-HALF, 0.0, -HALF), DVec3::new(HALF, 4.0, HALF)));
    let case = |light| {
        let problem = ShadowProblem::new(camera, light, bounds, ShadowMapSize::square(256)).unwrap();
        psm_light_case(&problem, &PsmOptions::default())
    };
    // Light comes from ahead of the viewer: the light's point at infinity is in front.
    assert_eq!(case(Light::directional(DVec3::new(0.0, -1.0, 1.0))), PsmLightCase::Regular);
    // Light from behind the viewer: inverted.
    assert_eq!(case(Light::directional(DVec3::new(0.0, -1.0, -1.0))), PsmLightCase::Inverted);
    assert_eq!(case(Light::directional(DVec3::new(1.0, -1.0, 0.0))), PsmLightCase::Directional);
}

#[test]
fn lispsm_tends_to_uniform_as_the_light_aligns_with_the_view() {
    let objects = Aabb::from_corners(DVec3::new(-30.0, 0.0, -30.0), DVec3::new(30.0, 4.0, 30.0));
    let bounds = SceneBounds { casters: objects, receivers: objects.union(&floor()) };
    let look = DVec3::new(0.0, -0.25, -1.0).normalize();
    let camera = walker(DVec3::new(0.0, 1.7, 25.0), look);
    let samples = visible_floor(&camera);
    // Towards the floor, orthogonal to the view.
    let down = (DVec3::NEG_Y - look * look.dot(DVec3::NEG_Y)).normalize();
    let mut previous_gap = f64::INFINITY;
    for gamma_degrees in [90.0_f64, 30.0, 10.0, 3.0, 1.0, 0.3, 0.1, 0.06, 0.058, 0.05] {
        if gamma_degrees == 10.0 {
            previous_gap = f64::INFINITY;
        }
        let g = gamma_degrees.to_radians();
        // A light travelling along the view direction, tilted by γ towards the floor.
        let light = Light::directional(look * g.cos() + down * g.sin());
        let problem = ShadowProblem::new(camera, light, bounds, ShadowMapSize::square(1024)).unwrap();
        let lispsm = median(&problem, &Parameterization::LiSpsm(Default::default()), &samples);
        let focused = median(&problem, &Parameterization::Focused, &samples);
        let gap = (lispsm / focused - 1.0).abs();
        eprintln!("γ = {gamma_degrees}: lispsm {lispsm} focused {focused} gap {gap}");
        if gamma_degrees >= 30.0 {
            assert!(
                lispsm < 0.5 * focused,
                "LiSPSM {lispsm} should clearly beat focused {focused} at γ = {gamma_degrees}°"
            );
        } else {
            assert!(gap <= previous_gap + 1e-3, "γ = {gamma_degrees}: gap {gap} grew from {previous_gap}");
            if gamma_degrees <= 0.1 {
                // Just above the fallback threshold: continuous, no visible jump.
                assert!(gap < 0.03, "γ = {gamma_degrees}: gap {gap} just above the fallback");
            }
        }
        previous_gap = gap;
    }
    assert_eq!(previous_gap, 0.0, "below the threshold LiSPSM is the uniform map");
}
