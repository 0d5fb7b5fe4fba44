//! Shared by the renderer tests: a device from the system's adapter (or a
//! skip), and small scenes and views.
#![allow(dead_code)]

use glam::{DVec3, UVec2};
use lixel::mesh::{ProceduralScene, Scene};
use lixel::render::Renderer;
use lixel::{Camera, Light, LightMatrix, Parameterization, ShadowMapSize, ShadowProblem};

/// A device and queue with the renderer's optional features where the
/// adapter has them, or `None` (test skipped) when there is no adapter.
///
/// # Panics
/// With `CI=true` a missing adapter is a failure, not a skip: CI installs
/// lavapipe (`mesa-vulkan-drivers`), so no adapter means a broken setup.
pub fn gpu() -> Option<(wgpu::Device, wgpu::Queue)> {
    let instance = wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
    let adapter = match pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions::default())) {
        Ok(adapter) => adapter,
        Err(e) => {
            let ci = std::env::var("CI").is_ok_and(|v| v == "true" || v == "1");
            assert!(!ci, "CI=true but no GPU adapter ({e}); install mesa-vulkan-drivers");
            eprintln!("skipping: no GPU adapter ({e}); install mesa-vulkan-drivers for lavapipe");
            return None;
        }
    };
    let required_features = adapter.features() & Renderer::optional_features();
    let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
        label: Some("lixel test device"),
        required_features,
        required_limits: wgpu::Limits::default(),
        ..Default::default()
    }))
    .expect("the adapter offers a device with default limits");
    Some((device, queue))
}

/// The tiny procedural scene (a few thousand triangles).
pub fn tiny_scene() -> Scene {
    ProceduralScene::tiny().build()
}

/// A viewer a little above the floor looking across the objects, at
/// `size x size` pixels.
pub fn walkthrough_camera(size: u32) -> Camera {
    Camera::look_at(
        DVec3::new(4.0, 5.0, 34.0),
        DVec3::new(0.0, 0.0, 0.0),
        DVec3::Y,
        55f64.to_radians(),
        UVec2::splat(size),
        0.5,
        150.0,
    )
    .expect("valid camera")
}

/// A low sun and a point light above the scene.
pub fn test_lights() -> Vec<Light> {
    vec![Light::directional(DVec3::new(0.6, -1.0, 0.35)), Light::point(DVec3::new(-8.0, 30.0, 12.0))]
}

/// One matrix per light for the scene and camera.
pub fn matrices(
    scene: &Scene,
    camera: &Camera,
    lights: &[Light],
    map: u32,
    parameterization: &Parameterization,
) -> Vec<LightMatrix> {
    lights
        .iter()
        .map(|light| {
            ShadowProblem::new(*camera, *light, scene.bounds(), ShadowMapSize::square(map))
                .and_then(|p| p.solve(parameterization))
                .expect("solvable configuration")
        })
        .collect()
}
