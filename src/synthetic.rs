//! Analytic test scenes (a floor, spheres, boxes) ray-cast on the CPU into
//! exactly what an engine reads back from its analysis pass: depth, shadow
//! bits and normals. Tests, benches and engines evaluating the optimizer
//! without a renderer use them.

use glam::{DVec2, DVec3, DVec4};

use crate::camera::Camera;
use crate::light::Light;
use crate::optimize::Readback;
use crate::scene::{Aabb, SceneBounds};

/// A sphere.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sphere {
    /// Centre.
    pub center: DVec3,
    /// Radius.
    pub radius: f64,
}

/// A scene of analytic shapes; every shape casts and receives shadows.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SyntheticScene {
    /// A square floor at height `y` with half-size `half_extent`, centred on the y axis.
    pub floor: Option<(f64, f64)>,
    /// Spheres.
    pub spheres: Vec<Sphere>,
    /// Boxes.
    pub boxes: Vec<Aabb>,
}

/// A CPU-rendered readback (owned buffers; see [`SyntheticReadback::as_readback`]).
#[derive(Clone, Debug, PartialEq)]
pub struct SyntheticReadback {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Depth-buffer values in `[0, 1]`, `1` where nothing was hit.
    pub depth: Vec<f32>,
    /// Bit `i`: in the shadow of light `i`.
    pub shadow_bits: Vec<u32>,
    /// Unit world normals (zero where nothing was hit).
    pub normals: Vec<[f32; 3]>,
}

impl SyntheticReadback {
    /// Borrowed view for [`Samples::from_readback`](crate::Samples::from_readback).
    #[must_use]
    pub fn as_readback(&self, with_normals: bool) -> Readback<'_> {
        Readback {
            width: self.width,
            height: self.height,
            depth: &self.depth,
            shadow_bits: &self.shadow_bits,
            normals: with_normals.then_some(&self.normals[..]),
            layout: crate::optimize::ReadbackLayout::default(),
        }
    }
}

#[derive(Clone, Copy)]
struct Hit {
    t: f64,
    normal: DVec3,
}

impl SyntheticScene {
    /// Bounds of everything (casters and receivers alike).
    #[must_use]
    pub fn bounds(&self) -> Option<SceneBounds> {
        let floor = self.floor.map(|(y, h)| Aabb::from_corners(DVec3::new(-h, y, -h), DVec3::new(h, y, h)));
        let spheres = self.spheres.iter().map(|s| Aabb { min: s.center - s.radius, max: s.center + s.radius });
        let all: Vec<Aabb> = floor.into_iter().chain(spheres).chain(self.boxes.iter().copied()).collect();
        let first = *all.first()?;
        let union = all.iter().fold(first, |acc, b| acc.union(b));
        Some(SceneBounds::uniform(union))
    }

    /// Nearest hit along `origin + t dir`, `t` in `(t_min, t_max)`.
    fn intersect(&self, origin: DVec3, dir: DVec3, t_min: f64, t_max: f64) -> Option<Hit> {
        let mut best: Option<Hit> = None;
        let mut consider = |hit: Option<Hit>| {
            if let Some(h) = hit {
                if h.t > t_min && h.t < t_max && best.is_none_or(|b| h.t < b.t) {
                    best = Some(h);
                }
            }
        };
        if let Some((y, half)) = self.floor {
            if dir.y != 0.0 {
                let t = (y - origin.y) / dir.y;
                let p = origin + dir * t;
                if p.x.abs() <= half && p.z.abs() <= half {
                    consider(Some(Hit { t, normal: if dir.y < 0.0 { DVec3::Y } else { DVec3::NEG_Y } }));
                }
            }
        }
        for s in &self.spheres {
            consider(sphere_hit(s, origin, dir, t_min));
        }
        for b in &self.boxes {
            consider(box_hit(b, origin, dir));
        }
        best
    }

    /// Ray-casts a `width x height` readback of `camera`'s view, with shadow
    /// bit `i` for `lights[i]` (at most 32).
    #[must_use]
    pub fn render(&self, camera: &Camera, lights: &[Light], width: u32, height: u32) -> SyntheticReadback {
        let n = (width as usize) * (height as usize);
        let mut out = SyntheticReadback {
            width,
            height,
            depth: vec![1.0; n],
            shadow_bits: vec![0; n],
            normals: vec![[0.0; 3]; n],
        };
        let clip_from_world = camera.clip_from_world();
        let world_from_screen = camera.screen_from_world().inverse();
        let viewport = camera.viewport().as_dvec2();
        let step = viewport / DVec2::new(f64::from(width.max(1)), f64::from(height.max(1)));
        let scale = self.bounds().map_or(1.0, |b| b.scene().diagonal().max(1e-12));
        for y in 0..height {
            for x in 0..width {
                let pixel = (DVec2::new(f64::from(x), f64::from(y)) + 0.5) * step;
                let near = world_from_screen.project_point3(pixel.extend(0.0));
                let far = world_from_screen.project_point3(pixel.extend(1.0));
                let dir = far - near;
                let Some(hit) = self.intersect(near, dir, 0.0, 1.0) else { continue };
                let p = near + dir * hit.t;
                let clip: DVec4 = clip_from_world * p.extend(1.0);
                let i = (y as usize) * (width as usize) + x as usize;
                out.depth[i] = (clip.z / clip.w) as f32;
                out.normals[i] = hit.normal.as_vec3().to_array();
                let lift = p + hit.normal * (1e-7 * scale);
                for (k, light) in lights.iter().take(crate::MAX_LIGHTS).enumerate() {
                    let (to, t_max) = match *light {
                        Light::Directional { direction } => (-direction, f64::INFINITY),
                        Light::Point { position } | Light::Spot { position, .. } => (position - lift, 1.0),
                    };
                    let facing = hit.normal.dot(to) > 0.0;
                    if !facing || self.intersect(lift, to, 1e-9, t_max).is_some() {
                        out.shadow_bits[i] |= 1 << k;
                    }
                }
            }
        }
        out
    }
}

fn sphere_hit(s: &Sphere, origin: DVec3, dir: DVec3, t_min: f64) -> Option<Hit> {
    let oc = origin - s.center;
    let a = dir.length_squared();
    let b = oc.dot(dir);
    let c = oc.length_squared() - s.radius * s.radius;
    let disc = b * b - a * c;
    if disc < 0.0 || a == 0.0 {
        return None;
    }
    let root = disc.sqrt();
    let t = [(-b - root) / a, (-b + root) / a].into_iter().find(|&t| t > t_min)?;
    let normal = (origin + dir * t - s.center).normalize();
    Some(Hit { t, normal: if normal.dot(dir) > 0.0 { -normal } else { normal } })
}

fn box_hit(b: &Aabb, origin: DVec3, dir: DVec3) -> Option<Hit> {
    let inv = dir.recip();
    let t0 = (b.min - origin) * inv;
    let t1 = (b.max - origin) * inv;
    let (lo, hi) = (t0.min(t1), t0.max(t1));
    let t_enter = lo.max_element();
    let t_exit = hi.min_element();
    if !(t_enter <= t_exit) || t_exit < 0.0 {
        return None;
    }
    let (t, axis) = if t_enter > 0.0 {
        (
            t_enter,
            if lo.x == t_enter {
                0
            } else if lo.y == t_enter {
                1
            } else {
                2
            },
        )
    } else {
        (
            t_exit,
            if hi.x == t_exit {
                0
            } else if hi.y == t_exit {
                1
            } else {
                2
            },
        )
    };
    let mut normal = DVec3::ZERO;
    normal[axis] = -dir[axis].signum();
    Some(Hit { t, normal })
}
