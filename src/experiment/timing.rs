//! The paper's Table 2: frame time against the number of lights and the map
//! resolution, for scene-optimized, focused and LiSPSM maps, measured in one
//! run so that the ratios are comparable; plus "focused + analysis" (focused
//! maps shown while the analysis passes, readbacks and optimizations run and
//! are thrown away), which isolates the machinery's own cost from what the
//! optimized maps' shapes do to the shadow and camera passes.
//!
//! The four pipelines are interleaved in blocks of whole optimizer cadences
//! (15 frames: five analysis passes, each light looked up once in a focused
//! map), the order rotating from round to round, so that drift in the
//! machine's speed reaches all of them alike. A block is timed from an idle
//! device to an idle device, so it holds all the GPU work of its frames;
//! within a block at most one frame is in flight besides the one being built.

use std::time::{Duration, Instant};

use glam::DVec3;

use super::{camera_for, light_for, load_scene, ExperimentConfig, ExperimentError};
use crate::optimize::{Optimizer, ScheduleOptions, ShadowScheduler};
use crate::render::{AnalysisRequest, Frame, Renderer};
use crate::{Camera, Light, LightMatrix, Parameterization, SceneBounds, ShadowMapSize, ShadowProblem};

/// What to time.
#[derive(Clone, Debug, PartialEq)]
pub struct TimingOptions {
    /// Light counts.
    pub lights: Vec<usize>,
    /// Square map sizes.
    pub maps: Vec<u32>,
    /// Frames timed per pipeline and cell, rounded up to whole blocks.
    pub frames: usize,
    /// Frames per block: one whole optimizer cadence (`optimize_every x
    /// focused_every` = 15 by default) so that every block holds the same
    /// mix of analysis passes.
    pub block: usize,
    /// Untimed blocks of each pipeline before the timed rounds of a cell.
    pub warmup_blocks: usize,
}

impl Default for TimingOptions {
    fn default() -> Self {
        Self { lights: vec![1, 2, 3, 4], maps: vec![500, 700, 1000], frames: 60, block: 15, warmup_blocks: 1 }
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
    /// Mean frame time of focused maps plus the scene-optimized pipeline's
    /// analysis passes, readbacks and optimizations, whose results are not
    /// used: the machinery's own cost, apart from what the optimized maps'
    /// shapes do to the shadow and camera passes.
    pub focused_with_analysis: Duration,
    /// Per-round ratios optimized / focused (each round times one block of
    /// each pipeline back to back): median, smallest and largest.
    pub round_ratios: [f64; 3],
    /// Timed rounds.
    pub rounds: usize,
    /// Optimizations run during the timed frames.
    pub optimizations: usize,
    /// Analysis passes queued during the timed frames.
    pub analyses: usize,
}

impl TimingRow {
    /// Mean optimized / focused frame time.
    #[must_use]
    pub fn optimized_ratio(&self) -> f64 {
        self.optimized.as_secs_f64() / self.focused.as_secs_f64()
    }

    /// Mean (focused + analysis) / focused frame time.
    #[must_use]
    pub fn analysis_ratio(&self) -> f64 {
        self.focused_with_analysis.as_secs_f64() / self.focused.as_secs_f64()
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Pipeline {
    Focused,
    LiSpsm,
    Optimized,
    /// Focused maps shown; analysis and optimization run but are discarded.
    FocusedWithAnalysis,
}

impl Pipeline {
    fn analyses(self) -> bool {
        matches!(self, Self::Optimized | Self::FocusedWithAnalysis)
    }
}

/// A slow walk along the view direction so that matrices change every frame.
fn walk(base: &Camera, frame: u64) -> Camera {
    let t = frame as f64;
    let eye = base.eye() + base.view_direction() * (0.02 * t) + DVec3::X * (0.01 * t);
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

/// One cell's fixed inputs.
struct Cell<'a> {
    base: Camera,
    lights: &'a [Light],
    bounds: SceneBounds,
    map: ShadowMapSize,
}

impl Cell<'_> {
    fn solve(&self, camera: Camera, map: ShadowMapSize, how: &Parameterization) -> crate::Result<Vec<LightMatrix>> {
        self.lights.iter().map(|&l| ShadowProblem::new(camera, l, self.bounds, map)?.solve(how)).collect()
    }
}

/// One pipeline's state, kept across its blocks.
struct Run {
    pipeline: Pipeline,
    frame: u64,
    scheduler: ShadowScheduler,
    optimizations: usize,
    analyses: usize,
    timed: Vec<Duration>,
}

impl Run {
    fn new(pipeline: Pipeline, lights: usize) -> Result<Self, ExperimentError> {
        let scheduler = ShadowScheduler::new(lights, ScheduleOptions::default(), Optimizer::new(Default::default()))?;
        Ok(Self { pipeline, frame: 0, scheduler, optimizations: 0, analyses: 0, timed: Vec::new() })
    }

