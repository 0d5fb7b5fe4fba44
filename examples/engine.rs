//! An engine's frame loop calling lixel — written the way an engine developer
//! would wire it in, with the engine's own conventions, through lixel's public
//! API only. Headless and solver-only (no renderer, no GPU):
//!
//! ```text
//! cargo run --example engine --no-default-features
//! ```
//!
//! The "engine" here is a toy with the conventions of a modern one:
//!
//! * **reverse-Z with an infinite far plane** (Bevy, Unreal, Godot 4.3+):
//!   glam's `perspective_infinite_reverse`, depth 1 at the near plane and 0 at
//!   infinity, depth test `Greater`, depth buffer cleared to 0;
//! * **TAA jitter**: every frame the projection is shifted by a sub-pixel
//!   Halton(2, 3) offset;
//! * **its own readback layout**: rows bottom-up (as `glReadPixels` returns
//!   them), reverse-Z depth values, a quarter-resolution analysis pass;
//! * a reverse-Z shadow pass, so the light matrix must come back in that
//!   convention too.
//!
//! Its "GPU" is a ray caster over a floor and a box (`EngineScene` below),
//! standing in for the analysis pass an engine already has: depth, one
//! shadow bit per light, normals.

use glam::{dcamera, DMat4, DVec2, DVec3, DVec4, UVec2};
use lixel::conventions::{DepthCompare, ShadowPassConvention};
use lixel::optimize::{Readback, ReadbackDepth, ReadbackLayout, RowOrder, SampleOptions};
use lixel::{
    optimize_light_matrix, Aabb, Camera, Light, LightMatrix, Samples, SceneBounds, ShadowMapSize, ShadowProblem,
};

fn main() -> Result<(), lixel::LixelError> {
    let viewport = UVec2::new(1280, 720); // the engine's full-resolution target
    let analysis = UVec2::new(160, 90); // its low-resolution analysis pass
    let scene = EngineScene::default();
    let sun = Light::directional(DVec3::new(0.5, -1.0, 0.35));
    // What may cast or receive shadows, in world units. Always finite, even
    // though the camera's far plane is not: lixel cuts the view there.
    let bounds = SceneBounds {
        casters: Aabb::from_corners(DVec3::new(-30.0, 0.0, -30.0), DVec3::new(30.0, 2.0, 30.0)),
        receivers: Aabb::from_corners(DVec3::new(-30.0, 0.0, -30.0), DVec3::new(30.0, 2.0, 30.0)),
    };
    let map = ShadowMapSize::square(2048);

    // The previous frame's light matrix: lixel starts from it and keeps it
    // when the new one is not clearly better (no popping between frames).
    let mut previous: Option<LightMatrix> = None;

    for frame in 0..8u32 {
        // 1. The engine's own camera matrices, exactly as it renders with them.
        let eye = DVec3::new(-2.0 + 0.4 * f64::from(frame), 1.7, 6.0);
        let view = dcamera::rh::view::look_at_mat4(eye, DVec3::new(0.0, 0.5, -5.0), DVec3::Y);
        let aspect = f64::from(viewport.x) / f64::from(viewport.y);
        let unjittered = dcamera::rh::proj::directx::perspective_infinite_reverse(1.0, aspect, 0.1);
        // TAA: shift the projection by a sub-pixel offset (in NDC: 2 px / size).
        let jitter = DVec2::new(halton(frame + 1, 2) - 0.5, halton(frame + 1, 3) - 0.5);
        let shift = 2.0 * jitter / viewport.as_dvec2();
        let proj = DMat4::from_translation(shift.extend(0.0)) * unjittered;

        // 2. Hand lixel the matrices as they are. It reads the conventions
        //    (reverse-Z, infinite far, jittered, right-handed) by itself.
        let camera = Camera::from_matrices(view, proj, viewport)?;
        if frame == 0 {
            let c = camera.conventions();
            println!(
                "camera read as: {:?}, depth {:?}, clip depth {:?} ({:?}), infinite far: {}, {:?}, near {}",
                c.projection,
                c.depth,
                c.clip_depth,
                c.clip_depth_inferred,
                c.infinite_far,
                c.centring,
                camera.z_near()
            );
        }

        // 3. The engine's analysis pass, read back in its own layout.
        let pass = scene.analysis_pass(view, proj, sun, analysis);
        let readback = Readback {
            width: analysis.x,
            height: analysis.y,
            depth: &pass.depth,
            shadow_bits: &pass.shadow_bits,
            normals: Some(&pass.normals),
            layout: ReadbackLayout {
                depth: ReadbackDepth::WindowReversed, // reverse-Z values, 0 = nothing drawn
                rows: RowOrder::BottomUp,             // row 0 is the bottom of the screen
                rect: None,                           // the whole viewport
            },
        };

        // 4. One shadow problem per light per frame; samples from the readback
        //    (bit 0 = this light), then the optimizer.
        let problem = ShadowProblem::new(camera, sun, bounds, map)?;
        let samples = Samples::from_readback(&problem, &readback, 0, &SampleOptions::default())?;
        let optimized = optimize_light_matrix(&samples, previous.as_ref())?;

        // 5. Back to the engine's convention for its reverse-Z shadow pass:
        //    upload `clip_from_world_f32()`, clear the shadow map to 0, test
        //    with `depth_compare`; in the lighting shader project with
        //    `texel_from_world` and compare the stored depth the same way.
        let engine = optimized.matrix.in_convention(ShadowPassConvention::REVERSE_Z);
        assert_eq!(engine.depth_compare, DepthCompare::Greater);
        let _upload: glam::Mat4 = engine.clip_from_world_f32();

        // Every shadowed point the engine sees lands in the map: check a few.
        let covered = pass.shadowed_points.iter().filter(|p| optimized.matrix.covers(**p, 1e-6)).count();
        println!(
            "frame {frame}: jitter ({:+.2}, {:+.2}) px, {} boundary samples, accepted {}, shadowed points in map {}/{}",
            jitter.x,
            jitter.y,
            samples.boundary().len(),
            optimized.report.accepted,
            covered,
            pass.shadowed_points.len()
        );
        previous = Some(optimized.matrix);
    }
    Ok(())
}

