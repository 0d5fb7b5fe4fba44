//! Scene-optimized light matrices (Chong & Gortler 2006, "Scene Optimized
//! Shadow Mapping"): from a low-resolution readback, choose the optical axis
//! `j` that minimizes the summed badness of the shadow-boundary samples, with
//! the minimum-area rectangle as the affine part.
//!
//! ```text
//! readback ──Samples::from_readback──▶ Samples ──optimize_light_matrix──▶ Optimized { matrix, report }
//! ```
//!
//! Engines call [`optimize_light_matrix`] (or keep an [`Optimizer`] to reuse
//! its buffers) every few frames per light; [`ShadowScheduler`] keeps the
//! per-light state and the paper's cadence.

mod extract;
mod holds;
mod objective;
mod samples;
mod schedule;
mod search;
mod stable;

use glam::{DMat3, DVec2, DVec3};

use crate::error::{LixelError, Result};
use crate::fit::{AffineFitOptions, FitWorkspace};
use crate::geometry::min_enclosing_cone_in;
use crate::matrix::{fit_homography, AxisFit, Fallback, LightMatrix, Method};

pub use extract::SampleWorkspace;
pub use objective::{objective, objective_gradient, plane_frame_gradient, sample_badness, BoundarySample};
pub use samples::{PixelRect, Readback, ReadbackDepth, ReadbackLayout, RowOrder, SampleCounts, SampleOptions, Samples};
pub use schedule::{AnalysisPlan, FramePlan, ScheduleOptions, ShadowScheduler};
pub use stable::{AcceptMeasure, TexelSnap};

/// The paper's rotation angles, in degrees (one negative for exploration).
pub const PAPER_ANGLES_DEGREES: [f64; 9] = [-10.0, 3.0, 5.0, 9.0, 16.0, 23.0, 30.0, 40.0, 50.0];

/// How the optical axis is searched.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub enum SearchStrategy {
    /// The paper's heuristic: rotate `j` against the gradient by each of
    /// [`OptimizeOptions::angles_degrees`], keep the best, repeat
    /// [`OptimizeOptions::iterations`] times.
    Paper,
    /// argmin's Nelder–Mead over two angles of `j` (affine part re-fitted
    /// inside the cost), for comparison with the heuristic.
    NelderMead {
        /// Iteration cap.
        max_iterations: u64,
    },
}

/// Which gradient steers the paper's rotation search.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GradientSource {
    /// Central differences of the objective with the affine part re-fitted
    /// for every `j` (four fits per iteration). The default: it is the
    /// function the search actually compares.
    Refit,
    /// The closed-form gradient with the affine part held fixed on the image
    /// plane ([`plane_frame_gradient`]). Cheaper, but it rewards zooming in
    /// on the boundary samples at the expense of coverage, which the re-fit
    /// then undoes: on lixel's walkthrough tests its direction often raises
    /// the re-fitted objective.
    Analytic,
}

/// Options of the optimizer: the paper's, but for [`hold`](Self::hold)
/// ([`OptimizeOptions::paper`] for exactly the paper's).
#[derive(Clone, Debug, PartialEq)]
pub struct OptimizeOptions {
    /// Gradient iterations. Default 3.
    pub iterations: usize,
    /// Rotation angles tried per iteration, degrees. Default [`PAPER_ANGLES_DEGREES`].
    pub angles_degrees: Vec<f64>,
    /// Hysteresis: accept the new matrix only if its
    /// [`accept_measure`](Self::accept_measure) is below this times the
    /// previous matrix's (re-fitted to the current samples). Default 0.8.
    pub accept_ratio: f64,
    /// What the hysteresis compares. Default [`AcceptMeasure::Median`] (the
    /// paper).
    pub accept_measure: AcceptMeasure,
    /// Texel snapping of the affine part: the image-plane directions are kept
    /// while `j` is, the texel size is on a ladder and the origin on whole
    /// texels ([`TexelSnap`]). The paper: `None`.
    pub snap: Option<TexelSnap>,
    /// Bounded rotation: an accepted axis turns at most this many degrees
    /// from the previous one per update. The paper: `None` (unbounded).
    pub max_turn_degrees: Option<f64>,
    /// While the previous axis is kept, keep the previous matrix itself
    /// (only its depth range re-fitted) as long as it holds every relevant
    /// sample and its re-fit would not replace it under the hysteresis
    /// above, instead of re-fitting its affine part to the samples (the
    /// paper). A re-fit follows the samples, which follow the matrix: on a
    /// still camera the loop need not come to rest. Default on (measured:
    /// README, "Temporal stability").
    pub hold: bool,
    /// Grow the rectangle by this fraction of the map on each side (the
    /// samples are sub-sampled). Default 0.01.
    pub margin_fraction: f64,
    /// The paper's shear heuristic for the affine part. Default off.
    pub shear: bool,
    /// Search strategy. Default [`SearchStrategy::Paper`].
    pub strategy: SearchStrategy,
    /// Gradient for [`SearchStrategy::Paper`]. Default [`GradientSource::Refit`].
    pub gradient: GradientSource,
}

