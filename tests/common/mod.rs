//! Seeded random shadow configurations shared by the property tests and benches.
#![allow(dead_code)]

use glam::{DVec3, UVec2};
use lixel::synthetic::{Sphere, SyntheticReadback, SyntheticScene};
use lixel::{Aabb, Camera, Light, SceneBounds, ShadowMapSize, ShadowProblem};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Number of general configurations per method: `LIXEL_PROP_CASES` or 4 000
/// (the method property tests add half as many from the hard regions). CI
/// runs the default; raise it for a hunt (`LIXEL_PROP_CASES=100000`).
pub fn cases() -> usize {
    std::env::var("LIXEL_PROP_CASES").ok().and_then(|s| s.parse().ok()).unwrap_or(4_000)
}

/// A fully specified configuration (printable, to turn failures into regressions).
#[derive(Clone, Copy, Debug)]
pub struct Config {
    pub eye: DVec3,
    pub target: DVec3,
    pub up: DVec3,
    pub fov_y: f64,
    pub viewport: UVec2,
    pub z_near: f64,
    pub z_far: f64,
    pub light: Light,
    pub bounds: SceneBounds,
    pub map: ShadowMapSize,
}

impl Config {
    pub fn camera(&self) -> Option<Camera> {
        Camera::look_at(self.eye, self.target, self.up, self.fov_y, self.viewport, self.z_near, self.z_far).ok()
    }

    pub fn problem(&self) -> Option<ShadowProblem> {
        ShadowProblem::new(self.camera()?, self.light, self.bounds, self.map).ok()
    }
}

fn log_uniform(rng: &mut impl Rng, lo: f64, hi: f64) -> f64 {
    (rng.random_range(lo.ln()..hi.ln())).exp()
}

fn unit(rng: &mut impl Rng) -> DVec3 {
    loop {
        let v = DVec3::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0));
        let l = v.length();
        if l > 1e-3 && l <= 1.0 {
            return v / l;
        }
    }
}

fn point_in(rng: &mut impl Rng, b: &Aabb) -> DVec3 {
    DVec3::new(
        if b.max.x > b.min.x { rng.random_range(b.min.x..=b.max.x) } else { b.min.x },
        if b.max.y > b.min.y { rng.random_range(b.min.y..=b.max.y) } else { b.min.y },
        if b.max.z > b.min.z { rng.random_range(b.min.z..=b.max.z) } else { b.min.z },
    )
}

