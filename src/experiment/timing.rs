//! The paper's Table 2: frame time against the number of lights and the map
//! resolution, for scene-optimized, focused and LiSPSM maps, measured in one
//! run so that the ratios are comparable; plus "focused + analysis" (focused
//! maps shown while the analysis passes, readbacks and optimizations run and
//! are thrown away), which isolates the machinery's own cost from what the
//! optimized maps' shapes do to the shadow and camera passes; and "focused +
//! `<lookup>`" for each lookup mode asked for ([`TimingOptions::lookups`]:
//! focused maps with, e.g., the SPSM lookup, its conservative shadow pass and
//! its lookup), paired against focused.
//!
//! The pipelines are interleaved in blocks of whole optimizer cadences
//! (15 frames: five analysis passes, each light looked up once in a focused
//! map), the order rotating from round to round, so that drift in the
//! machine's speed reaches all of them alike. A block is timed from an idle
//! device to an idle device, so it holds all the GPU work of its frames;
//! within a block at most one frame is in flight besides the one being built.

use std::time::{Duration, Instant};

use glam::DVec3;

use super::{camera_for, light_for, load_scene, ExperimentConfig, ExperimentError};
use crate::render::{
    GpuFrameTimes, LoopOptions, LoopPolicy, LoopView, Renderer, RendererOptions, ShadowLookup, ShadowLoop, SpsmOptions,
};

/// Pipelines of every cell before the lookup pipelines, in the order of
/// [`TimingRow::frame_times`].
const BASE_PIPELINES: usize = 4;
use crate::{Camera, Light, Parameterization, SceneBounds, ShadowMapSize};

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
    /// Collect GPU time per stage ([`StageTimes`]) with timestamp queries.
    /// Off by default: timestamps add work at every pass boundary, more for
    /// pipelines with more passes (on lavapipe, 4 lights, 1000² maps, one run
    /// each: optimized / focused 1.14 with them, 1.07 without), so a run with
    /// them is a breakdown, not the table.
    pub gpu_stages: bool,
    /// Lookup modes timed as "focused + `<lookup>`" pipelines, after the four
    /// standard ones (default: SPSM). Each adds a pipeline to every round.
    pub lookups: Vec<ShadowLookup>,
}

impl Default for TimingOptions {
    fn default() -> Self {
        Self {
            lights: vec![1, 2, 3, 4],
            maps: vec![500, 700, 1000],
            frames: 60,
            block: 15,
            warmup_blocks: 1,
            gpu_stages: false,
            lookups: vec![ShadowLookup::Spsm(SpsmOptions::default())],
        }
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
    /// Mean frame time of focused maps with each of
    /// [`TimingOptions::lookups`].
    pub focused_lookups: Vec<(ShadowLookup, Duration)>,
    /// Wall time of every timed block, per pipeline in the order of
    /// [`pipelines`](Self::pipelines); block `k` of every pipeline belongs to
    /// round `k` (the same frames of the walk, timed back to back), so they
    /// pair up.
    pub blocks: Vec<Vec<Duration>>,
    /// Timed rounds.
    pub rounds: usize,
    /// Optimizations run during the timed frames.
    pub optimizations: usize,
    /// Analysis passes queued during the timed frames.
    pub analyses: usize,
    /// Mean process CPU time per frame (all threads, lavapipe's included),
    /// per pipeline in the order of [`pipelines`](Self::pipelines); `None`
    /// off Linux.
    pub cpu: Vec<Option<Duration>>,
    /// Where each pipeline's frame time went, in the order of
    /// [`pipelines`](Self::pipelines).
    pub stages: Vec<StageTimes>,
}

/// The standard pipelines of a [`TimingRow`], first in
/// [`TimingRow::pipelines`]; the lookup pipelines follow.
pub const PIPELINES: [&str; BASE_PIPELINES] = ["focused", "LiSPSM", "scene-optimized", "focused + analysis"];

/// Mean cost per frame of one pipeline's stages over the timed frames.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StageTimes {
    /// GPU time of the shadow passes (timestamp queries; `None` without
    /// them). Includes the analysis pass's own focused maps.
    pub shadow: Option<Duration>,
    /// GPU time of the camera pass.
    pub camera: Option<Duration>,
    /// GPU time of the analysis pass, averaged over every frame (zero for
    /// pipelines without one).
    pub analysis: Option<Duration>,
    /// CPU time turning readbacks into samples and optimizing, averaged over
    /// every frame.
    pub optimize: Duration,
    /// CPU time solving the frame's matrices (focused, LiSPSM, and the
    /// analysis pass's focused maps), averaged over every frame.
    pub solve: Duration,
    /// Frames whose GPU timestamps came back (a sample of the timed frames).
    pub gpu_frames: usize,
}