impl Default for OptimizeOptions {
    fn default() -> Self {
        Self {
            iterations: 3,
            angles_degrees: PAPER_ANGLES_DEGREES.to_vec(),
            accept_ratio: 0.8,
            accept_measure: AcceptMeasure::Median,
            snap: None,
            max_turn_degrees: None,
            hold: true,
            margin_fraction: 0.01,
            shear: false,
            strategy: SearchStrategy::Paper,
            gradient: GradientSource::Refit,
        }
    }
}

impl OptimizeOptions {
    /// The paper's behaviour (Chong & Gortler 2006): the median rule with
    /// ratio 0.8, the kept matrix re-fitted every update, no texel snapping,
    /// no bound on the rotation of `j`.
    #[must_use]
    pub fn paper() -> Self {
        Self {
            accept_ratio: 0.8,
            accept_measure: AcceptMeasure::Median,
            snap: None,
            max_turn_degrees: None,
            hold: false,
            ..Self::default()
        }
    }
}

/// What the optimizer did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct OptimizeReport {
    /// The new matrix replaced the previous one (always true without one).
    pub accepted: bool,
    /// Objective `h` (summed badness) of the optimized matrix.
    pub objective_new: f64,
    /// Objective of the previous matrix re-fitted to the current samples.
    pub objective_prev: Option<f64>,
    /// Objective of the search's start (the better of focused and previous).
    pub objective_start: f64,
    /// Median badness of the optimized matrix over the boundary samples.
    pub median_new: f64,
    /// Median badness of the re-fitted previous matrix.
    pub median_prev: Option<f64>,
    /// Gradient iterations (or Nelder–Mead iterations) run.
    pub iterations: usize,
    /// Every rotation angle evaluated, degrees, in order.
    pub angles_tried: Vec<f64>,
    /// Boundary samples used.
    pub boundary_samples: usize,
    /// Relevant samples covered.
    pub relevant_samples: usize,
    /// Set when the focused matrix was returned instead.
    pub fallback: Option<Fallback>,
    /// The matrix returned is on a snapped texel grid
    /// ([`OptimizeOptions::snap`]).
    pub snapped: bool,
    /// The accepted axis was turned less far than the search went
    /// ([`OptimizeOptions::max_turn_degrees`]).
    pub turn_limited: bool,
    /// The previous matrix was returned unchanged but for its depth range
    /// ([`OptimizeOptions::hold`]).
    pub held: bool,
}

/// The chosen matrix and the report.
#[derive(Clone, Debug, PartialEq)]
pub struct Optimized {
    /// The matrix to render with: the optimized one if accepted, else the
    /// previous one re-fitted to the current samples (or the focused one).
    pub matrix: LightMatrix,
    /// What happened.
    pub report: OptimizeReport,
}

/// Scene-optimizes the light matrix for `samples`, given the previous frame's
/// matrix (if any). See [`Optimizer::optimize`].
///
/// # Errors
/// As [`Optimizer::optimize`].
pub fn optimize_light_matrix(samples: &Samples, prev: Option<&LightMatrix>) -> Result<Optimized> {
    Optimizer::new(OptimizeOptions::default()).optimize(samples, prev)
}

