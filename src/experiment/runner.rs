//! The running experiment: [`Runner`] holds the scene on the GPU, the ray
//! caster and the fixed camera, and turns one configuration (a light) into
//! every method's matrix, masks and counts against the truths.

use std::sync::{Arc, OnceLock};
use std::time::{Duration, Instant};

use super::{
    batch, camera_for, check_cascades, fold_cascade_masks, light_for, load_scene, rows, Coverage, ExperimentConfig,
    ExperimentError, MethodSpec, RunStage, RunStages, Truth, VisibilityError,
};
use crate::mesh::{PrimaryView, RayCaster, Scene, ShadowMasks};
use crate::optimize::{OptimizeOptions, SearchStrategy};
use crate::render::subpixel::AaSamples;
use crate::render::{
    FirstFrame, Frame, LoopOptions, LoopPolicy, LoopView, Renderer, RendererOptions, ShadowBias, ShadowFaces,
    ShadowLookup, ShadowLoop,
};
use crate::{Camera, Light, LightMatrix, LixelError, Parameterization, ShadowMapSize, ShadowProblem};

/// One method's result on one configuration.
#[derive(Clone, Debug, PartialEq)]
pub struct MethodResult {
    /// The matrix used (`None` when the method failed; a cascade method's
    /// first cascade).
    pub matrix: Option<LightMatrix>,
    /// A cascade method's cascades in order, nearest first (empty for the
    /// other methods).
    pub cascades: Vec<LightMatrix>,
    /// Counts against the truth.
    pub counts: Option<Counts>,
    /// Visibility error against the coverage truth (when it ran).
    pub visibility: Option<VisibilityError>,
    /// Frames the scene-optimized loop took (1 for the others).
    pub frames: usize,
    /// Fallback or error text.
    pub note: String,
}

impl MethodResult {
    /// A place holder until the method's shared frame is read (`batch.rs`).
    pub(super) fn pending() -> Self {
        Self { matrix: None, cascades: Vec::new(), counts: None, visibility: None, frames: 0, note: String::new() }
    }
}

/// Misclassification counts of one method on one configuration.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Counts {
    /// Pixels counted (visible and light-facing in the truth).
    pub counted: u64,
    /// Pixels lit in the truth but shadowed by the method.
    pub false_shadow: u64,
    /// Pixels shadowed in the truth but lit by the method.
    pub false_lit: u64,
}

impl Counts {
    /// `false_shadow + false_lit`.
    #[must_use]
    pub fn misclassified(&self) -> u64 {
        self.false_shadow + self.false_lit
    }

    /// Compares `masks` with `truth` for light 0.
    #[must_use]
    pub fn compare(masks: &ShadowMasks, truth: &ShadowMasks) -> Self {
        let mut c = Self::default();
        for i in 0..truth.depth.len().min(masks.depth.len()) {
            if !truth.visible(i) || truth.facing[i] & 1 == 0 {
                continue;
            }
            c.counted += 1;
            match (truth.shadow[i] & 1, masks.shadow[i] & 1) {
                (0, 1) => c.false_shadow += 1,
                (1, 0) => c.false_lit += 1,
                _ => {}
            }
        }
        c
    }
}

/// What the workers of a run share, read-only: the scene, its ray caster
/// and the camera's primary rays.
pub(super) struct Shared {
    pub(super) scene: Scene,
    pub(super) caster: Option<RayCaster>,
    /// The camera's primary rays at the screen size, traced on the first
    /// truth (by whichever worker gets there first) and shared by every
    /// light and worker (the run's camera never changes).
    pub(super) primary: OnceLock<PrimaryView>,
}

/// A running experiment: the scene on the GPU, the ray caster, the camera.
/// A run with several workers ([`ExperimentConfig::jobs`]) has one
/// `Runner` per worker, each with its own device and [`Renderer`], made by
/// [`worker`](Self::worker) and sharing the scene, the ray caster and the
/// primary rays.
pub struct Runner<'a> {
    pub(super) config: &'a ExperimentConfig,
    pub(super) shared: Arc<Shared>,
    pub(super) camera: Camera,
    pub(super) renderer: Renderer,
    pub(super) stages: RunStages,
    /// The last optimized loop's first frame: the next loop at the same
    /// configuration (another search) starts from it instead of rendering it.
    first_frame: FirstFrame,
}

