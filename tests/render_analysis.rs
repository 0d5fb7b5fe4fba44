//! The two analysis sources describe the same surface: the full-screen pass
//! over the camera's depth (the default) against drawing the scene again at
//! the analysis resolution, and both against an exact ray cast.

#![cfg(feature = "render")]

mod render_common;

use glam::{DVec3, UVec2};
use lixel::mesh::{RayCaster, Scene};
use lixel::render::{AnalysisReadback, AnalysisRequest, AnalysisSource, Frame, Renderer, RendererOptions};
use lixel::{Camera, Light, Parameterization};
use render_common::*;

/// One analysis readback of `scene` from `camera` with focused maps.
fn analysis(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    scene: &Scene,
    camera: &Camera,
    lights: &[Light],
    source: AnalysisSource,
) -> AnalysisReadback {
    let options = RendererOptions { analysis_size: (180, 180), analysis_source: source, ..Default::default() };
    let mut renderer = Renderer::new(device, queue, scene, options).unwrap();
    let matrices = matrices(scene, camera, lights, 1024, &Parameterization::Focused);
    let frame = Frame {
        camera,
        lights: &matrices,
        masks: false,
        analysis: Some(AnalysisRequest::default()),
        lookup: Default::default(),
    };
    renderer.render(&frame).unwrap();
    renderer.wait_idle().unwrap();
    renderer.try_take_analysis().expect("the device is idle: the readback is there")
}

/// Views of the tiny scene: the walkthrough camera at two screen sizes (the
/// analysis pixel's centre falls between full-resolution pixels at 512², and
/// the screen is smaller than twice the analysis at 300²), a camera looking
/// down at the floor, and one with near/far = 1/1000 (the experiment's ratio).
fn cameras() -> Vec<(&'static str, Camera)> {
    let look = |eye: DVec3, target: DVec3, size: u32, near: f64, far: f64| {
        Camera::look_at(eye, target, DVec3::Y, 55f64.to_radians(), UVec2::splat(size), near, far).unwrap()
    };
    vec![
        ("walkthrough 512", walkthrough_camera(512)),
        ("walkthrough 300", walkthrough_camera(300)),
        ("from above 512", look(DVec3::new(3.0, 30.0, 12.0), DVec3::new(0.0, 0.0, -2.0), 512, 0.5, 150.0)),
        ("near/far 1e-3", look(DVec3::new(4.0, 1.5, 34.0), DVec3::new(0.0, 0.5, 0.0), 640, 0.15, 150.0)),
    ]
}

/// Pixels whose 3x3 neighbourhood is visible in both readbacks.
fn interior(a: &AnalysisReadback, b: &AnalysisReadback) -> Vec<(u32, u32)> {
    let (w, h) = (a.masks.width, a.masks.height);
    let visible = |x: u32, y: u32| {
        let i = (y * w + x) as usize;
        a.masks.visible(i) && b.masks.visible(i)
    };
    (1..h - 1)
        .flat_map(|y| (1..w - 1).map(move |x| (x, y)))
        .filter(|&(x, y)| (y - 1..=y + 1).all(|yy| (x - 1..=x + 1).all(|xx| visible(xx, yy))))
        .collect()
}

#[test]
fn camera_depth_analysis_matches_the_geometry_pass() {
    let Some((device, queue)) = gpu() else { return };
    let scene = tiny_scene();
    let lights = test_lights();
    for (name, camera) in cameras() {
        let depth = analysis(&device, &queue, &scene, &camera, &lights, AnalysisSource::CameraDepth);
        let geometry = analysis(&device, &queue, &scene, &camera, &lights, AnalysisSource::Geometry);
        let n = (depth.masks.width * depth.masks.height) as usize;

        let visibility = (0..n).filter(|&i| depth.masks.visible(i) == geometry.masks.visible(i)).count();
        let inside = interior(&depth, &geometry);
        // Same surface point: world positions within 0.5% of the distance to the eye.
        let same_point = inside
            .iter()
            .filter(|&&(x, y)| {
                let (p, q) = (depth.world_point(x, y).unwrap(), geometry.world_point(x, y).unwrap());
                (p - q).length() <= 5e-3 * (q - camera.eye()).length()
            })
            .count();
        // Normals within 10 degrees (face normals against interpolated ones).
        let normals = inside
            .iter()
            .filter(|&&(x, y)| depth.normal(x, y).dot(geometry.normal(x, y)) >= 10f32.to_radians().cos())
            .count();
        let fraction = |count: usize, of: usize| count as f64 / of.max(1) as f64;
        println!(
            "{name}: visibility {:.4}, same point {:.4}, normals {:.4} ({} interior pixels)",
            fraction(visibility, n),
            fraction(same_point, inside.len()),
            fraction(normals, inside.len()),
            inside.len()
        );
        assert!(inside.len() > 5000, "{name}: the view shows the scene");
        assert!(fraction(visibility, n) >= 0.99, "{name}: visibility");
        assert!(fraction(same_point, inside.len()) >= 0.98, "{name}: surface points");
        assert!(fraction(normals, inside.len()) >= 0.95, "{name}: normals");
        for light in 0..lights.len() as u32 {
            let facing = inside
                .iter()
                .filter(|&&(x, y)| {
                    let i = (y * depth.masks.width + x) as usize;
                    (depth.masks.facing[i] ^ geometry.masks.facing[i]) >> light & 1 == 0
                })
                .count();
            let shadows = geometry.masks.agreement_away_from_boundaries(&depth.masks, light, 1);
            println!("  light {light}: facing {:.4}, shadow bits {shadows:?}", fraction(facing, inside.len()));
            assert!(fraction(facing, inside.len()) >= 0.98, "{name}, light {light}: facing bits");
            assert!(shadows.compared > 2000 && shadows.fraction() >= 0.99, "{name}, light {light}: {shadows:?}");
        }
    }
}