/// `out` = each point `x` of `xs` on the plane of `axis`, in the basis
/// `(e1, e2)`: `(e1·x, e2·x) / (axis·x)`. With AVX where the CPU has it
/// (four points' values a vector instruction instead of two: the same
/// operations per point, so the same bits).
fn project_onto_plane(axis: DVec3, (e1, e2): (DVec3, DVec3), xs: &[DVec3], out: &mut Vec<DVec2>) {
    // (A plain loop over a slice: `extend` of a mapped iterator would call
    // `Iterator::fold`, which is not inlined into the AVX function and so
    // not compiled for AVX. `resize` writes only what the buffer grows by.)
    #[inline(always)]
    fn project(axis: DVec3, e1: DVec3, e2: DVec3, xs: &[DVec3], out: &mut Vec<DVec2>) {
        out.truncate(xs.len());
        out.resize(xs.len(), DVec2::ZERO);
        for (o, x) in out.iter_mut().zip(xs) {
            *o = DVec2::new(e1.dot(*x), e2.dot(*x)) / axis.dot(*x);
        }
    }
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx")]
    fn project_avx(axis: DVec3, e1: DVec3, e2: DVec3, xs: &[DVec3], out: &mut Vec<DVec2>) {
        project(axis, e1, e2, xs, out);
    }
    avx_or_portable!(project_avx(axis, e1, e2, xs, out), project(axis, e1, e2, xs, out));
}

/// Scene-optimizes several lights: light `i` with `optimizers[i]` (its
/// reusable buffers), `samples[i]` and `prev[i]`. With the `rayon` feature
/// the lights run in parallel; each light's result is exactly what
/// [`Optimizer::optimize`] returns for it alone (the lights share nothing).
/// An engine extracts the samples of all its lights with
/// [`Samples::from_readback_all`] and calls this once per analysis frame.
///
/// # Errors
/// [`LixelError::UnusableSamples`] when the three slices differ in length;
/// each light's own error is in its entry.
pub fn optimize_lights(
    optimizers: &mut [Optimizer],
    samples: &[Samples],
    prev: &[Option<LightMatrix>],
) -> Result<Vec<Result<Optimized>>> {
    if optimizers.len() != samples.len() || prev.len() != samples.len() {
        return Err(LixelError::UnusableSamples { reason: "one optimizer and one previous matrix per light" });
    }
    #[cfg(feature = "rayon")]
    {
        use rayon::prelude::*;
        Ok(optimizers
            .par_iter_mut()
            .zip(samples.par_iter().zip(prev.par_iter()))
            .map(|(optimizer, (samples, prev))| optimizer.optimize(samples, prev.as_ref()))
            .collect())
    }
    #[cfg(not(feature = "rayon"))]
    {
        Ok(optimizers
            .iter_mut()
            .zip(samples.iter().zip(prev))
            .map(|(optimizer, (samples, prev))| optimizer.optimize(samples, prev.as_ref()))
            .collect())
    }
}

/// The optimizer with reusable buffers: once they have grown to the largest
/// sample set seen, [`optimize_into`](Self::optimize_into) allocates nothing
/// and [`optimize`](Self::optimize) only its report's
/// [`angles_tried`](OptimizeReport::angles_tried) (once, at its final size;
/// `tests/optimize_memory.rs` counts).
#[derive(Clone, Debug)]
pub struct Optimizer {
    options: OptimizeOptions,
    fit: FitWorkspace,
    projected: Vec<DVec2>,
    /// The relevant samples on the extreme rays' image plane (its own
    /// buffer: `projected` holds a candidate's few extreme rays, and
    /// [`project_onto_plane`] writes only what a buffer grows by).
    on_plane: Vec<DVec2>,
    extreme: Vec<DVec3>,
    badness: Vec<f64>,
    /// The boundary samples four at a time, component by component (filled
    /// by [`prepare`](Self::prepare) for the candidates' objectives).
    groups: objective::BoundaryGroups,
    /// Scratch of the extreme rays' hull and of the enclosing cone.
    sorted: Vec<DVec2>,
    hull: Vec<DVec2>,
    units: Vec<DVec3>,
    /// The spare buffer of [`optimize_into`](Self::optimize_into)'s reports.
    angles: Vec<f64>,
}

