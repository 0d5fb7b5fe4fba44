//! The built-in test scene: a floor with a few dozen objects on or near it,
//! like the scene of Chong & Gortler's experiments (1,137,772 triangles).
//!
//! The layout is deterministic (a seeded jittered grid) and independent of
//! the triangle budget, so every preset shows the same shapes, only more or
//! less finely tessellated.

use glam::{Affine3A, Quat, Vec3};

use super::{primitives, Role, Scene, SceneObject};

/// Parameters of the procedural scene.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProceduralScene {
    /// Total triangle budget, floor included. The scene uses at most this
    /// many and usually within a few percent of it.
    pub triangle_budget: usize,
    /// Objects per side of the jittered grid (`objects_per_side²` objects).
    pub objects_per_side: u32,
    /// Side length of the square floor, centred at the origin in `y = 0`.
    pub floor_size: f32,
    /// Seed of the layout.
    pub seed: u64,
}

impl Default for ProceduralScene {
    /// The paper-sized scene: 36 objects, about 1.1 million triangles.
    fn default() -> Self {
        Self { triangle_budget: 1_137_772, objects_per_side: 6, floor_size: 80.0, seed: 2006 }
    }
}

impl ProceduralScene {
    /// A few thousand triangles: for tests on software rasterizers.
    #[must_use]
    pub fn tiny() -> Self {
        Self { triangle_budget: 4_000, objects_per_side: 3, ..Self::default() }
    }

    /// About fifty thousand triangles, the full layout: quick examples.
    #[must_use]
    pub fn small() -> Self {
        Self { triangle_budget: 50_000, ..Self::default() }
    }

    /// Builds the scene.
    #[must_use]
    pub fn build(&self) -> Scene {
        let mut rng = SplitMix64(self.seed);
        let n = self.objects_per_side.max(1);
        let count = (n * n) as usize;
        // The floor gets a small, fixed share: it is flat and needs few triangles.
        let floor_budget = (self.triangle_budget / 50).clamp(2, 20_000);
        let per_object = (self.triangle_budget.saturating_sub(floor_budget) / count).max(24);
        let mut objects = vec![SceneObject {
            name: "floor".into(),
            mesh: primitives::floor(self.floor_size, floor_budget),
            role: Role::Receiver,
            albedo: Vec3::new(0.75, 0.72, 0.66),
        }];
        // Objects fill the middle 75% of the floor, so that shadows of
        // objects near the edge still land on it for most light directions.
        let extent = 0.75 * self.floor_size;
        let cell = extent / n as f32;
        for k in 0..count {
            let (i, j) = (k as u32 % n, k as u32 / n);
            let jitter = Vec3::new(rng.range(-0.25, 0.25), 0.0, rng.range(-0.25, 0.25)) * cell;
            let centre =
                Vec3::new(-0.5 * extent + (i as f32 + 0.5) * cell, 0.0, -0.5 * extent + (j as f32 + 0.5) * cell)
                    + jitter;
            let size = cell * rng.range(0.18, 0.32);
            let spin = Quat::from_rotation_y(rng.range(0.0, std::f32::consts::TAU));
            // Every fifth object floats: its shadow is detached from it.
            let lift = if k % 5 == 2 { size * rng.range(0.8, 1.6) } else { 0.0 };
            let (name, mesh, rest_height) = match k % 4 {
                0 => ("sphere", primitives::sphere(size, per_object), size),
                1 => {
                    let half = Vec3::new(size, size * rng.range(0.6, 2.2), size * rng.range(0.5, 1.0));
                    ("box", primitives::cuboid(half, per_object), half.y)
                }
                2 => {
                    let tilt = Quat::from_rotation_x(rng.range(0.0, 1.2));
                    let minor = 0.3 * size;
                    let mesh = primitives::torus(size, minor, per_object).transformed(&Affine3A::from_quat(tilt));
                    // Rest on the lowest point of the tilted torus.
                    let low = mesh.positions.iter().map(|p| p.y).fold(f32::INFINITY, f32::min);
                    ("torus", mesh, -low)
                }
                _ => {
                    let half_height = size * rng.range(0.8, 2.5);
                    ("cylinder", primitives::cylinder(0.6 * size, half_height, per_object), half_height)
                }
            };
            let place = Affine3A::from_rotation_translation(spin, centre + Vec3::Y * (rest_height + lift));
            objects.push(SceneObject {
                name: format!("{name} {k}"),
                mesh: mesh.transformed(&place),
                role: Role::CasterAndReceiver,
                albedo: palette(k),
            });
        }
        Scene { objects }
    }
}

/// A built-in scene at the default budget.
#[must_use]
pub fn default_scene() -> Scene {
    ProceduralScene::default().build()
}

/// Muted, distinguishable colours.
fn palette(k: usize) -> Vec3 {
    const COLOURS: [[f32; 3]; 6] = [
        [0.80, 0.36, 0.30],
        [0.32, 0.55, 0.78],
        [0.45, 0.70, 0.38],
        [0.86, 0.72, 0.30],
        [0.62, 0.42, 0.72],
        [0.35, 0.70, 0.70],
    ];
    Vec3::from_array(COLOURS[k % COLOURS.len()])
}

/// Sebastiano Vigna's SplitMix64: a tiny deterministic generator, enough for
/// a layout (no dependency on `rand` in the library).
struct SplitMix64(u64);

impl SplitMix64 {
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Uniform in `[lo, hi)`.
    fn range(&mut self, lo: f32, hi: f32) -> f32 {
        // Top 24 bits: exactly representable in f32.
        let unit = (self.next_u64() >> 40) as f32 / (1u64 << 24) as f32;
        lo + (hi - lo) * unit
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_hit_their_budgets_and_stay_on_the_floor() {
        for preset in [ProceduralScene::tiny(), ProceduralScene::small()] {
            let scene = preset.build();
            scene.validate().unwrap();
            let tris = scene.triangle_count();
            assert!(tris <= preset.triangle_budget && tris * 10 >= preset.triangle_budget * 6, "{tris}");
            let bounds = scene.bounds();
            assert!(bounds.casters.min.y >= -1e-4, "objects below the floor: {:?}", bounds.casters);
            assert!(bounds.receivers.max.x <= f64::from(preset.floor_size) / 2.0 + 1e-4);
            assert_eq!(bounds.receivers.min.y, 0.0);
        }
    }

    #[test]
    fn default_budget_is_paper_sized() {
        // Only counts: building 1.1M triangles takes a moment in debug.
        let preset = ProceduralScene::default();
        assert!((1_000_000..=1_200_000).contains(&preset.triangle_budget));
        assert_eq!(preset.objects_per_side.pow(2), 36);
    }
}
