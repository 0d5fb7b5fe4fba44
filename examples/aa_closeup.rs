//! A close-up of thin casters' shadows (slats thinner than a shadow-map
//! texel) three ways: the standard depth compare's bit, the antialiased
//! lookup's 32-sample visibility (`ShadowLookup::SubPixelAa`), and the
//! 32-sample ray-cast coverage truth. Prints each one's mean visibility
//! error and writes the three panels side by side.
//!
//! ```text
//! cargo run --example aa_closeup -- [--out aa_closeup.png] [--size 200] [--map 128]
//! ```

#[path = "support/mod.rs"]
mod support;

use glam::{DVec3, UVec2, Vec3};
use lixel::experiment::{Coverage, VisibilityError};
use lixel::mesh::{primitives, Mesh, RayCaster, Role, Scene, SceneObject};
use lixel::render::subpixel::bitmask::visibility_of_valid;
use lixel::render::subpixel::AaSamples;
use lixel::render::{Frame, Renderer, RendererOptions, ShadowLookup};
use lixel::{Camera, Light, Parameterization, ShadowMapSize, ShadowProblem};

fn main() {
    if let Err(e) = run() {
        eprintln!("aa_closeup: {e}");
        std::process::exit(1);
    }
}

fn shifted(mut mesh: Mesh, by: Vec3) -> Mesh {
    mesh.positions.iter_mut().for_each(|p| *p += by);
    mesh
}

fn run() -> Result<(), String> {
    let args = support::Args::from_env();
    let size: u32 = args.parse("--size", 200)?;
    let map: u32 = args.parse("--map", 128)?;
    let out = args.value("--out").unwrap_or("aa_closeup.png").to_string();
    let object = |name: &str, mesh, role| SceneObject { name: name.into(), mesh, role, albedo: Vec3::splat(0.8) };
    let mut objects = vec![object("floor", primitives::floor(12.0, 2), Role::Receiver)];
    for k in 0..9 {
        // Slats 0.04 wide, 0.3 apart: about a texel wide in the focused map.
        let slat = primitives::cuboid(Vec3::new(0.02, 1.0, 0.02), 12);
        let x = -1.2 + 0.3 * k as f32;
        objects.push(object(&format!("slat {k}"), shifted(slat, Vec3::new(x, 1.0, 0.0)), Role::CasterAndReceiver));
    }
    let scene = Scene { objects };
    let camera = Camera::look_at(
        DVec3::new(0.4, 2.6, 0.9),
        DVec3::new(0.4, 0.0, -0.8),
        DVec3::Y,
        38f64.to_radians(),
        UVec2::splat(size),
        0.5,
        50.0,
    )
    .map_err(|e| e.to_string())?;
    let light = Light::directional(DVec3::new(0.25, -0.8, -0.55));
    let matrix = ShadowProblem::new(camera, light, scene.bounds(), ShadowMapSize::square(map))
        .and_then(|p| p.solve(&Parameterization::Focused))
        .map_err(|e| e.to_string())?;
    let (device, queue, _) = support::gpu()?;
    let mut renderer = Renderer::new(&device, &queue, &scene, RendererOptions::default()).map_err(|e| e.to_string())?;
    let lights = [matrix];
    let frame = Frame { masks: true, lookup: ShadowLookup::SubPixelAa(AaSamples::X32), ..Frame::new(&camera, &lights) };
    renderer.render(&frame).map_err(|e| e.to_string())?;
    let masks = renderer.read_masks().map_err(|e| e.to_string())?;
    let occlusion = renderer.read_occlusion(0).map_err(|e| e.to_string())?;
    let valid = renderer.read_validity(0).map_err(|e| e.to_string())?;
    let caster = RayCaster::new(&scene);
    let truth = caster.trace_masks(&camera, &[light], size, size);
    let coverage = Coverage::trace(&caster, &camera, &light, &truth);
    let samples = AaSamples::X32;
    let standard = VisibilityError::of_masks(&masks, &truth, &coverage, samples);
    let aa = VisibilityError::of_valid_occlusion(&occlusion, &valid, &truth, &coverage, samples);
    let mean = |e: VisibilityError| e.mean().unwrap_or(f64::NAN);
    println!("mean visibility error: standard {:.4}, aa32 {:.4}", mean(standard), mean(aa));
    // Grey levels by visibility; pixels the truth does not count are dark.
    let panel = |visibility: &dyn Fn(usize) -> Option<f64>| {
        image::RgbaImage::from_fn(size, size, |x, y| {
            let i = (y * size + x) as usize;
            let v = visibility(i).map_or(20, |v| (50.0 + 200.0 * v).round() as u8);
            image::Rgba([v, v, v, 255])
        })
    };
    let counted = |i: usize| coverage.visibility(i, samples).is_some();
    let images = [
        panel(&|i| counted(i).then(|| if masks.shadow[i] & 1 != 0 { 0.0 } else { 1.0 })),
        panel(&|i| counted(i).then(|| visibility_of_valid(occlusion[i], valid[i], samples))),
        panel(&|i| coverage.visibility(i, samples)),
    ];
    support::montage(&images, 3).save(&out).map_err(|e| e.to_string())?;
    println!("standard | +aa32 | 32-sample ray-cast truth -> {out}");
    Ok(())
}
