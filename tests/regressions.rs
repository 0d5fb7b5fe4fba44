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

// ---- Issue 10: an independent contract checker's findings, one test each. ----

fn room_camera() -> Camera {
    Camera::look_at(
        DVec3::new(0.0, 1.7, 10.0),
        DVec3::ZERO,
        DVec3::Y,
        60f64.to_radians(),
        UVec2::new(800, 600),
        0.1,
        100.0,
    )
    .unwrap()
}

fn room() -> Aabb {
    Aabb::from_corners(DVec3::new(-10.0, 0.0, -10.0), DVec3::new(10.0, 3.0, 10.0))
}

/// Every point of a grid over `r` that the camera sees and the light reaches,
/// plus the solver's own visible receiver body (away from the light itself).
fn visible_lit_points(problem: &ShadowProblem) -> Vec<DVec3> {
    let r = problem.bounds().receivers;
    let clip = problem.camera().clip_from_world();
    let mut points = Vec::new();
    let n = 12;
    for i in 0..=n {
        for j in 0..=n {
            for k in 0..=n {
                let t = DVec3::new(f64::from(i), f64::from(j), f64::from(k)) / f64::from(n);
                let p = r.min + (r.max - r.min) * t;
                let c = clip * p.extend(1.0);
                let seen = c.w > 0.0 && c.x.abs() <= c.w && c.y.abs() <= c.w && c.z >= 0.0 && c.z <= c.w;
                let at_light = problem.light().position().is_some_and(|l| (p - l).length() < 1e-6);
                if seen && problem.light().reaches(p) && !at_light {
                    points.push(p);
                }
            }
        }
    }
    points
}

fn assert_covers_all(m: &lixel::LightMatrix, points: &[DVec3], what: &str) {
    assert!(m.clip_from_world.is_finite(), "{what}: non-finite matrix");
    for &p in points {
        assert!(m.covers(p, 1e-6), "{what}: {p} outside the map ({:?})", m.project(p));
        let z = m.project(p).unwrap().z;
        assert!(z <= 1.0 + 1e-6 && (z >= -1e-6 || m.needs_unclipped_depth), "{what}: {p} at depth {z}");
    }
}

/// Issue 10 case 1: a ceiling spot inside the receiver bounds (the commonest
/// indoor light) was refused with `LightInsideFocus` by every method but PSM.
/// A spot under 89° always fits its own frustum.
#[test]
fn ceiling_spot_inside_the_room_is_served_by_every_method() {
    for y in [2.9, 3.0, 3.1] {
        let spot = Light::spot(DVec3::new(0.0, y, 0.0), DVec3::NEG_Y, 30f64.to_radians());
        let problem =
            ShadowProblem::new(room_camera(), spot, SceneBounds::uniform(room()), ShadowMapSize::square(1024)).unwrap();
        let points = visible_lit_points(&problem);
        assert!(points.len() > 8, "{} points", points.len());
        for p in Parameterization::ALL_DEFAULT {
            let m = problem.solve(&p).unwrap_or_else(|e| panic!("y = {y}, {:?}: {e}", p.method()));
            assert_covers_all(&m, &points, &format!("y = {y}, {:?}", p.method()));
        }
        // The scene optimizer, from the same points as samples.
        let boundary: Vec<(DVec3, DVec3)> = points.iter().map(|&p| (p, DVec3::Y)).collect();
        let samples = lixel::Samples::from_points(&problem, &points, &boundary);
        let m = lixel::optimize_light_matrix(&samples, None).unwrap().matrix;
        assert_covers_all(&m, &points, &format!("y = {y}, optimized"));
    }
    // A point light at the same place is still inside R: that needs a cube map.
    let point = Light::point(DVec3::new(0.0, 2.9, 0.0));
    let problem =
        ShadowProblem::new(room_camera(), point, SceneBounds::uniform(room()), ShadowMapSize::square(1024)).unwrap();
    assert!(matches!(problem.solve(&Parameterization::Normal), Err(LixelError::LightInsideFocus { .. })));
}