/// Running sums behind a [`StageTimes`].
#[derive(Clone, Copy, Debug, Default)]
struct StageSums {
    shadow: Duration,
    camera: Duration,
    analysis: Duration,
    gpu_frames: u32,
    optimize: Duration,
    solve: Duration,
    frames: u32,
}

impl StageSums {
    fn add_gpu(&mut self, times: &GpuFrameTimes) {
        let (Some(camera), Some(shadow)) = (times.camera, times.shadow) else { return };
        self.shadow += shadow;
        self.camera += camera;
        self.analysis += times.analysis.unwrap_or_default();
        self.gpu_frames += 1;
    }

    fn merge(&mut self, other: &Self) {
        self.shadow += other.shadow;
        self.camera += other.camera;
        self.analysis += other.analysis;
        self.gpu_frames += other.gpu_frames;
        self.optimize += other.optimize;
        self.solve += other.solve;
        self.frames += other.frames;
    }

    fn means(&self) -> StageTimes {
        let gpu = |d: Duration| (self.gpu_frames > 0).then(|| d / self.gpu_frames);
        let cpu = |d: Duration| d / self.frames.max(1);
        StageTimes {
            shadow: gpu(self.shadow),
            camera: gpu(self.camera),
            analysis: gpu(self.analysis),
            optimize: cpu(self.optimize),
            solve: cpu(self.solve),
            gpu_frames: self.gpu_frames as usize,
        }
    }
}

impl TimingRow {
    /// Every pipeline's name: [`PIPELINES`], then `focused + <lookup>` for
    /// each of [`focused_lookups`](Self::focused_lookups).
    #[must_use]
    pub fn pipelines(&self) -> Vec<String> {
        let lookups = self.focused_lookups.iter().map(|(l, _)| format!("focused + {}", l.name()));
        PIPELINES.iter().map(|p| (*p).to_owned()).chain(lookups).collect()
    }

    /// Mean frame time per pipeline, in the order of
    /// [`pipelines`](Self::pipelines).
    #[must_use]
    pub fn frame_times(&self) -> Vec<Duration> {
        let base = [self.focused, self.lispsm, self.optimized, self.focused_with_analysis];
        base.into_iter().chain(self.focused_lookups.iter().map(|(_, d)| *d)).collect()
    }

    /// Mean frame time of pipeline `k` ([`pipelines`](Self::pipelines)) over
    /// focused's.
    #[must_use]
    pub fn ratio(&self, k: usize) -> f64 {
        let times = self.frame_times();
        times[k].as_secs_f64() / times[0].as_secs_f64()
    }

    /// Mean optimized / focused frame time.
    #[must_use]
    pub fn optimized_ratio(&self) -> f64 {
        self.ratio(2)
    }

    /// Per-round ratios of pipeline `k` ([`pipelines`](Self::pipelines)) to
    /// focused.
    #[must_use]
    pub fn round_ratios(&self, k: usize) -> Vec<f64> {
        self.round_ratios_to(k, 0)
    }

    /// Per-round ratios of pipeline `k` to pipeline `base` (both indices
    /// into [`pipelines`](Self::pipelines)): block `r` of each was timed in
    /// round `r`, so they pair up as [`round_ratios`](Self::round_ratios)
    /// do (e.g. `focused + ss32` against `focused + aa32`).
    #[must_use]
    pub fn round_ratios_to(&self, k: usize, base: usize) -> Vec<f64> {
        self.blocks[k].iter().zip(&self.blocks[base]).map(|(p, b)| p.as_secs_f64() / b.as_secs_f64()).collect()
    }

    /// Mean optimized / focused process CPU time per frame.
    #[must_use]
    pub fn optimized_cpu_ratio(&self) -> Option<f64> {
        Some(self.cpu[2]?.as_secs_f64() / self.cpu[0]?.as_secs_f64())
    }

    /// Mean (focused + analysis) / focused frame time.
    #[must_use]
    pub fn analysis_ratio(&self) -> f64 {
        self.ratio(3)
    }

