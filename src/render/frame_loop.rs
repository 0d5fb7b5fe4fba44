//! The shadow frame loop of an engine, in one place: [`ShadowLoop`].
//!
//! The solver's pieces are renderer-free ([`ShadowScheduler`] keeps the
//! per-light matrices and the paper's cadence, [`Optimizer`] moves a matrix
//! from a readback's samples); the renderer's are solver-free (an analysis
//! pass, a readback ring that never waits). Joining them has an order that is
//! easy to get subtly wrong — take the readback that has arrived, feed each
//! light's samples for the camera the pass was rendered with, fall back to a
//! focused matrix until a light has been optimized, plan the analysis pass
//! with small focused maps for the lights whose turn it is — so the loop
//! lives here once, and the experiment, the timing harness and the examples
//! all call it.

use std::time::{Duration, Instant};

use super::cascade_loop::{CascadePolicy, CascadeState, CascadeUpdate};
use super::{
    AnalysisReadback, AnalysisRequest, Frame, FrameReport, ReadbackLatency, RenderError, Renderer, ShadowLookup,
};
use crate::cascade::Splits;
use crate::optimize::{OptimizeOptions, OptimizeReport, Optimizer, ScheduleOptions, ShadowScheduler};
use crate::ShadowProblem;
use crate::{Camera, Fallback, Light, LightMatrix, LixelError, Parameterization, SceneBounds, ShadowMapSize};

/// Which matrices a [`ShadowLoop`] renders with.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub enum LoopPolicy {
    /// Every light solved with one parameterization each frame; no analysis
    /// passes.
    Fixed(Parameterization),
    /// Scene-optimized matrices: an analysis pass every few frames, each
    /// readback optimizing every light (focused matrices until a light's
    /// first optimization).
    Optimized,
    /// The fixed matrices are shown while the analysis passes, readbacks and
    /// optimizations of [`Optimized`](Self::Optimized) run and are thrown
    /// away: the machinery's own cost, for timing.
    FixedWithAnalysis(Parameterization),
    /// Cascaded suns: every directional light split into
    /// [`CascadePolicy::splits`] cascades, one map slot each (so
    /// [`LoopFrame::matrices`] holds one matrix per slot), with fixed or
    /// SDSM splits and fixed or scene-optimized cascade matrices; analysis
    /// passes every [`ScheduleOptions::optimize_every`] frames when the
    /// policy needs them. See `render/cascade_loop.rs`.
    Cascaded(CascadePolicy),
}

impl LoopPolicy {
    /// Whether the loop runs analysis passes and the optimizer.
    #[must_use]
    pub fn analyses(&self) -> bool {
        match self {
            Self::Fixed(_) => false,
            Self::Cascaded(c) => c.analyses(),
            Self::Optimized | Self::FixedWithAnalysis(_) => true,
        }
    }
}

/// Settings of a [`ShadowLoop`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LoopOptions {
    /// Cadence of the analysis passes and the focused lookups.
    pub schedule: ScheduleOptions,
    /// The optimizer's settings.
    pub optimize: OptimizeOptions,
    /// How the camera and analysis passes look shadows up.
    pub lookup: ShadowLookup,
}

/// What one frame sees: the camera, the lights, the scene bounds and the
/// size of every light's map.
#[derive(Clone, Copy, Debug)]
pub struct LoopView<'a> {
    /// The viewer.
    pub camera: &'a Camera,
    /// One map each (at most [`MAX_LIGHTS`](super::MAX_LIGHTS)).
    pub lights: &'a [Light],
    /// Bounds of the scene's casters and receivers.
    pub bounds: SceneBounds,
    /// The size of every light's map.
    pub map: ShadowMapSize,
}

impl LoopView<'_> {
    fn solve(&self, map: ShadowMapSize, how: &Parameterization) -> crate::Result<Vec<LightMatrix>> {
        self.lights.iter().map(|&light| self.solve_one(light, map, how)).collect()
    }

    fn solve_one(&self, light: Light, map: ShadowMapSize, how: &Parameterization) -> crate::Result<LightMatrix> {
        ShadowProblem::new(*self.camera, light, self.bounds, map)?.solve(how)
    }
}

