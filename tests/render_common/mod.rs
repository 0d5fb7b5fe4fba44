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

/// Reference images live here.
pub const REFERENCE_DIR: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/reference");

/// Compares `actual` with `tests/reference/{name}.png`: a pixel differs when
/// any channel differs by more than `channel_tolerance`; the test fails when
/// more than `max_differing` of the pixels differ (software rasterizers of
/// different versions disagree on a few edge pixels). On mismatch it writes
/// `{name}-actual.png` and `{name}-difference.png` next to the test binary's
/// temporary directory and says where. A missing reference is written from
/// `actual` (to review and commit) and the test fails.
pub fn assert_matches_reference(name: &str, actual: &image::RgbaImage, channel_tolerance: u8, max_differing: f64) {
    let reference_path = std::path::Path::new(REFERENCE_DIR).join(format!("{name}.png"));
    let Ok(reference) = image::open(&reference_path) else {
        std::fs::create_dir_all(REFERENCE_DIR).unwrap();
        actual.save(&reference_path).unwrap();
        panic!("no reference image; wrote {} from this run: review it and commit it", reference_path.display());
    };
    let reference = reference.to_rgba8();
    let out_dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("reference-mismatch");
    let write_outputs = |difference: &image::RgbaImage| {
        std::fs::create_dir_all(&out_dir).unwrap();
        actual.save(out_dir.join(format!("{name}-actual.png"))).unwrap();
        difference.save(out_dir.join(format!("{name}-difference.png"))).unwrap();
    };
    if reference.dimensions() != actual.dimensions() {
        write_outputs(actual);
        panic!(
            "{name}: size {:?} != reference {:?}; see {}",
            actual.dimensions(),
            reference.dimensions(),
            out_dir.display()
        );
    }
    let mut differing = 0usize;
    let difference = image::RgbaImage::from_fn(actual.width(), actual.height(), |x, y| {
        let (a, r) = (actual.get_pixel(x, y).0, reference.get_pixel(x, y).0);
        let delta = (0..4).map(|c| a[c].abs_diff(r[c])).max().unwrap_or(0);
        if delta > channel_tolerance {
            differing += 1;
            image::Rgba([255, 0, 0, 255])
        } else {
            // Amplified sub-tolerance differences, in grey.
            let g = delta.saturating_mul(16);
            image::Rgba([g, g, g, 255])
        }
    });
    let fraction = differing as f64 / f64::from(actual.width() * actual.height());
    if fraction > max_differing {
        write_outputs(&difference);
        panic!(
            "{name}: {differing} pixels ({:.3}%) differ by more than {channel_tolerance} (allowed {:.3}%); see {}",
            100.0 * fraction,
            100.0 * max_differing,
            out_dir.display()
        );
    }
}
