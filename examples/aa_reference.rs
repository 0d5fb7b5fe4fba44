//! How far sub-pixel antialiasing (Pan et al. 2009) can take the mean
//! visibility error, measured on the CPU, before any GPU implementation:
//! per configuration of an experiment preset, the error against the
//! ray-cast coverage truth of
//!
//! * `focused`: the renderer's focused map (a standard lookup, 0 or 1),
//! * `alias-free`: the exact centre-sample truth (the best any binary
//!   lookup can do),
//! * `facet-N`: the paper's facet approximation with every blocker found
//!   and no table rounding (`experiment::facet_reference_words`; a spot
//!   light's samples outside its cone are not counted), N sub-samples:
//!   the floor under a GPU `+aaN` lookup,
//!
//! and the time the coverage truth and the facet reference took.
//!
//! ```text
//! cargo run --release --example aa_reference -- [--preset quick|default|paper] [--configs 6] [--map 400]
//! ```

#[path = "support/mod.rs"]
mod support;

use std::time::Instant;

use lixel::experiment::{self, Coverage, ExperimentConfig, Runner, VisibilityError};
use lixel::mesh::RayCaster;
use lixel::render::subpixel::AaSamples;
use lixel::Parameterization;

fn main() {
    if let Err(e) = run() {
        eprintln!("aa_reference: {e}");
        std::process::exit(1);
    }
}

fn run() -> Result<(), String> {
    let args = support::Args::from_env();
    let preset = support::preset(&args)?;
    let base = ExperimentConfig::preset(preset);
    let config = ExperimentConfig {
        configs: args.parse("--configs", base.configs)?,
        map: args.parse("--map", base.map)?,
        screen: args.parse("--screen", base.screen)?,
        truth: experiment::Truth::RayCast,
        ..base
    };
    let (device, queue, info) = support::gpu()?;
    let mut runner = Runner::new(&config, &device, &queue).map_err(|e| e.to_string())?;
    let caster = RayCaster::new(runner.scene());
    println!(
        "adapter: {} ({:?}); {} triangles, {}² screen, {}² map, {} configurations",
        info.name,
        info.backend,
        runner.scene().triangle_count(),
        config.screen,
        config.map,
        config.configs
    );
    println!(
        "| config | counted | focused | alias-free | facet-8 | facet-16 | facet-32 | truth s | coverage s | facet s |"
    );
    println!("|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    let mut totals = [VisibilityError::default(); 5];
    let mut times = [0.0f64; 3];
    for index in 0..config.configs {
        let light = experiment::light_for(&config, runner.scene(), index);
        let start = Instant::now();
        let truth = caster.trace_masks(runner.camera(), &[light], config.screen, config.screen);
        let t_truth = start.elapsed().as_secs_f64();
        let start = Instant::now();
        let coverage = Coverage::trace(&caster, runner.camera(), &light, &truth);
        let t_coverage = start.elapsed().as_secs_f64();
        let start = Instant::now();
        let (facets, in_cone) = experiment::facet_reference_words(&caster, runner.camera(), &light, &truth);
        let t_facet = start.elapsed().as_secs_f64();
        let focused = runner
            .problem(light, config.map)
            .and_then(|p| p.solve(&Parameterization::Focused))
            .map_err(|e| e.to_string())?;
        let masks = runner.masks(&focused).map_err(|e| e.to_string())?;
        let errors = [
            VisibilityError::of_masks(&masks, &truth, &coverage, AaSamples::X32),
            VisibilityError::of_masks(&truth, &truth, &coverage, AaSamples::X32),
            VisibilityError::of_valid_occlusion(&facets, &in_cone, &truth, &coverage, AaSamples::X8),
            VisibilityError::of_valid_occlusion(&facets, &in_cone, &truth, &coverage, AaSamples::X16),
            VisibilityError::of_valid_occlusion(&facets, &in_cone, &truth, &coverage, AaSamples::X32),
        ];
        for (t, e) in totals.iter_mut().zip(&errors) {
            t.sum += e.sum;
            t.pixels += e.pixels;
        }
        for (t, x) in times.iter_mut().zip([t_truth, t_coverage, t_facet]) {
            *t += x;
        }
        let cells: Vec<String> = errors.iter().map(|e| format!("{:.4}", e.mean().unwrap_or(f64::NAN))).collect();
        println!(
            "| {index} | {} | {} | {t_truth:.2} | {t_coverage:.2} | {t_facet:.2} |",
            errors[0].pixels,
            cells.join(" | ")
        );
    }
    let cells: Vec<String> = totals.iter().map(|e| format!("{:.4}", e.mean().unwrap_or(f64::NAN))).collect();
    println!(
        "| all | {} | {} | {:.2} | {:.2} | {:.2} |",
        totals[0].pixels,
        cells.join(" | "),
        times[0],
        times[1],
        times[2]
    );
    let focused = totals[0].mean().unwrap_or(f64::NAN);
    for (name, e) in [("alias-free", totals[1]), ("facet-32", totals[4])] {
        println!("{name} / focused: {:.3}", e.mean().unwrap_or(f64::NAN) / focused);
    }
    Ok(())
}