/// The i-th configuration of stream `seed`. Every tenth kind is a hard case:
/// light along ±view, light parallel to the image plane, point light inside
/// the view frustum or behind the camera, extreme near/far, tiny/huge scenes.
pub fn config(seed: u64, index: usize) -> Config {
    let mut rng = ChaCha8Rng::seed_from_u64(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ index as u64);
    let scale = match index % 7 {
        0 => log_uniform(&mut rng, 1e-3, 1e-1),
        1 => log_uniform(&mut rng, 1e3, 1e5),
        _ => log_uniform(&mut rng, 0.5, 200.0),
    };
    // A floor with objects on it (walkthrough scenes), or a random box.
    let walkthrough = rng.random_bool(0.6);
    let (bounds, eye, target) = if walkthrough {
        let floor = Aabb::from_corners(DVec3::new(-scale, 0.0, -scale), DVec3::new(scale, 0.0, scale));
        let height = scale * rng.random_range(0.01..0.3);
        let objects = Aabb::from_corners(DVec3::new(-scale, 0.0, -scale), DVec3::new(scale, height, scale));
        let eye = DVec3::new(
            rng.random_range(-scale..scale),
            height * rng.random_range(0.05..2.0),
            rng.random_range(-scale..scale),
        );
        let dir = DVec3::new(rng.random_range(-1.0..1.0), rng.random_range(-0.5..0.1), rng.random_range(-1.0..1.0));
        let dir = dir.try_normalize().unwrap_or(DVec3::NEG_Z);
        (SceneBounds { casters: objects, receivers: objects.union(&floor) }, eye, eye + dir * scale)
    } else {
        let a = DVec3::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0));
        let b = DVec3::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0));
        let receivers = Aabb::from_corners(a * scale, b * scale);
        let casters = if rng.random_bool(0.5) {
            receivers
        } else {
            let c = point_in(&mut rng, &receivers);
            let d = point_in(&mut rng, &receivers);
            Aabb::from_corners(c, d)
        };
        let eye = if rng.random_bool(0.5) {
            point_in(&mut rng, &receivers)
        } else {
            unit(&mut rng) * scale * rng.random_range(1.0..5.0)
        };
        let target = point_in(&mut rng, &receivers);
        (SceneBounds { casters, receivers }, eye, target)
    };
    let target = if (target - eye).length() < 1e-6 * scale { eye + DVec3::NEG_Z * scale } else { target };
    let view = (target - eye).normalize();
    let up = if view.cross(DVec3::Y).length() < 1e-3 { DVec3::X } else { DVec3::Y };
    let (z_near, z_far) = match index % 11 {
        3 => (scale * 1e-6, scale * 1e4),
        4 => (scale * 1e-2, scale * 1e-1),
        _ => {
            let n = scale * log_uniform(&mut rng, 1e-4, 1e-1);
            (n, n * log_uniform(&mut rng, 10.0, 1e5))
        }
    };
    let fov_y = rng.random_range(10f64..140.0).to_radians();
    let viewport = UVec2::new(rng.random_range(16..2048), rng.random_range(16..2048));
    let map = match index % 5 {
        0 => ShadowMapSize::new(rng.random_range(1..4096), rng.random_range(1..64)),
        1 => ShadowMapSize::new(rng.random_range(1..64), rng.random_range(1..4096)),
        _ => ShadowMapSize::square(rng.random_range(16..4096)),
    };
    let (right, _) = view.any_orthonormal_pair();
    let far_away = scale * rng.random_range(3.0..50.0);
    let light = match index % 13 {
        // Exactly along the view direction, both ways.
        0 => Light::directional(view),
        1 => Light::directional(-view),
        // Parallel to the image plane.
        2 => Light::directional(right),
        // Point light inside the view frustum, in front of the eye.
        3 => Light::point(eye + view * scale * rng.random_range(0.01..0.5)),
        // Point light on the view axis behind the camera.
        4 => Light::point(eye - view * far_away),
        // Point light on the view axis far ahead.
        5 => Light::point(eye + view * far_away),
        // Point light inside the scene bounds.
        6 => Light::point(point_in(&mut rng, &bounds.scene())),
        7 | 8 => {
            let position = bounds.scene().center() + unit(&mut rng) * far_away;
            let aim = (point_in(&mut rng, &bounds.receivers) - position).normalize() + unit(&mut rng) * 0.3;
            Light::spot(position, aim, rng.random_range(5f64..85.0).to_radians())
        }
        9 | 10 => Light::point(bounds.scene().center() + unit(&mut rng) * far_away),
        _ => Light::directional(unit(&mut rng)),
    };
    Config { eye, target, up, fov_y, viewport, z_near, z_far, light, bounds, map }
}

/// A small synthetic scene (floor, two spheres, a box) in front of a fixed
/// camera, one problem per light, and its 96x96 readback.
pub fn setup(lights: &[Light]) -> (Vec<ShadowProblem>, SyntheticReadback) {
    setup_with_eye(lights, DVec3::new(0.0, 1.7, 4.0))
}

/// [`setup`] with the camera at `eye` (still looking at the scene).
pub fn setup_with_eye(lights: &[Light], eye: DVec3) -> (Vec<ShadowProblem>, SyntheticReadback) {
    let scene = SyntheticScene {
        floor: Some((0.0, 20.0)),
        spheres: vec![
            Sphere { center: DVec3::new(0.0, 1.0, -5.0), radius: 1.0 },
            Sphere { center: DVec3::new(3.0, 2.0, -9.0), radius: 1.5 },
        ],
        boxes: vec![Aabb::from_corners(DVec3::new(-4.0, 0.0, -8.0), DVec3::new(-2.0, 3.0, -6.0))],
    };
    let camera =
        Camera::look_at(eye, DVec3::new(0.0, 0.5, -6.0), DVec3::Y, 60f64.to_radians(), UVec2::new(800, 800), 0.1, 60.0)
            .unwrap();
    let problems = lights
        .iter()
        .map(|&l| ShadowProblem::new(camera, l, scene.bounds().unwrap(), ShadowMapSize::square(512)).unwrap())
        .collect();
    (problems, scene.render(&camera, lights, 96, 96))
}