    /// Feeds every light the newest readback, if one has arrived (never waits).
    fn consume_readback(&mut self, renderer: &mut Renderer, cell: &Cell<'_>) -> Result<usize, ExperimentError> {
        let Some(readback) = renderer.try_take_analysis() else { return Ok(0) };
        let mut optimized = 0;
        // The samples belong to the camera the pass was rendered with.
        for (i, samples) in readback.samples_all(cell.lights, cell.bounds, cell.map).into_iter().enumerate() {
            if self.scheduler.update(i, &samples?, self.frame).is_ok() {
                optimized += 1;
            }
        }
        Ok(optimized)
    }

    /// Renders `frames` frames from an idle device to an idle device and
    /// returns the wall time.
    fn block(&mut self, renderer: &mut Renderer, cell: &Cell<'_>, frames: usize) -> Result<Duration, ExperimentError> {
        renderer.wait_idle()?;
        let start = Instant::now();
        let mut previous = None;
        let (mut optimizations, mut analyses) = (0, 0);
        for _ in 0..frames {
            let camera = walk(&cell.base, self.frame);
            if self.pipeline.analyses() {
                optimizations += self.consume_readback(renderer, cell)?;
            }
            let matrices = match self.pipeline {
                Pipeline::Focused | Pipeline::FocusedWithAnalysis => {
                    cell.solve(camera, cell.map, &Parameterization::Focused)?
                }
                Pipeline::LiSpsm => cell.solve(camera, cell.map, &Parameterization::LiSpsm(Default::default()))?,
                Pipeline::Optimized => {
                    let mut matrices = Vec::with_capacity(cell.lights.len());
                    for i in 0..cell.lights.len() {
                        matrices.push(match self.scheduler.matrix(i) {
                            Some(m) => *m,
                            None => ShadowProblem::new(camera, cell.lights[i], cell.bounds, cell.map)?
                                .solve(&Parameterization::Focused)?,
                        });
                    }
                    matrices
                }
            };
            let mut analysis_lights = Vec::new();
            let mut analysis = false;
            if let Some(plan) = self.scheduler.plan(self.frame).analysis.filter(|_| self.pipeline.analyses()) {
                analysis = true;
                if plan.focused != 0 {
                    // Focused maps for the lights whose turn it is; the rest
                    // reuse the frame's maps.
                    let size = self.scheduler.focused_analysis_size(cell.map);
                    for (i, &light) in cell.lights.iter().enumerate() {
                        analysis_lights.push(if plan.is_focused(i) {
                            ShadowProblem::new(camera, light, cell.bounds, size)?.solve(&Parameterization::Focused)?
                        } else {
                            matrices[i]
                        });
                    }
                }
            }
            let request = analysis.then(|| AnalysisRequest {
                lights: (!analysis_lights.is_empty()).then_some(&analysis_lights[..]),
                tag: 0,
            });
            let report =
                renderer.render(&Frame { camera: &camera, lights: &matrices, masks: false, analysis: request })?;
            analyses += usize::from(report.analysis_queued);
            // At most one frame in flight besides the next one being built.
            if let Some(prev) = previous.replace(report.submission) {
                renderer.wait_for(&prev)?;
            }
            self.frame += 1;
        }
        renderer.wait_idle()?;
        let elapsed = start.elapsed();
        self.optimizations += optimizations;
        self.analyses += analyses;
        Ok(elapsed)
    }
}

fn median(values: &mut [f64]) -> f64 {
    values.sort_by(f64::total_cmp);
    match values.len() {
        0 => f64::NAN,
        n if n % 2 == 1 => values[n / 2],
        n => 0.5 * (values[n / 2 - 1] + values[n / 2]),
    }
}

/// Measures the table on `config`'s scene and screen; `progress` sees each
/// cell as it finishes.
///
/// # Errors
/// Scene, renderer and solver failures.
pub fn run_timing(
    config: &ExperimentConfig,
    options: &TimingOptions,
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    mut progress: impl FnMut(&TimingRow),
) -> Result<Vec<TimingRow>, ExperimentError> {
    let scene = load_scene(&config.scene)?;
    let base = camera_for(config, &scene)?;
    let mut renderer = Renderer::new(device, queue, &scene, super::experiment_renderer_options())?;
    let block = options.block.max(1);
    let rounds = options.frames.div_ceil(block).max(1);
    let mut rows = Vec::new();
    for &map in &options.maps {
        for &count in &options.lights {
            let lights: Vec<Light> = (0..count).map(|i| light_for(config, &scene, i)).collect();
            let cell = Cell { base, lights: &lights, bounds: scene.bounds(), map: ShadowMapSize::square(map) };
            let mut runs = [Pipeline::Focused, Pipeline::LiSpsm, Pipeline::Optimized, Pipeline::FocusedWithAnalysis]
                .map(|p| Run::new(p, count))
                .into_iter()
                .collect::<Result<Vec<_>, _>>()?;
            for run in &mut runs {
                for _ in 0..options.warmup_blocks {
                    run.block(&mut renderer, &cell, block)?;
                }
                run.optimizations = 0;
                run.analyses = 0;
            }
            for round in 0..rounds {
                let pipelines = runs.len();
                for k in 0..pipelines {
                    let run = &mut runs[(round + k) % pipelines];
                    let elapsed = run.block(&mut renderer, &cell, block)?;
                    run.timed.push(elapsed);
                }
            }
            let mean = |run: &Run| run.timed.iter().sum::<Duration>() / (rounds * block) as u32;
            let mut ratios: Vec<f64> =
                runs[2].timed.iter().zip(&runs[0].timed).map(|(o, f)| o.as_secs_f64() / f.as_secs_f64()).collect();
            let (lowest, highest) = ratios.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), &r| (lo.min(r), hi.max(r)));
            let row = TimingRow {
                lights: count,
                map,
                focused: mean(&runs[0]),
                lispsm: mean(&runs[1]),
                optimized: mean(&runs[2]),
                focused_with_analysis: mean(&runs[3]),
                round_ratios: [median(&mut ratios), lowest, highest],
                rounds,
                optimizations: runs[2].optimizations,
                analyses: runs[2].analyses,
            };
            progress(&row);
            rows.push(row);
            // Readbacks left in the ring belong to this cell.
            renderer.wait_idle()?;
            while renderer.try_take_analysis().is_some() {}
        }
    }
    Ok(rows)
}

