//! Cascaded sun shadows at equal total texels: `K` cascades of `s²` texels
//! against one map of `(s·√K)²`, misclassified pixels against an exact ray
//! cast, summed over several sun directions.
//!
//! ```text
//! cargo run --release --example cascades -- [--cascades 4] [--map 1024] [--size 512]
//!     [--preset large|default] [--suns 6] [--triangles 300000] [--picture cascades.png]
//! ```
//!
//! Methods: `focused` and `lispsm` (one map of `(s·√K)²`); `csm` (practical
//! λ = 0.75 splits of the camera range within the scene, focused maps);
//! `sdsm` (log splits inside the visible depth range of a readback, focused
//! maps); `sdsm-lispsm` (same splits, LiSPSM maps); `optimized-cascades`
//! (same splits, each cascade scene-optimized from the analysis readback,
//! rounds until no cascade switches, at most 8). The large preset puts the
//! eye 1.7 units above a 2000-unit floor with objects over 1500 units and a
//! far plane of 1500.

#[path = "support/mod.rs"]
mod support;

use glam::{DVec3, UVec2};
use lixel::cascade::{
    visible_depth_range, CascadeOptimizer, CascadeProblems, CascadeSplits, SplitScheme, SplitTracker,
};
use lixel::mesh::{ProceduralScene, RayCaster, Scene, ShadowMasks};
use lixel::optimize::{OptimizeOptions, Readback, SampleOptions};
use lixel::render::{AnalysisRequest, Frame, Renderer, RendererOptions};
use lixel::{Camera, LightMatrix, Parameterization, ShadowMapSize, ShadowProblem};

fn main() {
    if let Err(e) = run() {
        eprintln!("cascades: {e}");
        std::process::exit(1);
    }
}

/// The sun's shadow bit from a frame whose lights are its cascades: not lit
/// where no cascade faces the sun (facing away, or outside every cascade)
/// or the owning cascade's bit is set.
fn sun_masks(masks: &ShadowMasks) -> ShadowMasks {
    let mut out = masks.clone();
    for i in 0..out.shadow.len() {
        let (s, f) = (masks.shadow[i], masks.facing[i]);
        out.shadow[i] = u32::from(s != 0);
        out.facing[i] = u32::from(f != 0);
    }
    out
}

