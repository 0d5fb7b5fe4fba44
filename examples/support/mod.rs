//! Shared by the examples: a device, the walkthrough scenario, argument
//! parsing helpers. (Adapter selection lives here, not in the library.)
#![allow(dead_code)]

use std::f64::consts::TAU;

use glam::{DVec3, UVec2};
use lixel::mesh::{load_obj, ProceduralScene, Scene};
use lixel::render::Renderer;
use lixel::{Camera, Light};

/// A device with the renderer's optional features where available; the
/// instance honours `WGPU_BACKEND`.
pub fn gpu() -> Result<(wgpu::Device, wgpu::Queue, wgpu::AdapterInfo), String> {
    let instance = wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
    let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions::default()))
        .map_err(|e| format!("no GPU adapter ({e}); on Debian: apt-get install mesa-vulkan-drivers"))?;
    let required_features = adapter.features() & Renderer::optional_features();
    // Large maps need the adapter's own texture limit (lavapipe: 16384).
    let required_limits =
        wgpu::Limits { max_texture_dimension_2d: adapter.limits().max_texture_dimension_2d, ..wgpu::Limits::default() };
    let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
        label: Some("lixel example device"),
        required_features,
        required_limits,
        ..Default::default()
    }))
    .map_err(|e| format!("cannot open the device: {e}"))?;
    Ok((device, queue, adapter.get_info()))
}

/// `--preset tiny|small|default|<triangle budget>` or `--obj path`.
pub fn scene(preset: &str, obj: Option<&str>) -> Result<Scene, String> {
    if let Some(path) = obj {
        return load_obj(path).map_err(|e| e.to_string());
    }
    Ok(match preset {
        "tiny" => ProceduralScene::tiny(),
        "small" => ProceduralScene::small(),
        "default" => ProceduralScene::default(),
        budget => match budget.parse::<usize>() {
            Ok(triangle_budget) => ProceduralScene { triangle_budget, ..ProceduralScene::default() },
            Err(_) => return Err(format!("unknown preset {budget:?} (tiny, small, default or a triangle budget)")),
        },
    }
    .build())
}

/// The walkthrough at time `t` in `[0, 1)`: a viewer slightly above the
/// floor walking a loop around the objects (just outside them, on the
/// floor), looking across the scene.
pub fn walk_camera(t: f64, size: UVec2) -> Camera {
    let a = TAU * t;
    let eye = DVec3::new(36.0 * a.cos(), 2.0, 36.0 * a.sin());
    // Look across the middle, a little ahead along the walk.
    let ahead = DVec3::new(-a.sin(), 0.0, a.cos());
    let target = DVec3::new(0.0, 0.5, 0.0) + 8.0 * ahead;
    Camera::look_at(eye, target, DVec3::Y, 60f64.to_radians(), size, 0.1, 200.0).expect("valid camera")
}

/// `count` lights at time `t`: a sun circling high in the sky, then point
/// lights circling above the scene at different heights.
pub fn moving_lights(t: f64, count: usize) -> Vec<Light> {
    (0..count)
        .map(|i| {
            let a = TAU * (t + i as f64 / count.max(1) as f64);
            if i == 0 {
                Light::directional(DVec3::new(0.5 * a.cos(), -1.0, 0.5 * a.sin()))
            } else {
                let r = 18.0 + 6.0 * i as f64;
                Light::point(DVec3::new(r * (-a).cos(), 35.0 + 5.0 * i as f64, r * (-a).sin()))
            }
        })
        .collect()
}

/// Light `k` of 500 on a distant hemisphere, as in the paper's experiment
/// (a deterministic Fibonacci spiral over the upper hemisphere).
pub fn hemisphere_light(k: usize, total: usize) -> Light {
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    let z = (k as f64 + 0.5) / total as f64; // height, uniform in (0, 1]
    let r = (1.0 - z * z).sqrt();
    let phi = golden * k as f64;
    Light::directional(-DVec3::new(r * phi.cos(), z, r * phi.sin()))
}