/// The analysis readback a frame consumed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReadbackInfo {
    /// The frame that rendered it.
    pub frame: u64,
    /// How long it took to arrive.
    pub latency: ReadbackLatency,
    /// Bit `i`: light `i` was looked up in a plain focused map.
    pub focused: u32,
}

/// What [`ShadowLoop::frame`] did.
#[derive(Clone, Debug)]
pub struct LoopFrame {
    /// The matrices rendered, one per light (one per map slot for
    /// [`LoopPolicy::Cascaded`]: a sun's cascades are consecutive).
    pub matrices: Vec<LightMatrix>,
    /// The suns' cascade splits of the frame ([`LoopPolicy::Cascaded`]
    /// with a directional light; `None` otherwise).
    pub splits: Option<Splits>,
    /// The renderer's report of the frame.
    pub render: FrameReport,
    /// The readback consumed at the start of the frame, if one had arrived.
    pub readback: Option<ReadbackInfo>,
    /// Bit `i`: light `i` was optimized from that readback.
    pub optimized: u32,
    /// Bit `i`: light `i`'s samples or optimization failed; it keeps its
    /// matrix.
    pub failed: u32,
    /// Lights whose optimization fell back, with the reason.
    pub fallbacks: Vec<(usize, Fallback)>,
    /// World positions of the boundary samples each light was optimized
    /// from ([`Samples::boundary_world`](crate::Samples::boundary_world));
    /// empty when no readback arrived (or for a light whose samples failed).
    pub boundary_samples: Vec<Vec<glam::DVec3>>,
    /// Whether some light's (or cascade's) optimizer accepted a new matrix
    /// from the readback (no fallback).
    pub moved: bool,
    /// CPU time of taking the readback and optimizing.
    pub optimize_time: Duration,
    /// CPU time of solving the frame's matrices and the analysis maps.
    pub solve_time: Duration,
}

/// The result of [`ShadowLoop::settle`].
#[derive(Clone, Debug, PartialEq)]
pub struct Settled {
    /// The matrix of each light the loop settled on.
    pub matrices: Vec<LightMatrix>,
    /// Frames (analysis passes) it took.
    pub frames: usize,
    /// The optimizer's last fallback of each light, if it stopped on one.
    pub fallbacks: Vec<Option<Fallback>>,
}

/// The first frame of a [`ShadowLoop::settle_from`] kept for the next
/// loop at the same view (say, another search strategy): the analysis
/// readback of the focused matrices and what it was rendered for. Start
/// with `FirstFrame::default()`.
#[derive(Clone, Debug, Default)]
pub struct FirstFrame {
    kept: Option<KeptFirst>,
}

/// What [`FirstFrame`] holds.
#[derive(Clone, Debug)]
struct KeptFirst {
    lights: Vec<Light>,
    bounds: SceneBounds,
    map: ShadowMapSize,
    lookup: ShadowLookup,
    readback: AnalysisReadback,
}

impl FirstFrame {
    /// The kept readback when it was rendered for this view and lookup with
    /// exactly `matrices`.
    fn matching(
        &self,
        view: &LoopView<'_>,
        lookup: ShadowLookup,
        matrices: &[LightMatrix],
    ) -> Option<&AnalysisReadback> {
        self.kept
            .as_ref()
            .filter(|k| {
                k.lookup == lookup
                    && k.map == view.map
                    && k.bounds == view.bounds
                    && k.lights == view.lights
                    && k.readback.camera == *view.camera
                    && k.readback.lights == matrices
            })
            .map(|k| &k.readback)
    }

    /// Keeps `readback` as the first frame at `view` in `lookup`.
    fn keep(&mut self, view: &LoopView<'_>, lookup: ShadowLookup, readback: AnalysisReadback) {
        self.kept =
            Some(KeptFirst { lights: view.lights.to_vec(), bounds: view.bounds, map: view.map, lookup, readback });
    }
}

