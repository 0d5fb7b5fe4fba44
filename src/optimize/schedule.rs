//! The frame-loop helper: per-light state and the paper's cadence,
//! independent of any renderer.

use crate::error::{LixelError, Result};
use crate::matrix::LightMatrix;
use crate::optimize::{OptimizeReport, Optimizer, Samples};

/// Which matrices an analysis pass should render its shadow bits with.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AnalysisKind {
    /// The matrices currently in use (the usual case).
    CurrentMatrices,
    /// Plain focused matrices, so that shadow components outside the current
    /// (optimized, tighter) maps are not missed.
    Focused,
}

/// What the caller should do this frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FramePlan {
    /// Render a low-resolution analysis pass and start its readback.
    pub analysis: Option<AnalysisKind>,
}

/// Cadence of [`ShadowScheduler`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ScheduleOptions {
    /// Request an analysis pass (and so an optimization) every this many
    /// frames. The paper: 3.
    pub optimize_every: u32,
    /// Every this many analysis passes, render one with plain focused maps.
    /// Default 5 (every 15 frames with `optimize_every = 3`).
    pub focused_every: u32,
}

impl Default for ScheduleOptions {
    fn default() -> Self {
        Self { optimize_every: 3, focused_every: 5 }
    }
}

/// Per-light state of the frame loop.
#[derive(Clone, Debug, Default)]
struct LightState {
    matrix: Option<LightMatrix>,
    optimized_frame: Option<u64>,
    last_report: Option<OptimizeReport>,
}

/// Per-light state and cadence for up to 32 lights (one u32 of shadow bits).
///
/// ```text
/// each frame:    plan = scheduler.plan(frame)
///                if plan.analysis: render the analysis pass, start its readback
/// when a readback arrives (frames later):
///                for each light: scheduler.update(light, &samples, frame)
/// render with:   scheduler.matrix(light) (falls back to your focused matrix while None)
/// ```
#[derive(Clone, Debug)]
pub struct ShadowScheduler {
    options: ScheduleOptions,
    lights: Vec<LightState>,
    optimizer: Optimizer,
}

impl ShadowScheduler {
    /// The most lights one u32 shadow bitmask holds.
    pub const MAX_LIGHTS: usize = 32;

    /// A scheduler for `light_count` lights.
    ///
    /// # Errors
    /// [`LixelError::UnusableSamples`] for more than 32 lights or a zero cadence.
    pub fn new(light_count: usize, options: ScheduleOptions, optimizer: Optimizer) -> Result<Self> {
        if light_count > Self::MAX_LIGHTS {
            return Err(LixelError::UnusableSamples { reason: "at most 32 lights share one shadow bitmask" });
        }
        if options.optimize_every == 0 || options.focused_every == 0 {
            return Err(LixelError::UnusableSamples { reason: "cadences must be at least 1" });
        }
        Ok(Self { options, lights: vec![LightState::default(); light_count], optimizer })
    }

    /// What to render in frame `frame`: an analysis pass every
    /// `optimize_every` frames, every `focused_every`-th of them with plain
    /// focused maps. Frame 0 always analyses with focused maps (no matrix yet).
    #[must_use]
    pub fn plan(&self, frame: u64) -> FramePlan {
        let every = u64::from(self.options.optimize_every);
        if frame % every != 0 {
            return FramePlan { analysis: None };
        }
        let pass = frame / every;
        let kind = if pass % u64::from(self.options.focused_every) == 0 {
            AnalysisKind::Focused
        } else {
            AnalysisKind::CurrentMatrices
        };
        FramePlan { analysis: Some(kind) }
    }

    /// The matrix to render light `light` with, once one has been computed.
    #[must_use]
    pub fn matrix(&self, light: usize) -> Option<&LightMatrix> {
        self.lights.get(light)?.matrix.as_ref()
    }

    /// Replaces light `light`'s matrix (for example with a focused one at start-up).
    pub fn set_matrix(&mut self, light: usize, matrix: LightMatrix) {
        if let Some(state) = self.lights.get_mut(light) {
            state.matrix = Some(matrix);
        }
    }

    /// The report of light `light`'s last optimization.
    #[must_use]
    pub fn last_report(&self, light: usize) -> Option<&OptimizeReport> {
        self.lights.get(light)?.last_report.as_ref()
    }

    /// Frame in which light `light` was last optimized.
    #[must_use]
    pub fn optimized_frame(&self, light: usize) -> Option<u64> {
        self.lights.get(light)?.optimized_frame
    }

    /// Feeds light `light` the samples of a readback that arrived in frame
    /// `frame`: optimizes against its current matrix and keeps the result
    /// (the previous matrix re-fitted, if the new one was not accepted).
    /// A readback that never arrives simply never calls this: the previous
    /// matrices stay in use.
    ///
    /// # Errors
    /// [`LixelError::UnusableSamples`] for a light index out of range, and
    /// whatever [`Optimizer::optimize`] reports (the state is then unchanged).
    pub fn update(&mut self, light: usize, samples: &Samples, frame: u64) -> Result<&OptimizeReport> {
        let state = self.lights.get_mut(light).ok_or(LixelError::UnusableSamples { reason: "no such light" })?;
        let optimized = self.optimizer.optimize(samples, state.matrix.as_ref())?;
        state.matrix = Some(optimized.matrix);
        state.optimized_frame = Some(frame);
        Ok(state.last_report.insert(optimized.report))
    }
}
