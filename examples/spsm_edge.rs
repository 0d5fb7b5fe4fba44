//! One experiment configuration seen through a method with the standard and
//! the SPSM lookup: the light matrix's depth range and, for every pixel the
//! two lookups and the ray-cast truth disagree on, the post-projective
//! depths `zeta = z / w` of the receiver and of its occluder (the SPSM
//! lookup compares in `zeta`).
//!
//! ```text
//! cargo run --release --features cli --example spsm_edge -- [--preset quick|default]
//!     [--config 1] [--method optimized]
//! ```
//!
//! With `--trio FILE.png` it instead writes the README's image trio: the
//! configuration's matrix of `--method` (default `focused`), solved for the
//! preset's view, seen through a narrow camera (`--fov`, default 5°;
//! `--screen`, default 256) from the same eye, aimed at the screen window
//! across a shadow edge where the standard lookup misclassifies most, with
//! the standard lookup, the SPSM lookup and the ray-cast truth side by side
//! (the experiment's error overlay: truth's shading, false shadow red,
//! false lit blue), and prints the close-up's counts.

#[path = "support/mod.rs"]
mod support;

use glam::DVec3;
use lixel::experiment::{Counts, ExperimentConfig, MethodSpec, Preset, Runner};
use lixel::mesh::raycast::Ray;
use lixel::mesh::RayCaster;
use lixel::render::{ShadowLookup, SpsmOptions};
use lixel::{Light, LightMatrix};

fn main() {
    if let Err(e) = run() {
        eprintln!("spsm_edge: {e}");
        std::process::exit(1);
    }
}

fn run() -> Result<(), String> {
    let args = support::Args::from_env();
    let preset = match args.value("--preset").unwrap_or("quick") {
        "quick" => Preset::Quick,
        "default" => Preset::Default,
        "paper" => Preset::Paper,
        other => return Err(format!("unknown preset {other:?}")),
    };
    let index: usize = args.parse("--config", 1)?;
    if let Some(path) = args.value("--trio") {
        let name = args.value("--method").unwrap_or("focused");
        let base = MethodSpec::parse(name).ok_or_else(|| format!("unknown method {name:?}"))?;
        let fov: f64 = args.parse("--fov", 5.0)?;
        let screen: u32 = args.parse("--screen", 256)?;
        return trio(preset, index, base, (fov, screen), path);
    }
    let name = args.value("--method").unwrap_or("optimized");
    let base = MethodSpec::parse(name).ok_or_else(|| format!("unknown method {name:?}"))?;
    let mut config = ExperimentConfig::preset(preset);
    config.methods = vec![base, base.with_lookup(ShadowLookup::Spsm(SpsmOptions::default()))];
    config.coverage_samples = 0;
    let (device, queue, info) = support::gpu()?;
    eprintln!("adapter: {} ({:?})", info.name, info.backend);
    let mut runner = Runner::new(&config, &device, &queue).map_err(|e| e.to_string())?;
    let outcome = runner.run_config(index).map_err(|e| e.to_string())?;
    let (truth, _) = runner.truths(outcome.light).map_err(|e| e.to_string())?;
    let truth = truth.ok_or("no ray-cast truth")?;
    let caster = RayCaster::new(runner.scene());
    let world_from_clip = runner.camera().clip_from_world().inverse();
    for (method, result) in &outcome.results {
        let Some(m) = result.matrix else {
            println!("{}: failed ({})", method.name(), result.note);
            continue;
        };
        let counts = result.counts.unwrap_or_default();
        println!(
            "{}: misclassified {} (false shadow {}, false lit {}); depth {:?}, unclipped {}",
            method.name(),
            counts.misclassified(),
            counts.false_shadow,
            counts.false_lit,
            m.depth,
            m.needs_unclipped_depth
        );
        let masks = runner.masks_with(&m, method.lookup()).map_err(|e| e.to_string())?;
        assert_eq!(Counts::compare(&masks, &truth), counts, "masks reproduce the run's counts");
        // Receiver and occluder zeta of every truth-shadowed pixel.
        let spsm_matrix = lixel::render::spsm::depth_matrix(&m);
        let spsm_zeta = |p: DVec3| {
            let c = spsm_matrix * p.extend(1.0);
            c.z / c.w
        };
        let mut gaps = Vec::new();
        let mut wrong_gaps = Vec::new();
        let mut spsm_gaps = Vec::new();
        let mut zetas = (f64::INFINITY, f64::NEG_INFINITY);
        for i in 0..truth.depth.len() {
            if !truth.visible(i) || truth.facing[i] & 1 == 0 || truth.shadow[i] & 1 == 0 {
                continue;
            }
            let (x, y) = (i as u32 % truth.width, i as u32 / truth.width);
            let ndc = DVec3::new(
                (f64::from(x) + 0.5) / f64::from(truth.width) * 2.0 - 1.0,
                1.0 - (f64::from(y) + 0.5) / f64::from(truth.height) * 2.0,
                f64::from(truth.depth[i]),
            );
            let receiver = world_from_clip.project_point3(ndc);
            let Some(occluder) = occluder(&caster, receiver, &outcome.light) else { continue };
            let (Some(r), Some(o)) = (m.project(receiver), m.project(occluder)) else { continue };
            zetas = (zetas.0.min(r.z).min(o.z), zetas.1.max(r.z).max(o.z));
            gaps.push(r.z - o.z);
            spsm_gaps.push(spsm_zeta(receiver) - spsm_zeta(occluder));
            if masks.shadow[i] & 1 == 0 {
                wrong_gaps.push(r.z - o.z);
            }
        }
        println!(
            "  zeta over shadowed receivers and their occluders: [{:.7}, {:.7}]; receiver - occluder gap: {}; on false-lit pixels: {}",
            zetas.0,
            zetas.1,
            quantiles(&mut gaps),
            quantiles(&mut wrong_gaps)
        );
        println!("  SPSM depth row: gap {}", quantiles(&mut spsm_gaps));
        print_w(&m);
    }
    Ok(())
}

