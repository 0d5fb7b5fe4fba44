//! Cascaded sun shadows at equal total texels: `K` cascades of `s²` texels
//! against one map of `(s·√K)²`, misclassified pixels against an exact ray
//! cast, summed over several sun directions.
//!
//! ```text
//! cargo run --release --example cascades -- [--cascades 4] [--map 1024] [--size 512]
//!     [--preset large|default] [--suns 6] [--triangles 300000] [--picture cascades.png [--picture-method csm]]
//!     [--walk FRAMES [--sun I]]
//! ```
//!
//! Methods: `focused` and `lispsm` (one map of `(s·√K)²`); the cascaded
//! ones are [`ShadowLoop`] policies ([`CascadePolicy`]) settled at the view
//! (`ShadowLoop::settle`: analysis passes until no cascade moves, at most
//! 8): `csm` (practical λ = 0.75 splits of the camera range within the
//! scene, texel-snapped focused maps), `sdsm` (log splits inside the visible
//! depth range of the analysis readback, focused maps), `sdsm-lispsm` (same
//! splits, LiSPSM maps), `optimized-cascades` (same splits, each cascade
//! scene-optimized from the readback). `--picture` tints the first sun's
//! image by cascade for one cascaded method (optimized-cascades unless
//! `--picture-method` names another). The large preset is the experiment's
//! (`lixel experiment --preset large`: [`SceneSource::Large`], its camera
//! from `experiment::camera_for`): the eye 1.7 units above a 2000-unit floor
//! with objects over 1500 units and a far plane of 1500. The experiment
//! measures the same methods (`--cascades N`); this example adds the
//! `--walk` and the `--picture`.

#[path = "support/mod.rs"]
mod support;

use glam::UVec2;
use lixel::experiment::stability::CameraPath;
use lixel::experiment::{self, ExperimentConfig, Preset, RatioEstimate, SceneSource};
use lixel::mesh::{Flicker, RayCaster, Scene, ShadowMasks};
use lixel::render::{CascadePolicy, Frame, LoopOptions, LoopPolicy, LoopView, Renderer, RendererOptions, ShadowLoop};
use lixel::{Camera, LightMatrix, Parameterization, ShadowMapSize, ShadowProblem};

fn main() {
    if let Err(e) = run() {
        eprintln!("cascades: {e}");
        std::process::exit(1);
    }
}

fn render_masks(
    renderer: &mut Renderer,
    camera: &Camera,
    matrices: &[LightMatrix],
    cascaded: bool,
) -> Result<ShadowMasks, String> {
    if !cascaded {
        renderer.set_cascades(0, None);
    }
    let frame = Frame { camera, lights: matrices, masks: true, analysis: None, lookup: Default::default() };
    renderer.render(&frame).map_err(|e| e.to_string())?;
    let masks = renderer.read_masks().map_err(|e| e.to_string())?;
    // The sun's bit from a frame whose lights are its cascades.
    Ok(if cascaded { experiment::fold_cascade_masks(&masks, &[0, matrices.len()]) } else { masks })
}

/// The last frame's picture with each pixel tinted by the cascade that
/// shaded it (its facing bit): red, green, blue, yellow, ...
fn picture(renderer: &Renderer, path: &str) -> Result<(), String> {
    const TINTS: [[f32; 3]; 8] = [
        [1.0, 0.3, 0.3],
        [0.3, 1.0, 0.3],
        [0.4, 0.5, 1.0],
        [1.0, 1.0, 0.3],
        [1.0, 0.3, 1.0],
        [0.3, 1.0, 1.0],
        [1.0, 0.6, 0.2],
        [0.7, 0.7, 0.7],
    ];
    let mut image = renderer.read_color().map_err(|e| e.to_string())?;
    let masks = renderer.read_masks().map_err(|e| e.to_string())?;
    for (i, px) in image.pixels_mut().enumerate() {
        let f = masks.facing[i];
        if f != 0 {
            let tint = TINTS[f.trailing_zeros() as usize % 8];
            for (v, t) in px.0.iter_mut().zip(tint) {
                *v = (f32::from(*v) * 0.55 + 255.0 * 0.45 * t).min(255.0) as u8;
            }
        }
    }
    image.save(path).map_err(|e| format!("{path}: {e}"))
}

