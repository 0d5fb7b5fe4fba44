//! Cascaded shadow maps for sun lights: the view frustum cut by depth into
//! slices, one [`ShadowProblem`] (and one map) per slice.
//!
//! Why a module of its own: a cascade is not a new parameterization but a
//! new *problem*. Each slice's problem is the original one with the camera's
//! depth range narrowed to the slice ([`ShadowProblem::depth_slice`]), so its
//! view body `V` is the frustum slice and every method (focused, LiSPSM,
//! plane-optimal, PSM, the scene optimizer) solves it unchanged, with the
//! same contract: a typed error, or a matrix holding the slice's relevant
//! points `V_k ∩ R ∩ L`.
//!
//! ```text
//! CascadeSplits ──place / for_problem──▶ Splits ──CascadeProblems::new──▶ one ShadowProblem per slice ──solve──▶ one LightMatrix per slice
//!        ▲                                   │
//!        └── SplitTracker (SDSM: visible depth range from the readback, with hysteresis)
//!                                            └── Splits::choose(view depth): the per-pixel cascade and blend weight
//! ```
//!
//! Split schemes are the engines' (Zhang et al. 2006, "parallel-split shadow
//! maps": uniform, logarithmic and their λ-blend, the "practical" scheme);
//! sample-distribution shadow maps (Lauritzen et al. 2010) place them inside
//! the depth range the camera actually sees ([`visible_depth_range`]).

mod samples;

use crate::camera::Camera;
use crate::conventions::{ClipDepth, ProjectionHints};
use crate::error::{LixelError, Result};
use crate::matrix::LightMatrix;
use crate::methods::Parameterization;
use crate::problem::ShadowProblem;

pub use samples::{linear_view_depths, visible_depth_range, CascadeOptimizer, SplitTracker};

/// Most cascades one light may have (map array layers in the renderer).
pub const MAX_CASCADES: usize = 8;

/// Where the split boundaries go between near `n` and far `f`, for `K`
/// cascades (boundary `i` of `0..=K`).
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub enum SplitScheme {
    /// `n + (f - n)·i/K`: equal lengths (wastes texels near the eye).
    Uniform,
    /// `n·(f/n)^(i/K)`: equal ratios, the ideal for a perspective camera.
    /// Falls back to [`Uniform`](Self::Uniform) where `n <= 0` (orthographic
    /// cameras whose near plane is at or behind the eye).
    Logarithmic,
    /// `λ·log + (1 - λ)·uniform` (Zhang et al.'s "practical" split, the
    /// engines' default with `λ` about 0.5-0.9). `lambda` in `[0, 1]`.
    Practical {
        /// Weight of the logarithmic scheme.
        lambda: f64,
    },
}

/// A cascade split policy: how many cascades, where their boundaries go and
/// how far neighbouring cascades overlap (the blend band).
///
/// Cascade `k` owns view depths `[b_k, b_(k+1))`; its map also covers the
/// blend band of the previous cascade, the last `overlap · (b_k - b_(k-1))`
/// before `b_k`, where a renderer fades from cascade `k-1` to `k`
/// ([`Splits::choose`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CascadeSplits {
    /// Number of cascades, `1..=MAX_CASCADES`. Default 4.
    pub count: usize,
    /// Boundary placement. Default `Practical { lambda: 0.75 }`.
    pub scheme: SplitScheme,
    /// Blend band as a fraction of the finer cascade's length, `[0, 1)`. Default 0.1.
    pub overlap: f64,
}

impl Default for CascadeSplits {
    fn default() -> Self {
        Self { count: 4, scheme: SplitScheme::Practical { lambda: 0.75 }, overlap: 0.1 }
    }
}

fn invalid(reason: &'static str) -> LixelError {
    LixelError::InvalidCascades { reason }
}

impl CascadeSplits {
    /// Checks the policy.
    ///
    /// # Errors
    /// [`LixelError::InvalidCascades`] for a count outside `1..=MAX_CASCADES`,
    /// an overlap outside `[0, 1)` or a `lambda` outside `[0, 1]`.
    pub fn validate(&self) -> Result<()> {
        if !(1..=MAX_CASCADES).contains(&self.count) {
            return Err(invalid("cascade count must be 1 to MAX_CASCADES"));
        }
        if !(0.0..1.0).contains(&self.overlap) {
            return Err(invalid("overlap must be in [0, 1)"));
        }
        if let SplitScheme::Practical { lambda } = self.scheme {
            if !(0.0..=1.0).contains(&lambda) {
                return Err(invalid("practical split lambda must be in [0, 1]"));
            }
        }
        Ok(())
    }

