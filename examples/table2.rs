//! The paper's Table 2 on this machine: mean frame time for 1-4 lights and
//! 500², 700², 1000² shadow maps, scene-optimized pipeline vs focused vs
//! LiSPSM, as ratios to focused, all measured in one run. The same
//! measurement as `lixel experiment --timing` (see
//! `lixel::experiment::run_timing` for the protocol), from an engine's point
//! of view: one device, one scene, and a printed table.
//!
//! ```text
//! cargo run --release --example table2 -- [--triangles 200000] [--size 512]
//!     [--frames 60] [--lights 1,2,3,4] [--maps 500,700,1000]
//! ```

#[path = "support/mod.rs"]
mod support;

use lixel::experiment::{self, ExperimentConfig, Preset, SceneSource, TimingOptions};

fn main() {
    if let Err(e) = run() {
        eprintln!("table2: {e}");
        std::process::exit(1);
    }
}

fn run() -> Result<(), String> {
    let args = support::Args::from_env();
    let config = ExperimentConfig {
        scene: SceneSource::Builtin { triangles: args.parse("--triangles", 200_000)? },
        screen: args.parse("--size", 512)?,
        ..ExperimentConfig::preset(Preset::Default)
    };
    let options = TimingOptions {
        lights: args.list("--lights", &[1, 2, 3, 4])?,
        maps: args.list("--maps", &[500, 700, 1000])?,
        frames: args.parse("--frames", 60)?,
        ..TimingOptions::default()
    };
    let (device, queue, info) = support::gpu()?;
    println!(
        "adapter: {} ({:?}); {:?}; {}² screen; {} frames per pipeline and cell",
        info.name, info.backend, config.scene, config.screen, options.frames
    );
    let rows = experiment::run_timing(&config, &options, &device, &queue, |row| {
        eprintln!("  {} lights, {}²: scene-optimized / focused {:.3}", row.lights, row.map, row.optimized_ratio());
    })
    .map_err(|e| e.to_string())?;
    println!("\n{}", experiment::timing_markdown(&rows));
    Ok(())
}