fn run() -> Result<(), String> {
    let args = support::Args::from_env();
    let k: usize = args.parse("--cascades", 4)?;
    let map: u32 = args.parse("--map", 1024)?;
    let size: u32 = args.parse("--size", 512)?;
    let suns: usize = args.parse("--suns", 6)?;
    let large = args.value("--preset").unwrap_or("large") == "large";
    let triangles: usize = args.parse("--triangles", 300_000)?;
    let (scene, camera): (Scene, Camera) = if large {
        let config = ExperimentConfig {
            scene: SceneSource::Large { triangles },
            screen: size,
            ..ExperimentConfig::preset(Preset::Large)
        };
        let scene = experiment::load_scene(&config.scene).map_err(|e| e.to_string())?;
        let camera = experiment::camera_for(&config, &scene).map_err(|e| e.to_string())?;
        (scene, camera)
    } else {
        (support::scene("default", None)?, support::walk_camera(0.1, UVec2::splat(size)))
    };
    let single = ShadowMapSize::square(((f64::from(map) * (k as f64).sqrt()).round()) as u32);
    let cascade_map = ShadowMapSize::square(map);
    let (device, queue, info) = support::gpu()?;
    eprintln!(
        "adapter: {} ({:?}); {} triangles; {k} cascades of {map}² vs one map of {}²",
        info.name,
        info.backend,
        scene.triangle_count(),
        single.width
    );
    let caster = RayCaster::new(&scene);
    let options = RendererOptions::default();
    let mut renderer = Renderer::new(&device, &queue, &scene, options).map_err(|e| e.to_string())?;
    if let Some(frames) = args.value("--walk") {
        let frames: usize = frames.parse().map_err(|e| format!("--walk: {e}"))?;
        let sun: usize = args.parse("--sun", 0)?;
        let light = support::hemisphere_light(sun + suns / 3, suns + suns / 3 + suns / 2);
        let view = WalkView { scene: &scene, caster: &caster, camera, light, map: cascade_map, size };
        return walk(&device, &queue, &view, k, frames);
    }
    let names = ["focused", "lispsm", "csm", "sdsm", "sdsm-lispsm", "optimized-cascades"];
    let picture_method = args.value("--picture-method").unwrap_or("optimized-cascades");
    if !names[2..].contains(&picture_method) {
        return Err(format!("--picture-method {picture_method:?}: one of {:?}", &names[2..]));
    }
    let mut totals = vec![0u64; names.len()];
    let mut truth_shadowed = 0usize;
    for s in 0..suns {
        // Suns between about 15° and 60° above the horizon.
        let light = support::hemisphere_light(s + suns / 3, suns + suns / 3 + suns / 2);
        let truth = caster.trace_masks(&camera, &[light], size, size);
        truth_shadowed += truth.shadowed_count(0);
        let one = ShadowProblem::new(camera, light, scene.bounds(), single).map_err(|e| e.to_string())?;
        let mut counts = Vec::new();
        for p in [Parameterization::Focused, Parameterization::LiSpsm(Default::default())] {
            let m = one.solve(&p).map_err(|e| e.to_string())?;
            counts.push(render_masks(&mut renderer, &camera, &[m], false)?.misclassified(&truth, 0).unwrap_or(0));
        }
        // The cascaded methods, each driven by the frame loop at this view
        // until it settles.
        let policies = [
            CascadePolicy::csm(k),
            CascadePolicy::sdsm(k, Parameterization::Focused),
            CascadePolicy::sdsm(k, Parameterization::LiSpsm(Default::default())),
            CascadePolicy::optimized(k),
        ];
        let mut last_splits = None;
        for (i, policy) in policies.into_iter().enumerate() {
            let mut shadows =
                ShadowLoop::new(LoopPolicy::Cascaded(policy), 1, LoopOptions::default()).map_err(|e| e.to_string())?;
            let view = LoopView { camera: &camera, lights: &[light], bounds: scene.bounds(), map: cascade_map };
            let settled = shadows.settle(&mut renderer, &view, 8).map_err(|e| e.to_string())?;
            // The loop left the renderer's cascades set for these matrices.
            counts.push(
                render_masks(&mut renderer, &camera, &settled.matrices, true)?.misclassified(&truth, 0).unwrap_or(0),
            );
            if let (0, true, Some(path)) = (s, names[i + 2] == picture_method, args.value("--picture")) {
                picture(&renderer, path)?;
            }
            last_splits = shadows.frame(&mut renderer, &view).map_err(|e| e.to_string())?.splits;
        }
        let splits = last_splits.ok_or("no splits")?;
        eprintln!("sun {s} {:?}: splits {:?}: {counts:?}", light, splits.boundaries());
        for (t, c) in totals.iter_mut().zip(&counts) {
            *t += c;
        }
    }
    println!("| method | misclassified | vs csm | vs sdsm |");
    println!("|---|---:|---:|---:|");
    for (name, t) in names.iter().zip(&totals) {
        println!(
            "| {name} | {t} | {:.3} | {:.3} |",
            *t as f64 / totals[2].max(1) as f64,
            *t as f64 / totals[3].max(1) as f64
        );
    }
    println!("({suns} suns, {size}² pixels, {truth_shadowed} truly shadowed pixels)");
    Ok(())
}