/// A candidate axis with its fitted homography (NDC) and objective.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Candidate {
    pub axis: DVec3,
    pub homography: DMat3,
    pub objective: f64,
}

impl Optimizer {
    /// An optimizer with `options`.
    #[must_use]
    pub fn new(options: OptimizeOptions) -> Self {
        Self {
            options,
            fit: FitWorkspace::default(),
            projected: Vec::new(),
            on_plane: Vec::new(),
            extreme: Vec::new(),
            badness: Vec::new(),
            groups: objective::BoundaryGroups::default(),
            sorted: Vec::new(),
            hull: Vec::new(),
            units: Vec::new(),
            angles: Vec::new(),
        }
    }

    /// The options.
    #[must_use]
    pub fn options(&self) -> &OptimizeOptions {
        &self.options
    }

    /// Scene-optimizes the light matrix for `samples`.
    ///
    /// 1. With no relevant or no boundary samples, returns the focused matrix
    ///    with [`Fallback::NoUsableSamples`].
    /// 2. Starts from the better (lower objective) of the focused axis and the
    ///    previous matrix's axis, each re-fitted to the samples.
    /// 3. Searches `j` (see [`SearchStrategy`]); every candidate's affine part
    ///    is the minimum-area rectangle around the relevant samples, and a
    ///    candidate that puts any relevant sample behind the light is skipped.
    ///    The result's objective is never worse than the start's.
    /// 4. Accepts the result over the previous matrix only if its
    ///    [`AcceptMeasure`] (the paper: median badness) is below
    ///    `accept_ratio` times the previous one's; an accepted axis turns at
    ///    most [`OptimizeOptions::max_turn_degrees`] from the previous one.
    /// 5. While the previous axis is kept: with [`OptimizeOptions::hold`],
    ///    the previous matrix itself where it still holds every sample; with
    ///    [`OptimizeOptions::snap`], the matrix shown is put on a snapped
    ///    texel grid (the previous matrix's image-plane directions while its
    ///    axis is kept, else the new fit's), where that holds every sample.
    ///
    /// # Errors
    /// Only what computing the focused matrix reports (a point light inside
    /// the visible receivers), or [`LixelError::UnusableSamples`] when the
    /// relevant samples surround a point light.
    pub fn optimize(&mut self, samples: &Samples, prev: Option<&LightMatrix>) -> Result<Optimized> {
        let mut report = OptimizeReport::default();
        let matrix = self.optimize_report(samples, prev, &mut report)?;
        Ok(Optimized { matrix, report })
    }

    /// [`optimize`](Self::optimize), writing the report into `report` and
    /// reusing its [`angles_tried`](OptimizeReport::angles_tried) buffer:
    /// once warm, a call allocates nothing (`tests/optimize_memory.rs`
    /// counts). Matrix and report are the same as `optimize`'s; on error
    /// `report` is left as it was.
    ///
    /// # Errors
    /// As [`optimize`](Self::optimize).
    pub fn optimize_into(
        &mut self,
        samples: &Samples,
        prev: Option<&LightMatrix>,
        report: &mut OptimizeReport,
    ) -> Result<LightMatrix> {
        // Two angle buffers take turns: the one in `report` until this call
        // succeeds, and the optimizer's spare.
        let mut fresh = OptimizeReport { angles_tried: std::mem::take(&mut self.angles), ..OptimizeReport::default() };
        fresh.angles_tried.clear();
        match self.optimize_report(samples, prev, &mut fresh) {
            Ok(matrix) => {
                self.angles = std::mem::replace(report, fresh).angles_tried;
                Ok(matrix)
            }
            Err(e) => {
                self.angles = fresh.angles_tried;
                Err(e)
            }
        }
    }

