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

#[path = "support/mod.rs"]
mod support;

use glam::DVec3;
use lixel::experiment::{Counts, ExperimentConfig, MethodKind, Preset, Runner};
use lixel::mesh::raycast::Ray;
use lixel::mesh::RayCaster;
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
    let name = args.value("--method").unwrap_or("optimized");
    let base = MethodKind::parse(name).ok_or_else(|| format!("unknown method {name:?}"))?;
    let mut config = ExperimentConfig::preset(preset);
    config.methods = vec![base, base.with_spsm()];
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
