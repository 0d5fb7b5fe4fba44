//! Shared by the renderer tests: a device from the system's adapter (or a
//! skip), and small scenes and views.
#![allow(dead_code)]

use glam::{DVec3, UVec2};
use lixel::mesh::{ProceduralScene, Scene};
use lixel::render::Gpu;
use lixel::{Camera, Light, LightMatrix, Parameterization, ShadowMapSize, ShadowProblem};

/// A device and queue from [`Gpu::open`] (Vulkan, else GL; `WGPU_BACKEND`
/// when set), or `None` (test skipped) when there is no adapter.
///
/// # Panics
/// With `CI=true` a missing adapter is a failure, not a skip.
pub fn gpu() -> Option<(wgpu::Device, wgpu::Queue)> {
    gpu_on(None).map(|g| (g.device, g.queue))
}

/// A device on `backends` (`None`: as [`gpu`]), or `None` (skipped) when
/// there is no such adapter; with `CI=true` a missing adapter fails. With
/// `backends: None` and `LIXEL_EXPECT_BACKEND` set (`vulkan`, `gl`), the
/// adapter must be on that backend.
pub fn gpu_on(backends: Option<wgpu::Backends>) -> Option<Gpu> {
    match Gpu::open(backends, "lixel test device") {
        Ok(gpu) => {
            // `.ci/run` sets this for its GL run so that a Vulkan adapter
            // found by mistake cannot pass for GL.
            if let (None, Ok(expected)) = (backends, std::env::var("LIXEL_EXPECT_BACKEND")) {
                assert_eq!(gpu.info.backend.to_string(), expected, "adapter {}", gpu.describe());
            }
            Some(gpu)
        }
        Err(e) => {
            let ci = std::env::var("CI").is_ok_and(|v| v == "true" || v == "1");
            assert!(!ci, "CI=true but {e}");
            eprintln!("skipping: {e}");
            None
        }
    }
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
