//! The viewer's camera: a position, a yaw and a pitch, moved like a fly
//! camera (WASD, mouse look) or orbited around a target point (mouse drag,
//! wheel to zoom). Kept separate from the window so that a camera path and
//! the tests set it directly.

use glam::{DVec3, UVec2};

use crate::Camera;

/// A fly / orbit camera; [`camera`](Self::camera) turns it into the
/// library's [`Camera`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FlyCamera {
    /// Eye position.
    pub eye: DVec3,
    /// Rotation about +y, radians (0: looking along -z).
    pub yaw: f64,
    /// Elevation of the view direction, radians (positive: up).
    pub pitch: f64,
    /// Vertical field of view, radians.
    pub fov_y: f64,
    /// Near plane distance.
    pub near: f64,
    /// Far plane distance.
    pub far: f64,
    /// The point orbiting turns around.
    pub target: DVec3,
    /// Movement speed, world units per second.
    pub speed: f64,
}

impl FlyCamera {
    /// A camera at `eye` looking at `target`; `far` also sets the speed
    /// (a tenth of it per second) and `near` a thousandth of `far`.
    #[must_use]
    pub fn look_at(eye: DVec3, target: DVec3, fov_y: f64, far: f64) -> Self {
        let mut c = Self { eye, yaw: 0.0, pitch: 0.0, fov_y, near: far * 1e-3, far, target, speed: 0.1 * far };
        c.look_towards(target);
        c
    }

    /// Turns the camera to look at `point` (and orbit around it).
    pub fn look_towards(&mut self, point: DVec3) {
        let d = point - self.eye;
        if d.length_squared() > 0.0 {
            self.yaw = (-d.x).atan2(-d.z);
            self.pitch = (d.y / d.length()).clamp(-1.0, 1.0).asin();
            self.target = point;
        }
    }

    /// The unit view direction.
    #[must_use]
    pub fn forward(&self) -> DVec3 {
        let (sy, cy) = self.yaw.sin_cos();
        let (sp, cp) = self.pitch.sin_cos();
        DVec3::new(-sy * cp, sp, -cy * cp)
    }

    /// The unit right vector (horizontal).
    #[must_use]
    pub fn right(&self) -> DVec3 {
        let (sy, cy) = self.yaw.sin_cos();
        DVec3::new(cy, 0.0, -sy)
    }

    /// Moves by `amount` along (right, up, forward) in world units.
    pub fn fly(&mut self, amount: DVec3) {
        let delta = self.right() * amount.x + DVec3::Y * amount.y + self.forward() * amount.z;
        self.eye += delta;
        self.target += delta;
    }

    /// Mouse look: turns by the given angles (radians); pitch stays inside ±89°.
    pub fn turn(&mut self, yaw: f64, pitch: f64) {
        let limit = 89f64.to_radians();
        self.yaw += yaw;
        self.pitch = (self.pitch + pitch).clamp(-limit, limit);
        self.target = self.eye + self.forward() * (self.target - self.eye).length().max(1e-6);
    }

    /// Orbits the eye around the target by the given angles (radians).
    pub fn orbit(&mut self, yaw: f64, pitch: f64) {
        let distance = (self.target - self.eye).length().max(1e-6);
        let limit = 89f64.to_radians();
        self.yaw += yaw;
        self.pitch = (self.pitch + pitch).clamp(-limit, limit);
        self.eye = self.target - self.forward() * distance;
    }

    /// Moves the eye towards the target by the fraction `f` of the distance
    /// (negative: away); never onto the target.
    pub fn zoom(&mut self, f: f64) {
        let distance = (self.target - self.eye).length();
        let new = (distance * (1.0 - f)).clamp(self.near * 2.0, self.far * 0.5);
        self.eye = self.target - self.forward() * new;
    }

    /// The library's camera with `viewport` pixels.
    ///
    /// # Errors
    /// [`LixelError`](crate::LixelError) for a degenerate camera (zero
    /// viewport, non-finite position).
    pub fn camera(&self, viewport: UVec2) -> crate::Result<Camera> {
        let up = if self.forward().y.abs() > 0.999 { DVec3::Z } else { DVec3::Y };
        Camera::look_at(self.eye, self.eye + self.forward(), up, self.fov_y, viewport, self.near, self.far)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn look_at_faces_the_target() {
        let c = FlyCamera::look_at(DVec3::new(1.0, 2.0, 3.0), DVec3::new(-2.0, 0.5, -4.0), 1.0, 100.0);
        let want = (DVec3::new(-2.0, 0.5, -4.0) - DVec3::new(1.0, 2.0, 3.0)).normalize();
        assert!((c.forward() - want).length() < 1e-12, "{:?} vs {want:?}", c.forward());
        assert!(c.right().dot(c.forward()).abs() < 1e-12);
    }

    #[test]
    fn orbit_keeps_the_distance_to_the_target() {
        let mut c = FlyCamera::look_at(DVec3::new(0.0, 5.0, 20.0), DVec3::ZERO, 1.0, 100.0);
        let before = (c.target - c.eye).length();
        c.orbit(0.7, -0.2);
        assert!(((c.target - c.eye).length() - before).abs() < 1e-9);
        assert!((c.forward() - (c.target - c.eye).normalize()).length() < 1e-9);
    }
}