/// The `index`-th element of the Halton sequence in `base`, in `[0, 1)`.
fn halton(mut index: u32, base: u32) -> f64 {
    let (mut result, mut f) = (0.0, 1.0);
    while index > 0 {
        f /= f64::from(base);
        result += f * f64::from(index % base);
        index /= base;
    }
    result
}

/// The toy engine's world: a floor and a box. Stands in for its renderer.
struct EngineScene {
    floor_half: f64,
    block: (DVec3, DVec3),
}

impl Default for EngineScene {
    fn default() -> Self {
        Self { floor_half: 30.0, block: (DVec3::new(-1.0, 0.0, -6.0), DVec3::new(1.0, 2.0, -4.0)) }
    }
}

/// What the engine's analysis pass produces, in the engine's layout.
struct AnalysisPass {
    depth: Vec<f32>,
    shadow_bits: Vec<u32>,
    normals: Vec<[f32; 3]>,
    /// World positions of shadowed pixels (for the example's own check).
    shadowed_points: Vec<DVec3>,
}

impl EngineScene {
    /// Nearest hit `(t, normal)` along `origin + t·dir`, `t > 1e-6`.
    fn hit(&self, origin: DVec3, dir: DVec3) -> Option<(f64, DVec3)> {
        let mut best: Option<(f64, DVec3)> = None;
        if dir.y < 0.0 {
            let t = -origin.y / dir.y;
            let p = origin + dir * t;
            if p.x.abs() <= self.floor_half && p.z.abs() <= self.floor_half {
                best = Some((t, DVec3::Y));
            }
        }
        // Slab test against the box.
        let (lo, hi) = self.block;
        let inv = dir.recip();
        let (a, b) = ((lo - origin) * inv, (hi - origin) * inv);
        let (near, far) = (a.min(b), a.max(b));
        let (t0, t1) = (near.max_element(), far.min_element());
        if t0 <= t1 && t0 > 1e-6 && best.is_none_or(|(t, _)| t0 < t) {
            let axis = if near.x == t0 {
                DVec3::X
            } else if near.y == t0 {
                DVec3::Y
            } else {
                DVec3::Z
            };
            best = Some((t0, -axis * dir.dot(axis).signum()));
        }
        best
    }

    /// Ray-casts the analysis pass: rows bottom-up, reverse-Z depth (cleared
    /// to 0), shadow bit 0 for `sun`, world normals.
    fn analysis_pass(&self, view: DMat4, proj: DMat4, sun: Light, size: UVec2) -> AnalysisPass {
        let clip_from_world = proj * view;
        let world_from_clip = clip_from_world.inverse();
        let Light::Directional { direction } = sun else { unreachable!("the example's sun is directional") };
        let n = (size.x * size.y) as usize;
        let mut pass = AnalysisPass {
            depth: vec![0.0; n],
            shadow_bits: vec![0; n],
            normals: vec![[0.0; 3]; n],
            shadowed_points: Vec::new(),
        };
        for row in 0..size.y {
            for x in 0..size.x {
                // Row 0 is the bottom: NDC y grows with the row index.
                let ndc = (DVec2::new(f64::from(x), f64::from(row)) + 0.5) / size.as_dvec2() * 2.0 - 1.0;
                let near = world_from_clip.project_point3(ndc.extend(1.0)); // reverse-Z: near is 1
                let mid = world_from_clip.project_point3(ndc.extend(0.5));
                let Some((t, normal)) = self.hit(near, (mid - near).normalize()) else { continue };
                let p = near + (mid - near).normalize() * t;
                let clip = clip_from_world * DVec4::from((p, 1.0));
                let i = (row * size.x + x) as usize;
                pass.depth[i] = (clip.z / clip.w) as f32;
                pass.normals[i] = normal.as_vec3().to_array();
                let lit_side = normal.dot(-direction) > 0.0;
                if !lit_side || self.hit(p + normal * 1e-6, -direction).is_some() {
                    pass.shadow_bits[i] = 1;
                    pass.shadowed_points.push(p);
                }
            }
        }
        pass
    }
}