/// What the walk sees.
struct WalkView<'a> {
    scene: &'a Scene,
    caster: &'a RayCaster,
    camera: Camera,
    light: lixel::Light,
    map: ShadowMapSize,
    size: u32,
}

/// `--walk FRAMES`: the cascaded loops along the stability tooling's
/// camera path (a slow walk and turn, [`CameraPath`]), paired frame by
/// frame (the order alternating): frame time (the loop's frame, waited
/// for: solving, optimizing and rendering), misclassified pixels, and
/// flicker ([`Flicker`], as `lixel experiment --stability` defines it).
/// Each loop is settled at the first view first, and has a renderer of its
/// own (so that no loop takes another's analysis readbacks).
fn walk(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    view: &WalkView<'_>,
    k: usize,
    frames: usize,
) -> Result<(), String> {
    let all = ["csm", "sdsm", "optimized-cascades"];
    // CASCADES_ONLY=NAME: that method alone (for debugging; no ratios).
    let only = std::env::var("CASCADES_ONLY").ok();
    let names: Vec<&str> = all.into_iter().filter(|n| only.as_deref().is_none_or(|o| o == *n)).collect();
    let mut loops = Vec::new();
    let mut renderers = Vec::new();
    let policy_of = |name: &str| match name {
        "csm" => CascadePolicy::csm(k),
        "sdsm" => CascadePolicy::sdsm(k, Parameterization::Focused),
        _ => CascadePolicy::optimized(k),
    };
    for policy in names.iter().map(|n| policy_of(n)) {
        renderers
            .push(Renderer::new(device, queue, view.scene, RendererOptions::default()).map_err(|e| e.to_string())?);
        let renderer = renderers.last_mut().ok_or("no renderer")?;
        let mut shadows =
            ShadowLoop::new(LoopPolicy::Cascaded(policy), 1, LoopOptions::default()).map_err(|e| e.to_string())?;
        let lights = [view.light];
        let first = LoopView { camera: &view.camera, lights: &lights, bounds: view.scene.bounds(), map: view.map };
        shadows.settle(renderer, &first, 8).map_err(|e| e.to_string())?;
        loops.push(shadows);
    }
    let path = CameraPath { frames, walk: 0.04, turn_degrees: 12.0 };
    let diagonal = view.scene.bounds().scene().diagonal();
    let mut times = vec![Vec::new(); names.len()];
    let mut misclassified = vec![0u64; names.len()];
    let mut flicker = vec![Flicker::default(); names.len()];
    let mut previous: Vec<Option<(ShadowMasks, ShadowMasks)>> = vec![None; names.len()];
    for f in 0..frames {
        let camera = path.camera(&view.camera, diagonal, f).map_err(|e| e.to_string())?;
        let truth = view.caster.trace_masks(&camera, &[view.light], view.size, view.size);
        let lights = [view.light];
        let loop_view = LoopView { camera: &camera, lights: &lights, bounds: view.scene.bounds(), map: view.map };
        let order: Vec<usize> = if f % 2 == 0 { (0..names.len()).collect() } else { (0..names.len()).rev().collect() };
        for m in order {
            let renderer = &mut renderers[m];
            let start = std::time::Instant::now();
            let done = loops[m].frame(renderer, &loop_view).map_err(|e| e.to_string())?;
            renderer.wait_for(&done.render.submission).map_err(|e| e.to_string())?;
            times[m].push(start.elapsed().as_secs_f64());
            // Untimed: the same matrices (cascades as the loop set them) with masks.
            let masks = render_masks(renderer, &camera, &done.matrices, true)?;
            misclassified[m] += masks.misclassified(&truth, 0).unwrap_or(0);
            if std::env::var_os("CASCADES_DEBUG").is_some() {
                // Per cascade: pixels it owns, and whether its matrix is the
                // slice's focused one (F) or another (O).
                let raw = renderer.read_masks().map_err(|e| e.to_string())?;
                let owned: Vec<usize> = (0..k).map(|c| raw.facing.iter().filter(|&&b| b == 1 << c).count()).collect();
                let problem =
                    ShadowProblem::new(camera, view.light, view.scene.bounds(), view.map).map_err(|e| e.to_string())?;
                let kinds: String = match &done.splits {
                    Some(s) => lixel::cascade::CascadeProblems::new(&problem, s.clone())
                        .map_err(|e| e.to_string())?
                        .solve(&Parameterization::Focused)
                        .iter()
                        .zip(&done.matrices)
                        .map(|(f, m)| if f.as_ref().ok() == Some(m) { 'F' } else { 'O' })
                        .collect(),
                    None => String::new(),
                };
                let (mut false_shadow, mut false_lit) = (0, 0);
                for i in 0..truth.shadow.len() {
                    if truth.visible(i) && truth.facing[i] & 1 == 1 {
                        match (truth.shadow[i] & 1, masks.shadow[i] & 1) {
                            (0, 1) => false_shadow += 1,
                            (1, 0) => false_lit += 1,
                            _ => {}
                        }
                    }
                }
                eprintln!(
                    "frame {f} {}: misclassified {} (false shadow {false_shadow}, false lit {false_lit}), cascades {kinds} own {owned:?}, readback {:?}, optimized {:#b} failed {:#b} moved {} splits {:?}",
                    names[m],
                    masks.misclassified(&truth, 0).unwrap_or(0),
                    done.readback.map(|r| r.frame),
                    done.optimized,
                    done.failed,
                    done.moved,
                    done.splits.as_ref().map(|s| s.boundaries().to_vec())
                );
            }
            if let Some((a, truth_a)) = &previous[m] {
                flicker[m] = flicker[m].merged(Flicker::between(0, a, truth_a, &masks, &truth));
            }
            previous[m] = Some((masks, truth.clone()));
        }
    }
    let median = |t: &[f64]| {
        let mut t = t.to_vec();
        t.sort_by(f64::total_cmp);
        t[t.len() / 2]
    };
    println!("| method | median frame (ms) | frame time vs csm (paired, 95%) | misclassified | flicker (%) |");
    println!("|---|---:|---:|---:|---:|");
    for (m, name) in names.iter().enumerate() {
        let ratios: Vec<f64> = times[m].iter().zip(&times[0]).map(|(a, b)| a / b).collect();
        let ratio = RatioEstimate::from_ratios(&ratios).map_or_else(|| "-".to_owned(), |r| r.to_string());
        println!(
            "| {name} | {:.1} | {ratio} | {} | {:.3} |",
            1e3 * median(&times[m]),
            misclassified[m],
            100.0 * flicker[m].share()
        );
    }
    println!("({frames} frames of a walk of 4% of the scene diagonal turning 12°, {}² pixels)", view.size);
    Ok(())
}
