//! `lixel view`: the command line of the viewer (feature `view`); the
//! viewer itself is `lixel::view`.

use std::path::PathBuf;
use std::time::Instant;

use glam::DVec3;
use lixel::experiment::{LightKind, MethodSpec, Preset};
use lixel::view::{self, CameraPath, Overlays, ViewConfig, Viewer, WindowOptions};

use crate::{gpu, parse_vec3, BackendArg, SceneFileArgs};

#[derive(clap::Args)]
pub(crate) struct ViewArgs {
    /// Scene, camera, light positions and sizes of an experiment preset.
    #[arg(long, value_enum, default_value = "default")]
    preset: Preset,
    #[command(flatten)]
    scene: SceneFileArgs,
    /// Method of every light: normal, focused, focused-snapped, lispsm, psm,
    /// plane-optimal, optimized, optimized-argmin (keys 1-8 in the window),
    /// each also with `+spsm` or `+sgsm`.
    #[arg(long, default_value = "optimized")]
    method: String,
    /// Number of lights (the experiment's first configurations).
    #[arg(long, default_value_t = 1)]
    lights: usize,
    /// Light kind.
    #[arg(long, value_enum)]
    light: Option<LightKind>,
    /// Seed of the light positions.
    #[arg(long)]
    seed: Option<u64>,
    /// Square shadow-map resolution.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
    map: Option<u32>,
    /// Window (or screenshot) size, square.
    #[arg(long, value_parser = clap::value_parser!(u32).range(16..))]
    screen: Option<u32>,
    /// Eye position x,y,z.
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    eye: Option<DVec3>,
    /// Look-at point x,y,z.
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    target: Option<DVec3>,
    /// Analysis pass every N frames (scene-optimized).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
    cadence: Option<u32>,
    /// Overlays at the start, comma-separated: density, grid, error, map, hud, none.
    #[arg(long, default_value = "hud")]
    overlay: String,
    /// Render offscreen (no display needed) and write the last frame to this PNG.
    #[arg(long)]
    screenshot: Option<PathBuf>,
    /// Frames to render: for --screenshot (default 30), else close the window after them.
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..))]
    frames: Option<u64>,
    /// Camera path file: lines `frame eye.x eye.y eye.z target.x target.y target.z`.
    #[arg(long)]
    path: Option<PathBuf>,
    /// Turn the lights (degrees per second; Space toggles in the window).
    #[arg(long, default_value_t = 30.0)]
    animate: f64,
    /// wgpu backend for --screenshot: auto, vulkan or gl (the window takes `WGPU_BACKEND`).
    #[arg(long, value_enum, default_value = "auto")]
    backend: BackendArg,
}

fn config(args: &ViewArgs) -> Result<ViewConfig, String> {
    let mut c = ViewConfig::preset(args.preset);
    let e = &mut c.experiment;
    if let Some(scene) = args.scene.source() {
        e.scene = scene;
    }
    e.light = args.light.unwrap_or(e.light);
    e.seed = args.seed.unwrap_or(e.seed);
    e.map = args.map.unwrap_or(e.map);
    e.screen = args.screen.unwrap_or(e.screen);
    e.eye = args.eye.or(e.eye);
    e.target = args.target.or(e.target);
    c.method = MethodSpec::parse(args.method.trim()).ok_or_else(|| {
        format!("--method: unknown method {:?}; valid methods: {}", args.method, MethodSpec::valid_names())
    })?;
    c.lights = args.lights;
    c.overlays = Overlays::parse(&args.overlay).map_err(|e| e.to_string())?;
    if let Some(n) = args.cadence {
        c.schedule.optimize_every = n;
    }
    Ok(c)
}

pub(crate) fn run(args: &ViewArgs) -> Result<(), String> {
    let config = config(args)?;
    let path = args.path.as_deref().map(CameraPath::load).transpose().map_err(|e| e.to_string())?;
    let Some(file) = &args.screenshot else {
        let options = WindowOptions { frames: args.frames, path, animate_degrees_per_second: args.animate };
        let summary = view::run_window(config, options).map_err(|e| e.to_string())?;
        eprintln!("{} frames, {:.1} fps", summary.frames, summary.fps());
        return Ok(());
    };
    let gpu = gpu(args.backend)?;
    eprintln!("adapter: {}", gpu.describe());
    let mut viewer =
        Viewer::new(&gpu.device, &gpu.queue, config, view::SCREENSHOT_FORMAT).map_err(|e| e.to_string())?;
    let frames = args.frames.unwrap_or(30);
    let started = Instant::now();
    let image = viewer.screenshot(frames, path.as_ref()).map_err(|e| e.to_string())?;
    let elapsed = started.elapsed();
    image.save(file).map_err(|e| format!("screenshot {}: {e}", file.display()))?;
    let stats = viewer.stats();
    eprintln!(
        "{frames} frames of {} at {}x{} in {:.2} s ({:.1} ms a frame, each waited for) -> {}",
        viewer.method().name(),
        viewer.size().x,
        viewer.size().y,
        elapsed.as_secs_f64(),
        elapsed.as_secs_f64() * 1e3 / frames as f64,
        file.display()
    );
    if let Some(e) = stats.error {
        eprintln!(
            "error vs ray-cast truth: {} false shadow, {} false light of {} counted",
            e.false_shadow, e.false_light, e.counted
        );
    }
    Ok(())
}