    /// The splits of view depths `[near, far]` (distances along the view
    /// direction).
    ///
    /// # Errors
    /// [`LixelError::InvalidCascades`] for an invalid policy
    /// ([`Self::validate`]), a non-finite or empty range, or a range too thin
    /// (in `f64`) for strictly increasing boundaries.
    pub fn place(&self, near: f64, far: f64) -> Result<Splits> {
        self.validate()?;
        if !(near.is_finite() && far.is_finite() && far > near) {
            return Err(invalid("split range must be finite with near < far"));
        }
        let k = self.count;
        let lambda = match self.scheme {
            SplitScheme::Uniform => 0.0,
            SplitScheme::Logarithmic => 1.0,
            SplitScheme::Practical { lambda } => lambda,
        };
        let lambda = if near > 0.0 { lambda } else { 0.0 };
        let mut boundaries: Vec<f64> = (0..=k)
            .map(|i| {
                let t = i as f64 / k as f64;
                let uniform = near + (far - near) * t;
                let log = if lambda > 0.0 { near * (far / near).powf(t) } else { uniform };
                lambda * log + (1.0 - lambda) * uniform
            })
            .collect();
        // Exact ends: the cascades cover exactly what was asked.
        boundaries[0] = near;
        boundaries[k] = far;
        if boundaries.windows(2).any(|w| !(w[1] > w[0])) {
            return Err(invalid("depth range too thin for strictly increasing split boundaries"));
        }
        let bands = boundaries.windows(2).take(k - 1).map(|w| self.overlap * (w[1] - w[0])).collect();
        Ok(Splits { boundaries, bands })
    }

    /// The fixed (engine-style) splits of `problem`'s camera: from its near
    /// plane to its far plane or to the deepest corner of the scene bounds,
    /// whichever is nearer (an infinite far plane included). When the scene
    /// lies wholly before the near plane (nothing to see), the camera's own
    /// range is split, its infinite far plane put at
    /// [`INFINITE_FAR_CORNER_RATIO`](crate::INFINITE_FAR_CORNER_RATIO)` · near`.
    ///
    /// # Errors
    /// As [`Self::place`].
    pub fn for_problem(&self, problem: &ShadowProblem) -> Result<Splits> {
        let (near, far) = view_range(problem);
        self.place(near, far)
    }
}

/// The camera's depth range limited to the scene bounds (see
/// [`CascadeSplits::for_problem`]).
pub(crate) fn view_range(problem: &ShadowProblem) -> (f64, f64) {
    let camera = problem.camera();
    let near = camera.z_near();
    let deepest =
        problem.bounds().scene().corners().iter().map(|&p| camera.view_depth(p)).fold(f64::NEG_INFINITY, f64::max);
    let camera_far = if camera.z_far().is_finite() {
        camera.z_far()
    } else {
        near.abs().max(f64::MIN_POSITIVE) * crate::INFINITE_FAR_CORNER_RATIO
    };
    // A little beyond the deepest corner, so the last slice holds it.
    let scene_far = deepest + 1e-6 * deepest.abs().max(near.abs());
    let far = if scene_far > near { scene_far.min(camera.z_far()) } else { camera_far };
    (near, far)
}

/// Split boundaries and blend bands along the view depth.
#[derive(Clone, Debug, PartialEq)]
pub struct Splits {
    /// `K + 1` strictly increasing view depths.
    boundaries: Vec<f64>,
    /// `bands[k]`: blend band before boundary `k + 1`, for `k < K - 1`.
    bands: Vec<f64>,
}

/// The cascade a view depth uses ([`Splits::choose`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CascadeChoice {
    /// The cascade that owns the depth.
    pub index: usize,
    /// Weight of cascade `index + 1` in `[0, 1)`: non-zero only inside the
    /// blend band at the end of cascade `index`.
    pub blend: f64,
}

