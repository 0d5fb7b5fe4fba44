//! The frame-loop helper: per-light state and the paper's cadence,
//! independent of any renderer.

use crate::error::{LixelError, Result};
use crate::matrix::LightMatrix;
use crate::optimize::{OptimizeReport, Optimizer, Samples};
use crate::scene::ShadowMapSize;

/// Which maps an analysis pass looks each light's shadows up in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct AnalysisPlan {
    /// Bit `i`: look light `i` up in a plain focused map (built at
    /// [`ShadowScheduler::focused_analysis_size`]), so that shadow components
    /// outside its current, tighter map are not missed. Other lights use the
    /// maps the frame renders anyway.
    pub focused: u32,
}

impl AnalysisPlan {
    /// Whether light `light` is looked up in a plain focused map.
    #[must_use]
    pub fn is_focused(&self, light: usize) -> bool {
        light < crate::MAX_LIGHTS && self.focused >> light & 1 == 1
    }
}

/// What the caller should do this frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FramePlan {
    /// Render a low-resolution analysis pass and start its readback.
    pub analysis: Option<AnalysisPlan>,
}

/// Cadence of [`ShadowScheduler`].
///
/// With `n` lights, analysis pass `p` (frame `p * optimize_every`) looks
/// light `i` up in a focused map when `p % focused_every == i * focused_every / n`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ScheduleOptions {
    /// Request an analysis pass (and so an optimization) every this many
    /// frames. The paper: 3.
    pub optimize_every: u32,
    /// Every this many analysis passes, each light is looked up once in a
    /// plain focused map. Default 5 (every 15 frames with
    /// `optimize_every = 3`). The lights take turns (staggered evenly over
    /// the passes), so no frame renders every light's extra map at once.
    pub focused_every: u32,
    /// Largest side of the focused maps an analysis pass looks lights up in
    /// ([`ShadowScheduler::focused_analysis_size`]). Their bits are
    /// only looked at the analysis resolution, and they are there to find
    /// shadows outside the current maps, not to place boundaries to the
    /// texel, so they need not be as large as the maps shown. Default 360,
    /// twice the default 180x180 analysis; 0 for no limit.
    pub focused_map_limit: u32,
}

impl Default for ScheduleOptions {
    fn default() -> Self {
        Self { optimize_every: 3, focused_every: 5, focused_map_limit: 360 }
    }
}

/// Per-light state of the frame loop. Each light has its own optimizer (its
/// buffers), so that lights can be optimized concurrently.
#[derive(Clone, Debug)]
struct LightState {
    optimizer: Optimizer,
    matrix: Option<LightMatrix>,
    optimized_frame: Option<u64>,
    last_report: Option<OptimizeReport>,
}

/// Per-light state and cadence for up to 32 lights (one u32 of shadow bits).
///
/// ```text
/// each frame:    plan = scheduler.plan(frame)
///                if plan.analysis: render the analysis pass (light i looked up in a
///                                  focused map where plan.is_focused(i)), start its readback
/// when a readback arrives (frames later):
///                scheduler.update_all(Samples::from_readback_all(..), frame)
///                (or, light by light, scheduler.update(light, &samples, frame))
/// render with:   scheduler.matrix(light) (falls back to your focused matrix while None)
/// ```
#[derive(Clone, Debug)]
pub struct ShadowScheduler {
    options: ScheduleOptions,
    lights: Vec<LightState>,
}

impl ShadowScheduler {
    /// A scheduler for `light_count` lights.
    ///
    /// # Errors
    /// [`LixelError::UnusableSamples`] for more than [`MAX_LIGHTS`](crate::MAX_LIGHTS) lights or a zero cadence.
    pub fn new(light_count: usize, options: ScheduleOptions, optimizer: Optimizer) -> Result<Self> {
        if light_count > crate::MAX_LIGHTS {
            return Err(LixelError::UnusableSamples { reason: "at most 32 lights share one shadow bitmask" });
        }
        if options.optimize_every == 0 || options.focused_every == 0 {
            return Err(LixelError::UnusableSamples { reason: "cadences must be at least 1" });
        }
        let state = LightState { optimizer, matrix: None, optimized_frame: None, last_report: None };
        Ok(Self { options, lights: vec![state; light_count] })
    }

    /// What to render in frame `frame`: an analysis pass every
    /// `optimize_every` frames; in every `focused_every` consecutive passes
    /// each light is looked up once in a plain focused map, the lights
    /// spread evenly over the passes (see [`ScheduleOptions`]).
    #[must_use]
    pub fn plan(&self, frame: u64) -> FramePlan {
        let every = u64::from(self.options.optimize_every);
        if !frame.is_multiple_of(every) {
            return FramePlan { analysis: None };
        }
        let turns = u64::from(self.options.focused_every);
        let turn = (frame / every) % turns;
        let n = self.lights.len() as u64;
        let focused = (0..n).filter(|&i| i * turns / n == turn).fold(0u32, |bits, i| bits | 1 << i);
        FramePlan { analysis: Some(AnalysisPlan { focused }) }
    }