    /// Mean (focused + `lookup`) / focused frame time; `None` when `lookup`
    /// was not timed.
    #[must_use]
    pub fn lookup_ratio(&self, lookup: ShadowLookup) -> Option<f64> {
        let i = self.focused_lookups.iter().position(|(l, _)| *l == lookup)?;
        Some(self.ratio(BASE_PIPELINES + i))
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Pipeline {
    Focused,
    LiSpsm,
    Optimized,
    /// Focused maps shown; analysis and optimization run but are discarded.
    FocusedWithAnalysis,
    /// Focused maps with another lookup.
    FocusedLookup(ShadowLookup),
}

impl Pipeline {
    /// The frame loop's policy for this pipeline.
    fn policy(self) -> LoopPolicy {
        match self {
            Self::Focused => LoopPolicy::Fixed(Parameterization::Focused),
            Self::LiSpsm => LoopPolicy::Fixed(Parameterization::LiSpsm(Default::default())),
            Self::Optimized => LoopPolicy::Optimized,
            Self::FocusedWithAnalysis => LoopPolicy::FixedWithAnalysis(Parameterization::Focused),
            Self::FocusedLookup(_) => LoopPolicy::Fixed(Parameterization::Focused),
        }
    }

    /// The frame loop's settings (the lookup) for this pipeline.
    fn options(self) -> LoopOptions {
        match self {
            Self::FocusedLookup(lookup) => LoopOptions { lookup, ..Default::default() },
            _ => LoopOptions::default(),
        }
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

/// One pipeline's state, kept across its blocks.
struct Run {
    shadows: ShadowLoop,
    optimizations: usize,
    analyses: usize,
    timed: Vec<Duration>,
    /// CPU time of each timed block (`None` where unavailable).
    cpu: Vec<Option<Duration>>,
    /// Sums over the timed blocks.
    sums: StageSums,
}

impl Run {
    fn new(pipeline: Pipeline, lights: usize) -> Result<Self, ExperimentError> {
        Ok(Self {
            shadows: ShadowLoop::new(pipeline.policy(), lights, pipeline.options())?,
            optimizations: 0,
            analyses: 0,
            timed: Vec::new(),
            cpu: Vec::new(),
            sums: StageSums::default(),
        })
    }

    /// Renders `frames` frames from an idle device to an idle device; a
    /// `timed` block records its wall time, the process's CPU time, its
    /// stage sums and its counts (a warm-up block only advances the walk and
    /// the optimizer).
    fn block(
        &mut self,
        renderer: &mut Renderer,
        cell: &Cell<'_>,
        frames: usize,
        timed: bool,
    ) -> Result<(), ExperimentError> {
        renderer.wait_idle()?;
        let cpu_start = process_cpu_time();
        let start = Instant::now();
        let mut previous = None;
        let (mut optimizations, mut analyses) = (0, 0);
        let mut sums = StageSums::default();
        for _ in 0..frames {
            let camera = walk(&cell.base, self.shadows.frames());
            let view = LoopView { camera: &camera, lights: cell.lights, bounds: cell.bounds, map: cell.map };
            let frame = self.shadows.frame(renderer, &view)?;
            sums.optimize += frame.optimize_time;
            sums.solve += frame.solve_time;
            optimizations += frame.optimized.count_ones() as usize;
            analyses += usize::from(frame.render.analysis_queued);
            // At most one frame in flight besides the next one being built.
            if let Some(prev) = previous.replace(frame.render.submission) {
                renderer.wait_for(&prev)?;
            }
            while let Some(times) = renderer.try_take_gpu_times() {
                sums.add_gpu(&times);
            }
            sums.frames += 1;
        }
        renderer.wait_idle()?;
        let elapsed = start.elapsed();
        let cpu = process_cpu_time().zip(cpu_start).map(|(end, begin)| end.saturating_sub(begin));
        while let Some(times) = renderer.try_take_gpu_times() {
            sums.add_gpu(&times);
        }
        if timed {
            self.timed.push(elapsed);
            self.cpu.push(cpu);
            self.sums.merge(&sums);
            self.optimizations += optimizations;
            self.analyses += analyses;
        }
        Ok(())
    }
}

/// CPU time of this process so far, all threads together (on lavapipe the
/// "GPU" is the rasterizer's threads, so this is the work a frame costs, less
/// exposed to other load on the machine than wall time). Linux only (the sum
/// of `/proc/self/task/*/schedstat`); `None` elsewhere.
fn process_cpu_time() -> Option<Duration> {
    let mut total = 0u64;
    for task in std::fs::read_dir("/proc/self/task").ok()? {
        let Ok(task) = task else { continue };
        // A thread may exit between listing and reading: skip it.
        let Ok(text) = std::fs::read_to_string(task.path().join("schedstat")) else { continue };
        total += text.split_whitespace().next()?.parse::<u64>().ok()?;
    }
    Some(Duration::from_nanos(total))
}

/// A ratio estimated from paired blocks: the geometric mean of the per-block
/// ratios with a 95% confidence interval (normal approximation on the logs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RatioEstimate {
    /// Geometric mean of the ratios.
    pub ratio: f64,
    /// Lower and upper ends of the 95% interval.
    pub interval: [f64; 2],
    /// Paired blocks behind it.
    pub pairs: usize,
}

impl RatioEstimate {
    /// `None` for fewer than two ratios or non-positive ones.
    #[must_use]
    pub fn from_ratios(ratios: &[f64]) -> Option<Self> {
        if ratios.len() < 2 || ratios.iter().any(|&r| !(r > 0.0 && r.is_finite())) {
            return None;
        }
        let n = ratios.len() as f64;
        let logs: Vec<f64> = ratios.iter().map(|r| r.ln()).collect();
        let mean = logs.iter().sum::<f64>() / n;
        let variance = logs.iter().map(|l| (l - mean).powi(2)).sum::<f64>() / (n - 1.0);
        let half = 1.96 * (variance / n).sqrt();
        Some(Self { ratio: mean.exp(), interval: [(mean - half).exp(), (mean + half).exp()], pairs: ratios.len() })
    }
}

impl std::fmt::Display for RatioEstimate {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{:.3} ({:.3}–{:.3})", self.ratio, self.interval[0], self.interval[1])
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
    let renderer_options = RendererOptions { timestamps: options.gpu_stages, ..super::experiment_renderer_options() };
    let mut renderer = Renderer::new(device, queue, &scene, renderer_options)?;
    let block = options.block.max(1);
    let rounds = options.frames.div_ceil(block).max(1);
    let mut rows = Vec::new();
    for &map in &options.maps {
        for &count in &options.lights {
            let lights: Vec<Light> = (0..count).map(|i| light_for(config, &scene, i)).collect();
            let cell = Cell { base, lights: &lights, bounds: scene.bounds(), map: ShadowMapSize::square(map) };
            let base = [Pipeline::Focused, Pipeline::LiSpsm, Pipeline::Optimized, Pipeline::FocusedWithAnalysis];
            let lookups = options.lookups.iter().map(|&l| Pipeline::FocusedLookup(l));
            let mut runs =
                base.into_iter().chain(lookups).map(|p| Run::new(p, count)).collect::<Result<Vec<_>, _>>()?;
            for run in &mut runs {
                for _ in 0..options.warmup_blocks {
                    run.block(&mut renderer, &cell, block, false)?;
                }
            }
            for round in 0..rounds {
                let pipelines = runs.len();
                for k in 0..pipelines {
                    runs[(round + k) % pipelines].block(&mut renderer, &cell, block, true)?;
                }
            }
            let frames = (rounds * block) as u32;
            let mean = |run: &Run| run.timed.iter().sum::<Duration>() / frames;
            let mean_cpu = |run: &Run| run.cpu.iter().copied().sum::<Option<Duration>>().map(|d| d / frames);
            let row = TimingRow {
                lights: count,
                map,
                focused: mean(&runs[0]),
                lispsm: mean(&runs[1]),
                optimized: mean(&runs[2]),
                focused_with_analysis: mean(&runs[3]),
                focused_lookups: options
                    .lookups
                    .iter()
                    .zip(&runs[BASE_PIPELINES..])
                    .map(|(&l, r)| (l, mean(r)))
                    .collect(),
                blocks: runs.iter().map(|r| r.timed.clone()).collect(),
                rounds,
                optimizations: runs[2].optimizations,
                analyses: runs[2].analyses,
                stages: runs.iter().map(|r| r.sums.means()).collect(),
                cpu: runs.iter().map(mean_cpu).collect(),
            };
            progress(&row);
            rows.push(row);
            // Readbacks left in the ring belong to this cell.
            renderer.wait_idle()?;
            renderer.discard_analyses();
        }
    }
    Ok(rows)
}

/// The table as markdown, ratios against focused.
#[must_use]
pub fn timing_markdown(rows: &[TimingRow]) -> String {
    // The lookup pipelines of the first row name the extra columns (every
    // row of a run times the same lookups).
    let lookups: Vec<&str> =
        rows.first().map_or_else(Vec::new, |r| r.focused_lookups.iter().map(|(l, _)| l.name()).collect());
    let mut md = String::from("| lights | map | focused ms | LiSPSM ms | scene-optimized ms | focused + analysis ms |");
    for l in &lookups {
        md.push_str(&format!(" focused + {l} ms |"));
    }
    md.push_str(" LiSPSM / focused | optimized / focused | optimized / focused, paired rounds (95% CI) | (focused + analysis) / focused |");
    for l in &lookups {
        md.push_str(&format!(" {l} / focused, paired rounds (95% CI) |"));
    }
    md.push_str(" CPU time optimized / focused | analyses | optimizations |\n|---:|---:|---:|---:|---:|---:|");
    md.push_str(&"---:|".repeat(lookups.len()));
    md.push_str("---:|---:|---|---:|");
    md.push_str(&"---|".repeat(lookups.len()));
    md.push_str("---:|---:|---:|\n");
    for r in rows {
        let ms = |d: Duration| d.as_secs_f64() * 1e3;
        let paired =
            |k| RatioEstimate::from_ratios(&r.round_ratios(k)).map_or_else(|| "-".to_owned(), |e| e.to_string());
        let cpu = r.optimized_cpu_ratio().map_or_else(|| "-".to_owned(), |c| format!("{c:.3}"));
        md.push_str(&format!(
            "| {} | {}² | {:.1} | {:.1} | {:.1} | {:.1} |",
            r.lights,
            r.map,
            ms(r.focused),
            ms(r.lispsm),
            ms(r.optimized),
            ms(r.focused_with_analysis),
        ));
        for (_, d) in &r.focused_lookups {
            md.push_str(&format!(" {:.1} |", ms(*d)));
        }
        md.push_str(&format!(
            " {:.3} | {:.3} | {} | {:.3} |",
            r.ratio(1),
            r.optimized_ratio(),
            paired(2),
            r.analysis_ratio()
        ));
        for k in 0..r.focused_lookups.len() {
            md.push_str(&format!(" {} |", paired(BASE_PIPELINES + k)));
        }
        md.push_str(&format!(" {cpu} | {} | {} |\n", r.analyses, r.optimizations));
    }
    if rows.is_empty() {
        return md;
    }
    md.push_str(
        "\nOver all cells (per-cell ratios of mean frame times: median and largest; every paired round of every \
         cell: geometric mean with its 95% confidence interval):\n\n",
    );
    let base = [
        (2, "scene-optimized / focused".to_owned()),
        (3, "(focused + analysis) / focused".to_owned()),
        (1, "LiSPSM / focused".to_owned()),
    ];
    let lookups = lookups.iter().enumerate().map(|(i, l)| (BASE_PIPELINES + i, format!("(focused + {l}) / focused")));
    for (k, what) in base.into_iter().chain(lookups) {
        let mut cells: Vec<f64> = rows.iter().map(|r| r.ratio(k)).collect();
        let largest = cells.iter().copied().fold(0.0f64, f64::max);
        let all: Vec<f64> = rows.iter().flat_map(|r| r.round_ratios(k)).collect();
        let pooled = RatioEstimate::from_ratios(&all)
            .map_or_else(|| "-".to_owned(), |e| format!("{e} over {} paired rounds", e.pairs));
        md.push_str(&format!(
            "- {what}: cells median {:.3}, largest {largest:.3}; all rounds {pooled}\n",
            median(&mut cells)
        ));
    }
    // Every later lookup against every earlier one, per cell (their map
    // sizes differ): e.g. the supersampled baseline against the
    // antialiased lookup, paired by round like the ratios to focused.
    let names: Vec<&str> = rows[0].focused_lookups.iter().map(|(l, _)| l.name()).collect();
    for (i, a) in names.iter().enumerate() {
        for (j, b) in names.iter().enumerate().skip(i + 1) {
            let cells: Vec<String> = rows
                .iter()
                .map(|r| {
                    let e = RatioEstimate::from_ratios(&r.round_ratios_to(BASE_PIPELINES + j, BASE_PIPELINES + i))
                        .map_or_else(|| "-".to_owned(), |e| e.to_string());
                    format!("{} lights {}²: {e}", r.lights, r.map)
                })
                .collect();
            md.push_str(&format!(
                "- (focused + {b}) / (focused + {a}), paired rounds per cell: {}\n",
                cells.join("; ")
            ));
        }
    }
    let mut cpu: Vec<f64> = rows.iter().filter_map(TimingRow::optimized_cpu_ratio).collect();
    if !cpu.is_empty() {
        md.push_str(&format!(
            "- scene-optimized / focused, process CPU time (all threads): cells median {:.3}\n",
            median(&mut cpu)
        ));
    }
    md.push_str(&stages_markdown(rows));
    md
}

/// Where each pipeline's frame time went, one row per cell and pipeline.
fn stages_markdown(rows: &[TimingRow]) -> String {
    let with_gpu = rows.iter().flat_map(|r| &r.stages).any(|s| s.gpu_frames > 0);
    let mut md = String::from(
        "\nWhere the time went, ms per frame: the loop thread's CPU time turning readbacks into samples and \
         optimizing, and solving matrices; the process's CPU time (all threads, lavapipe's included)",
    );
    md.push_str(if with_gpu {
        "; GPU time per stage from timestamp queries, on the frames whose stamps came back.\n\n\
         | lights | map | pipeline | frame | CPU optimize | CPU solve | CPU time (all threads) | GPU shadow | GPU camera | GPU analysis | GPU frames |\n\
         |---:|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|\n"
    } else {
        " (`--timing-gpu-stages` adds GPU time per stage).\n\n\
         | lights | map | pipeline | frame | CPU optimize | CPU solve | CPU time (all threads) |\n\
         |---:|---:|---|---:|---:|---:|---:|\n"
    });
    let ms = |d: Duration| format!("{:.1}", d.as_secs_f64() * 1e3);
    let or_dash = |d: Option<Duration>| d.map_or_else(|| "-".to_owned(), ms);
    for r in rows {
        for (((name, frame), stage), cpu) in r.pipelines().iter().zip(r.frame_times()).zip(&r.stages).zip(&r.cpu) {
            md.push_str(&format!(
                "| {} | {}² | {name} | {} | {} | {} | {} |",
                r.lights,
                r.map,
                ms(frame),
                ms(stage.optimize),
                ms(stage.solve),
                or_dash(*cpu)
            ));
            if with_gpu {
                md.push_str(&format!(
                    " {} | {} | {} | {} |",
                    or_dash(stage.shadow),
                    or_dash(stage.camera),
                    or_dash(stage.analysis),
                    stage.gpu_frames
                ));
            }
            md.push('\n');
        }
    }
    md
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::subpixel::AaSamples;

    /// Lookups are paired against each other round by round: aa32 blocks
    /// 2 and 4 ms, ss32 8 and 8 ms give per-round ratios 4 and 2, whose
    /// geometric mean is √8.
    #[test]
    fn lookups_pair_with_each_other_by_round() {
        let ms = |v: &[u64]| v.iter().map(|&m| Duration::from_millis(m)).collect::<Vec<_>>();
        let (aa, ss) = (ShadowLookup::SubPixelAa(AaSamples::X32), ShadowLookup::Supersampled(AaSamples::X32));
        let row = TimingRow {
            lights: 1,
            map: 256,
            focused: Duration::from_millis(1),
            lispsm: Duration::from_millis(1),
            optimized: Duration::from_millis(1),
            focused_with_analysis: Duration::from_millis(1),
            focused_lookups: vec![(aa, Duration::from_millis(3)), (ss, Duration::from_millis(8))],
            blocks: vec![ms(&[1, 1]), ms(&[1, 1]), ms(&[1, 1]), ms(&[1, 1]), ms(&[2, 4]), ms(&[8, 8])],
            rounds: 2,
            optimizations: 0,
            analyses: 0,
            cpu: vec![None; 6],
            stages: vec![StageTimes::default(); 6],
        };
        assert_eq!(row.round_ratios_to(5, 4), vec![4.0, 2.0]);
        assert_eq!(row.round_ratios(4), vec![2.0, 4.0]);
        let md = timing_markdown(&[row]);
        let line = md.lines().find(|l| l.starts_with("- (focused + ss32) / (focused + aa32)")).unwrap();
        assert!(line.contains("1 lights 256²: 2.828 ("), "{line}");
        assert!(!md.contains("(focused + aa32) / (focused + ss32)"), "each pair once");
    }
}