impl CascadeChoice {
    /// The cascade whose lookup gives a pixel's binary shadow bit: `index`,
    /// or `index + 1` from the middle of the blend band on (`blend >=
    /// 0.5`). With two lookups blended by weight, this is the blended
    /// visibility rounded, ties going to the farther cascade. The renderer's
    /// mask bits follow it (`render::Renderer::set_cascades`).
    #[must_use]
    pub fn bit_owner(&self) -> usize {
        if self.blend >= 0.5 {
            self.index + 1
        } else {
            self.index
        }
    }
}

impl Splits {
    /// Splits from explicit boundaries (strictly increasing, finite, at
    /// least two) and an overlap fraction (as [`CascadeSplits::overlap`]).
    ///
    /// # Errors
    /// [`LixelError::InvalidCascades`] when they are not.
    pub fn from_boundaries(boundaries: &[f64], overlap: f64) -> Result<Self> {
        let k = boundaries.len().saturating_sub(1);
        if !(1..=MAX_CASCADES).contains(&k) {
            return Err(invalid("cascade count must be 1 to MAX_CASCADES"));
        }
        if !(0.0..1.0).contains(&overlap) {
            return Err(invalid("overlap must be in [0, 1)"));
        }
        if boundaries.iter().any(|b| !b.is_finite()) || boundaries.windows(2).any(|w| !(w[1] > w[0])) {
            return Err(invalid("split boundaries must be finite and strictly increasing"));
        }
        let bands = boundaries.windows(2).take(k - 1).map(|w| overlap * (w[1] - w[0])).collect();
        Ok(Self { boundaries: boundaries.to_vec(), bands })
    }

    /// Number of cascades.
    #[must_use]
    pub fn count(&self) -> usize {
        self.boundaries.len() - 1
    }

    /// The `count() + 1` boundaries, nearest first.
    #[must_use]
    pub fn boundaries(&self) -> &[f64] {
        &self.boundaries
    }

    /// Nearest depth covered.
    #[must_use]
    pub fn near(&self) -> f64 {
        self.boundaries[0]
    }

    /// Farthest depth covered.
    #[must_use]
    pub fn far(&self) -> f64 {
        self.boundaries[self.count()]
    }

    /// Length of the blend band at the end of cascade `k` (zero for the last).
    #[must_use]
    pub fn band(&self, k: usize) -> f64 {
        self.bands.get(k).copied().unwrap_or(0.0)
    }

    /// The view depths cascade `k`'s map covers: `[b_k - band(k - 1), b_(k+1)]`.
    ///
    /// # Panics
    /// If `k >= count()`.
    #[must_use]
    pub fn slice(&self, k: usize) -> (f64, f64) {
        let before = if k == 0 { 0.0 } else { self.band(k - 1) };
        (self.boundaries[k] - before, self.boundaries[k + 1])
    }

    /// The cascade for a pixel at view depth `depth`: the `k` with
    /// `b_k <= depth < b_(k+1)` (the last cascade includes the far end), and
    /// the weight of cascade `k + 1` in the blend band, rising linearly from
    /// 0 at `b_(k+1) - band(k)` towards 1 at `b_(k+1)`. `None` outside
    /// `[near, far]` or for a non-finite depth. The renderer implements the
    /// same choice (`render::Renderer::set_cascades`, `cascade_weight` and
    /// `cascade_owns` in `shaders/common.wgsl`; `tests/render_cascades.rs`
    /// checks that they agree) and, where this says `None`, gives depths
    /// nearer than `near` to the first cascade and beyond `far` to the last.
    #[must_use]
    pub fn choose(&self, depth: f64) -> Option<CascadeChoice> {
        if !(depth >= self.near() && depth <= self.far()) {
            return None;
        }
        let last = self.count() - 1;
        let index = (0..last).find(|&k| depth < self.boundaries[k + 1]).unwrap_or(last);
        let band = self.band(index);
        let start = self.boundaries[index + 1] - band;
        let blend = if band > 0.0 && depth > start { ((depth - start) / band).min(1.0 - f64::EPSILON) } else { 0.0 };
        Some(CascadeChoice { index, blend })
    }
}

