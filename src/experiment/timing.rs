//! The paper's Table 2: frame time against the number of lights and the map
//! resolution, for scene-optimized, focused and LiSPSM maps, measured in one
//! run so that the ratios are comparable.

use std::time::{Duration, Instant};

use glam::DVec3;

use super::{camera_for, light_for, load_scene, ExperimentConfig, ExperimentError};
use crate::optimize::{AnalysisKind, Optimizer, Readback, SampleOptions, ScheduleOptions, ShadowScheduler};
use crate::render::{AnalysisRequest, Frame, Renderer};
use crate::{Camera, LightMatrix, Parameterization, Samples, ShadowMapSize, ShadowProblem};

/// What to time.
#[derive(Clone, Debug, PartialEq)]
pub struct TimingOptions {
    /// Light counts.
    pub lights: Vec<usize>,
    /// Square map sizes.
    pub maps: Vec<u32>,
    /// Frames timed per cell (after `warmup`).
    pub frames: usize,
    /// Frames run first and not timed.
    pub warmup: usize,
}

impl Default for TimingOptions {
    fn default() -> Self {
        Self { lights: vec![1, 2, 3, 4], maps: vec![500, 700, 1000], frames: 30, warmup: 6 }
    }
}

/// One cell of the table.
#[derive(Clone, Debug, PartialEq)]
pub struct TimingRow {
    /// Lights.
    pub lights: usize,
    /// Map size.
    pub map: u32,
    /// Mean frame time with focused maps.
    pub focused: Duration,
    /// Mean frame time with LiSPSM maps.
    pub lispsm: Duration,
    /// Mean frame time of the scene-optimized pipeline (analysis every 3
    /// frames, readback consumed when it arrives, optimization per light).
    pub optimized: Duration,
    /// Optimizations run during the timed frames.
    pub optimizations: usize,
}

#[derive(Clone, Copy, PartialEq, Eq)]
enum Pipeline {
    Focused,
    LiSpsm,
    Optimized,
}

/// A slow walk along the view direction so that matrices change every frame.
fn walk(base: &Camera, frame: usize) -> Camera {
    let eye = base.eye() + base.view_direction() * (0.02 * frame as f64) + DVec3::X * (0.01 * frame as f64);
    Camera::look_at(
        eye,
        eye + base.view_direction(),
        DVec3::Y,
        60f64.to_radians(),
        base.viewport(),
        base.z_near(),
        base.z_far(),
    )
    .unwrap_or(*base)
}