/// Issue 10 case 2: point and spot lights 1e5..1e9 away are suns written as
/// points. LiSPSM reported `NotInFront`, PSM `PsmHullAroundLight` and
/// plane-optimal `PlaneDegenerate` where the directional light they approach
/// has no fallback at all.
#[test]
fn far_point_and_spot_lights_behave_like_the_sun_they_approach() {
    let dir = DVec3::new(1.0, 2.0, 0.5).normalize();
    let sun = ShadowProblem::new(
        room_camera(),
        Light::directional(-dir),
        SceneBounds::uniform(room()),
        ShadowMapSize::square(1024),
    )
    .unwrap();
    for distance in [1e5, 1e6, 1e7, 1e8, 1e9] {
        for light in [Light::point(dir * distance), Light::spot(dir * distance, -dir, 10f64.to_radians())] {
            let problem =
                ShadowProblem::new(room_camera(), light, SceneBounds::uniform(room()), ShadowMapSize::square(1024))
                    .unwrap();
            let points = visible_lit_points(&problem);
            for p in Parameterization::ALL_DEFAULT {
                let what = format!("{light:?} {:?}", p.method());
                let m = problem.solve(&p).unwrap_or_else(|e| panic!("{what}: {e}"));
                let m_sun = sun.solve(&p).unwrap();
                assert_eq!(
                    m.fallback.is_some(),
                    m_sun.fallback.is_some(),
                    "{what}: {:?} vs the sun's {:?}",
                    m.fallback,
                    m_sun.fallback
                );
                assert_covers_all(&m, &points, &what);
            }
        }
    }
}

/// Issue 10 case 3: a light in (or grazing) the plane of a flat receiver: the
/// casters between the visible floor and the light fell outside the depth
/// range (−1.28e3) while `needs_unclipped_depth` was false. A sunset.
#[test]
fn casters_at_grazing_light_stay_in_the_depth_range() {
    let receivers = Aabb::from_corners(DVec3::new(-50.0, 0.0, -50.0), DVec3::new(50.0, 0.0, 50.0));
    let casters = Aabb::from_corners(DVec3::new(-50.0, 0.0, -50.0), DVec3::new(50.0, 20.0, 50.0));
    let cameras = [
        Camera::look_at(
            DVec3::new(0.0, 0.0, 40.0),
            DVec3::new(5.0, 0.0, 0.0),
            DVec3::Y,
            60f64.to_radians(),
            UVec2::new(370, 737),
            0.03,
            0.07,
        )
        .unwrap(),
        Camera::look_at(
            DVec3::new(0.0, 5.0, 60.0),
            DVec3::ZERO,
            DVec3::Y,
            60f64.to_radians(),
            UVec2::new(800, 600),
            0.1,
            200.0,
        )
        .unwrap(),
    ];
    for camera in cameras {
        for h in [0.0, 1e-6, 1e-4, 1e-2] {
            let light = Light::point(DVec3::new(-300.0, h, 10.0));
            let problem =
                ShadowProblem::new(camera, light, SceneBounds { casters, receivers }, ShadowMapSize::square(1024))
                    .unwrap();
            let floor = problem.visible_receiver_body();
            for p in Parameterization::ALL_DEFAULT {
                let what = format!("h = {h}, {:?}", p.method());
                let m = problem.solve(&p).unwrap_or_else(|e| panic!("{what}: {e}"));
                for &v in floor.vertices() {
                    let zv = m.project(v).unwrap().z;
                    for t in [1e-3, 0.01, 0.1, 0.3, 0.5, 0.7, 0.9, 0.99] {
                        let q = light.position().unwrap() + (v - light.position().unwrap()) * t;
                        if !casters.contains(q) {
                            continue;
                        }
                        let z = m.project(q).map_or(f64::NAN, |n| n.z);
                        assert!(
                            z <= zv + 1e-9 && (z >= -1e-6 || m.needs_unclipped_depth),
                            "{what}: caster {q} at depth {z} (receiver {zv})"
                        );
                    }
                }
            }
        }
    }
}

