//! Cascades from the analysis readback: the visible depth range (SDSM split
//! placement, with hysteresis) and one scene optimization per cascade from
//! the same readback.
//!
//! Why through a linear-depth readback: each cascade's problem has its own
//! (sliced) camera, whose depth convention differs from the camera the
//! readback was rendered with. Distances along the view direction are the
//! same for both, so the readback is converted once to
//! [`ReadbackDepth::LinearView`]; read against a cascade's camera, every
//! pixel outside the slice then falls outside its depth range `[0, 1)` and
//! counts as empty. The samples of cascade `k` are exactly the pixels whose
//! view depth lies in [`Splits::slice`]`(k)`, through the one sample
//! extractor [`Samples::from_readback`].

use crate::camera::Camera;
use crate::cascade::{view_range, CascadeProblems, CascadeSplits, Splits};
use crate::error::{LixelError, Result};
use crate::matrix::LightMatrix;
use crate::optimize::{OptimizeOptions, Optimized, Optimizer, Readback, ReadbackDepth, SampleOptions, Samples};
use crate::problem::ShadowProblem;

/// The readback's depths as distances along `camera`'s view direction
/// (non-finite where nothing was drawn), in the readback's own row order
/// and rectangle: the `depth` of an equivalent readback with
/// [`ReadbackDepth::LinearView`].
///
/// # Errors
/// [`LixelError::UnusableSamples`] when the depth buffer does not match
/// `width x height`.
pub fn linear_view_depths(camera: &Camera, readback: &Readback<'_>) -> Result<Vec<f32>> {
    if readback.depth.len() != readback.width as usize * readback.height as usize {
        return Err(LixelError::UnusableSamples { reason: "readback buffers do not match its size" });
    }
    let view_from_clip = camera.clip_from_view().inverse();
    // Distance at lixel depth `z` (forward, [0, 1)); the depth row has no x, y terms.
    let lixel_distance = |z: f64| {
        let p = view_from_clip * glam::DVec4::new(0.0, 0.0, z, 1.0);
        -p.z / p.w
    };
    let to_distance = |v: f32| -> f32 {
        let v = f64::from(v);
        if !v.is_finite() {
            return f32::NAN;
        }
        let d = match readback.layout.depth {
            ReadbackDepth::Lixel if v >= 1.0 => f64::NAN,
            ReadbackDepth::Window | ReadbackDepth::GlWindow if v >= 1.0 => f64::NAN,
            ReadbackDepth::WindowReversed if v <= 0.0 => f64::NAN,
            ReadbackDepth::Lixel => lixel_distance(v),
            ReadbackDepth::Window | ReadbackDepth::WindowReversed => camera.distance_at_source_depth(v),
            ReadbackDepth::GlWindow => camera.distance_at_source_depth(2.0 * v - 1.0),
            ReadbackDepth::LinearView => v,
        };
        if d.is_finite() {
            d as f32
        } else {
            f32::NAN
        }
    };
    Ok(readback.depth.iter().map(|&v| to_distance(v)).collect())
}

/// The nearest and farthest view depth the readback saw (SDSM's depth
/// bounds), within `camera`'s own range; `None` when it saw nothing.
///
/// # Errors
/// As [`linear_view_depths`].
pub fn visible_depth_range(camera: &Camera, readback: &Readback<'_>) -> Result<Option<(f64, f64)>> {
    let depths = linear_view_depths(camera, readback)?;
    let (near, far) = (camera.z_near(), camera.z_far());
    let range = depths
        .iter()
        .map(|&d| f64::from(d))
        .filter(|d| d.is_finite() && *d >= near && *d <= far)
        .fold(None, |acc: Option<(f64, f64)>, d| Some(acc.map_or((d, d), |(lo, hi)| (lo.min(d), hi.max(d)))));
    Ok(range)
}