/// The hard region a [`hard_config`] comes from (for failure messages and counts).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Region {
    /// A spot light inside the receiver bounds (a ceiling spot).
    SpotInside,
    /// A spot light just outside the receiver bounds, aimed in.
    SpotAround,
    /// A point light 1e-3..1e9 scene scales from the receivers.
    PointAtDistance,
    /// A point or directional light in, or grazing, the plane of a flat floor.
    Grazing,
    /// Scenes of scale up to 1e13 (coordinates near the supported limit).
    Huge,
}

/// The i-th configuration of stream `seed` drawn on purpose from the regions
/// an independent contract checker found violations in (issue 10).
pub fn hard_config(seed: u64, index: usize) -> (Config, Region) {
    let mut config = config(seed, index);
    let mut rng = ChaCha8Rng::seed_from_u64(seed.wrapping_mul(0xD1B5_4A32_D192_ED03) ^ index as u64);
    let r = config.bounds.receivers;
    let scale = config.bounds.scene().diagonal().max(1e-3);
    let aim = |rng: &mut ChaCha8Rng, from: DVec3| {
        (point_in(rng, &r) - from).try_normalize().unwrap_or(DVec3::NEG_Y) + unit(rng) * 0.3
    };
    let region = match index % 5 {
        0 => {
            let position = point_in(&mut rng, &r);
            let dir = if rng.random_bool(0.5) { DVec3::NEG_Y + unit(&mut rng) * 0.2 } else { unit(&mut rng) };
            config.light = Light::spot(position, dir, rng.random_range(5f64..88.0).to_radians());
            Region::SpotInside
        }
        1 => {
            let c = r.center();
            let half = (r.max - r.min) * 0.5;
            let out = unit(&mut rng);
            let position = c + out * (half.length() * rng.random_range(0.9..1.3) + scale * 1e-3);
            let dir = aim(&mut rng, position);
            config.light = Light::spot(position, dir, rng.random_range(5f64..88.0).to_radians());
            Region::SpotAround
        }
        2 => {
            let from = point_in(&mut rng, &r);
            let distance = (scale * 10f64.powf(rng.random_range(-3.0..9.0))).min(1e14);
            let position = from + unit(&mut rng) * distance;
            config.light = if rng.random_bool(0.7) {
                Light::point(position)
            } else {
                Light::spot(
                    position,
                    (from - position).normalize() + unit(&mut rng) * 1e-3,
                    rng.random_range(1f64..60.0).to_radians(),
                )
            };
            Region::PointAtDistance
        }
        3 => {
            // Flat floor at y = floor; light in its plane or just off it.
            let floor = r.min.y;
            config.bounds.receivers = Aabb::from_corners(r.min, DVec3::new(r.max.x, floor, r.max.z));
            let h = match rng.random_range(0..4) {
                0 => 0.0,
                1 => scale * 1e-9 * rng.random_range(-1.0..1.0),
                2 => scale * 10f64.powf(rng.random_range(-8.0..-2.0)),
                _ => -scale * 10f64.powf(rng.random_range(-8.0..-2.0)),
            };
            let horizontal = DVec3::new(rng.random_range(-1.0..1.0), 0.0, rng.random_range(-1.0..1.0))
                .try_normalize()
                .unwrap_or(DVec3::X);
            config.light = if rng.random_bool(0.6) {
                let d = scale * 10f64.powf(rng.random_range(0.0..4.0));
                Light::point(r.center().with_y(floor + h) + horizontal * d)
            } else {
                Light::directional(-horizontal + DVec3::Y * (h / scale).clamp(-1.0, 1.0) * -1.0)
            };
            Region::Grazing
        }
        _ => {
            let k = 10f64.powf(rng.random_range(5.0..13.0)) / scale.max(1e-3);
            let s = |v: DVec3| v * k;
            config.eye = s(config.eye);
            config.target = s(config.target);
            config.z_near *= k;
            config.z_far *= k;
            config.bounds.casters = Aabb { min: s(config.bounds.casters.min), max: s(config.bounds.casters.max) };
            config.bounds.receivers = Aabb { min: s(config.bounds.receivers.min), max: s(config.bounds.receivers.max) };
            config.light = match config.light {
                Light::Point { position } => Light::point(s(position)),
                Light::Spot { position, direction, outer_half_angle_radians } => {
                    Light::spot(s(position), direction, outer_half_angle_radians)
                }
                directional => directional,
            };
            Region::Huge
        }
    };
    (config, region)
}