/// The table as markdown, ratios against focused.
#[must_use]
pub fn timing_markdown(rows: &[TimingRow]) -> String {
    let mut md = String::from(
        "| lights | map | focused ms | LiSPSM ms | scene-optimized ms | focused + analysis ms | LiSPSM / focused | optimized / focused | per round: median (min–max) | (focused + analysis) / focused | analyses | optimizations |\n\
         |---:|---:|---:|---:|---:|---:|---:|---:|---|---:|---:|---:|\n",
    );
    for r in rows {
        let ms = |d: Duration| d.as_secs_f64() * 1e3;
        let [median, lowest, highest] = r.round_ratios;
        md.push_str(&format!(
            "| {} | {}² | {:.1} | {:.1} | {:.1} | {:.1} | {:.3} | {:.3} | {median:.3} ({lowest:.3}–{highest:.3}) | {:.3} | {} | {} |\n",
            r.lights,
            r.map,
            ms(r.focused),
            ms(r.lispsm),
            ms(r.optimized),
            ms(r.focused_with_analysis),
            ms(r.lispsm) / ms(r.focused),
            r.optimized_ratio(),
            r.analysis_ratio(),
            r.analyses,
            r.optimizations
        ));
    }
    if !rows.is_empty() {
        for (what, ratio) in [
            ("Scene-optimized / focused", TimingRow::optimized_ratio as fn(&TimingRow) -> f64),
            ("(Focused + analysis) / focused", TimingRow::analysis_ratio),
        ] {
            let mut all: Vec<f64> = rows.iter().map(ratio).collect();
            let largest = all.iter().copied().fold(0.0f64, f64::max);
            md.push_str(&format!("\n{what} over all cells: median {:.3}, largest {largest:.3}.", median(&mut all)));
        }
        md.push('\n');
    }
    md
}