/// Sample-distribution split placement with hysteresis: the splits follow
/// the visible depth range of each readback, but move only when that range
/// leaves the current one or the current one is looser than twice the
/// padding, so they do not jitter frame to frame.
///
/// The hysteresis is asymmetric, because a readback lags the camera: a
/// range that leaves the current one grows it at once to hold both (the
/// union: what the camera saw a few frames ago may be in view again, and
/// beyond the end splits a surface is looked up outside its cascade's map),
/// while a range that is too loose shrinks only once
/// [`SHRINK_AFTER`](Self::SHRINK_AFTER) readbacks in a row found it too
/// loose (a camera pressed against an object sees a short range for a few
/// frames; the frame after it turns away the far field is back). Splits
/// placed without a readback (the fixed ones) shrink at the first.
///
/// Splits are placed over the visible range padded by `hysteresis` (a ratio
/// for perspective cameras, `hysteresis ·` the camera's range for
/// orthographic ones), clamped to the camera's range limited to the scene
/// ([`CascadeSplits::for_problem`]).
/// With no readback yet, or one that saw nothing, the splits are the fixed
/// ones of that range.
#[derive(Clone, Debug)]
pub struct SplitTracker {
    policy: CascadeSplits,
    hysteresis: f64,
    range: Option<(f64, f64)>,
    splits: Option<Splits>,
    replaced: u64,
    /// Whether the current range came from a readback.
    seen_range: bool,
    /// Readbacks in a row that found the current range too loose.
    loose_readbacks: u32,
}

impl SplitTracker {
    /// Consecutive readbacks that must find the splits too loose before
    /// they shrink.
    pub const SHRINK_AFTER: u32 = 2;

    /// A tracker for `policy`; `hysteresis` (for example 0.1) is the padding
    /// and tolerance described above.
    ///
    /// # Errors
    /// [`LixelError::InvalidCascades`] for an invalid policy or a hysteresis
    /// that is not finite and non-negative.
    pub fn new(policy: CascadeSplits, hysteresis: f64) -> Result<Self> {
        policy.validate()?;
        if !(hysteresis >= 0.0 && hysteresis.is_finite()) {
            return Err(LixelError::InvalidCascades { reason: "hysteresis must be finite and non-negative" });
        }
        Ok(Self { policy, hysteresis, range: None, splits: None, replaced: 0, seen_range: false, loose_readbacks: 0 })
    }

    /// The current splits, if any update ran.
    #[must_use]
    pub fn splits(&self) -> Option<&Splits> {
        self.splits.as_ref()
    }

    /// How many times the splits were (re-)placed.
    #[must_use]
    pub fn replacements(&self) -> u64 {
        self.replaced
    }

    /// Updates the splits for `problem` (the full, unsliced problem) given
    /// the visible depth range of the latest readback (`None`: no readback,
    /// or it saw nothing) and returns them.
    ///
    /// # Errors
    /// As [`CascadeSplits::place`] (a visible range too thin for the count).
    pub fn update(&mut self, problem: &ShadowProblem, visible: Option<(f64, f64)>) -> Result<&Splits> {
        let (lo_limit, hi_limit) = view_range(problem);
        let camera = problem.camera();
        let ratio = !camera.is_orthographic() && lo_limit > 0.0;
        let pad = self.hysteresis * (hi_limit - lo_limit);
        let grow = |(lo, hi): (f64, f64), times: f64| -> (f64, f64) {
            let (lo, hi) = if ratio {
                let f = (1.0 + self.hysteresis).powf(times);
                (lo / f, hi * f)
            } else {
                (lo - pad * times, hi + pad * times)
            };
            (lo.max(lo_limit), hi.min(hi_limit))
        };
        let seen = match visible {
            Some((lo, hi)) if hi >= lo && lo < hi_limit && hi > lo_limit => (lo.max(lo_limit), hi.min(hi_limit)),
            _ => (lo_limit, hi_limit),
        };
        let mut target = grow(seen, 1.0);
        let from_readback = visible.is_some();
        // Keep the splits while they hold what was seen and are not more
        // than twice the padding too loose (for SHRINK_AFTER readbacks in a
        // row, when the range came from a readback); a range that does not
        // hold what was seen grows to the union.
        let keep = match (self.range, &self.splits) {
            (Some(current), Some(_)) => {
                let loose = grow(seen, 2.0);
                let holds = current.0 <= seen.0 && current.1 >= seen.1;
                let tight = current.0 >= loose.0 && current.1 <= loose.1;
                self.loose_readbacks = if holds && !tight && from_readback { self.loose_readbacks + 1 } else { 0 };
                if !holds && from_readback && self.seen_range {
                    target = (target.0.min(current.0), target.1.max(current.1));
                }
                holds && (tight || (self.seen_range && from_readback && self.loose_readbacks < Self::SHRINK_AFTER))
            }
            _ => false,
        };
        if !keep {
            let (lo, hi) = if target.1 > target.0 { target } else { (lo_limit, hi_limit) };
            self.splits = Some(self.policy.place(lo, hi)?);
            self.range = Some((lo, hi));
            self.replaced += 1;
            self.seen_range = from_readback;
            self.loose_readbacks = 0;
        }
        Ok(self.splits.as_ref().expect("placed above"))
    }
}

