//! The renderer's shadow bits agree with an exact CPU ray cast.

#![cfg(feature = "render")]

mod render_common;

use lixel::mesh::RayCaster;
use lixel::render::{Frame, Renderer, RendererOptions};
use lixel::Parameterization;
use render_common::*;

/// Shadow bits (full-resolution masks and the analysis readback) match the
/// ray-traced truth on at least 99% of pixels away from shadow boundaries,
/// for a directional and a point light, with focused and LiSPSM maps.
#[test]
fn shadow_bits_agree_with_ray_cast() {
    let Some((device, queue)) = gpu() else { return };
    let scene = tiny_scene();
    let camera = walkthrough_camera(128);
    let lights = test_lights();
    let caster = RayCaster::new(&scene);
    let truth = caster.trace_masks(&camera, &lights, 128, 128);
    let mut renderer = Renderer::new(&device, &queue, &scene, RendererOptions::default()).unwrap();
    for parameterization in [Parameterization::Focused, Parameterization::LiSpsm(Default::default())] {
        let matrices = matrices(&scene, &camera, &lights, 1024, &parameterization);
        renderer.render(&Frame { camera: &camera, lights: &matrices, masks: true, analysis: None }).unwrap();
        let gpu = renderer.read_masks().unwrap();
        for light in 0..lights.len() as u32 {
            let agreement = truth.agreement_away_from_boundaries(&gpu, light, 1);
            eprintln!("{parameterization:?} light {light}: {agreement:?} = {:.4}", agreement.fraction());
            assert!(agreement.compared > 2000, "too few pixels compared: {agreement:?}");
            assert!(agreement.fraction() >= 0.99, "{parameterization:?} light {light}: {agreement:?}");
            assert!(truth.shadowed_count(light) > 100, "the view shows shadows of light {light}");
        }
    }
}