impl std::fmt::Debug for Runner<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Runner").field("config", self.config).field("camera", &self.camera).finish_non_exhaustive()
    }
}

/// Everything one configuration produced.
#[derive(Clone, Debug)]
pub struct ConfigOutcome {
    /// The light.
    pub light: Light,
    /// Per method, in the config's method order.
    pub results: Vec<(MethodSpec, MethodResult)>,
    /// Pixels where the two truths disagree (when both were computed), and pixels compared.
    pub truth_disagreement: Option<(u64, u64)>,
    /// Wall time of the configuration.
    pub elapsed: Duration,
}

impl<'a> Runner<'a> {
    /// Loads the scene, builds the ray caster and the renderer.
    ///
    /// # Errors
    /// Scene, camera or renderer failures.
    pub fn new(
        config: &'a ExperimentConfig,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> Result<Self, ExperimentError> {
        if config.configs == 0 || config.screen == 0 || config.map == 0 || config.methods.is_empty() {
            return Err(ExperimentError::Config("configs, screen, map and methods must be non-empty".into()));
        }
        if config.coverage_samples != 0 && AaSamples::from_count(config.coverage_samples).is_none() {
            return Err(ExperimentError::Config(format!(
                "coverage samples must be 0 (off), 8, 16 or 32, not {}",
                config.coverage_samples
            )));
        }
        check_cascades(config)?;
        let scene = load_scene(&config.scene)?;
        let camera = camera_for(config, &scene)?;
        let caster = matches!(config.truth, Truth::RayCast | Truth::Both).then(|| RayCaster::new(&scene));
        let shared = Arc::new(Shared { scene, caster, primary: OnceLock::new() });
        Self::with_shared(config, shared, camera, device, queue)
    }