    /// The body of [`optimize`](Self::optimize), filling `report` (given
    /// empty but for its angle buffer's capacity).
    fn optimize_report(
        &mut self,
        samples: &Samples,
        prev: Option<&LightMatrix>,
        report: &mut OptimizeReport,
    ) -> Result<LightMatrix> {
        let focused = samples.focused.clone()?;
        report.boundary_samples = samples.boundary.len();
        report.relevant_samples = samples.relevant.len();
        if samples.relevant.is_empty() || samples.boundary.is_empty() {
            report.fallback = Some(Fallback::NoUsableSamples);
            report.accepted = true;
            let mut matrix = focused;
            matrix.method = Method::Optimized;
            matrix.fallback = Some(Fallback::NoUsableSamples);
            return Ok(matrix);
        }
        self.prepare(samples)?;
        let frame = samples.frame;
        let into_frame = |m: &LightMatrix| frame.axis_from_world_row(m.clip_from_world.row(3));
        let start_focused = self.candidate(samples, into_frame(&focused));
        let start_prev = prev.and_then(|m| self.candidate(samples, into_frame(m)));
        let start = match (start_focused, start_prev) {
            (Some(f), Some(p)) => {
                if p.objective <= f.objective {
                    p
                } else {
                    f
                }
            }
            (Some(c), None) | (None, Some(c)) => c,
            // Neither axis sees every relevant sample: use the narrowest cone.
            (None, None) => {
                let axis = self.cone_axis(samples)?;
                self.candidate(samples, axis)
                    .ok_or(LixelError::UnusableSamples { reason: "relevant samples surround the light" })?
            }
        };
        report.objective_start = start.objective;
        let best = match self.options.strategy {
            SearchStrategy::Paper => search::paper(self, samples, start, report),
            SearchStrategy::NelderMead { max_iterations } => {
                search::nelder_mead(self, samples, start, max_iterations, report)
            }
        };
        report.objective_new = best.objective;
        report.median_new = self.median(samples, &best.homography);
        let accepted = match start_prev {
            None => true,
            Some(prev_candidate) => {
                let median_prev = self.median(samples, &prev_candidate.homography);
                report.objective_prev = Some(prev_candidate.objective);
                report.median_prev = Some(median_prev);
                let (new, old) = match self.options.accept_measure {
                    AcceptMeasure::Median => (report.median_new, median_prev),
                    AcceptMeasure::Objective => (best.objective, prev_candidate.objective),
                };
                new < self.options.accept_ratio * old
            }
        };
        report.accepted = accepted;
        let mut new_h = best.homography;
        if let (true, Some(limit), Some(prev_candidate)) = (accepted, self.options.max_turn_degrees, start_prev) {
            let axis = stable::turn_towards(prev_candidate.axis, best.axis, limit.to_radians());
            if axis.angle_between(best.axis) > 1e-12 {
                if let Some(turned) = self.candidate(samples, axis) {
                    new_h = turned.homography;
                    report.turn_limited = true;
                }
            }
        }
        let (chosen_h, other_h) = match start_prev {
            None => (new_h, None),
            Some(p) if accepted => (new_h, Some(p.homography)),
            Some(p) => (p.homography, Some(new_h)),
        };
        let mut matrix = self.finish(samples, chosen_h);
        // The previous matrix's homography in this frame, while its axis is kept.
        let kept = prev.filter(|_| !accepted).and_then(|m| stable::homography_in(&frame, m));
        // Held while the re-fit would not replace it under the same
        // hysteresis (a camera walking in would otherwise keep a large map).
        let refit_figure = match self.options.accept_measure {
            AcceptMeasure::Median => report.median_prev,
            AcceptMeasure::Objective => report.objective_prev,
        };
        let held = kept
            .filter(|_| self.options.hold)
            .filter(|h| {
                refit_figure.is_some_and(|refit| !(refit < self.options.accept_ratio * self.figure(samples, h)))
            })
            .map(|h| self.finish(samples, h))
            .filter(|m| self.holds_samples(samples, m));
        if let Some(held) = held {
            matrix = held;
            report.held = true;
        } else if let Some(snap) = self.options.snap {
            // The grid's directions: the previous matrix's while its axis is
            // kept, else the new fit's.
            let reference = kept.unwrap_or(chosen_h);
            let margin = self.options.margin_fraction.max(0.0);
            let snapped = stable::snap(samples, &reference, chosen_h.row(2), &self.extreme, snap, margin)
                .map(|h| self.finish(samples, h))
                .filter(|m| self.holds_samples(samples, m));
            if let Some(snapped) = snapped {
                matrix = snapped;
                report.snapped = true;
            }
        }
        // The answer must hold every relevant sample (not only the extreme
        // rays it was fitted to): otherwise the other matrix (made only
        // then), else the focused one.
        if self.holds_samples(samples, &matrix) {
            return Ok(matrix);
        }
        let other = other_h.map(|h| self.finish(samples, h));
        if let Some(other) = other.filter(|m| self.holds_samples(samples, m)) {
            report.accepted = !report.accepted;
            report.snapped = false;
            report.held = false;
            return Ok(other);
        }
        report.fallback = Some(Fallback::NoUsableSamples);
        report.snapped = false;
        report.held = false;
        let mut matrix = focused;
        matrix.method = Method::Optimized;
        matrix.fallback = Some(Fallback::NoUsableSamples);
        Ok(matrix)
    }