/// Measures the table on `config`'s scene and screen.
///
/// # Errors
/// Scene, renderer and solver failures.
pub fn run_timing(
    config: &ExperimentConfig,
    options: &TimingOptions,
    device: &wgpu::Device,
    queue: &wgpu::Queue,
) -> Result<Vec<TimingRow>, ExperimentError> {
    let scene = load_scene(&config.scene)?;
    let base = camera_for(config, &scene)?;
    let mut renderer = Renderer::new(device, queue, &scene, super::experiment_renderer_options())?;
    let bounds = scene.bounds();
    let mut rows = Vec::new();
    for &map in &options.maps {
        for &count in &options.lights {
            let lights: Vec<_> = (0..count).map(|i| light_for(config, &scene, i)).collect();
            let mut time = |pipeline| -> Result<(Duration, usize), ExperimentError> {
                let mut scheduler =
                    ShadowScheduler::new(count, ScheduleOptions::default(), Optimizer::new(Default::default()))?;
                let mut optimizations = 0;
                let mut previous = None;
                let mut timed = Duration::ZERO;
                for frame in 0..options.warmup + options.frames {
                    let start = Instant::now();
                    let camera = walk(&base, frame);
                    let problems: Vec<ShadowProblem> = lights
                        .iter()
                        .map(|&l| ShadowProblem::new(camera, l, bounds, ShadowMapSize::square(map)))
                        .collect::<Result<_, _>>()?;
                    let solve = |p: &ShadowProblem, param: &Parameterization| p.solve(param);
                    let matrices: Vec<LightMatrix> = match pipeline {
                        Pipeline::Focused => {
                            problems.iter().map(|p| solve(p, &Parameterization::Focused)).collect::<Result<_, _>>()?
                        }
                        Pipeline::LiSpsm => problems
                            .iter()
                            .map(|p| solve(p, &Parameterization::LiSpsm(Default::default())))
                            .collect::<Result<_, _>>()?,
                        Pipeline::Optimized => {
                            // Consume a readback if one has arrived (never wait).
                            if let Some(readback) = renderer.try_take_analysis() {
                                let (bits, normals) = readback.optimizer_buffers();
                                let masks = &readback.masks;
                                let input = Readback {
                                    width: masks.width,
                                    height: masks.height,
                                    depth: &masks.depth,
                                    shadow_bits: &bits,
                                    normals: Some(&normals),
                                };
                                for (i, p) in problems.iter().enumerate() {
                                    let samples =
                                        Samples::from_readback(p, &input, i as u32, &SampleOptions::default())?;
                                    if scheduler.update(i, &samples, frame as u64).is_ok() {
                                        optimizations += usize::from(frame >= options.warmup);
                                    }
                                }
                            }
                            problems
                                .iter()
                                .enumerate()
                                .map(|(i, p)| match scheduler.matrix(i) {
                                    Some(m) => Ok(*m),
                                    None => solve(p, &Parameterization::Focused),
                                })
                                .collect::<Result<_, _>>()?
                        }
                    };
                    let focused: Vec<LightMatrix>;
                    let analysis = match (pipeline, scheduler.plan(frame as u64).analysis) {
                        (Pipeline::Optimized, Some(kind)) => {
                            focused = if kind == AnalysisKind::Focused {
                                problems
                                    .iter()
                                    .map(|p| solve(p, &Parameterization::Focused))
                                    .collect::<Result<_, _>>()?
                            } else {
                                Vec::new()
                            };
                            Some(AnalysisRequest { lights: (!focused.is_empty()).then_some(&focused[..]), tag: 0 })
                        }
                        _ => None,
                    };
                    let report =
                        renderer.render(&Frame { camera: &camera, lights: &matrices, masks: false, analysis })?;
                    // At most one frame in flight: wait for the previous one.
                    if let Some(prev) = previous.replace(report.submission) {
                        renderer.wait_for(&prev)?;
                    }
                    if frame >= options.warmup {
                        timed += start.elapsed();
                    }
                }
                renderer.wait_idle()?;
                while renderer.try_take_analysis().is_some() {}
                Ok((timed / options.frames.max(1) as u32, optimizations))
            };
            let (focused, _) = time(Pipeline::Focused)?;
            let (lispsm, _) = time(Pipeline::LiSpsm)?;
            let (optimized, optimizations) = time(Pipeline::Optimized)?;
            rows.push(TimingRow { lights: count, map, focused, lispsm, optimized, optimizations });
        }
    }
    Ok(rows)
}

/// The table as markdown, ratios against focused.
#[must_use]
pub fn timing_markdown(rows: &[TimingRow]) -> String {
    let mut md = String::from(
        "| lights | map | focused ms | LiSPSM ms | scene-optimized ms | LiSPSM / focused | optimized / focused | optimizations |\n|---:|---:|---:|---:|---:|---:|---:|---:|\n",
    );
    for r in rows {
        let ms = |d: Duration| d.as_secs_f64() * 1e3;
        md.push_str(&format!(
            "| {} | {}² | {:.1} | {:.1} | {:.1} | {:.3} | {:.3} | {} |\n",
            r.lights,
            r.map,
            ms(r.focused),
            ms(r.lispsm),
            ms(r.optimized),
            ms(r.lispsm) / ms(r.focused),
            ms(r.optimized) / ms(r.focused),
            r.optimizations
        ));
    }
    md
}