/// Scene optimization per cascade from one readback: the pixels are
/// partitioned by view depth ([`Splits::slice`]), and each cascade keeps its
/// own [`Optimizer`] and previous matrix, so each has its own hysteresis
/// ([`OptimizeOptions::accept_ratio`]).
#[derive(Clone, Debug)]
pub struct CascadeOptimizer {
    optimizers: Vec<Optimizer>,
    previous: Vec<Option<LightMatrix>>,
}

impl CascadeOptimizer {
    /// An optimizer for up to `count` cascades.
    #[must_use]
    pub fn new(count: usize, options: &OptimizeOptions) -> Self {
        Self { optimizers: (0..count).map(|_| Optimizer::new(options.clone())).collect(), previous: vec![None; count] }
    }

    /// Cascade `k`'s current matrix, if it was optimized.
    #[must_use]
    pub fn matrix(&self, k: usize) -> Option<&LightMatrix> {
        self.previous.get(k).and_then(Option::as_ref)
    }

    /// The samples of each cascade of light `light_index` from the readback
    /// of the full camera ([`CascadeProblems::camera`]).
    ///
    /// # Errors
    /// What [`linear_view_depths`] and [`Samples::from_readback`] report.
    pub fn samples(
        cascades: &CascadeProblems,
        readback: &Readback<'_>,
        light_index: u32,
        options: &SampleOptions,
    ) -> Result<Vec<Samples>> {
        let depth = linear_view_depths(cascades.camera(), readback)?;
        let mut layout = readback.layout;
        layout.depth = ReadbackDepth::LinearView;
        let linear = Readback { depth: &depth, layout, ..*readback };
        cascades.problems().iter().map(|p| Samples::from_readback(p, &linear, light_index, options)).collect()
    }

    /// Optimizes every cascade from its samples (as [`Self::samples`]
    /// returns them), each against its own previous matrix; entry `k` is
    /// cascade `k`'s result.
    ///
    /// # Errors
    /// [`LixelError::InvalidCascades`] when there are more cascades than
    /// this optimizer was made for; each cascade's own error is in its entry.
    pub fn optimize(&mut self, samples: &[Samples]) -> Result<Vec<Result<Optimized>>> {
        if samples.len() > self.optimizers.len() {
            return Err(LixelError::InvalidCascades { reason: "more cascades than the optimizer was made for" });
        }
        Ok(samples
            .iter()
            .enumerate()
            .map(|(k, s)| {
                let result = self.optimizers[k].optimize(s, self.previous[k].as_ref());
                if let Ok(optimized) = &result {
                    self.previous[k] = Some(optimized.matrix);
                }
                result
            })
            .collect())
    }
}

#[cfg(test)]
mod tests {
    use glam::{DVec3, UVec2};

    use super::*;
    use crate::{Aabb, Light, SceneBounds, ShadowMapSize};