/// The closest occluder between `receiver` and the light.
fn occluder(caster: &RayCaster, receiver: DVec3, light: &Light) -> Option<DVec3> {
    let Light::Point { position } = *light else { return None };
    let to_light = (position - receiver).as_vec3();
    let origin = receiver.as_vec3() + to_light.normalize() * 1e-3;
    let hit = caster.bvh().closest_hit(&Ray { origin, direction: to_light }, 1.0)?;
    Some((origin + to_light * hit.t).as_dvec3())
}

fn quantiles(v: &mut [f64]) -> String {
    if v.is_empty() {
        return "none".into();
    }
    v.sort_by(f64::total_cmp);
    let q = |f: f64| v[((v.len() - 1) as f64 * f) as usize];
    format!("n {} min {:.3e} 10% {:.3e} median {:.3e} 90% {:.3e}", v.len(), q(0.0), q(0.1), q(0.5), q(0.9))
}

fn print_w(m: &LightMatrix) {
    let row = |r: usize| m.clip_from_world.row(r);
    println!("  clip z row {:?}\n  clip w row {:?}", row(2), row(3));
}

/// The README's trio (see the module docs).
fn trio(preset: Preset, index: usize, base: MethodSpec, (fov, screen): (f64, u32), path: &str) -> Result<(), String> {
    let mut config = ExperimentConfig::preset(preset);
    config.methods = vec![base];
    config.coverage_samples = 0;
    let (device, queue, _) = support::gpu()?;
    // The matrix, solved for the preset's whole view.
    let (matrix, light, window, eye) = {
        let mut runner = Runner::new(&config, &device, &queue).map_err(|e| e.to_string())?;
        let outcome = runner.run_config(index).map_err(|e| e.to_string())?;
        let m = outcome.results[0].1.matrix.ok_or("the method failed")?;
        let truth = runner.truths(outcome.light).map_err(|e| e.to_string())?.0.ok_or("no ray-cast truth")?;
        let masks = runner.masks_with(&m, base.lookup()).map_err(|e| e.to_string())?;
        // The 16x16 window across a shadow edge (all counted, 30-70% of it
        // shadowed in the truth) with the most pixels the standard lookup
        // misclassifies.
        let (w, h) = (truth.width as usize, truth.height as usize);
        let counted = |i: usize| truth.visible(i) && truth.facing[i] & 1 == 1;
        let mut best = (0, 0, 0);
        for y in (0..h.saturating_sub(16)).step_by(4) {
            for x in (0..w.saturating_sub(16)).step_by(4) {
                let window = || (y..y + 16).flat_map(|yy| (x..x + 16).map(move |xx| yy * w + xx));
                if !window().all(counted) {
                    continue;
                }
                let shadowed = window().filter(|&i| truth.shadow[i] & 1 == 1).count();
                if !(77..=179).contains(&shadowed) {
                    continue;
                }
                let n = window().filter(|&i| (truth.shadow[i] ^ masks.shadow[i]) & 1 == 1).count();
                if n > best.0 {
                    best = (n, x + 8, y + 8);
                }
            }
        }
        if best.0 == 0 {
            return Err("no shadow edge with standard-lookup errors in view".into());
        }
        let i = best.2 * w + best.1;
        let ndc = DVec3::new(
            (best.1 as f64 + 0.5) / w as f64 * 2.0 - 1.0,
            1.0 - (best.2 as f64 + 0.5) / h as f64 * 2.0,
            f64::from(truth.depth[i]),
        );
        let target = runner.camera().clip_from_world().inverse().project_point3(ndc);
        (m, outcome.light, target, runner.camera().eye())
    };
    // The close-up: same eye, narrow field of view, the same matrix.
    let close = ExperimentConfig { eye: Some(eye), target: Some(window), fov_y_degrees: fov, screen, ..config.clone() };
    let mut runner = Runner::new(&close, &device, &queue).map_err(|e| e.to_string())?;
    let truth = runner.truths(light).map_err(|e| e.to_string())?.0.ok_or("no ray-cast truth")?;
    let mut panels = Vec::new();
    for method in [base, base.with_lookup(ShadowLookup::Spsm(SpsmOptions::default()))] {
        let masks = runner.masks_with(&matrix, method.lookup()).map_err(|e| e.to_string())?;
        let c = Counts::compare(&masks, &truth);
        println!(
            "{}: {} misclassified of {} (false shadow {}, false lit {})",
            method.name(),
            c.misclassified(),
            c.counted,
            c.false_shadow,
            c.false_lit
        );
        panels.push(lixel::experiment::error_overlay(&masks, &truth));
    }
    panels.push(lixel::experiment::error_overlay(&truth, &truth));
    let (w, h) = (truth.width, truth.height);
    let gap = 4;
    let mut out = image::RgbaImage::from_pixel(3 * w + 2 * gap, h, image::Rgba([255, 255, 255, 255]));
    for (k, panel) in panels.iter().enumerate() {
        image::imageops::overlay(&mut out, panel, i64::from(k as u32 * (w + gap)), 0);
    }
    out.save(path).map_err(|e| format!("{path}: {e}"))?;
    println!("target {window:?}, eye {eye:?}, fov {fov} deg; wrote {path}");
    Ok(())
}