    /// Whether `matrix` is finite and holds every relevant sample, checked
    /// in world coordinates as a renderer evaluates it (composing `G` with a
    /// far light's translation rounds differently from light coordinates).
    fn holds_samples(&self, samples: &Samples, matrix: &LightMatrix) -> bool {
        let slack = samples.problem.tolerances().coverage_slack;
        matrix.clip_from_world.is_finite()
            && holds::holds_all_points(&matrix.homography, &samples.relevant, slack)
            && holds::covers_all(matrix, &samples.relevant_world, slack)
    }

    /// The objective of optical axis `axis` (light coordinates of
    /// [`Samples::frame`]) with its affine part fitted to `samples`; `None`
    /// when a relevant sample would be behind the light.
    ///
    /// # Errors
    /// [`LixelError::UnusableSamples`] when the samples have no extreme rays.
    pub fn objective_for_axis(&mut self, samples: &Samples, axis: DVec3) -> Result<Option<f64>> {
        self.prepare(samples)?;
        Ok(self.candidate(samples, axis).map(|c| c.objective))
    }

    /// What every candidate of `samples` needs: the extreme rays and the
    /// boundary samples' groups.
    fn prepare(&mut self, samples: &Samples) -> Result<()> {
        self.find_extreme_rays(samples)?;
        self.groups.fill(&samples.boundary);
        Ok(())
    }

    /// The relevant samples' extreme rays: the vertices of their hull on one
    /// image plane. Any axis that sees all of them sees every sample, and the
    /// hull on its plane is the projection of these rays (math.md §4).
    fn find_extreme_rays(&mut self, samples: &Samples) -> Result<()> {
        let axis = self.cone_axis(samples)?;
        let (e1, e2) = axis.any_orthonormal_pair();
        project_onto_plane(axis, (e1, e2), &samples.relevant, &mut self.on_plane);
        crate::fit::convex_hull_2d_into(&self.on_plane, &mut self.sorted, &mut self.hull);
        self.extreme.clear();
        // Unnormalized: for a directional light this restores X~ = (s, t, 1)
        // exactly, which the depth row's `w_min` needs.
        self.extreme.extend(self.hull.iter().map(|s| e1 * s.x + e2 * s.y + axis));
        if self.extreme.is_empty() {
            return Err(LixelError::UnusableSamples { reason: "no finite relevant sample" });
        }
        Ok(())
    }

    /// An axis in front of every relevant sample.
    fn cone_axis(&mut self, samples: &Samples) -> Result<DVec3> {
        if samples.frame.is_orthographic() {
            return Ok(DVec3::Z);
        }
        min_enclosing_cone_in(&samples.relevant, &mut self.units)
            .filter(|c| c.cos_half_angle > samples.problem.tolerances().min_front_cosine)
            .map(|c| c.axis)
            .ok_or(LixelError::UnusableSamples { reason: "relevant samples surround the light" })
    }

    fn fit_options(&self, samples: &Samples) -> AffineFitOptions {
        let map = samples.problem.map_size();
        AffineFitOptions {
            margin_texels: self.options.margin_fraction.max(0.0) * f64::from(map.width.max(map.height)),
            shear: self.options.shear,
            ..*samples.problem.fit_options()
        }
    }