    fn problem() -> ShadowProblem {
        let camera = Camera::look_at(
            DVec3::new(0.0, 2.0, 0.0),
            DVec3::new(0.0, 1.0, -10.0),
            DVec3::Y,
            1.0,
            UVec2::new(64, 64),
            0.1,
            500.0,
        )
        .unwrap();
        let scene = Aabb::from_corners(DVec3::new(-300.0, 0.0, -300.0), DVec3::new(300.0, 5.0, 300.0));
        ShadowProblem::new(
            camera,
            Light::directional(DVec3::new(1.0, -1.0, 0.2)),
            SceneBounds::uniform(scene),
            ShadowMapSize::square(64),
        )
        .unwrap()
    }

    #[test]
    fn splits_hold_still_for_small_changes_and_follow_large_ones() {
        let problem = problem();
        let mut tracker = SplitTracker::new(CascadeSplits::default(), 0.1).unwrap();
        let first = tracker.update(&problem, Some((1.0, 50.0))).unwrap().clone();
        assert!(first.near() <= 1.0 && first.far() >= 50.0);
        assert!(first.near() > 0.85 && first.far() < 60.0, "{first:?}");
        // Small moves inside the padding: the same splits.
        for range in [(1.02, 49.0), (0.95, 52.0), (0.97, 54.0)] {
            assert_eq!(tracker.update(&problem, Some(range)).unwrap(), &first);
        }
        assert_eq!(tracker.replacements(), 1);
        // Seeing nearer than the splits: re-placed at once, holding it and
        // what the splits held (a readback lags the camera).
        let nearer = tracker.update(&problem, Some((0.5, 20.0))).unwrap().clone();
        assert!(nearer.near() <= 0.5 && nearer.far() == first.far(), "{nearer:?}");
        // Far tighter: re-placed once two readbacks in a row say so.
        assert_eq!(tracker.update(&problem, Some((0.5, 10.0))).unwrap(), &nearer);
        let tight = tracker.update(&problem, Some((0.5, 10.0))).unwrap().clone();
        assert!(tight.far() < 15.0 && tight.far() >= 10.0, "{tight:?}");
        assert_eq!(tracker.replacements(), 3);
        // A tight readback between loose ones starts the count again.
        for range in [(0.5, 4.0), (0.5, 10.0), (0.5, 4.0)] {
            assert_eq!(tracker.update(&problem, Some(range)).unwrap(), &tight, "{range:?}");
        }
        assert_eq!(tracker.replacements(), 3);
        // Nothing seen: the fixed splits of the camera range within the scene.
        let fixed = tracker.update(&problem, None).unwrap().clone();
        assert_eq!(fixed.near(), 0.1);
        let deepest =
            problem.bounds().scene().corners().iter().map(|&p| problem.camera().view_depth(p)).fold(0.0, f64::max);
        assert!(fixed.far() >= deepest && fixed.far() < deepest * (1.0 + 1e-5), "{fixed:?} vs {deepest}");
        assert!(SplitTracker::new(CascadeSplits::default(), f64::NAN).is_err());
    }

    #[test]
    fn linear_depths_agree_for_every_readback_convention() {
        let problem = problem();
        let camera = problem.camera();
        let distances = [0.5, 3.0, 40.0, 499.0];
        let lixel: Vec<f32> = distances.iter().map(|&d| camera.depth_at_distance(d) as f32).chain([1.0]).collect();
        let bits = [0u32; 5];
        let readback = Readback {
            width: 5,
            height: 1,
            depth: &lixel,
            shadow_bits: &bits,
            normals: None,
            layout: Default::default(),
        };
        let got = linear_view_depths(camera, &readback).unwrap();
        for (g, d) in got.iter().zip(distances) {
            assert!((f64::from(*g) - d).abs() < 1e-3 * d, "{g} vs {d}");
        }
        assert!(got[4].is_nan());
        let range = visible_depth_range(camera, &readback).unwrap().unwrap();
        assert!((range.0 - 0.5).abs() < 1e-3 && (range.1 - 499.0).abs() < 0.5, "{range:?}");
        let short = Readback { width: 6, ..readback };
        assert!(linear_view_depths(camera, &short).is_err());
    }
}