    /// Another worker of the same run on `device`: its own renderer (the
    /// scene uploaded again, the camera captured again), the scene, ray
    /// caster and primary rays shared with `self`.
    ///
    /// # Errors
    /// Renderer failures.
    pub fn worker(&self, device: &wgpu::Device, queue: &wgpu::Queue) -> Result<Runner<'a>, ExperimentError> {
        Self::with_shared(self.config, Arc::clone(&self.shared), self.camera, device, queue)
    }

    fn with_shared(
        config: &'a ExperimentConfig,
        shared: Arc<Shared>,
        camera: Camera,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> Result<Self, ExperimentError> {
        let options = experiment_renderer_options();
        let mut renderer = Renderer::new(device, queue, &shared.scene, options)?;
        // Every configuration and method sees the scene through this one
        // camera: draw it once, shade the capture per method (same masks).
        renderer.capture_view(&camera)?;
        Ok(Self { config, shared, camera, renderer, stages: RunStages::default(), first_frame: FirstFrame::default() })
    }

    /// The camera.
    #[must_use]
    pub fn camera(&self) -> &Camera {
        &self.camera
    }

    /// The scene.
    #[must_use]
    pub fn scene(&self) -> &Scene {
        &self.shared.scene
    }

    /// Wall time per stage so far.
    #[must_use]
    pub fn stages(&self) -> &RunStages {
        &self.stages
    }

    /// The problem of one light at map size `map`.
    ///
    /// # Errors
    /// Invalid lights (never for the hemisphere's).
    pub fn problem(&self, light: Light, map: u32) -> Result<ShadowProblem, LixelError> {
        ShadowProblem::new(self.camera, light, self.shared.scene.bounds(), ShadowMapSize::square(map))
    }

    /// Renders the camera view with `matrix` (masks included) and waits for
    /// it; with `masks_only`, not when the last frame already wrote its masks
    /// ([`Renderer::has_masks_of`]: an optimized loop's last frame).
    pub(super) fn render_view(
        &mut self,
        matrix: &LightMatrix,
        lookup: ShadowLookup,
        masks_only: bool,
    ) -> Result<(), ExperimentError> {
        // One map per light: no cascades left over from a cascade method.
        self.renderer.set_cascades(0, None);
        let lights = std::slice::from_ref(matrix);
        let frame = Frame { camera: &self.camera, lights, masks: true, analysis: None, lookup };
        if masks_only && self.renderer.has_masks_of(&frame) {
            return Ok(());
        }
        let report = self.renderer.render(&frame)?;
        Ok(self.renderer.wait_for(&report.submission)?)
    }

    /// Renders the camera view with `matrix` and reads back its masks.
    ///
    /// # Errors
    /// Renderer failures.
    pub fn masks(&mut self, matrix: &LightMatrix) -> Result<ShadowMasks, ExperimentError> {
        self.masks_with(matrix, ShadowLookup::default())
    }

    /// [`masks`](Self::masks) with another lookup (a method's:
    /// [`MethodSpec::lookup`]).
    ///
    /// The masks come from the last frame when it wrote them for the same
    /// matrix and lookup (an optimized loop's last frame,
    /// [`Renderer::has_masks_of`]), else from a frame of their own.
    ///
    /// # Errors
    /// Renderer failures.
    pub fn masks_with(&mut self, matrix: &LightMatrix, lookup: ShadowLookup) -> Result<ShadowMasks, ExperimentError> {
        self.render_view(matrix, lookup, true)?;
        Ok(self.renderer.read_masks()?)
    }

    /// The camera's color image with `matrix` (for the report's pictures).
    ///
    /// # Errors
    /// Renderer failures.
    pub fn color(&mut self, matrix: &LightMatrix) -> Result<image::RgbaImage, ExperimentError> {
        self.color_with(matrix, ShadowLookup::default())
    }

    /// [`color`](Self::color) with another lookup.
    ///
    /// # Errors
    /// Renderer failures.
    pub fn color_with(
        &mut self,
        matrix: &LightMatrix,
        lookup: ShadowLookup,
    ) -> Result<image::RgbaImage, ExperimentError> {
        self.render_view(matrix, lookup, false)?;
        Ok(self.renderer.read_color()?)
    }

    /// Ground truth for `light`: ray cast, or the focused 4000² map.
    ///
    /// # Errors
    /// Renderer failures.
    pub fn truths(&mut self, light: Light) -> Result<(Option<ShadowMasks>, Option<ShadowMasks>), ExperimentError> {
        let size = self.config.screen;
        let ray = match &self.shared.caster {
            Some(caster) => {
                let view = self.shared.primary.get_or_init(|| caster.primary_view(&self.camera, size, size));
                Some(caster.trace_masks_from(view, &[light]))
            }
            None => None,
        };
        let focused = if matches!(self.config.truth, Truth::Focused4000 | Truth::Both) {
            let m = self.problem(light, 4000)?.solve(&Parameterization::Focused)?;
            Some(self.masks(&m)?)
        } else {
            None
        };
        Ok((ray, focused))
    }

    /// The matrix of one method (scene-optimized: through the frame loop).
    /// Returns the matrix, the frames it took and a note.
    pub(super) fn matrix(
        &mut self,
        method: MethodSpec,
        problem: &ShadowProblem,
        nearest: Option<f64>,
    ) -> Result<(LightMatrix, usize, String), ExperimentError> {
        let Some(p) = method.parameterization(nearest) else {
            // The loop's analysis bits come from the method's lookup.
            return self.settle(problem, method.search().strategy(), method.lookup());
        };
        let m = problem.solve(&p)?;
        let note = m.fallback.map(rows::fallback_note).unwrap_or_default();
        Ok((m, 1, note))
    }

    /// The scene-optimized frame loop at this configuration, paused at its
    /// view until it settles ([`ShadowLoop::settle`]).
    pub(super) fn settle(
        &mut self,
        problem: &ShadowProblem,
        strategy: SearchStrategy,
        lookup: ShadowLookup,
    ) -> Result<(LightMatrix, usize, String), ExperimentError> {
        let optimize = OptimizeOptions { strategy, ..Default::default() };
        let options = LoopOptions { optimize, lookup, ..Default::default() };
        self.renderer.set_cascades(0, None);
        let mut shadows = ShadowLoop::new(LoopPolicy::Optimized, 1, options)?;
        let view = LoopView {
            camera: problem.camera(),
            lights: std::slice::from_ref(problem.light()),
            bounds: *problem.bounds(),
            map: problem.map_size(),
        };
        let settled =
            shadows.settle_from(&mut self.renderer, &view, self.config.max_optimize_frames, &mut self.first_frame)?;
        let note = settled.fallbacks[0].map(rows::fallback_note).unwrap_or_default();
        Ok((settled.matrices[0], settled.frames, note))
    }

    /// The matrices of `method` for `light`: one map of `map`² with PSM's
    /// near plane at `nearest`, or a cascade method's cascades (of
    /// `config.map`² each; the renderer's cascades left marked for
    /// [`method_masks_of`](Self::method_masks_of)). Returns the matrices,
    /// the frames and a note; the solver's refusals as
    /// [`ExperimentError::Solver`].
    pub(super) fn solve_method(
        &mut self,
        method: MethodSpec,
        light: Light,
        map: u32,
        nearest: Option<f64>,
    ) -> Result<(Vec<LightMatrix>, usize, String), ExperimentError> {
        if let Some(cascade) = method.cascade() {
            return self.settle_cascades(cascade, light, method.lookup());
        }
        let problem = self.problem(light, map)?;
        let (m, frames, note) = self.matrix(method, &problem, nearest)?;
        Ok((vec![m], frames, note))
    }

    /// The masks of `method` rendered with the `matrices` of
    /// [`solve_method`](Self::solve_method), called right after it: a
    /// cascade method's with the sun's cascade bits folded into bit 0
    /// ([`fold_cascade_masks`]).
    pub(super) fn method_masks_of(
        &mut self,
        method: MethodSpec,
        matrices: &[LightMatrix],
    ) -> Result<ShadowMasks, ExperimentError> {
        let lookup = method.lookup();
        if method.cascade().is_none() {
            let matrix = matrices.first().ok_or_else(|| ExperimentError::Config("no matrix".into()))?;
            return self.masks_with(matrix, lookup);
        }
        // The loop left the renderer's cascades marked for these matrices.
        let frame = Frame { camera: &self.camera, lights: matrices, masks: true, analysis: None, lookup };
        let report = self.renderer.render(&frame)?;
        self.renderer.wait_for(&report.submission)?;
        Ok(fold_cascade_masks(&self.renderer.read_masks()?, &[0, matrices.len()]))
    }

    /// Runs configuration `index`.
    ///
    /// # Errors
    /// Renderer and solver failures that are not a method's own (a method's
    /// error is recorded in its result).
    pub fn run_config(&mut self, index: usize) -> Result<ConfigOutcome, ExperimentError> {
        let start = Instant::now();
        let light = light_for(self.config, &self.shared.scene, index);
        let (ray, focused_truth) = self.truths(light)?;
        let mut lap = self.stages.lap(RunStage::Truth, start);
        let truth_disagreement = match (&ray, &focused_truth) {
            (Some(a), Some(b)) => {
                let c = Counts::compare(b, a);
                Some((c.misclassified(), c.counted))
            }
            _ => None,
        };
        // The coverage truth goes with the ray-cast one (same rays, same pixels).
        let samples = AaSamples::from_count(self.config.coverage_samples);
        let coverage = match (&ray, &self.shared.caster, samples) {
            (Some(centre), Some(caster), Some(_)) => Some(Coverage::trace(caster, &self.camera, &light, centre)),
            _ => None,
        };
        lap = self.stages.lap(RunStage::Coverage, lap);
        let truth = ray.or(focused_truth).ok_or_else(|| ExperimentError::Config("no ground truth".into()))?;
        // What a depth readback supplies to PSM: the nearest visible depth.
        let nearest = nearest_view_depth(&self.camera, &truth);
        let mut results = Vec::with_capacity(self.config.methods.len());
        // Methods whose masks come from a frame shared with others (`batch.rs`).
        let mut shared = Vec::new();
        for &method in &self.config.methods {
            // A method solved through frames of its own: the shared frame
            // goes first, the loop's first (focused) map in its layer 0.
            if method.parameterization(nearest).is_none() && !shared.is_empty() {
                let focused = shared.iter().position(|p: &batch::Pending| p.method.matrix() == crate::Method::Focused);
                let pending = std::mem::take(&mut shared);
                lap = self.finish_shared(pending, focused, &mut results, &truth, coverage.as_ref(), lap)?;
            }
            let solved = self.solve_method(method, light, self.config.single_map(), nearest);
            lap = self.stages.lap(RunStage::Matrices, lap);
            let result = match solved {
                Ok((matrices, frames, note)) if batch::shares_frame(method) => {
                    shared.push(batch::Pending { index: results.len(), method, matrices, frames, note });
                    MethodResult::pending()
                }
                Ok((matrices, frames, note)) => {
                    let masks = self.method_masks_of(method, &matrices)?;
                    lap = self.stages.lap(RunStage::Lookups, lap);
                    let result =
                        self.method_result(method, matrices, frames, note, &masks, &truth, coverage.as_ref())?;
                    lap = self.stages.lap(RunStage::Compare, lap);
                    result
                }
                Err(ExperimentError::Solver(e)) => MethodResult {
                    matrix: None,
                    cascades: Vec::new(),
                    counts: None,
                    visibility: None,
                    frames: 0,
                    note: e.to_string(),
                },
                Err(e) => return Err(e),
            };
            results.push((method, result));
        }
        // The last method solved first: its loop's last frame drew its map
        // into layer 0.
        let last = shared.len().checked_sub(1);
        self.finish_shared(shared, last, &mut results, &truth, coverage.as_ref(), lap)?;
        Ok(ConfigOutcome { light, results, truth_disagreement, elapsed: start.elapsed() })
    }

    /// One method's result from its masks: counts against the truth, the
    /// visibility error against the coverage truth (when it ran), and for
    /// the antialiased lookups their words and counts, read from the frame
    /// just rendered for this method.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn method_result(
        &mut self,
        method: MethodSpec,
        matrices: Vec<LightMatrix>,
        frames: usize,
        note: String,
        masks: &ShadowMasks,
        truth: &ShadowMasks,
        coverage: Option<&Coverage>,
    ) -> Result<MethodResult, ExperimentError> {
        let samples = AaSamples::from_count(self.config.coverage_samples);
        // `+aaN`: the renderer's occlusion words (over its valid
        // samples) against the truth of the same N sub-samples; others:
        // the shadow bit.
        let visibility = match (coverage, samples, method.lookup()) {
            (Some(c), Some(_), ShadowLookup::SubPixelAa(n)) => {
                let (occluded, valid) = (self.occlusion(matrices.len())?, self.validity(matrices.len())?);
                Some(VisibilityError::of_valid_occlusion(&occluded, &valid, truth, c, n))
            }
            (Some(c), Some(_), ShadowLookup::Supersampled(n)) => {
                Some(VisibilityError::of_supersampled(&self.supersampled(matrices.len())?, masks, truth, c, n))
            }
            (Some(c), Some(s), _) => Some(VisibilityError::of_masks(masks, truth, c, s)),
            _ => None,
        };
        // The antialiased passes' counts go to the note (pair-list
        // use and the pixels that kept the standard bit).
        let note = match method.lookup() {
            ShadowLookup::SubPixelAa(_) => {
                let s = self.aa_stats(matrices.len())?;
                let aa = format!(
                    "aa pairs {} exact {} (uncertain {}) overflow {} wide {} silhouette {}",
                    s.pairs, s.exact_pixels, s.uncertain_pixels, s.overflow_pixels, s.wide_pixels, s.silhouette_texels
                );
                if note.is_empty() {
                    aa
                } else {
                    format!("{note}; {aa}")
                }
            }
            _ => note,
        };
        let counts = Some(Counts::compare(masks, truth));
        let cascades = if method.cascade().is_some() { matrices.clone() } else { Vec::new() };
        Ok(MethodResult { matrix: matrices.first().copied(), cascades, counts, visibility, frames, note })
    }

    /// Mean misclassified pixels of `method` at map size `map` over the first
    /// `count` configurations (the resolution-equivalence measurements).
    ///
    /// # Errors
    /// Renderer failures.
    pub fn mean_at_resolution(&mut self, method: MethodSpec, map: u32, count: usize) -> Result<f64, ExperimentError> {
        Ok(self.means_at_resolutions(&[(method, map)], count)?[0])
    }

    /// [`mean_at_resolution`](Self::mean_at_resolution) for several
    /// (method, map size) runs at once: each configuration's truth is
    /// computed once and shared by every run (the ladder has a dozen sizes),
    /// and each run's sum is taken in configuration order, so the means are
    /// bit-identical to one run at a time. `NaN` for a run no configuration
    /// could solve.
    ///
    /// # Errors
    /// Renderer failures.
    pub fn means_at_resolutions(
        &mut self,
        runs: &[(MethodSpec, u32)],
        count: usize,
    ) -> Result<Vec<f64>, ExperimentError> {
        let per_config = (0..count).map(|index| self.misclassified_at(runs, index)).collect::<Result<Vec<_>, _>>()?;
        Ok(means_in_order(runs.len(), &per_config))
    }

    /// Misclassified pixels of each (method, map size) run on configuration
    /// `index` against its truth, traced once for all runs; `None` for a
    /// run whose solver refused the configuration.
    ///
    /// # Errors
    /// Renderer failures.
    pub(super) fn misclassified_at(
        &mut self,
        runs: &[(MethodSpec, u32)],
        index: usize,
    ) -> Result<Vec<Option<u64>>, ExperimentError> {
        let light = light_for(self.config, &self.shared.scene, index);
        let (ray, focused_truth) = self.truths(light)?;
        let Some(truth) = ray.or(focused_truth) else { return Ok(vec![None; runs.len()]) };
        let nearest = nearest_view_depth(&self.camera, &truth);
        let mut counts = Vec::with_capacity(runs.len());
        for &(method, map) in runs {
            counts.push(match self.solve_method(method, light, map, nearest) {
                Ok((matrices, ..)) => {
                    let masks = self.method_masks_of(method, &matrices)?;
                    Some(Counts::compare(&masks, &truth).misclassified())
                }
                Err(ExperimentError::Solver(_)) => None,
                Err(e) => return Err(e),
            });
        }
        Ok(counts)
    }
}