/// Why a frame failed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum LoopError {
    /// The renderer refused the frame or the device failed.
    #[error(transparent)]
    Render(#[from] RenderError),
    /// A matrix could not be solved (bad camera, light or bounds), or, in
    /// [`ShadowLoop::settle`], a readback could not be optimized.
    #[error(transparent)]
    Solve(#[from] LixelError),
}

/// The buffers [`ShadowLoop`] extracts each analysis's samples into
/// ([`AnalysisReadback::samples_all_into`]).
#[derive(Clone, Debug, Default)]
struct KeptSamples {
    samples: Vec<crate::Samples>,
    workspace: crate::optimize::SampleWorkspace,
    bits: Vec<u32>,
}

/// The frame loop: per-light matrices, the analysis cadence, the
/// non-blocking readback and the optimizer, one call per frame.
///
/// ```no_run
/// # fn demo(renderer: &mut lixel::render::Renderer, camera: &lixel::Camera, lights: &[lixel::Light],
/// #         bounds: lixel::SceneBounds) -> Result<(), lixel::render::LoopError> {
/// use lixel::render::{LoopOptions, LoopPolicy, LoopView, ShadowLoop};
/// let mut shadows = ShadowLoop::new(LoopPolicy::Optimized, lights.len(), LoopOptions::default())?;
/// let map = lixel::ShadowMapSize::square(1024);
/// for _frame in 0..3 {
///     let done = shadows.frame(renderer, &LoopView { camera, lights, bounds, map })?;
///     // done.matrices were rendered; done.render.submission paces frames.
/// }
/// # Ok(()) }
/// ```
#[derive(Clone, Debug)]
pub struct ShadowLoop {
    policy: LoopPolicy,
    lookup: ShadowLookup,
    scheduler: ShadowScheduler,
    /// The last analysis's samples and their extraction buffers, reused.
    kept: KeptSamples,
    /// The cascade state of [`LoopPolicy::Cascaded`].
    cascades: Option<CascadeState>,
    optimize_every: u32,
    frame: u64,
}

impl ShadowLoop {
    /// A loop for `light_count` lights.
    ///
    /// # Errors
    /// [`LixelError::UnusableSamples`] for more than 32 lights or a zero
    /// cadence (see [`ShadowScheduler::new`]); [`LixelError::InvalidCascades`]
    /// for an invalid cascade policy.
    pub fn new(policy: LoopPolicy, light_count: usize, options: LoopOptions) -> Result<Self, LixelError> {
        let cascades = match &policy {
            LoopPolicy::Cascaded(c) => Some(CascadeState::new(c, light_count, options.optimize.clone())?),
            _ => None,
        };
        let optimize_every = options.schedule.optimize_every;
        let scheduler = ShadowScheduler::new(light_count, options.schedule, Optimizer::new(options.optimize))?;
        Ok(Self {
            policy,
            lookup: options.lookup,
            scheduler,
            kept: KeptSamples::default(),
            cascades,
            optimize_every,
            frame: 0,
        })
    }

    /// Every light's samples from `readback`, extracted into the loop's kept
    /// buffers, optimized by the scheduler. Where some light's samples
    /// cannot be extracted, light by light instead (each light keeps its own
    /// error). With `boundary`, also each light's boundary samples (world).
    fn optimize_readback(
        &mut self,
        readback: &AnalysisReadback,
        view: &LoopView<'_>,
        boundary: Option<&mut Vec<Vec<glam::DVec3>>>,
    ) -> Result<Vec<Result<OptimizeReport, LixelError>>, LixelError> {
        let KeptSamples { samples, workspace, bits } = &mut self.kept;
        match readback.samples_all_into(view.lights, view.bounds, view.map, samples, workspace, bits) {
            Ok(()) => {
                if let Some(boundary) = boundary {
                    *boundary = samples.iter().map(|s| s.boundary_world().to_vec()).collect();
                }
                self.scheduler.update_all_from(samples, self.frame)
            }
            Err(_) => {
                let samples = readback.samples_all(view.lights, view.bounds, view.map);
                if let Some(boundary) = boundary {
                    *boundary = samples
                        .iter()
                        .map(|s| s.as_ref().map(|s| s.boundary_world().to_vec()).unwrap_or_default())
                        .collect();
                }
                self.scheduler.update_all(samples, self.frame)
            }
        }
    }

    /// The policy.
    #[must_use]
    pub fn policy(&self) -> &LoopPolicy {
        &self.policy
    }

    /// Frames rendered so far.
    #[must_use]
    pub fn frames(&self) -> u64 {
        self.frame
    }

    /// The per-light state (current optimized matrices, last reports).
    #[must_use]
    pub fn scheduler(&self) -> &ShadowScheduler {
        &self.scheduler
    }

    /// Renders one frame: consumes the newest analysis readback if one has
    /// arrived (never waits), optimizes every light from it, renders the
    /// lights' current matrices and, when the cadence says so, an analysis
    /// pass. Frame pacing ([`Renderer::wait_for`]) is the caller's.
    ///
    /// # Errors
    /// [`LoopError::Render`] when the renderer refuses the frame;
    /// [`LoopError::Solve`] when a light's matrix cannot be solved or the
    /// view's lights differ in number from the loop's. A light
    /// whose optimization fails is not an error: it keeps its matrix
    /// ([`LoopFrame::failed`]).
    pub fn frame(&mut self, renderer: &mut Renderer, view: &LoopView<'_>) -> Result<LoopFrame, LoopError> {
        self.check_lights(view)?;
        if let LoopPolicy::Cascaded(policy) = &self.policy {
            let policy = policy.clone();
            return self.cascade_frame(&policy, renderer, view, false);
        }
        let analyses = self.policy.analyses();
        let optimizing = Instant::now();
        let (mut optimized, mut failed, mut fallbacks, mut moved) = (0u32, 0u32, Vec::new(), false);
        let mut boundary_samples = Vec::new();
        let readback = if analyses { renderer.try_take_analysis() } else { None };
        if let Some(r) = &readback {
            // The samples belong to the camera the pass was rendered with.
            for (i, report) in self.optimize_readback(r, view, Some(&mut boundary_samples))?.into_iter().enumerate() {
                match report {
                    Ok(report) => {
                        optimized |= 1 << i;
                        moved |= report.accepted && report.fallback.is_none();
                        fallbacks.extend(report.fallback.map(|f| (i, f)));
                    }
                    Err(_) => failed |= 1 << i,
                }
            }
        }
        let readback = readback.map(|r| ReadbackInfo { frame: r.frame, latency: r.latency, focused: r.tag });
        // Zero for a policy without analysis: nothing was taken or optimized.
        let optimize_time = if analyses { optimizing.elapsed() } else { Duration::ZERO };

        let solving = Instant::now();
        let matrices = match &self.policy {
            LoopPolicy::Fixed(how) | LoopPolicy::FixedWithAnalysis(how) => view.solve(view.map, how)?,
            // (Cascaded frames are cascade_frame's.)
            LoopPolicy::Optimized | LoopPolicy::Cascaded(_) => {
                // Focused until the optimizer has reached a light.
                let mut matrices = Vec::with_capacity(view.lights.len());
                for (i, &light) in view.lights.iter().enumerate() {
                    matrices.push(match self.scheduler.matrix(i) {
                        Some(m) => *m,
                        None => view.solve_one(light, view.map, &Parameterization::Focused)?,
                    });
                }
                matrices
            }
        };
        let plan = if analyses { self.scheduler.plan(self.frame).analysis } else { None };
        // Small focused maps for the lights whose turn it is; the rest reuse
        // the frame's maps.
        let mut analysis_lights = Vec::new();
        if let Some(plan) = plan.filter(|p| p.focused != 0) {
            let size = self.scheduler.focused_analysis_size(view.map);
            for (i, &light) in view.lights.iter().enumerate() {
                analysis_lights.push(if plan.is_focused(i) {
                    view.solve_one(light, size, &Parameterization::Focused)?
                } else {
                    matrices[i]
                });
            }
        }
        let solve_time = solving.elapsed();

        let analysis = plan.map(|plan| AnalysisRequest {
            lights: (!analysis_lights.is_empty()).then_some(&analysis_lights[..]),
            tag: plan.focused,
        });
        let render = self.render(renderer, view, &matrices, analysis)?;
        Ok(LoopFrame {
            matrices,
            splits: None,
            render,
            readback,
            optimized,
            failed,
            fallbacks,
            boundary_samples,
            moved,
            optimize_time,
            solve_time,
        })
    }

    /// [`frame`](Self::frame) for [`LoopPolicy::Cascaded`].
    fn cascade_frame(
        &mut self,
        policy: &CascadePolicy,
        renderer: &mut Renderer,
        view: &LoopView<'_>,
        force_analysis: bool,
    ) -> Result<LoopFrame, LoopError> {
        let state = self.cascades.as_mut().ok_or(LixelError::InvalidCascades { reason: "no cascade state" })?;
        let analyses = policy.analyses();
        let optimizing = Instant::now();
        let readback = if analyses { renderer.try_take_analysis() } else { None };
        let update = match &readback {
            Some(r) => state.take_readback(policy, r, view)?,
            None => CascadeUpdate::default(),
        };
        let readback = readback.map(|r| ReadbackInfo { frame: r.frame, latency: r.latency, focused: r.tag });
        let optimize_time = if analyses { optimizing.elapsed() } else { Duration::ZERO };
        let solving = Instant::now();
        let (matrices, splits) = state.solve(policy, renderer, view)?;
        let solve_time = solving.elapsed();
        let analysis = (analyses && (force_analysis || self.frame.is_multiple_of(u64::from(self.optimize_every))))
            .then_some(AnalysisRequest { lights: None, tag: 0 });
        let render = self.render(renderer, view, &matrices, analysis)?;
        Ok(LoopFrame {
            matrices,
            splits,
            render,
            readback,
            optimized: update.optimized,
            failed: update.failed,
            fallbacks: update.fallbacks,
            boundary_samples: update.boundary_samples,
            moved: update.moved,
            optimize_time,
            solve_time,
        })
    }

    /// The view has as many lights as the loop was made for.
    fn check_lights(&self, view: &LoopView<'_>) -> Result<(), LixelError> {
        if view.lights.len() == self.scheduler.light_count() {
            Ok(())
        } else {
            Err(LixelError::UnusableSamples { reason: "the view's lights differ in number from the loop's" })
        }
    }

    /// Renders the loop's frame (no masks, the loop's lookup) and counts it.
    fn render(
        &mut self,
        renderer: &mut Renderer,
        view: &LoopView<'_>,
        lights: &[LightMatrix],
        analysis: Option<AnalysisRequest<'_>>,
    ) -> Result<FrameReport, LoopError> {
        let report =
            renderer.render(&Frame { camera: view.camera, lights, masks: false, analysis, lookup: self.lookup })?;
        self.frame += 1;
        Ok(report)
    }

    /// The loop at a fixed view, as in a walkthrough that pauses: starting
    /// from focused matrices, each frame renders an analysis pass with the
    /// current matrices in their own maps, waits for its readback and
    /// optimizes every light; it stops when no light's optimizer moved its
    /// matrix any more (no 20% median improvement) or one fell back, or
    /// after `max_frames`. Blocks; the policy does not matter, except
    /// [`LoopPolicy::Cascaded`]: its frames (one analysis pass each, waited
    /// for) run until a readback moved no cascade (at once for a policy
    /// without analysis), and [`Settled::matrices`] holds one per map slot.
    ///
    /// # Errors
    /// Renderer failures, and a light whose matrix cannot be solved or whose
    /// readback cannot be optimized.
    pub fn settle(
        &mut self,
        renderer: &mut Renderer,
        view: &LoopView<'_>,
        max_frames: usize,
    ) -> Result<Settled, LoopError> {
        self.check_lights(view)?;
        if let LoopPolicy::Cascaded(policy) = &self.policy {
            let policy = policy.clone();
            return self.settle_cascades(&policy, renderer, view, max_frames);
        }
        self.settle_from(renderer, view, max_frames, &mut FirstFrame::default())
    }

    /// [`settle`](Self::settle) whose first frame may come from `first`:
    /// every settle starts with the same frame at a view — the focused
    /// matrices with an analysis pass in the loop's lookup — whatever its
    /// search, so a loop at the view, lights, bounds, map size and lookup of
    /// the frame `first` holds takes that frame's readback instead of
    /// rendering it again (and counts it as its first frame); otherwise it
    /// renders its first frame and leaves it in `first`. The readback is a
    /// function of the frame and the renderer's options, so `first` must
    /// only be shared between loops on one renderer.
    ///
    /// # Errors
    /// As [`settle`](Self::settle).
    pub fn settle_from(
        &mut self,
        renderer: &mut Renderer,
        view: &LoopView<'_>,
        max_frames: usize,
        first: &mut FirstFrame,
    ) -> Result<Settled, LoopError> {
        for (i, m) in view.solve(view.map, &Parameterization::Focused)?.into_iter().enumerate() {
            self.scheduler.set_matrix(i, m);
        }
        let current = |s: &ShadowScheduler| -> Vec<LightMatrix> {
            (0..view.lights.len()).filter_map(|i| s.matrix(i).copied()).collect()
        };
        let max_frames = max_frames.max(1);
        for frame in 1..=max_frames {
            let matrices = current(&self.scheduler);
            let kept = first.matching(view, self.lookup, &matrices).filter(|_| frame == 1);
            let readback = match kept {
                Some(kept) => {
                    self.frame += 1;
                    kept.clone()
                }
                None => {
                    let readback = self.analysis_frame(renderer, view, &matrices, frame)?;
                    if frame == 1 {
                        first.keep(view, self.lookup, readback.clone());
                    }
                    readback
                }
            };
            let mut fallbacks = Vec::with_capacity(view.lights.len());
            let mut moved = false;
            for report in self.optimize_readback(&readback, view, None)? {
                let report = report?;
                moved |= report.accepted && report.fallback.is_none();
                fallbacks.push(report.fallback);
            }
            if !moved || fallbacks.iter().any(Option::is_some) {
                return Ok(Settled { matrices: current(&self.scheduler), frames: frame, fallbacks });
            }
        }
        let fallbacks = vec![None; view.lights.len()];
        Ok(Settled { matrices: current(&self.scheduler), frames: max_frames, fallbacks })
    }

    /// Renders `matrices` with an analysis pass tagged `frame` and waits
    /// for its readback.
    fn analysis_frame(
        &mut self,
        renderer: &mut Renderer,
        view: &LoopView<'_>,
        matrices: &[LightMatrix],
        frame: usize,
    ) -> Result<AnalysisReadback, LoopError> {
        let analysis = Some(AnalysisRequest { lights: None, tag: frame as u32 });
        let report = self.render(renderer, view, matrices, analysis)?;
        renderer.wait_for(&report.submission)?;
        loop {
            if let Some(r) = renderer.try_take_analysis() {
                return Ok(r);
            }
            renderer.wait_idle()?;
        }
    }

    /// [`settle`](Self::settle) for [`LoopPolicy::Cascaded`].
    fn settle_cascades(
        &mut self,
        policy: &CascadePolicy,
        renderer: &mut Renderer,
        view: &LoopView<'_>,
        max_frames: usize,
    ) -> Result<Settled, LoopError> {
        renderer.discard_analyses();
        let mut frames = 0;
        loop {
            frames += 1;
            let done = self.cascade_frame(policy, renderer, view, true)?;
            renderer.wait_for(&done.render.submission)?;
            renderer.wait_idle()?;
            let settled = !policy.analyses() || (done.readback.is_some() && !done.moved);
            // One more frame than analyses: the last readback is consumed.
            if settled || frames > max_frames.max(1) {
                let mut fallbacks = vec![None; view.lights.len()];
                for (i, f) in done.fallbacks {
                    fallbacks[i] = Some(f);
                }
                return Ok(Settled { matrices: done.matrices, frames, fallbacks });
            }
        }
    }
}