/// A tiny flag parser: `--name value` pairs and bare `--flag`s.
pub struct Args(Vec<String>);

impl Args {
    pub fn from_env() -> Self {
        Self(std::env::args().skip(1).collect())
    }

    pub fn flag(&self, name: &str) -> bool {
        self.0.iter().any(|a| a == name)
    }

    pub fn value(&self, name: &str) -> Option<&str> {
        self.0.iter().position(|a| a == name).and_then(|i| self.0.get(i + 1)).map(String::as_str)
    }

    pub fn parse<T: std::str::FromStr>(&self, name: &str, default: T) -> Result<T, String> {
        match self.value(name) {
            Some(v) => v.parse().map_err(|_| format!("{name}: cannot parse {v:?}")),
            None => Ok(default),
        }
    }

    pub fn list<T: std::str::FromStr + Clone>(&self, name: &str, default: &[T]) -> Result<Vec<T>, String> {
        match self.value(name) {
            Some(v) => v.split(',').map(|s| s.parse().map_err(|_| format!("{name}: cannot parse {s:?}"))).collect(),
            None => Ok(default.to_vec()),
        }
    }
}

/// Side-by-side montage of equally sized images, `columns` per row, with a
/// 4-pixel white gutter.
pub fn montage(images: &[image::RgbaImage], columns: usize) -> image::RgbaImage {
    let (w, h) = images.first().map_or((1, 1), |i| i.dimensions());
    let gutter = 4;
    let columns = columns.max(1) as u32;
    let rows = (images.len() as u32).div_ceil(columns);
    let mut out = image::RgbaImage::from_pixel(
        columns * (w + gutter) + gutter,
        rows * (h + gutter) + gutter,
        image::Rgba([255, 255, 255, 255]),
    );
    for (k, img) in images.iter().enumerate() {
        let (c, r) = (k as u32 % columns, k as u32 / columns);
        image::imageops::overlay(
            &mut out,
            img,
            i64::from(gutter + c * (w + gutter)),
            i64::from(gutter + r * (h + gutter)),
        );
    }
    out
}

/// The frame loop's policy by name: `focused`, `lispsm` or `optimized`.
pub fn parse_policy(name: &str) -> Result<lixel::render::LoopPolicy, String> {
    use lixel::render::LoopPolicy;
    use lixel::Parameterization;
    match name {
        "focused" => Ok(LoopPolicy::Fixed(Parameterization::Focused)),
        "focused-snapped" => Ok(LoopPolicy::Fixed(Parameterization::FocusedSnapped(Default::default()))),
        "lispsm" => Ok(LoopPolicy::Fixed(Parameterization::LiSpsm(Default::default()))),
        "optimized" => Ok(LoopPolicy::Optimized),
        other => Err(format!("unknown method {other:?} (focused, focused-snapped, lispsm, optimized)")),
    }
}

/// Settings of one run of the frame loop.
pub struct LoopConfig {
    /// Its name, as given to [`parse_policy`].
    pub method: String,
    pub policy: lixel::render::LoopPolicy,
    pub lights: usize,
    pub map: u32,
    pub size: u32,
    pub frames: u64,
    /// Frames of the walk per full loop (animation speed).
    pub frames_per_loop: u64,
    /// Frames in flight: after submitting frame `n`, wait for `n + 1 - in_flight`.
    pub in_flight: u64,
    /// Write `frame-NNNN.png` every this many frames into the directory.
    pub png: Option<(u64, std::path::PathBuf)>,
    /// Also measure each frame against the ray-cast truth (misclassified
    /// pixels, flicker since the previous frame). Costs a second camera pass
    /// with masks and a ray cast per frame, so frame times include it.
    pub flicker: bool,
}

