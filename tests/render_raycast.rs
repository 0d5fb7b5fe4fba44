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
        renderer
            .render(&Frame {
                camera: &camera,
                lights: &matrices,
                masks: true,
                analysis: None,
                lookup: Default::default(),
            })
            .unwrap();
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

/// A spot light reaches only its cone: outside it the surface is neither
/// lit nor shadowed (its facing bit is clear), in the renderer's masks, in
/// the analysis pass and in the ray cast alike.
#[test]
fn spot_cones_bound_the_lit_region() {
    let Some((device, queue)) = gpu() else { return };
    let scene = tiny_scene();
    let camera = walkthrough_camera(160);
    let position = glam::DVec3::new(-3.0, 22.0, 6.0);
    let spot = lixel::Light::spot(position, glam::DVec3::new(0.1, -1.0, -0.15), 22f64.to_radians());
    let point = lixel::Light::point(position);
    let caster = RayCaster::new(&scene);
    let truth = caster.trace_masks(&camera, &[spot, point], 160, 160);
    let options = RendererOptions { analysis_size: (160, 160), ..Default::default() };
    let mut renderer = Renderer::new(&device, &queue, &scene, options).unwrap();
    let matrices = matrices(&scene, &camera, &[spot, point], 1024, &Parameterization::Focused);
    let analysis = lixel::render::AnalysisRequest::default();
    let frame =
        Frame { camera: &camera, lights: &matrices, masks: true, analysis: Some(analysis), lookup: Default::default() };
    renderer.render(&frame).unwrap();
    renderer.wait_idle().unwrap();
    let gpu = renderer.read_masks().unwrap();
    let readback = renderer.try_take_analysis().unwrap();
    let count = |masks: &lixel::mesh::ShadowMasks, light: u32| {
        (0..masks.depth.len()).filter(|&i| masks.visible(i) && masks.facing[i] >> light & 1 == 1).count()
    };
    // The cone leaves out much of what the point light at the same place reaches.
    let (inside, all) = (count(&truth, 0), count(&truth, 1));
    assert!(inside > 1000 && (inside as f64) < 0.8 * all as f64, "cone {inside} of {all} pixels");
    for masks in [&gpu, &readback.masks] {
        let visible = (0..truth.depth.len()).filter(|&i| truth.visible(i) && masks.visible(i));
        let (mut same, mut compared) = (0, 0);
        for i in visible {
            compared += 1;
            same += usize::from((truth.facing[i] ^ masks.facing[i]) & 1 == 0);
        }
        let fraction = same as f64 / compared as f64;
        assert!(fraction >= 0.99, "spot reach agrees on {fraction:.4} of {compared} pixels");
        let shadows = truth.agreement_away_from_boundaries(masks, 0, 1);
        assert!(shadows.compared > 500 && shadows.fraction() >= 0.99, "spot shadows: {shadows:?}");
    }
}