impl ShadowProblem {
    /// This problem with the camera's depth range narrowed to view depths
    /// `[near, far]` (distances along the view direction): its view body is
    /// that slice of the frustum, and every method maps the slice's relevant
    /// points. Light, bounds, map size, fit options and tolerances are kept.
    ///
    /// # Errors
    /// [`LixelError::InvalidCascades`] when `[near, far]` is not finite with
    /// `near < far`, or a perspective slice does not start in front of the
    /// eye; what [`Camera::from_matrices_with`] reports for a slice it cannot
    /// hold (one so thin that its depth row is singular).
    pub fn depth_slice(&self, near: f64, far: f64) -> Result<Self> {
        let camera = slice_camera(self.camera(), near, far)?;
        Ok(Self::new(camera, *self.light(), *self.bounds(), self.map_size())?
            .with_fit(*self.fit_options())
            .with_tolerances(*self.tolerances()))
    }
}

/// `camera` with its depth range set to `[near, far]`, in lixel's convention.
fn slice_camera(camera: &Camera, near: f64, far: f64) -> Result<Camera> {
    if !(near.is_finite() && far.is_finite() && far > near) {
        return Err(invalid("slice must be finite with near < far"));
    }
    let mut proj = camera.clip_from_view();
    // Normalised: w = -z (perspective, d = -z) or 1; depth 0 at near, 1 at far.
    let (a, b) = if camera.is_orthographic() {
        (1.0 / (near - far), near / (near - far))
    } else {
        if !(near > 0.0) {
            return Err(invalid("a perspective slice must start in front of the eye"));
        }
        (far / (near - far), near * far / (near - far))
    };
    proj.x_axis.z = 0.0;
    proj.y_axis.z = 0.0;
    proj.z_axis.z = a;
    proj.w_axis.z = b;
    Camera::from_matrices_with(
        camera.view_from_world(),
        proj,
        camera.viewport(),
        &ProjectionHints::clip_depth(ClipDepth::ZeroToOne),
    )
}

/// One [`ShadowProblem`] per cascade, from splits.
#[derive(Clone, Debug)]
pub struct CascadeProblems {
    camera: Camera,
    splits: Splits,
    problems: Vec<ShadowProblem>,
}

impl CascadeProblems {
    /// Slices `problem` at `splits` ([`Splits::slice`]; each cascade keeps
    /// the problem's map size: `K` maps of that size).
    ///
    /// # Errors
    /// As [`ShadowProblem::depth_slice`].
    pub fn new(problem: &ShadowProblem, splits: Splits) -> Result<Self> {
        let problems = (0..splits.count())
            .map(|k| {
                let (near, far) = splits.slice(k);
                problem.depth_slice(near, far)
            })
            .collect::<Result<_>>()?;
        Ok(Self { camera: *problem.camera(), splits, problems })
    }

    /// The full (unsliced) camera.
    #[must_use]
    pub fn camera(&self) -> &Camera {
        &self.camera
    }

    /// The splits.
    #[must_use]
    pub fn splits(&self) -> &Splits {
        &self.splits
    }

    /// Cascade `k`'s problem is `problems()[k]`.
    #[must_use]
    pub fn problems(&self) -> &[ShadowProblem] {
        &self.problems
    }

