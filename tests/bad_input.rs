//! Bad input gets a typed error, never a panic or a silently wrong matrix.

use glam::{DMat4, DVec3, UVec2};
use lixel::optimize::{Readback, SampleOptions};
use lixel::{
    Aabb, Camera, Light, LixelError, Parameterization, PlaneOptimalOptions, Samples, SceneBounds, ShadowMapSize,
    ShadowProblem,
};

fn camera() -> Camera {
    Camera::look_at(DVec3::new(0.0, 2.0, 10.0), DVec3::ZERO, DVec3::Y, 1.0, UVec2::new(640, 480), 0.1, 100.0).unwrap()
}

fn bounds() -> SceneBounds {
    SceneBounds::uniform(Aabb::from_corners(DVec3::splat(-5.0), DVec3::new(5.0, 2.0, 5.0)))
}

#[test]
fn degenerate_cameras_are_rejected() {
    let ok = |eye: DVec3, target: DVec3, up: DVec3, fov: f64, vp: UVec2, near: f64, far: f64| {
        Camera::look_at(eye, target, up, fov, vp, near, far)
    };
    let (e, t, u, vp) = (DVec3::new(0.0, 2.0, 10.0), DVec3::ZERO, DVec3::Y, UVec2::new(64, 64));
    assert!(matches!(ok(DVec3::NAN, t, u, 1.0, vp, 0.1, 10.0), Err(LixelError::NonFinite { .. })));
    assert!(matches!(ok(e, e, u, 1.0, vp, 0.1, 10.0), Err(LixelError::DegenerateCamera { .. })));
    assert!(matches!(ok(e, t, (t - e).normalize(), 1.0, vp, 0.1, 10.0), Err(LixelError::DegenerateCamera { .. })));
    for fov in [0.0, std::f64::consts::PI, -1.0] {
        assert!(matches!(ok(e, t, u, fov, vp, 0.1, 10.0), Err(LixelError::DegenerateCamera { .. })));
    }
    assert!(matches!(ok(e, t, u, 1.0, UVec2::new(0, 64), 0.1, 10.0), Err(LixelError::DegenerateCamera { .. })));
    for (near, far) in [(0.0, 10.0), (-1.0, 10.0), (10.0, 10.0), (10.0, 1.0)] {
        assert!(matches!(ok(e, t, u, 1.0, vp, near, far), Err(LixelError::DegenerateCamera { .. })), "{near} {far}");
    }
    // An orthographic projection is a camera too (issue 13); a projective
    // w row of neither kind is not.
    let ortho = glam::dcamera::rh::proj::directx::orthographic(-1.0, 1.0, -1.0, 1.0, 0.1, 10.0);
    assert!(Camera::from_matrices(DMat4::IDENTITY, ortho, vp).is_ok());
    let mut skewed = ortho;
    skewed.x_axis.w = 0.5;
    assert!(matches!(
        Camera::from_matrices(DMat4::IDENTITY, skewed, vp),
        Err(LixelError::InvalidProjection { property: lixel::conventions::CameraProperty::ProjectionKind, .. })
    ));
    // A view matrix that scales is not rigid.
    let persp = glam::dcamera::rh::proj::directx::perspective(1.0, 1.0, 0.1, 10.0);
    assert!(Camera::from_matrices(DMat4::from_scale(DVec3::splat(2.0)), persp, vp).is_err());
    assert!(Camera::from_matrices(DMat4::IDENTITY, persp, vp).is_ok());
}

#[test]
fn bad_lights_bounds_and_maps_are_rejected() {
    let problem = |light, bounds, map| ShadowProblem::new(camera(), light, bounds, map);
    let map = ShadowMapSize::square(512);
    assert!(matches!(problem(Light::point(DVec3::NAN), bounds(), map), Err(LixelError::NonFinite { .. })));
    assert!(matches!(problem(Light::directional(DVec3::ZERO), bounds(), map), Err(LixelError::InvalidLight { .. })));
    let wide_spot = Light::spot(DVec3::new(0.0, 10.0, 0.0), DVec3::NEG_Y, 90f64.to_radians());
    assert!(matches!(problem(wide_spot, bounds(), map), Err(LixelError::InvalidLight { .. })));
    let inverted = SceneBounds::uniform(Aabb { min: DVec3::ONE, max: DVec3::ZERO });
    assert!(matches!(problem(Light::point(DVec3::Y * 10.0), inverted, map), Err(LixelError::InvalidBounds { .. })));
    let nan = SceneBounds::uniform(Aabb { min: DVec3::NAN, max: DVec3::ONE });
    assert!(matches!(problem(Light::point(DVec3::Y * 10.0), nan, map), Err(LixelError::NonFinite { .. })));
    assert!(matches!(
        problem(Light::point(DVec3::Y * 10.0), bounds(), ShadowMapSize::new(0, 512)),
        Err(LixelError::ZeroMapSize { .. })
    ));
}

#[test]
fn a_point_light_inside_the_visible_receivers_needs_a_cube_map() {
    let p = ShadowProblem::new(camera(), Light::point(DVec3::new(0.0, 1.0, 0.0)), bounds(), ShadowMapSize::square(256))
        .unwrap();
    for param in Parameterization::ALL_DEFAULT {
        assert!(matches!(p.solve(&param), Err(LixelError::LightInsideFocus { .. })), "{:?}", param.method());
    }
}

#[test]
fn bad_planes_and_readbacks_are_rejected() {
    let p =
        ShadowProblem::new(camera(), Light::directional(DVec3::NEG_Y), bounds(), ShadowMapSize::square(256)).unwrap();
    let nan_plane = lixel::geometry::Plane { normal: DVec3::NAN, offset: 0.0 };
    assert!(p.solve(&Parameterization::PlaneOptimal(PlaneOptimalOptions::on_plane(nan_plane))).is_err());
    let zero_plane = lixel::geometry::Plane { normal: DVec3::ZERO, offset: 0.0 };
    assert!(matches!(
        p.solve(&Parameterization::PlaneOptimal(PlaneOptimalOptions::on_plane(zero_plane))),
        Err(LixelError::InvalidPlane { .. })
    ));
    let depth = vec![0.5f32; 16];
    let bits = vec![0u32; 15];
    let short =
        Readback { width: 4, height: 4, depth: &depth, shadow_bits: &bits, normals: None, layout: Default::default() };
    assert!(Samples::from_readback(&p, &short, 0, &SampleOptions::default()).is_err());
    let bits = vec![0u32; 16];
    let fine =
        Readback { width: 4, height: 4, depth: &depth, shadow_bits: &bits, normals: None, layout: Default::default() };
    assert!(Samples::from_readback(&p, &fine, 32, &SampleOptions::default()).is_err());
    // A readback of NaN depths is not an error: it simply has no samples.
    let nan_depth = vec![f32::NAN; 16];
    let nans = Readback {
        width: 4,
        height: 4,
        depth: &nan_depth,
        shadow_bits: &bits,
        normals: None,
        layout: Default::default(),
    };
    let samples = Samples::from_readback(&p, &nans, 0, &SampleOptions::default()).unwrap();
    assert_eq!(samples.relevant_count(), 0);
    let result = lixel::optimize_light_matrix(&samples, None).unwrap();
    assert_eq!(result.report.fallback, Some(lixel::Fallback::NoUsableSamples));
}
