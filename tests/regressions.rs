//! Every bug found by the property tests, with its raw input.

mod common;

use glam::{DVec3, UVec2};
use lixel::{Aabb, Camera, Light, LixelError, Parameterization, SceneBounds, ShadowMapSize, ShadowProblem};

/// PSM #3789 (seed 3): a point light inside the receiver box, so PSM's hull
/// `H` reaches the light; the casters between `H`'s vertices and the light
/// were outside the depth range because the depth row ignored `H` itself.
#[test]
fn psm_caster_next_to_light_stays_in_depth_range() {
    let camera = Camera::look_at(
        DVec3::new(-62.079816527295215, -12.650374634803192, 33.105967001644366),
        DVec3::new(-71.89094185387096, -51.832058696276256, 33.18112862102762),
        DVec3::Y,
        2.0433665319445624,
        UVec2::new(1262, 766),
        6.296197821416158,
        11627.3648529891,
    )
    .unwrap();
    let light = Light::point(DVec3::new(15.612182393439724, -33.02944680365609, 33.12246259791413));
    let bounds = SceneBounds {
        casters: Aabb {
            min: DVec3::new(-4.895975843070104, -39.02379507024628, 33.10641348487199),
            max: DVec3::new(16.939401548568682, -6.427624259338344, 33.118090018378794),
        },
        receivers: Aabb {
            min: DVec3::new(-74.06125003453307, -61.361028967025234, 33.02472659412257),
            max: DVec3::new(26.67857240568508, -3.0949825150004546, 33.2147089754312),
        },
    };
    let problem = ShadowProblem::new(camera, light, bounds, ShadowMapSize::square(3612)).unwrap();
    let m = problem.solve(&Parameterization::Psm(Default::default())).unwrap();
    let shadowed = DVec3::new(15.659738467986106, -33.07881789166541, 33.02472659412257);
    let caster = DVec3::new(15.614560197167043, -33.03191535805656, 33.11757579772455);
    let z = |p: DVec3| m.project(p).unwrap().z;
    assert!(z(shadowed) >= 0.0 && z(shadowed) <= 1.0);
    assert!(z(caster) >= 0.0 || m.needs_unclipped_depth, "caster depth {}", z(caster));
}

/// Plane-optimal #4230 (seed 6): a distant point light barely below the
/// floor's plane makes the floor's own `w` tiny; the blend accepted an axis
/// closer to the vanishing line than the matrix builder allows, which then
/// reported `NotInFront`.
#[test]
fn plane_optimal_with_light_grazing_the_plane_is_accepted_by_the_builder() {
    let camera = Camera::look_at(
        DVec3::new(-63.20899153815092, 2.615369400877717, 11.991133692752413),
        DVec3::new(-95.71359402578547, 2.4866832235505827, 71.87797370615722),
        DVec3::Y,
        1.8359691318505027,
        UVec2::new(1438, 415),
        1.5166986415034587,
        22327.624005166872,
    )
    .unwrap();
    let light = Light::point(DVec3::new(-1672.1430658868596, -3.7544231747451384, 2976.3091111020076));
    let b = Aabb {
        min: DVec3::new(-68.13955789262589, 0.0, -68.13955789262589),
        max: DVec3::new(68.13955789262589, 9.31226212554883, 68.13955789262589),
    };
    let problem = ShadowProblem::new(camera, light, SceneBounds::uniform(b), ShadowMapSize::new(1086, 8)).unwrap();
    let m = problem.solve(&Parameterization::PlaneOptimal(Default::default())).unwrap();
    for p in problem.visible_receiver_body().vertices() {
        assert!(m.covers(*p, 1e-6), "{p} not covered");
    }
}

/// Focused #6 (seed 2): the view frustum (far = 13) sees no receiver, and the
/// point light sits inside the receiver box, so the normal-map fallback is
/// impossible too. This used to surface as `LightInsideFocus`, which blamed
/// the light for what is really "nothing visible"; it is now `NothingVisible`.
#[test]
fn nothing_visible_with_light_inside_receivers_is_its_own_error() {
    let camera = Camera::look_at(
        DVec3::new(-168.8696199214554, 250.16583992741215, 154.07481864950273),
        DVec3::new(-57.62237208056687, 51.91048605980892, -32.75767063457019),
        DVec3::Y,
        1.4480275498614061,
        UVec2::new(410, 1547),
        0.28431332020716193,
        13.255336602234225,
    )
    .unwrap();
    let light = Light::point(DVec3::new(-47.98522848833273, 44.26400657801584, -25.392214449411494));
    let bounds = SceneBounds {
        casters: Aabb {
            min: DVec3::new(-51.43397199657864, 45.968724417854844, -48.33958758539766),
            max: DVec3::new(-46.941228724517, 57.15117069068273, -38.80427576800658),
        },
        receivers: Aabb {
            min: DVec3::new(-58.393568078676616, 42.372860387502094, -48.540306388866306),
            max: DVec3::new(-40.37237052947377, 60.47806545159298, -23.28270089286162),
        },
    };
    let problem = ShadowProblem::new(camera, light, bounds, ShadowMapSize::new(44, 1142)).unwrap();
    assert!(problem.visible_receiver_body().is_empty());
    for p in Parameterization::ALL_DEFAULT.into_iter().skip(1) {
        assert!(
            matches!(problem.solve(&p), Err(LixelError::NothingVisible { .. })),
            "{:?}: {:?}",
            p.method(),
            problem.solve(&p)
        );
    }
}
