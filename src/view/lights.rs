//! The viewer's lights: the experiment's configurations (point lights on a
//! distant hemisphere, or directional lights from it), each held as an
//! azimuth and an elevation around the scene centre so that the arrow keys
//! (or the animation) can move them over the hemisphere.

use glam::DVec3;

use crate::experiment::{light_for, ExperimentConfig, LightKind};
use crate::mesh::Scene;
use crate::Light;

/// Lights on a hemisphere around the scene centre.
#[derive(Clone, Debug, PartialEq)]
pub struct LightRig {
    kind: LightKind,
    centre: DVec3,
    /// Per light: (azimuth, elevation, distance), radians and world units.
    spherical: Vec<(f64, f64, f64)>,
}

impl LightRig {
    /// The experiment's lights `0..count` of `config` for `scene`.
    #[must_use]
    pub fn new(config: &ExperimentConfig, scene: &Scene, count: usize) -> Self {
        let centre = scene.bounds().scene().center();
        let spherical = (0..count)
            .map(|i| {
                let (dir, distance) = match light_for(config, scene, i) {
                    Light::Directional { direction } => (-direction, 1.0),
                    other => {
                        let offset = other.position().unwrap_or(centre + DVec3::Y) - centre;
                        (offset.normalize_or(DVec3::Y), offset.length())
                    }
                };
                (dir.z.atan2(dir.x), dir.y.clamp(-1.0, 1.0).asin(), distance)
            })
            .collect();
        Self { kind: config.light, centre, spherical }
    }

    /// Number of lights.
    #[must_use]
    pub fn len(&self) -> usize {
        self.spherical.len()
    }

    /// Whether there is no light.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.spherical.is_empty()
    }

    /// Turns every light about the vertical axis and raises it (radians);
    /// elevations stay between 2° and 89°.
    pub fn rotate(&mut self, azimuth: f64, elevation: f64) {
        for (a, e, _) in &mut self.spherical {
            *a += azimuth;
            *e = (*e + elevation).clamp(2f64.to_radians(), 89f64.to_radians());
        }
    }

    /// The lights.
    #[must_use]
    pub fn lights(&self) -> Vec<Light> {
        self.spherical
            .iter()
            .map(|&(a, e, distance)| {
                let dir = DVec3::new(a.cos() * e.cos(), e.sin(), a.sin() * e.cos());
                match self.kind {
                    LightKind::Point => Light::point(self.centre + dir * distance),
                    LightKind::Directional => Light::directional(-dir),
                }
            })
            .collect()
    }
}