/// What one frame did and cost.
#[derive(Clone, Debug, Default)]
pub struct FrameRecord {
    pub frame: u64,
    /// From this frame's start to the next frame's start.
    pub wall_ms: f64,
    /// Solving (or optimizing) the light matrices on the CPU.
    pub solve_ms: f64,
    /// Encoding and submitting.
    pub encode_ms: f64,
    pub gpu: Option<lixel::render::GpuFrameTimes>,
    pub analysis_queued: bool,
    pub analysis_skipped: bool,
    /// The analysis readback consumed this frame: (its frame, latency frames, ready ms, taken ms).
    pub readback: Option<(u64, u64, f64, f64)>,
    pub matrices_updated: usize,
    /// Shadow passes and the triangles they drew after per-object culling.
    pub shadow_passes: u32,
    pub shadow_triangles: u64,
    /// With `LoopConfig::flicker`: misclassified pixels summed over the
    /// lights, and the flicker since the previous frame (all lights).
    pub misclassified: Option<u64>,
    pub flicker: Option<lixel::mesh::Flicker>,
}

impl FrameRecord {
    pub const CSV_HEADER: &'static str = "frame,wall_ms,solve_ms,encode_ms,gpu_shadow_ms,gpu_camera_ms,gpu_analysis_ms,gpu_total_ms,analysis_queued,analysis_skipped,readback_frame,latency_frames,latency_ready_ms,latency_taken_ms,matrices_updated,shadow_passes,shadow_triangles,misclassified,flicker_stable,flicker_flipped";

    pub fn csv_row(&self) -> String {
        let ms = |d: Option<std::time::Duration>| d.map_or(String::new(), |d| format!("{:.3}", d.as_secs_f64() * 1e3));
        let g = self.gpu.unwrap_or_default();
        let (rb_frame, lat_frames, ready, taken) =
            self.readback.map_or((String::new(), String::new(), String::new(), String::new()), |r| {
                (r.0.to_string(), r.1.to_string(), format!("{:.3}", r.2), format!("{:.3}", r.3))
            });
        let opt = |v: Option<u64>| v.map_or(String::new(), |v| v.to_string());
        format!(
            "{},{:.3},{:.3},{:.3},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
            self.frame,
            self.wall_ms,
            self.solve_ms,
            self.encode_ms,
            ms(self.gpu.and(g.shadow)),
            ms(self.gpu.and(g.camera)),
            ms(self.gpu.and(g.analysis)),
            ms(self.gpu.and(g.total)),
            u8::from(self.analysis_queued),
            u8::from(self.analysis_skipped),
            rb_frame,
            lat_frames,
            ready,
            taken,
            self.matrices_updated,
            self.shadow_passes,
            self.shadow_triangles,
            opt(self.misclassified),
            opt(self.flicker.map(|f| f.stable)),
            opt(self.flicker.map(|f| f.flipped))
        )
    }
}