/// Each run's mean of [`Runner::misclassified_at`]'s counts, summed in
/// configuration order (so the means are the same bits however the
/// configurations were spread over workers); `NaN` for a run no
/// configuration could solve.
pub(super) fn means_in_order(runs: usize, per_config: &[Vec<Option<u64>>]) -> Vec<f64> {
    let mut sums = vec![(0.0f64, 0usize); runs];
    for counts in per_config {
        for (count, (total, n)) in counts.iter().zip(&mut sums) {
            if let Some(c) = count {
                *total += *c as f64;
                *n += 1;
            }
        }
    }
    sums.into_iter().map(|(total, n)| if n == 0 { f64::NAN } else { total / n as f64 }).collect()
}

/// The one shadow policy of every experiment, for every method: the
/// renderer's default — linear light depth with the slope-scaled
/// [`ShadowBias::default`], both faces drawn (so OBJ scenes need not be
/// closed). [`ShadowFaces::AwayFromLight`] (second-depth) lowers every
/// method's count a little on closed scenes without changing their order.
#[must_use]
pub fn experiment_renderer_options() -> RendererOptions {
    RendererOptions {
        readback_slots: 2,
        shadow_faces: ShadowFaces::Both,
        bias: ShadowBias::default(),
        // Nothing here reads GPU stage times (the timing table turns them
        // back on); without them a layer's map is kept for a later frame
        // that would draw it again.
        timestamps: false,
        reuse_maps: true,
        ..RendererOptions::default()
    }
}

/// The smallest view depth of any visible pixel of `masks`.
pub(super) fn nearest_view_depth(camera: &Camera, masks: &ShadowMasks) -> Option<f64> {
    // NDC depth d of a perspective [0, 1] projection: view depth = n f / (f - d (f - n)).
    let (n, f) = (camera.z_near(), camera.z_far());
    masks.depth.iter().filter(|&&d| d < 1.0).map(|&d| n * f / (f - f64::from(d) * (f - n))).min_by(f64::total_cmp)
}
