//! The frame loop: a camera walk and moving lights over the default scene,
//! with the optimizer cadence of the paper (analysis pass every 3 frames,
//! each light looked up in a small focused map every 5th pass, asynchronous
//! readback). Writes PNG frames and a per-frame timing CSV (GPU timestamps
//! where available). With `--flicker` it also counts each frame's
//! misclassified pixels against a ray-cast truth and the flicker between
//! consecutive frames (pixels whose shadow bit changes while the truth's does
//! not; `lixel::mesh::Flicker`), at the cost of a second camera pass and a
//! ray cast per frame (frame times then include them).
//!
//! ```text
//! cargo run --release --example frame_loop -- [--preset tiny|small|default] [--obj file.obj]
//!     [--method optimized|focused|focused-snapped|lispsm] [--lights 2] [--map 1024] [--size 750]
//!     [--frames 60] [--png-every 10] [--in-flight 2] [--flicker] [--out target/frame_loop]
//! ```

#[path = "support/mod.rs"]
mod support;

use std::io::Write;
use std::path::PathBuf;

use lixel::render::{Renderer, RendererOptions};

fn main() {
    if let Err(e) = run() {
        eprintln!("frame_loop: {e}");
        std::process::exit(1);
    }
}

fn run() -> Result<(), String> {
    let args = support::Args::from_env();
    let scene = support::scene(args.value("--preset").unwrap_or("default"), args.value("--obj"))?;
    let out = PathBuf::from(args.value("--out").unwrap_or("target/frame_loop"));
    std::fs::create_dir_all(&out).map_err(|e| format!("{}: {e}", out.display()))?;
    let config = support::LoopConfig {
        method: args.value("--method").unwrap_or("optimized").to_owned(),
        policy: support::parse_policy(args.value("--method").unwrap_or("optimized"))?,
        lights: args.parse("--lights", 2)?,
        map: args.parse("--map", 1024)?,
        size: args.parse("--size", 750)?,
        frames: args.parse("--frames", 60)?,
        frames_per_loop: args.parse("--frames-per-loop", 240)?,
        in_flight: args.parse("--in-flight", 2)?,
        png: Some((args.parse("--png-every", 10)?, out.clone())),
        flicker: args.flag("--flicker"),
    };
    let (device, queue, info) = support::gpu()?;
    eprintln!("adapter: {} ({:?}); {} triangles", info.name, info.backend, scene.triangle_count());
    let mut renderer = Renderer::new(&device, &queue, &scene, RendererOptions::default()).map_err(|e| e.to_string())?;
    let records = support::run_loop(&mut renderer, &scene, &config)?;

    let csv_path = out.join("timings.csv");
    let mut csv = std::fs::File::create(&csv_path).map_err(|e| format!("{}: {e}", csv_path.display()))?;
    writeln!(csv, "{}", support::FrameRecord::CSV_HEADER).map_err(|e| e.to_string())?;
    for r in &records {
        writeln!(csv, "{}", r.csv_row()).map_err(|e| e.to_string())?;
    }
    let steady: Vec<_> = records.iter().skip(3).collect();
    let mean = |f: &dyn Fn(&support::FrameRecord) -> Option<f64>| {
        let v: Vec<f64> = steady.iter().filter_map(|r| f(r)).collect();
        (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64)
    };
    let show = |v: Option<f64>| v.map_or("-".into(), |v| format!("{v:.2}"));
    println!(
        "{} frames, {} ({} lights, {}² maps, {}² screen)",
        records.len(),
        config.method,
        config.lights,
        config.map,
        config.size
    );
    println!("mean frame time         {} ms", show(mean(&|r| Some(r.wall_ms))));
    println!(
        "mean GPU time           {} ms",
        show(mean(&|r| r.gpu.and_then(|g| g.total).map(|d| d.as_secs_f64() * 1e3)))
    );
    let triangles = renderer.triangle_count() as f64;
    println!(
        "shadow triangles drawn  {}% of passes x scene (per-object culling)",
        show(mean(&|r| (r.shadow_passes > 0)
            .then(|| 100.0 * r.shadow_triangles as f64 / (f64::from(r.shadow_passes) * triangles))))
    );
    println!(
        "readback latency        {} frames, {} ms (ready), {} ms (taken)",
        show(mean(&|r| r.readback.map(|x| x.1 as f64))),
        show(mean(&|r| r.readback.map(|x| x.2))),
        show(mean(&|r| r.readback.map(|x| x.3)))
    );
    let stats = renderer.readback_ring().stats();
    println!(
        "readbacks               {} submitted, {} taken, {} refused (ring full), {} discarded",
        stats.submitted, stats.taken, stats.refused, stats.discarded
    );
    if config.flicker {
        let flicker =
            records.iter().filter_map(|r| r.flicker).fold(lixel::mesh::Flicker::default(), |a, b| a.merged(b));
        let transitions = records.iter().filter(|r| r.flicker.is_some()).count();
        println!(
            "flicker                 {:.3}% of truth-stable pixels flip per frame ({} flips over {transitions} frame pairs, all lights)",
            100.0 * flicker.share(),
            flicker.flipped
        );
        println!(
            "misclassified           {} px per frame (all lights, ray-cast truth)",
            show(mean(&|r| r.misclassified.map(|m| m as f64)))
        );
    }
    println!("wrote {} and PNG frames to {}", csv_path.display(), out.display());
    Ok(())
}