/// Issue 10 case 4: an empty visible receiver body and samples that all share
/// one light depth gave `alpha = inf` in the depth row.
#[test]
fn optimizer_with_empty_view_body_and_one_depth_is_finite() {
    let camera = Camera::look_at(
        DVec3::new(0.0, 10.0, 20.0),
        DVec3::new(0.0, 5.0, 0.0),
        DVec3::Y,
        60f64.to_radians(),
        UVec2::new(800, 600),
        0.1,
        100.0,
    )
    .unwrap();
    let unseen = Aabb::from_corners(DVec3::new(-1.0, 0.0, 200.0), DVec3::new(1.0, 1.0, 202.0));
    let p = ShadowProblem::new(
        camera,
        Light::directional(DVec3::NEG_Y),
        SceneBounds::uniform(unseen),
        ShadowMapSize::square(1024),
    )
    .unwrap();
    let rel = [DVec3::new(0.0, 5.0, 0.0), DVec3::new(1.0, 5.0, 0.0), DVec3::new(0.0, 5.0, 1.0)];
    let boundary = [(DVec3::new(0.5, 5.0, 0.5), DVec3::Y)];
    let s = lixel::Samples::from_points(&p, &rel, &boundary);
    let m = lixel::optimize_light_matrix(&s, None).unwrap().matrix;
    assert_covers_all(&m, &[rel[0], rel[1], rel[2], boundary[0].0], "optimized");
}

/// Issue 10 case 5: a boundary sample whose surface is seen edge-on (n·v ≈
/// 1e-17) has no usable derivative; it must be dropped, not make the
/// optimizer fail with "relevant samples surround the light".
#[test]
fn edge_on_boundary_samples_are_dropped() {
    let camera = room_camera();
    let view = camera.view_direction();
    for light in [Light::directional(DVec3::new(0.3, -1.0, 0.2)), Light::point(DVec3::new(3.0, 20.0, 1.0))] {
        let p = ShadowProblem::new(camera, light, SceneBounds::uniform(room()), ShadowMapSize::square(1024)).unwrap();
        let at = DVec3::new(0.5, 0.0, 0.5);
        // Normals orthogonal to the ray from the eye, up to 1e-17 .. 1e-9.
        let ray = (at - camera.eye()).normalize();
        let n0 = ray.cross(view.cross(DVec3::Y)).normalize();
        let n0 = (n0 - ray * n0.dot(ray)).normalize();
        // Facing the light (up), so only the edge-on test can drop it.
        let n0 = if n0.y < 0.0 { -n0 } else { n0 };
        let good = [(DVec3::new(-1.0, 0.0, 0.0), DVec3::Y), (DVec3::new(1.0, 0.0, -1.0), DVec3::Y)];
        for k in 0..26 {
            let n = (n0 + ray * (f64::from(k) * 2.5e-17 * 1.7f64.powi(k))).normalize();
            let boundary = [good[0], (at, n), good[1]];
            let s = lixel::Samples::from_points(&p, &[], &boundary);
            assert_eq!(s.boundary().len(), 2, "{light:?}, n·ray = {:e}", n.dot(ray));
            let m = lixel::optimize_light_matrix(&s, None).unwrap_or_else(|e| panic!("{light:?}: {e}")).matrix;
            assert_covers_all(&m, &[at, good[0].0, good[1].0], "optimized");
        }
    }
}

/// Issue 10 case 6 (found again by `degenerate_sample_sets_with_prev_keep_every_sample`,
/// #4422): one boundary sample, a point light 3e8 away and the LiSPSM matrix
/// as `prev`. The re-fitted previous axis sees the sample's narrow bundle of
/// directions almost sideways; in light coordinates the map held it, but
/// composed with the light's huge translation the world matrix put it at NDC
/// (−626, 271). The optimizer now checks its answer in world coordinates and
/// falls back.
#[test]
fn optimizer_map_holds_its_only_sample_with_a_lispsm_prev() {
    let camera = Camera::look_at(
        DVec3::new(1.7663401204351978, -1.4824802845358152, 0.03533648844389248),
        DVec3::new(-0.4765910971237193, -1.4462992964311587, 0.8782304903448566),
        DVec3::Y,
        2.4056148331440976,
        UVec2::new(1537, 651),
        0.0004628444950518022,
        0.023402689733434283,
    )
    .unwrap();
    let light = Light::point(DVec3::new(48515688.005764134, 257973828.9889152, -170423095.4202528));
    let b = Aabb {
        min: DVec3::new(-1.446604203033655, -1.671662160195352, -2.2255799429952585),
        max: DVec3::new(2.5145980225528244, -1.4118779613351713, 2.46568258372483),
    };
    let p = ShadowProblem::new(camera, light, SceneBounds::uniform(b), ShadowMapSize::square(3947)).unwrap();
    let at = DVec3::new(1.7737615910637061, -1.463359231615163, 0.07589669055858078);
    let n = DVec3::new(-0.517189921699419, 0.8312014583868846, 0.20400666770491735);
    let s = lixel::Samples::from_points(&p, &[], &[(at, n)]);
    let prev = p.solve(&Parameterization::LiSpsm(Default::default())).unwrap();
    let m = lixel::optimize_light_matrix(&s, Some(&prev)).unwrap().matrix;
    assert_covers_all(&m, &[at], "optimized with a LiSPSM prev");
}