    /// The size to build the focused map of a light looked up in one
    /// ([`AnalysisPlan::is_focused`]) when it is shown with `map`: `map` scaled down (aspect kept) so that its
    /// larger side is at most [`ScheduleOptions::focused_map_limit`].
    #[must_use]
    pub fn focused_analysis_size(&self, map: ShadowMapSize) -> ShadowMapSize {
        let limit = self.options.focused_map_limit;
        let larger = map.width.max(map.height);
        if limit == 0 || larger <= limit {
            return map;
        }
        let scale =
            |side: u32| ((u64::from(side) * u64::from(limit) + u64::from(larger) / 2) / u64::from(larger)).max(1);
        ShadowMapSize { width: scale(map.width) as u32, height: scale(map.height) as u32 }
    }

    /// The number of lights it schedules.
    #[must_use]
    pub fn light_count(&self) -> usize {
        self.lights.len()
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
        state.update(samples, frame)
    }

    /// [`Self::update`] for every light at once: `samples[i]` belongs to light
    /// `i` (an `Err` there is passed through and leaves the light as it
    /// was). With the `rayon` feature the lights are optimized in parallel;
    /// the results equal light-by-light [`Self::update`] calls.
    ///
    /// # Errors
    /// [`LixelError::UnusableSamples`] when `samples` does not have one entry
    /// per light; each light's own error is in its entry.
    pub fn update_all(&mut self, samples: Vec<Result<Samples>>, frame: u64) -> Result<Vec<Result<OptimizeReport>>> {
        if samples.len() != self.lights.len() {
            return Err(LixelError::UnusableSamples { reason: "one sample set per light" });
        }
        let one = |(state, samples): (&mut LightState, Result<Samples>)| {
            samples.and_then(|samples| state.update(&samples, frame).cloned())
        };
        self.update_each(samples, one)
    }

    /// [`Self::update_all`] with every light's samples present (borrowed:
    /// an engine keeps them and extracts into them with
    /// [`Samples::from_readback_all_into`]). The results equal
    /// `update_all` given the same samples.
    ///
    /// # Errors
    /// As [`Self::update_all`].
    pub fn update_all_from(&mut self, samples: &[Samples], frame: u64) -> Result<Vec<Result<OptimizeReport>>> {
        if samples.len() != self.lights.len() {
            return Err(LixelError::UnusableSamples { reason: "one sample set per light" });
        }
        let one = |(state, samples): (&mut LightState, &Samples)| state.update(samples, frame).cloned();
        self.update_each(samples, one)
    }

    /// Runs `one` for every light and its samples (in parallel with rayon).
    #[cfg(feature = "rayon")]
    fn update_each<S, I>(
        &mut self,
        samples: I,
        one: impl Fn((&mut LightState, S)) -> Result<OptimizeReport> + Send + Sync,
    ) -> Result<Vec<Result<OptimizeReport>>>
    where
        I: rayon::iter::IntoParallelIterator<Item = S>,
        I::Iter: rayon::iter::IndexedParallelIterator,
        S: Send,
    {
        use rayon::prelude::*;
        Ok(self.lights.par_iter_mut().zip(samples).map(one).collect())
    }

    /// Runs `one` for every light and its samples.
    #[cfg(not(feature = "rayon"))]
    fn update_each<S, I>(
        &mut self,
        samples: I,
        one: impl Fn((&mut LightState, S)) -> Result<OptimizeReport>,
    ) -> Result<Vec<Result<OptimizeReport>>>
    where
        I: IntoIterator<Item = S>,
    {
        Ok(self.lights.iter_mut().zip(samples).map(one).collect())
    }
}

impl LightState {
    /// Optimizes into the last report's buffers (`Optimizer::optimize_into`);
    /// on error the state, last report included, is unchanged.
    fn update(&mut self, samples: &Samples, frame: u64) -> Result<&OptimizeReport> {
        let had_report = self.last_report.is_some();
        let mut report = self.last_report.take().unwrap_or_default();
        match self.optimizer.optimize_into(samples, self.matrix.as_ref(), &mut report) {
            Ok(matrix) => {
                self.matrix = Some(matrix);
                self.optimized_frame = Some(frame);
                Ok(self.last_report.insert(report))
            }
            Err(e) => {
                if had_report {
                    self.last_report = Some(report);
                }
                Err(e)
            }
        }
    }
}