/// Runs the animated frame loop and returns one record per frame.
pub fn run_loop(
    renderer: &mut lixel::render::Renderer,
    scene: &Scene,
    config: &LoopConfig,
) -> Result<Vec<FrameRecord>, String> {
    use lixel::mesh::{Flicker, RayCaster, ShadowMasks};
    use lixel::render::{Frame, LoopOptions, LoopView, ShadowLoop};
    use lixel::ShadowMapSize;
    use std::time::Instant;

    let bounds = scene.bounds();
    // Per-light matrices, the paper's cadence (analysis every 3 frames, each
    // light's focused lookup every 5th pass), readback and optimizer.
    let mut shadows =
        ShadowLoop::new(config.policy.clone(), config.lights, LoopOptions::default()).map_err(|e| e.to_string())?;
    let mut records: Vec<FrameRecord> = Vec::with_capacity(config.frames as usize);
    let mut submissions = std::collections::VecDeque::new();
    let mut previous_start: Option<Instant> = None;
    let caster = config.flicker.then(|| RayCaster::new(scene));
    let mut previous: Option<(ShadowMasks, ShadowMasks)> = None;
    for n in 0..config.frames {
        let start = Instant::now();
        if let (Some(prev), Some(last)) = (previous_start, records.last_mut()) {
            last.wall_ms = start.duration_since(prev).as_secs_f64() * 1e3;
        }
        previous_start = Some(start);
        let mut record = FrameRecord { frame: n, ..Default::default() };

        let t = n as f64 / config.frames_per_loop as f64;
        let camera = walk_camera(t, UVec2::splat(config.size));
        let lights = moving_lights(0.37 * t, config.lights);
        let view = LoopView { camera: &camera, lights: &lights, bounds, map: ShadowMapSize::square(config.map) };
        let frame = shadows.frame(renderer, &view).map_err(|e| e.to_string())?;
        if let Some(r) = &frame.readback {
            record.readback = Some((
                r.frame,
                r.latency.frames,
                r.latency.ready.as_secs_f64() * 1e3,
                r.latency.taken.as_secs_f64() * 1e3,
            ));
        }
        record.matrices_updated = frame.optimized.count_ones() as usize;
        record.solve_ms = (frame.optimize_time + frame.solve_time).as_secs_f64() * 1e3;
        let report = frame.render;
        record.encode_ms = report.cpu_time.as_secs_f64() * 1e3;
        record.analysis_queued = report.analysis_queued;
        record.analysis_skipped = report.analysis_skipped;
        record.shadow_passes = report.shadow_passes;
        record.shadow_triangles = report.shadow_triangles;
        submissions.push_back(report.submission);

        if let Some(caster) = &caster {
            // The frame's matrices again, with masks, against the ray-cast truth.
            let report = renderer
                .render(&Frame { masks: true, ..Frame::new(&camera, &frame.matrices) })
                .map_err(|e| e.to_string())?;
            renderer.wait_for(&report.submission).map_err(|e| e.to_string())?;
            let masks = renderer.read_masks().map_err(|e| e.to_string())?;
            let truth = caster.trace_masks(&camera, &lights, config.size, config.size);
            let lights = 0..lights.len() as u32;
            record.misclassified = Some(lights.clone().filter_map(|l| masks.misclassified(&truth, l)).sum());
            if let Some((prev, prev_truth)) = &previous {
                let each = lights.map(|l| Flicker::between(l, prev, prev_truth, &masks, &truth));
                record.flicker = Some(each.fold(Flicker::default(), Flicker::merged));
            }
            previous = Some((masks, truth));
        }

        if let Some((every, dir)) = &config.png {
            if n % every == 0 {
                let image = renderer.read_color().map_err(|e| e.to_string())?;
                image.save(dir.join(format!("frame-{n:04}.png"))).map_err(|e| e.to_string())?;
            }
        }
        // Frame pacing, like a swapchain: at most `in_flight` frames queued.
        while submissions.len() as u64 >= config.in_flight.max(1) {
            let oldest = submissions.pop_front().expect("non-empty");
            renderer.wait_for(&oldest).map_err(|e| e.to_string())?;
        }
        while let Some(times) = renderer.try_take_gpu_times() {
            if let Some(r) = records.get_mut(times.frame as usize) {
                r.gpu = Some(times);
            } else if times.frame == n {
                record.gpu = Some(times);
            }
        }
        records.push(record);
    }
    renderer.wait_idle().map_err(|e| e.to_string())?;
    if let (Some(prev), Some(last)) = (previous_start, records.last_mut()) {
        last.wall_ms = prev.elapsed().as_secs_f64() * 1e3;
    }
    while let Some(times) = renderer.try_take_gpu_times() {
        if let Some(r) = records.get_mut(times.frame as usize) {
            r.gpu = Some(times);
        }
    }
    Ok(records)
}

/// `--preset NAME` (default `quick`) as the experiment's preset, by the
/// CLI's own names.
#[cfg(feature = "cli")]
pub fn preset(args: &Args) -> Result<lixel::experiment::Preset, String> {
    let name = args.value("--preset").unwrap_or("quick");
    <lixel::experiment::Preset as clap::ValueEnum>::from_str(name, false).map_err(|e| format!("--preset: {e}"))
}