    /// Solves every cascade with one parameterization; entry `k` is cascade
    /// `k`'s matrix or its typed error.
    #[must_use]
    pub fn solve(&self, parameterization: &Parameterization) -> Vec<Result<LightMatrix>> {
        self.problems.iter().map(|p| p.solve(parameterization)).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn schemes_place_the_textbook_boundaries() {
        let log = CascadeSplits { count: 4, scheme: SplitScheme::Logarithmic, overlap: 0.0 };
        let b = log.place(1.0, 10_000.0).unwrap();
        for (got, want) in b.boundaries().iter().zip([1.0, 10.0, 100.0, 1000.0, 10_000.0]) {
            assert!((got - want).abs() <= 1e-9 * want, "{got} vs {want}");
        }
        let uniform = CascadeSplits { scheme: SplitScheme::Uniform, ..log };
        assert_eq!(uniform.place(0.0, 8.0).unwrap().boundaries(), &[0.0, 2.0, 4.0, 6.0, 8.0]);
        let half = CascadeSplits { scheme: SplitScheme::Practical { lambda: 0.5 }, ..log };
        let p = half.place(1.0, 10_000.0).unwrap();
        let want = 0.5 * 10.0 + 0.5 * (1.0 + 9999.0 / 4.0);
        assert!((p.boundaries()[1] - want).abs() < 1e-9);
        // Orthographic near at the eye: log falls back to uniform.
        assert_eq!(log.place(0.0, 8.0).unwrap().boundaries(), &[0.0, 2.0, 4.0, 6.0, 8.0]);
    }

    #[test]
    fn bad_policies_are_typed_errors() {
        let ok = CascadeSplits::default();
        for bad in [
            CascadeSplits { count: 0, ..ok },
            CascadeSplits { count: MAX_CASCADES + 1, ..ok },
            CascadeSplits { overlap: 1.0, ..ok },
            CascadeSplits { overlap: f64::NAN, ..ok },
            CascadeSplits { scheme: SplitScheme::Practical { lambda: 1.5 }, ..ok },
        ] {
            assert!(matches!(bad.place(1.0, 2.0), Err(LixelError::InvalidCascades { .. })), "{bad:?}");
        }
        assert!(matches!(ok.place(2.0, 1.0), Err(LixelError::InvalidCascades { .. })));
        assert!(matches!(ok.place(1.0, f64::INFINITY), Err(LixelError::InvalidCascades { .. })));
        // Too thin for four distinct f64 boundaries.
        assert!(matches!(ok.place(1e15, 1e15 + 0.25), Err(LixelError::InvalidCascades { .. })));
        assert!(Splits::from_boundaries(&[1.0, 1.0], 0.0).is_err());
        assert!(Splits::from_boundaries(&[1.0], 0.0).is_err());
    }

    #[test]
    fn a_slice_problem_sees_only_its_slice() {
        use glam::{DVec3, UVec2};
        let camera = Camera::look_at(
            DVec3::new(0.0, 1.7, 0.0),
            DVec3::new(0.0, 1.0, -10.0),
            DVec3::Y,
            1.0,
            UVec2::new(64, 48),
            0.1,
            1000.0,
        )
        .unwrap();
        let scene = crate::Aabb::from_corners(DVec3::new(-800.0, 0.0, -800.0), DVec3::new(800.0, 4.0, 800.0));
        let sun = crate::Light::directional(DVec3::new(0.3, -1.0, 0.2));
        let problem =
            ShadowProblem::new(camera, sun, crate::SceneBounds::uniform(scene), crate::ShadowMapSize::square(256))
                .unwrap();
        let cascades = CascadeProblems::new(&problem, CascadeSplits::default().for_problem(&problem).unwrap()).unwrap();
        let mut widths = Vec::new();
        for (k, p) in cascades.problems().iter().enumerate() {
            let (near, far) = cascades.splits().slice(k);
            assert!(
                (p.camera().z_near() - near).abs() <= 1e-12 * far && (p.camera().z_far() - far).abs() <= 1e-9 * far
            );
            let body = p.visible_receiver_body();
            assert!(!body.is_empty());
            for v in body.vertices() {
                let d = camera.view_depth(*v);
                assert!(
                    d >= near * (1.0 - 1e-9) && d <= far * (1.0 + 1e-9),
                    "cascade {k}: depth {d} outside [{near}, {far}]"
                );
            }
            let m = p.solve(&Parameterization::Focused).unwrap();
            // World width of the map along its first axis: grows with the slice.
            widths.push(2.0 / m.clip_from_world.row(0).truncate().length());
        }
        assert!(widths.windows(2).all(|w| w[1] > w[0]), "{widths:?}");
        let full = problem.solve(&Parameterization::Focused).unwrap();
        assert!(widths[0] * 10.0 < 2.0 / full.clip_from_world.row(0).truncate().length(), "{widths:?}");
    }

    #[test]
    fn choose_blends_inside_the_band_only() {
        let s = Splits::from_boundaries(&[1.0, 2.0, 4.0], 0.5).unwrap();
        assert_eq!(s.choose(1.0), Some(CascadeChoice { index: 0, blend: 0.0 }));
        assert_eq!(s.choose(1.4), Some(CascadeChoice { index: 0, blend: 0.0 }));
        let c = s.choose(1.75).unwrap();
        assert_eq!(c.index, 0);
        assert!((c.blend - 0.5).abs() < 1e-12);
        assert_eq!(s.choose(2.0), Some(CascadeChoice { index: 1, blend: 0.0 }));
        assert_eq!(s.choose(4.0), Some(CascadeChoice { index: 1, blend: 0.0 }));
        assert_eq!(s.choose(4.1), None);
        assert_eq!(s.choose(0.9), None);
        assert_eq!(s.choose(f64::NAN), None);
        assert_eq!(s.slice(1), (1.5, 4.0));
    }
}