    /// Fits `axis` to the samples and scores it; `None` if a relevant sample
    /// is not in front of the light.
    pub(crate) fn candidate(&mut self, samples: &Samples, axis: DVec3) -> Option<Candidate> {
        // Below `+∞` is exactly "finite" (NaN is below nothing).
        self.candidate_below(samples, axis, f64::INFINITY)
    }

    /// [`candidate`](Self::candidate) when its objective is below `bound`
    /// (else `None`), its sum stopped once it reaches `bound`
    /// ([`objective::objective_below`]): the same decision as comparing a
    /// full candidate's objective with `bound`, for less work on the
    /// candidates that lose.
    pub(crate) fn candidate_below(&mut self, samples: &Samples, axis: DVec3, bound: f64) -> Option<Candidate> {
        let fit = self.fit_options(samples);
        let setup = AxisFit {
            frame: &samples.frame,
            map: samples.problem.map_size(),
            fit: &fit,
            tolerances: samples.problem.tolerances(),
            // The extreme rays are the relevant samples' hull, in order.
            polygon: true,
        };
        let homography = fit_homography(&setup, axis, &self.extreme, &mut self.fit, &mut self.projected)?;
        let texel = objective::texel_homography(&homography, samples.problem.map_size());
        let value = objective::objective_below(&texel, &self.groups, &samples.boundary, bound)?;
        value.is_finite().then_some(Candidate { axis: homography.row(2), homography, objective: value })
    }

    /// The hysteresis figure ([`AcceptMeasure`]) of `homography`.
    fn figure(&mut self, samples: &Samples, homography: &DMat3) -> f64 {
        match self.options.accept_measure {
            AcceptMeasure::Median => self.median(samples, homography),
            AcceptMeasure::Objective => {
                let texel = objective::texel_homography(homography, samples.problem.map_size());
                objective::objective(&texel, &samples.boundary)
            }
        }
    }

    fn median(&mut self, samples: &Samples, homography: &DMat3) -> f64 {
        let texel = objective::texel_homography(homography, samples.problem.map_size());
        objective::median_badness(&texel, &self.groups, &samples.boundary, &mut self.badness)
    }

    fn finish(&self, samples: &Samples, homography: DMat3) -> LightMatrix {
        // `finish` folds the depth over `focus` then `depth_points`: the
        // receivers' body's vertices, then every relevant sample (kept once,
        // not copied into a second list per pixel), and the casters' bounds.
        samples
            .problem
            .placement(
                samples.frame,
                homography.row(2),
                &samples.depth_points,
                &samples.relevant_world,
                Some(&samples.casters),
                Method::Optimized,
                None,
            )
            .finish(homography, &self.extreme)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `project_onto_plane` (with AVX where this CPU has it) gives the
    /// scalar expression's bits, into a buffer that shrinks and grows
    /// between calls; points behind the plane and NaN included.
    #[test]
    fn projection_equals_the_scalar_one() {
        let mut unit = crate::test_rng::unit(0xA076_1D64_78BD_642F_u64);
        let mut next = move || unit() * 2.0 - 1.0;
        let mut out = Vec::new();
        for case in 0..500 {
            let axis = DVec3::new(0.2 * next(), 0.2 * next(), 1.0).normalize();
            let (e1, e2) = axis.any_orthonormal_pair();
            let mut xs: Vec<DVec3> =
                (0..(case * 7) % 61).map(|_| DVec3::new(next(), next(), 1.0 + 0.9 * next())).collect();
            if let Some(x) = xs.get_mut(case % 13) {
                x.y = if case % 2 == 0 { f64::NAN } else { -x.y };
            }
            project_onto_plane(axis, (e1, e2), &xs, &mut out);
            assert_eq!(out.len(), xs.len());
            for (o, x) in out.iter().zip(&xs) {
                let scalar = DVec2::new(e1.dot(*x), e2.dot(*x)) / axis.dot(*x);
                assert_eq!([o.x.to_bits(), o.y.to_bits()], [scalar.x.to_bits(), scalar.y.to_bits()], "case {case}");
            }
        }
    }
}
