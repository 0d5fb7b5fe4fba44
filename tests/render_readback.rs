//! The analysis readback never holds up a frame.

#![cfg(feature = "render")]

mod render_common;

use lixel::mesh::RayCaster;
use lixel::optimize::{Optimizer, ScheduleOptions, ShadowScheduler};
use lixel::render::{AnalysisRequest, Frame, Renderer, RendererOptions};
use lixel::{LightMatrix, Parameterization, ShadowMapSize};
use render_common::*;

fn renderer(device: &wgpu::Device, queue: &wgpu::Queue, slots: usize) -> Renderer {
    let options = RendererOptions { analysis_size: (64, 64), readback_slots: slots, ..Default::default() };
    Renderer::new(device, queue, &tiny_scene(), options).unwrap()
}

/// While an analysis readback is pending, later frames are still rendered
/// and submitted; the data arrives frames later with its latency measured.
#[test]
fn frames_keep_submitting_while_a_readback_is_pending() {
    let Some((device, queue)) = gpu() else { return };
    let mut renderer = renderer(&device, &queue, 2);
    let scene = tiny_scene();
    let camera = walkthrough_camera(128);
    let lights = matrices(&scene, &camera, &test_lights(), 512, &Parameterization::Focused);
    let first = renderer
        .render(&Frame {
            camera: &camera,
            lights: &lights,
            masks: false,
            analysis: Some(AnalysisRequest::default()),
            lookup: Default::default(),
        })
        .unwrap();
    assert!(first.analysis_queued);
    for expected in 1..6 {
        assert_eq!(renderer.readback_ring().in_flight(), 1, "the readback is still pending (not taken)");
        let report = renderer
            .render(&Frame {
                camera: &camera,
                lights: &lights,
                masks: false,
                analysis: None,
                lookup: Default::default(),
            })
            .unwrap();
        assert_eq!(report.frame, expected);
    }
    renderer.wait_idle().unwrap();
    let readback = renderer.try_take_analysis().expect("the GPU finished: the data is there");
    assert_eq!(readback.frame, 0);
    assert_eq!(readback.latency.frames, 6);
    assert!(readback.latency.ready <= readback.latency.taken);
    assert_eq!(renderer.readback_ring().in_flight(), 0);
    assert!(renderer.try_take_analysis().is_none(), "each readback is handed out once");
    // The data is the analysis view: shadows agree with the ray cast.
    let truth = RayCaster::new(&scene).trace_masks(&camera, &test_lights(), 64, 64);
    for light in 0..2 {
        let agreement = truth.agreement_away_from_boundaries(&readback.masks, light, 1);
        assert!(agreement.compared > 300 && agreement.fraction() >= 0.99, "light {light}: {agreement:?}");
    }
    let centre = readback.world_point(32, 40).expect("the floor is visible there");
    assert!(centre.y.abs() < 5.0, "{centre}");
}

/// With every slot in flight, a frame skips its analysis pass instead of
/// waiting for a slot.
#[test]
fn a_full_ring_skips_analysis_instead_of_waiting() {
    let Some((device, queue)) = gpu() else { return };
    let mut renderer = renderer(&device, &queue, 2);
    let scene = tiny_scene();
    let camera = walkthrough_camera(128);
    let lights = matrices(&scene, &camera, &test_lights(), 256, &Parameterization::Focused);
    let frame = Frame {
        camera: &camera,
        lights: &lights,
        masks: false,
        analysis: Some(AnalysisRequest::default()),
        lookup: Default::default(),
    };
    let reports: Vec<_> = (0..4).map(|_| renderer.render(&frame).unwrap()).collect();
    assert!(reports[0].analysis_queued && reports[1].analysis_queued);
    assert!(reports[2].analysis_skipped && reports[3].analysis_skipped);
    assert_eq!(renderer.readback_ring().stats().refused, 2);
    renderer.wait_idle().unwrap();
    // The newest arrives; the older one is superseded and discarded.
    assert_eq!(renderer.try_take_analysis().map(|r| r.frame), Some(1));
    assert!(renderer.try_take_analysis().is_none());
    assert_eq!(renderer.readback_ring().in_flight(), 0);
}

/// A readback that never arrives leaves the previous matrices in place,
/// while frames go on; once data arrives the optimizer updates them.
#[test]
fn a_missing_readback_keeps_the_previous_matrices() {
    let Some((device, queue)) = gpu() else { return };
    let mut renderer = renderer(&device, &queue, 2);
    let scene = tiny_scene();
    let camera = walkthrough_camera(128);
    let lights = test_lights();
    let map = ShadowMapSize::square(256);
    let focused = matrices(&scene, &camera, &lights, 256, &Parameterization::Focused);
    let mut scheduler =
        ShadowScheduler::new(lights.len(), ScheduleOptions::default(), Optimizer::new(Default::default())).unwrap();
    for (light, m) in focused.iter().enumerate() {
        scheduler.set_matrix(light, *m);
    }
    let current =
        |s: &ShadowScheduler| -> Vec<LightMatrix> { (0..lights.len()).map(|i| *s.matrix(i).unwrap()).collect() };
    for _ in 0..9 {
        let lights_now = current(&scheduler);
        let frame = Frame {
            camera: &camera,
            lights: &lights_now,
            masks: false,
            analysis: Some(AnalysisRequest::default()),
            lookup: Default::default(),
        };
        renderer.render(&frame).unwrap();
        // The readback never arrives: nothing is taken, nothing updated.
        assert_eq!(current(&scheduler), focused);
        assert!((0..lights.len()).all(|i| scheduler.optimized_frame(i).is_none()));
    }
    assert_eq!(renderer.next_frame(), 9);
    renderer.wait_idle().unwrap();
    let readback = renderer.try_take_analysis().expect("the readback arrives once the device is idle");
    for (i, light) in lights.iter().enumerate() {
        let samples = readback.samples(*light, scene.bounds(), map, i as u32).unwrap();
        scheduler.update(i, &samples, 9).unwrap();
        assert_eq!(scheduler.optimized_frame(i), Some(9));
    }
}
