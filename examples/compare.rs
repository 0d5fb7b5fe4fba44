//! The paper's Figure 4: one configuration rendered with every method at the
//! same shadow-map resolution, side by side, with each method's shadow map
//! and its misclassified pixels against an exact ray cast.
//!
//! ```text
//! cargo run --release --example compare -- [--preset tiny|small|default] [--obj file.obj]
//!     [--size 750] [--map 400] [--light k] [--out target/compare]
//! ```
//!
//! Writes `compare.png` (views, in the order printed), `maps.png` (shadow
//! maps), `masks.png` (shadow bits: light 0 red), one PNG per method, and
//! prints the misclassified-pixel counts (the paper's Table 1 measure).

#[path = "support/mod.rs"]
mod support;

use std::path::PathBuf;

use glam::UVec2;
use lixel::mesh::RayCaster;
use lixel::render::{
    masks_image, shadow_map_image, Frame, LoopOptions, LoopPolicy, LoopView, Renderer, RendererOptions, ShadowLoop,
};
use lixel::{LightMatrix, Parameterization, ShadowMapSize, ShadowProblem};

fn main() {
    if let Err(e) = run() {
        eprintln!("compare: {e}");
        std::process::exit(1);
    }
}

fn run() -> Result<(), String> {
    let args = support::Args::from_env();
    let scene = support::scene(args.value("--preset").unwrap_or("default"), args.value("--obj"))?;
    let size: u32 = args.parse("--size", 750)?;
    let map: u32 = args.parse("--map", 400)?;
    let light_index: usize = args.parse("--light", 137)?;
    let out = PathBuf::from(args.value("--out").unwrap_or("target/compare"));
    std::fs::create_dir_all(&out).map_err(|e| format!("{}: {e}", out.display()))?;

    let (device, queue, info) = support::gpu()?;
    eprintln!("adapter: {} ({:?}); {} triangles", info.name, info.backend, scene.triangle_count());
    let camera = support::walk_camera(0.1, UVec2::splat(size));
    let light = support::hemisphere_light(light_index, 500);
    let problem =
        ShadowProblem::new(camera, light, scene.bounds(), ShadowMapSize::square(map)).map_err(|e| e.to_string())?;

    // The methods of Figure 4, in order.
    let mut methods: Vec<(&str, LightMatrix)> = Vec::new();
    for parameterization in Parameterization::ALL_DEFAULT {
        match problem.solve(&parameterization) {
            Ok(m) => methods.push((parameterization.method().name(), m)),
            Err(e) => eprintln!("{}: {e}", parameterization.method().name()),
        }
    }

    let truth = RayCaster::new(&scene).trace_masks(&camera, &[light], size, size);
    let mut renderer = Renderer::new(&device, &queue, &scene, RendererOptions::default()).map_err(|e| e.to_string())?;
    // Scene-optimized: the frame loop at this fixed view, from the focused
    // map, until the optimizer keeps its previous matrix (at most 12 frames).
    let view = LoopView {
        camera: &camera,
        lights: std::slice::from_ref(&light),
        bounds: scene.bounds(),
        map: problem.map_size(),
    };
    let mut shadows = ShadowLoop::new(LoopPolicy::Optimized, 1, LoopOptions::default()).map_err(|e| e.to_string())?;
    let optimized = shadows.settle(&mut renderer, &view, 12).map_err(|e| e.to_string())?.matrices[0];
    methods.push(("optimized", optimized));
    let (mut views, mut maps, mut masks) = (Vec::new(), Vec::new(), Vec::new());
    println!("{:<16} {:>14} {:>10}", "method", "misclassified", "fallback");
    for (name, matrix) in &methods {
        renderer
            .render(&Frame {
                camera: &camera,
                lights: std::slice::from_ref(matrix),
                masks: true,
                analysis: None,
                lookup: Default::default(),
            })
            .map_err(|e| e.to_string())?;
        let view = renderer.read_color().map_err(|e| e.to_string())?;
        let gpu_masks = renderer.read_masks().map_err(|e| e.to_string())?;
        let shadow_map = renderer.read_shadow_map(0).map_err(|e| e.to_string())?;
        let wrong = gpu_masks.misclassified(&truth, 0).unwrap_or(0);
        println!("{name:<16} {wrong:>14} {:>10}", matrix.fallback.map_or("-".to_string(), |f| format!("{f:?}")));
        view.save(out.join(format!("{name}.png"))).map_err(|e| e.to_string())?;
        let map_image = shadow_map_image(&shadow_map);
        // Shadow maps are shown at the view's size so the montage lines up.
        maps.push(image::imageops::resize(&map_image, size, size, image::imageops::FilterType::Nearest));
        masks.push(masks_image(&gpu_masks));
        views.push(view);
    }
    for (file, images) in [("compare.png", &views), ("maps.png", &maps), ("masks.png", &masks)] {
        support::montage(images, 3).save(out.join(file)).map_err(|e| e.to_string())?;
    }
    println!("ray-cast truth: {} shadowed pixels; images in {}", truth.shadowed_count(0), out.display());
    Ok(())
}
