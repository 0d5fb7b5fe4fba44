//! The default view of a loaded model: outside its bounding sphere, a
//! little above it, at the distance where the sphere just fits the view.
//!
//! The built-in scene has a walkthrough camera (viewer a little above a wide
//! floor, as in the paper). A user's model has no such layout: a camera
//! placed "a little above the floor at the scene's edge" ends up inside or
//! against a scanned statue, and most lights then light nothing it sees.
//! Framing the bounding sphere instead works for any size, position and
//! shape, and shows the floor around the model (when there is one) where its
//! shadows fall.

use glam::DVec3;

use crate::mesh::Scene;

/// Elevation of the default view above the horizontal, in degrees: high
/// enough to see the model's top and its shadows on the floor, low enough
/// to see its front.
pub const ELEVATION_DEGREES: f64 = 25.0;

/// Where the camera looks from and to, and its depth range.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Framing {
    /// Eye position.
    pub eye: DVec3,
    /// Look-at point.
    pub target: DVec3,
    /// Near plane distance.
    pub near: f64,
    /// Far plane distance: the farthest corner of the whole scene (floor
    /// included).
    pub far: f64,
}

/// Frames the scene's casters (the model; the floor is a receiver) for a
/// square view of vertical field of view `fov_y` (radians). `eye`/`target`
/// given by the user are kept; a missing target is the bounding-sphere
/// centre; a missing eye looks at the target from the front (`+z`) at
/// [`ELEVATION_DEGREES`], far enough that the whole sphere is in view.
#[must_use]
pub fn frame_model(scene: &Scene, eye: Option<DVec3>, target: Option<DVec3>, fov_y: f64) -> Framing {
    let bounds = scene.bounds();
    let model = bounds.casters;
    let center = model.center();
    let radius = (0.5 * model.diagonal()).max(f64::MIN_POSITIVE.sqrt());
    let target = target.unwrap_or(center);
    let eye = eye.unwrap_or_else(|| {
        // The sphere around the model seen from `target` subtends at most the
        // field of view when the eye is this far from it.
        let half = (0.5 * fov_y).clamp(1e-3, 0.5 * std::f64::consts::PI - 1e-3);
        let distance = (target.distance(center) + radius) / half.sin();
        let elevation = ELEVATION_DEGREES.to_radians();
        target + DVec3::new(0.0, elevation.sin(), elevation.cos()) * distance
    });
    let scene_box = bounds.scene();
    let farthest = (0..8)
        .map(|k| {
            let pick = |bit: usize, lo: f64, hi: f64| if k & bit == 0 { lo } else { hi };
            let (lo, hi) = (scene_box.min, scene_box.max);
            DVec3::new(pick(1, lo.x, hi.x), pick(2, lo.y, hi.y), pick(4, lo.z, hi.z)).distance(eye)
        })
        .fold(0.0, f64::max);
    let far = 1.01 * farthest.max(radius);
    Framing { eye, target, near: far * 1e-3, far }
}

#[cfg(test)]
mod tests {
    use glam::{UVec2, Vec3};

    use super::*;
    use crate::mesh::{primitives, Role, SceneObject};
    use crate::Camera;

    fn scene_at(offset: Vec3, size: f32) -> Scene {
        let mut mesh = primitives::cuboid(Vec3::new(0.3, 1.0, 0.2) * size, 12);
        for p in &mut mesh.positions {
            *p += offset;
        }
        Scene {
            objects: vec![SceneObject { name: "m".into(), mesh, role: Role::CasterAndReceiver, albedo: Vec3::ONE }],
        }
    }

    /// Every vertex of the model projects inside the screen and in front of
    /// the eye, at any size and position; the model is not a speck.
    #[test]
    fn model_is_inside_the_view_and_fills_it() {
        for (offset, size) in [(Vec3::ZERO, 1.0), (Vec3::new(0.0, -1000.0, 0.0), 5.0), (Vec3::new(1e6, 0.0, 1e6), 1e-3)]
        {
            let scene = scene_at(offset, size);
            let fov = 60f64.to_radians();
            let f = frame_model(&scene, None, None, fov);
            let camera = Camera::look_at(f.eye, f.target, DVec3::Y, fov, UVec2::splat(100), f.near, f.far).unwrap();
            let mut ndc_extent = 0.0f64;
            for p in &scene.objects[0].mesh.positions {
                let clip = camera.clip_from_world() * p.as_dvec3().extend(1.0);
                assert!(clip.w > 0.0, "{offset} {size}: behind the eye");
                let ndc = clip.truncate() / clip.w;
                assert!(ndc.x.abs() <= 1.0 && ndc.y.abs() <= 1.0 && (0.0..=1.0).contains(&ndc.z), "{ndc}");
                ndc_extent = ndc_extent.max(ndc.y.abs());
            }
            // A 2 x 0.6 x 0.4 box: its height spans more than half the screen.
            assert!(ndc_extent > 0.5, "{offset} {size}: model fills only {ndc_extent}");
        }
    }
}