fn render_masks(
    renderer: &mut Renderer,
    camera: &Camera,
    matrices: &[LightMatrix],
    splits: Option<&lixel::cascade::Splits>,
) -> Result<ShadowMasks, String> {
    renderer.set_cascades(0, splits);
    let frame = Frame { camera, lights: matrices, masks: true, analysis: None, lookup: Default::default() };
    renderer.render(&frame).map_err(|e| e.to_string())?;
    let masks = renderer.read_masks().map_err(|e| e.to_string())?;
    Ok(if splits.is_some() { sun_masks(&masks) } else { masks })
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

fn solve_all(cascades: &CascadeProblems, p: &Parameterization) -> Result<Vec<LightMatrix>, String> {
    cascades.solve(p).into_iter().collect::<Result<_, _>>().map_err(|e| e.to_string())
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
        let scene =
            ProceduralScene { triangle_budget: triangles, objects_per_side: 40, floor_size: 2000.0, seed: 2026 };
        let eye = DVec3::new(3.0, 1.7, 760.0);
        let camera = Camera::look_at(
            eye,
            eye + DVec3::new(0.05, -0.04, -1.0),
            DVec3::Y,
            60f64.to_radians(),
            UVec2::splat(size),
            0.1,
            1500.0,
        )
        .map_err(|e| e.to_string())?;
        (scene.build(), camera)
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
    let names = ["focused", "lispsm", "csm", "sdsm", "sdsm-lispsm", "optimized-cascades"];
    let mut totals = vec![0u64; names.len()];
    let mut truth_shadowed = 0usize;
    for s in 0..suns {
        // Suns between about 15° and 60° above the horizon.
        let light = support::hemisphere_light(s + suns / 3, suns + suns / 3 + suns / 2);
        let truth = caster.trace_masks(&camera, &[light], size, size);
        truth_shadowed += truth.shadowed_count(0);
        let one = ShadowProblem::new(camera, light, scene.bounds(), single).map_err(|e| e.to_string())?;
        let problem = ShadowProblem::new(camera, light, scene.bounds(), cascade_map).map_err(|e| e.to_string())?;
        let mut counts = Vec::new();
        for p in [Parameterization::Focused, Parameterization::LiSpsm(Default::default())] {
            let m = one.solve(&p).map_err(|e| e.to_string())?;
            counts.push(render_masks(&mut renderer, &camera, &[m], None)?.misclassified(&truth, 0).unwrap_or(0));
        }
        // csm: fixed practical splits.
        let csm = CascadeSplits { count: k, scheme: SplitScheme::Practical { lambda: 0.75 }, overlap: 0.1 };
        let fixed = CascadeProblems::new(&problem, csm.for_problem(&problem).map_err(|e| e.to_string())?)
            .map_err(|e| e.to_string())?;
        let m = solve_all(&fixed, &Parameterization::Focused)?;
        counts.push(
            render_masks(&mut renderer, &camera, &m, Some(fixed.splits()))?.misclassified(&truth, 0).unwrap_or(0),
        );
        // sdsm: the visible depth range of a first frame's readback (here the
        // csm frame's full-resolution depth).
        let depth_frame = render_masks(&mut renderer, &camera, &m, Some(fixed.splits()))?;
        if let (0, Some(path)) = (s, args.value("--picture")) {
            picture(&renderer, path)?;
        }
        let bits = vec![0u32; depth_frame.depth.len()];
        let rb = Readback {
            width: size,
            height: size,
            depth: &depth_frame.depth,
            shadow_bits: &bits,
            normals: None,
            layout: Default::default(),
        };
        let visible = visible_depth_range(&camera, &rb).map_err(|e| e.to_string())?;
        let sdsm_policy = CascadeSplits { count: k, scheme: SplitScheme::Logarithmic, overlap: 0.1 };
        let mut tracker = SplitTracker::new(sdsm_policy, 0.05).map_err(|e| e.to_string())?;
        let splits = tracker.update(&problem, visible).map_err(|e| e.to_string())?.clone();
        let sdsm = CascadeProblems::new(&problem, splits.clone()).map_err(|e| e.to_string())?;
        for p in [Parameterization::Focused, Parameterization::LiSpsm(Default::default())] {
            let m = solve_all(&sdsm, &p)?;
            counts.push(render_masks(&mut renderer, &camera, &m, Some(&splits))?.misclassified(&truth, 0).unwrap_or(0));
        }
        // optimized-cascades: rounds of analysis readback -> per-cascade optimization.
        let mut matrices = solve_all(&sdsm, &Parameterization::Focused)?;
        let mut optimizer = CascadeOptimizer::new(k, &OptimizeOptions::default());
        renderer.set_cascades(0, Some(&splits));
        for _round in 0..8 {
            renderer.discard_analyses();
            let frame = Frame {
                camera: &camera,
                lights: &matrices,
                masks: false,
                analysis: Some(AnalysisRequest::default()),
                lookup: Default::default(),
            };
            let report = renderer.render(&frame).map_err(|e| e.to_string())?;
            renderer.wait_for(&report.submission).map_err(|e| e.to_string())?;
            let Some(readback) = renderer.try_take_analysis() else { break };
            let m = &readback.masks;
            let bits: Vec<u32> =
                (0..m.depth.len()).map(|i| u32::from(m.visible(i) && (m.facing[i] == 0 || m.shadow[i] != 0))).collect();
            let input = Readback {
                width: m.width,
                height: m.height,
                depth: &m.depth,
                shadow_bits: &bits,
                normals: Some(&readback.normals),
                layout: Default::default(),
            };
            let samples =
                CascadeOptimizer::samples(&sdsm, &input, 0, &SampleOptions::default()).map_err(|e| e.to_string())?;
            let results = optimizer.optimize(&samples).map_err(|e| e.to_string())?;
            let mut switched = false;
            for (c, r) in results.into_iter().enumerate() {
                let r = r.map_err(|e| e.to_string())?;
                switched |= r.matrix != matrices[c];
                matrices[c] = r.matrix;
            }
            if !switched {
                break;
            }
        }
        counts.push(
            render_masks(&mut renderer, &camera, &matrices, Some(&splits))?.misclassified(&truth, 0).unwrap_or(0),
        );
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
