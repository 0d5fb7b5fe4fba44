//! Reference images: the camera view, the masks and a shadow map of the
//! tiny scene (128x128, widths multiples of 64).

#![cfg(feature = "render")]

mod render_common;

use lixel::render::{masks_image, shadow_map_image, Frame, Renderer, RendererOptions};
use lixel::Parameterization;
use render_common::*;

/// A pixel may differ by 3 levels per channel; 0.5% of pixels may differ more.
const CHANNEL_TOLERANCE: u8 = 3;
const MAX_DIFFERING: f64 = 0.005;

#[test]
fn renders_match_reference_images() {
    let Some((device, queue)) = gpu() else { return };
    let scene = tiny_scene();
    let camera = walkthrough_camera(128);
    let lights = matrices(&scene, &camera, &test_lights(), 256, &Parameterization::Focused);
    let mut renderer = Renderer::new(&device, &queue, &scene, RendererOptions::default()).unwrap();
    renderer
        .render(&Frame { camera: &camera, lights: &lights, masks: true, analysis: None, lookup: Default::default() })
        .unwrap();

    assert_matches_reference("camera-focused", &renderer.read_color().unwrap(), CHANNEL_TOLERANCE, MAX_DIFFERING);
    assert_matches_reference("masks-focused", &masks_image(&renderer.read_masks().unwrap()), 0, MAX_DIFFERING);
    let map = renderer.read_shadow_map(0).unwrap();
    assert_eq!((map.width, map.height), (256, 256));
    assert_matches_reference("shadow-map-focused-sun", &shadow_map_image(&map), CHANNEL_TOLERANCE, MAX_DIFFERING);
}