/// Issue 10 case 7: coordinates beyond the supported range (|x| <= 1e15) are
/// a typed error; at the edge of the range the solver still works.
#[test]
fn coordinates_beyond_the_supported_range_are_a_typed_error() {
    let limit = lixel::MAX_COORDINATE;
    for (scale, ok) in [(limit * 0.5, true), (limit * 0.99, true), (limit * 4.0, false), (1e150, false), (1e200, false)]
    {
        let camera = Camera::look_at(
            DVec3::new(0.0, 0.2, 1.0) * scale,
            DVec3::ZERO,
            DVec3::Y,
            60f64.to_radians(),
            UVec2::new(800, 600),
            0.01 * scale,
            10.0 * scale,
        );
        let Ok(camera) = camera else {
            assert!(!ok, "camera at scale {scale} refused");
            continue;
        };
        let b = Aabb::from_corners(DVec3::new(-0.5, 0.0, -0.5) * scale, DVec3::new(0.5, 0.1, 0.5) * scale);
        let light = Light::point(DVec3::new(0.1, 0.9, 0.2) * scale);
        let problem = ShadowProblem::new(camera, light, SceneBounds::uniform(b), ShadowMapSize::square(512));
        if !ok {
            assert!(matches!(problem, Err(LixelError::OutOfRange { .. })), "scale {scale}: {problem:?}");
            continue;
        }
        let problem = problem.unwrap();
        let points = visible_lit_points(&problem);
        for p in Parameterization::ALL_DEFAULT {
            let m = problem.solve(&p).unwrap_or_else(|e| panic!("scale {scale} {:?}: {e}", p.method()));
            assert_covers_all(&m, &points, &format!("scale {scale} {:?}", p.method()));
        }
    }
    // Samples beyond the range are dropped as invalid, never mapped.
    let problem = ShadowProblem::new(
        room_camera(),
        Light::directional(DVec3::NEG_Y),
        SceneBounds::uniform(room()),
        ShadowMapSize::square(64),
    )
    .unwrap();
    let huge = DVec3::new(1e200, 0.0, -1e200);
    let s = lixel::Samples::from_points(&problem, &[huge, DVec3::ZERO], &[(huge, DVec3::Y)]);
    assert_eq!(s.relevant_count(), 1);
    let m = lixel::optimize_light_matrix(&s, None).unwrap().matrix;
    assert!(m.clip_from_world.is_finite());
}

/// Checks every visible receiver-body vertex (away from the light) is in the
/// map and the depth range.
fn assert_holds_body(problem: &ShadowProblem, p: Parameterization) {
    let m = problem.solve(&p).unwrap_or_else(|e| panic!("{:?}: {e}", p.method()));
    let l = problem.light().position();
    let body: Vec<DVec3> = problem
        .visible_receiver_body()
        .vertices()
        .iter()
        .copied()
        .filter(|&v| l.is_none_or(|l| (v - l).length() > 1e-6 * problem.scale()))
        .collect();
    assert_covers_all(&m, &body, &format!("{:?}", p.method()));
}

