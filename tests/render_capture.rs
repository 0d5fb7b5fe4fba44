//! A captured view (`Renderer::capture_view`) shades frames from its camera
//! with one full-screen pass; the masks must be exactly those of a drawn
//! camera pass, for every lookup mode.

#![cfg(feature = "render")]

mod render_common;

use lixel::render::{AnalysisRequest, Frame, Renderer, RendererOptions, ShadowLookup};
use lixel::Parameterization;
use render_common::*;

fn frame<'a>(
    camera: &'a lixel::Camera,
    lights: &'a [lixel::LightMatrix],
    lookup: ShadowLookup,
    analysis: bool,
) -> Frame<'a> {
    Frame { camera, lights, masks: true, analysis: analysis.then(AnalysisRequest::default), lookup }
}

#[test]
fn deferred_frames_give_the_masks_of_drawn_frames_for_every_lookup() {
    let Some((device, queue)) = gpu() else { return };
    let scene = tiny_scene();
    let options = RendererOptions { analysis_size: (48, 48), readback_slots: 2, ..Default::default() };
    let mut renderer = Renderer::new(&device, &queue, &scene, options).unwrap();
    let camera = walkthrough_camera(96);
    let lights = matrices(&scene, &camera, &test_lights(), 256, &Parameterization::Focused);

    // Drawn first, for every lookup (masks, colour, and the antialiased
    // lookup's occlusion words).
    let mut drawn = Vec::new();
    for lookup in ShadowLookup::ALL {
        let report = renderer.render(&frame(&camera, &lights, lookup, false)).unwrap();
        assert!(report.camera_triangles > 0);
        renderer.wait_for(&report.submission).unwrap();
        let occlusion = matches!(lookup, ShadowLookup::SubPixelAa(_)).then(|| renderer.read_occlusion(0).unwrap());
        drawn.push((renderer.read_masks().unwrap(), renderer.read_color().unwrap(), occlusion));
    }

    renderer.capture_view(&camera).unwrap();
    assert_eq!(renderer.captured_view(), Some(&camera));
    for (lookup, (masks, color, occlusion)) in ShadowLookup::ALL.into_iter().zip(&drawn) {
        let report = renderer.render(&frame(&camera, &lights, lookup, false)).unwrap();
        assert_eq!(report.camera_triangles, 0, "{}: the capture is shaded, not the scene drawn", lookup.name());
        renderer.wait_for(&report.submission).unwrap();
        let deferred = renderer.read_masks().unwrap();
        assert!(deferred.depth.iter().any(|&d| d < 1.0), "{}: nothing visible", lookup.name());
        assert!(deferred == *masks, "{}: deferred masks differ from the drawn pass's", lookup.name());
        if let Some(words) = occlusion {
            assert_eq!(&renderer.read_occlusion(0).unwrap(), words, "{}: occlusion words", lookup.name());
        }
        // The colour only sees the 8-bit albedo.
        let c = renderer.read_color().unwrap();
        let worst =
            c.pixels().zip(color.pixels()).flat_map(|(a, b)| (0..4).map(move |k| a.0[k].abs_diff(b.0[k]))).max();
        assert!(worst.unwrap() <= 2, "{}: colour differs by {worst:?}", lookup.name());
    }

    // The analysis pass reads what a drawn pass leaves (depth and masks).
    let mut analyses = Vec::new();
    for capture in [true, false] {
        if capture {
            renderer.capture_view(&camera).unwrap();
        } else {
            renderer.release_view();
            assert_eq!(renderer.captured_view(), None);
        }
        let report = renderer.render(&frame(&camera, &lights, ShadowLookup::DepthCompare, true)).unwrap();
        assert_eq!(report.camera_triangles == 0, capture);
        renderer.wait_idle().unwrap();
        analyses.push(renderer.try_take_analysis().expect("queued and finished").masks);
    }
    assert!(analyses[0] == analyses[1], "the analysis readback differs after a deferred camera pass");

    // Another camera is drawn, the capture kept for its own.
    renderer.capture_view(&camera).unwrap();
    let other = walkthrough_camera(80);
    let report = renderer.render(&frame(&other, &lights, ShadowLookup::DepthCompare, false)).unwrap();
    assert!(report.camera_triangles > 0);
    let report = renderer.render(&frame(&camera, &lights, ShadowLookup::DepthCompare, false)).unwrap();
    assert_eq!(report.camera_triangles, 0);
    renderer.wait_for(&report.submission).unwrap();
    assert!(renderer.read_masks().unwrap() == drawn[0].0, "the capture outlives a frame from another camera");
}