#[test]
fn camera_depth_analysis_agrees_with_ray_cast() {
    let Some((device, queue)) = gpu() else { return };
    let scene = tiny_scene();
    let lights = test_lights();
    let caster = RayCaster::new(&scene);
    for (name, camera) in cameras() {
        let readback = analysis(&device, &queue, &scene, &camera, &lights, AnalysisSource::CameraDepth);
        // The ray cast at the analysis resolution samples the same points:
        // the centres of analysis pixels scaled to the full viewport.
        let truth = caster.trace_masks(&camera, &lights, 180, 180);
        for light in 0..lights.len() as u32 {
            let agreement = truth.agreement_away_from_boundaries(&readback.masks, light, 1);
            println!("{name}, light {light}: {agreement:?}");
            assert!(agreement.compared > 2000 && agreement.fraction() >= 0.99, "{name}, light {light}: {agreement:?}");
        }
    }
}

/// Analysis matrices equal to the frame's reuse its maps (no extra shadow
/// pass); a different one gets its own map and its own bits.
#[test]
fn analysis_reuses_the_frames_maps_where_the_matrices_agree() {
    let Some((device, queue)) = gpu() else { return };
    let scene = tiny_scene();
    let camera = walkthrough_camera(256);
    let lights = test_lights();
    let shown = matrices(&scene, &camera, &lights, 1024, &Parameterization::Focused);
    let small = matrices(&scene, &camera, &lights, 200, &Parameterization::Focused);
    let options = RendererOptions { analysis_size: (128, 128), ..Default::default() };
    let mut renderer = Renderer::new(&device, &queue, &scene, options).unwrap();
    let mut run = |frame_lights: &[lixel::LightMatrix], analysis_lights: Option<&[lixel::LightMatrix]>| {
        let request = AnalysisRequest { lights: analysis_lights, tag: 0 };
        let report = renderer
            .render(&Frame {
                camera: &camera,
                lights: frame_lights,
                masks: false,
                analysis: Some(request),
                lookup: Default::default(),
            })
            .unwrap();
        renderer.wait_idle().unwrap();
        (report.shadow_passes, renderer.try_take_analysis().unwrap())
    };
    let (passes, own) = run(&shown, None);
    assert_eq!(passes, 2);
    let (passes, same) = run(&shown, Some(&shown));
    assert_eq!(passes, 2, "equal matrices reuse the frame's maps");
    assert_eq!(same.masks.shadow, own.masks.shadow);
    // Light 1 looked up in a small focused map, light 0 in the frame's.
    let mixed_lights = [shown[0], small[1]];
    let (passes, mixed) = run(&shown, Some(&mixed_lights));
    assert_eq!(passes, 3, "one extra map");
    let (_, reference) = run(&mixed_lights, None);
    let bit = |m: &AnalysisReadback, light: u32| m.masks.shadow.iter().map(|w| w >> light & 1).collect::<Vec<_>>();
    // Light 0: the camera pass's bits either way.
    assert_eq!(bit(&mixed, 0), bit(&own, 0));
    // Light 1: looked up by the analysis pass at the analysis pixel's point,
    // against the camera pass's bits at the nearest full-resolution pixel
    // when the small map is the frame's own; they differ only on boundaries.
    let (a, b) = (bit(&mixed, 1), bit(&reference, 1));
    let same = a.iter().zip(&b).filter(|(x, y)| x == y).count() as f64 / a.len() as f64;
    assert!(same >= 0.99, "light 1 agrees on {same:.4}");
    assert_ne!(bit(&mixed, 1), bit(&own, 1), "a 200² map draws different boundaries than a 1024² one");
}

/// `samples_all_into` (what `ShadowLoop` extracts with, into kept buffers)
/// gives `samples_all`'s samples, with the buffers holding another camera's
/// and another light count's samples before.
#[test]
fn samples_all_into_kept_buffers_equals_samples_all() {
    let Some((device, queue)) = gpu() else { return };
    let scene = tiny_scene();
    let lights = test_lights();
    let map = lixel::ShadowMapSize::square(1024);
    let (mut kept, mut workspace, mut bits) = (Vec::new(), lixel::optimize::SampleWorkspace::new(), Vec::new());
    for (name, camera) in cameras() {
        for count in [lights.len(), 1] {
            let lights = &lights[..count];
            let readback = analysis(&device, &queue, &scene, &camera, lights, AnalysisSource::CameraDepth);
            let fresh = readback.samples_all(lights, scene.bounds(), map);
            readback.samples_all_into(lights, scene.bounds(), map, &mut kept, &mut workspace, &mut bits).unwrap();
            let fresh: Vec<_> = fresh.into_iter().map(Result::unwrap).collect();
            assert_eq!(format!("{kept:?}"), format!("{fresh:?}"), "{name}, {count} lights");
        }
    }
}
