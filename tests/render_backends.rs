//! The Vulkan (lavapipe) and GL (llvmpipe through EGL) backends give the
//! same masks and the same experiment counts, within a stated tolerance:
//! the two drivers rasterize a few edge pixels differently, nothing more.
//! Skipped when either backend has no adapter (a failure under `CI=true`).
#![cfg(feature = "cli")]

#[path = "render_common/mod.rs"]
mod render_common;

use lixel::experiment::{self, ExperimentConfig, Preset, Truth};
use lixel::render::{Frame, Gpu, Renderer, RendererOptions};
use lixel::Parameterization;

/// Pixels (of all counted ones) on which the two backends may disagree.
const MAX_DISAGREEMENT: f64 = 0.002;
/// Depth difference of a shadow-map texel that counts as disagreement
/// (the drivers interpolate depth with different rounding).
const MAX_DEPTH_DIFFERENCE: f32 = 1e-5;

/// Texels on a caster silhouette (a depth jump to a 4-neighbour) where the
/// drivers' coverage rules may pick the other surface; strongly warped maps
/// (PSM) have long silhouettes of thin texels. Limit on those, of all texels.
const MAX_EDGE_DISAGREEMENT: f64 = 0.01;
/// Depth step between neighbouring texels that marks a silhouette.
const EDGE_JUMP: f32 = 1e-3;

fn on_edge(map: &lixel::render::DepthImage, i: usize) -> bool {
    let (w, h) = (map.width as usize, map.height as usize);
    let (x, y) = (i % w, i / w);
    let d = map.depth[i];
    let near = |nx: usize, ny: usize| (map.depth[ny * w + nx] - d).abs() > EDGE_JUMP;
    (x > 0 && near(x - 1, y))
        || (x + 1 < w && near(x + 1, y))
        || (y > 0 && near(x, y - 1))
        || (y + 1 < h && near(x, y + 1))
}

fn both() -> Option<(Gpu, Gpu)> {
    let vulkan = render_common::gpu_on(Some(wgpu::Backends::VULKAN))?;
    let gl = render_common::gpu_on(Some(wgpu::Backends::GL))?;
    assert_eq!(vulkan.info.backend, wgpu::Backend::Vulkan);
    assert_eq!(gl.info.backend, wgpu::Backend::Gl);
    Some((vulkan, gl))
}

#[test]
fn vulkan_and_gl_masks_agree() {
    let Some((vulkan, gl)) = both() else { return };
    let scene = render_common::tiny_scene();
    let camera = render_common::walkthrough_camera(256);
    let lights = render_common::test_lights();
    let renderer = |gpu: &Gpu| Renderer::new(&gpu.device, &gpu.queue, &scene, RendererOptions::default()).unwrap();
    let (mut a, mut b) = (renderer(&vulkan), renderer(&gl));
    for parameterization in Parameterization::ALL_DEFAULT {
        let matrices = render_common::matrices(&scene, &camera, &lights, 512, &parameterization);
        let masks = |r: &mut Renderer| {
            r.render(&Frame {
                camera: &camera,
                lights: &matrices,
                masks: true,
                analysis: None,
                lookup: Default::default(),
            })
            .unwrap();
            r.read_masks().unwrap()
        };
        let (ma, mb) = (masks(&mut a), masks(&mut b));
        let pixels = ma.depth.len();
        let differing = (0..pixels)
            .filter(|&i| ma.visible(i) != mb.visible(i) || ma.shadow[i] != mb.shadow[i] || ma.facing[i] != mb.facing[i])
            .count();
        let visible = (0..pixels).filter(|&i| ma.visible(i)).count();
        let shadowed = (0..pixels).filter(|&i| ma.shadow[i] != 0).count();
        let name = parameterization.method().name();
        eprintln!("{name}: {differing} of {pixels} pixels differ ({visible} visible, {shadowed} in some shadow)");
        assert!(visible > pixels / 4 && shadowed > pixels / 50, "{name}: a view without much to compare");
        assert!(
            differing as f64 <= MAX_DISAGREEMENT * pixels as f64,
            "{name}: {differing} of {pixels} pixels differ between Vulkan and GL"
        );
        for light in 0..matrices.len() {
            let (da, db) = (a.read_shadow_map(light).unwrap(), b.read_shadow_map(light).unwrap());
            let texels = da.depth.len();
            let delta = |(x, y): (&f32, &f32)| (x - y).abs();
            let off = |i: usize| (da.depth[i] - db.depth[i]).abs() > MAX_DEPTH_DIFFERENCE;
            let (edge, interior) = (0..texels).filter(|&i| off(i)).partition::<Vec<_>, _>(|&i| on_edge(&da, i));
            let largest = da.depth.iter().zip(&db.depth).map(delta).fold(0.0, f32::max);
            eprintln!(
                "{name} light {light}: {} of {texels} shadow-map texels differ away from depth edges, {} on edges \
                 (largest difference {largest:e})",
                interior.len(),
                edge.len()
            );
            assert!(
                interior.len() as f64 <= MAX_DISAGREEMENT * texels as f64,
                "{name} light {light}: {} texels away from depth edges differ",
                interior.len()
            );
            assert!(
                edge.len() as f64 <= MAX_EDGE_DISAGREEMENT * texels as f64,
                "{name} light {light}: {} edge texels differ",
                edge.len()
            );
        }
    }
}

#[test]
fn vulkan_and_gl_experiment_counts_agree() {
    let Some((vulkan, gl)) = both() else { return };
    let dir = std::env::temp_dir().join(format!("lixel-backends-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let config = |name: &str| ExperimentConfig {
        out: dir.join(name),
        configs: 3,
        equivalence_configs: 0,
        truth: Truth::RayCast,
        ..ExperimentConfig::preset(Preset::Quick)
    };
    let a = experiment::run(&config("vulkan"), &vulkan.device, &vulkan.queue, &mut |_| {}).unwrap();
    let b = experiment::run(&config("gl"), &gl.device, &gl.queue, &mut |_| {}).unwrap();
    let c = config("vulkan");
    let pixels = f64::from(c.screen) * f64::from(c.screen);
    for (ma, mb) in a.methods.iter().zip(&b.methods) {
        assert_eq!(ma.method, mb.method);
        let delta = (ma.mean - mb.mean).abs();
        eprintln!(
            "{:<16} vulkan {:>9.1}  gl {:>9.1}  |difference| {:.1} ({:.4}% of {pixels} pixels)",
            ma.method.name(),
            ma.mean,
            mb.mean,
            delta,
            100.0 * delta / pixels
        );
        assert!(ma.mean.is_finite() && mb.mean.is_finite(), "{:?}: no counts", ma.method);
        assert!(delta <= MAX_DISAGREEMENT * pixels, "{:?}: vulkan {} vs gl {}", ma.method, ma.mean, mb.mean);
    }
    assert!(std::fs::read_to_string(dir.join("gl/report.md")).unwrap().contains("(gl)"));
    let _ = std::fs::remove_dir_all(&dir);
}