/// Plane-optimal, hard region "grazing" #67163 (seed 6, 90k run): a point
/// light 4e-10 above the floor's plane. The blended axis kept every floor
/// point's `w` above β times the least one in exact arithmetic, but those `w`
/// were 1e-12 of `|X~|`, and in `f64` a floor corner landed at depth
/// −2.2e-5. The finished matrix is now checked in world coordinates, and
/// plane-optimal reports `PlaneDegenerate` when f64 cannot hold its map.
#[test]
fn plane_optimal_with_light_in_the_floor_plane_keeps_the_depth_range() {
    let camera = Camera::look_at(
        DVec3::new(1.9360924026467237, -0.9268913780529672, 0.6654245810146547),
        DVec3::new(-0.22494039241767558, 0.23956020652308835, 0.3756719905191404),
        DVec3::Y,
        2.3557597320547092,
        UVec2::new(1659, 1717),
        0.04328949380293638,
        1262.4021651725532,
    )
    .unwrap();
    let light = Light::point(DVec3::new(-22.375779810112363, -0.40109724211488135, -2.499877035266119));
    let bounds = SceneBounds {
        casters: Aabb {
            min: DVec3::new(-0.28174752506620226, -0.4010972415401152, -0.4961496543060369),
            max: DVec3::new(-0.10572361657447339, 0.46432358122034617, 0.44767088330862304),
        },
        receivers: Aabb {
            min: DVec3::new(-0.28174752506620226, -0.4010972415401152, -0.4961496543060369),
            max: DVec3::new(-0.10572361657447339, -0.4010972415401152, 0.44767088330862304),
        },
    };
    let problem = ShadowProblem::new(camera, light, bounds, ShadowMapSize::square(948)).unwrap();
    assert_holds_body(&problem, Parameterization::PlaneOptimal(Default::default()));
}

/// Plane-optimal, "grazing" #62508: a directional light 6e-10 below
/// horizontal over a flat floor reported `NotInFront`.
#[test]
fn plane_optimal_with_horizontal_sun_over_a_floor_is_not_an_error() {
    let camera = Camera::look_at(
        DVec3::new(51.02038592423175, 26.120094933132638, -75.38953243922113),
        DVec3::new(27.201416520090795, -3.1962779393709897, -60.66330686653177),
        DVec3::Y,
        1.0836830685586671,
        UVec2::new(1242, 706),
        0.05318870711353478,
        35.97460133767505,
    )
    .unwrap();
    let light = Light::directional(DVec3::new(0.47161202471064134, -6.124734391820019e-10, -0.8818061567874934));
    let bounds = SceneBounds {
        casters: Aabb {
            min: DVec3::new(18.036484207714864, 17.127048398932317, -56.54890056347891),
            max: DVec3::new(29.786993862873132, 38.77960190163786, -53.83358497355999),
        },
        receivers: Aabb {
            min: DVec3::new(16.333821802019088, -6.310620529748651, -77.41105186135864),
            max: DVec3::new(51.72056996986384, -6.310620529748651, -1.5720713398092554),
        },
    };
    let problem = ShadowProblem::new(camera, light, bounds, ShadowMapSize::square(4059)).unwrap();
    assert_holds_body(&problem, Parameterization::PlaneOptimal(Default::default()));
}

/// PSM, "spot inside" #61240 (seed 3): a spot 0.16 above a 1.6e5-wide floor,
/// pointing down, unseen by the camera. Its lit body (0.2 across) lies
/// within the solver's resolution of the light, so every vertex was "at the
/// light" and the normal-map fallback failed with `NothingVisible`. The map
/// now holds the spot's whole frustum.
#[test]
fn tiny_spot_body_next_to_the_light_maps_the_spot_frustum() {
    let camera = Camera::look_at(
        DVec3::new(50902.27611541787, 3234.7428144806586, -14893.803113702146),
        DVec3::new(21513.353664694787, 904.8995846768225, -90056.06913286846),
        DVec3::Y,
        2.0867248902305975,
        UVec2::new(745, 1546),
        212.93640831103676,
        2053800.3899117818,
    )
    .unwrap();
    let light = Light::spot(
        DVec3::new(24253.13819602439, 0.16196630520639854, 11090.878758657476),
        DVec3::new(-0.18838262852575793, -0.9809061206941504, -0.04832357245153932),
        0.45060970862140015,
    );
    let b = Aabb::from_corners(
        DVec3::new(-80737.24769538532, 0.0, -80737.24769538532),
        DVec3::new(80737.24769538532, 2074.5274577591513, 80737.24769538532),
    );
    let problem = ShadowProblem::new(camera, light, SceneBounds::uniform(b), ShadowMapSize::new(1066, 24)).unwrap();
    for p in Parameterization::ALL_DEFAULT {
        let m = problem.solve(&p).unwrap_or_else(|e| panic!("{:?}: {e}", p.method()));
        // The lit floor under the spot lies in the map.
        let under = light.position().unwrap()
            + DVec3::new(-0.18838262852575793, -0.9809061206941504, -0.04832357245153932) * 0.16;
        assert!(m.covers(under.with_y(0.0), 1e-6), "{:?}", p.method());
    }
}
