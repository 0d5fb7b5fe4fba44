//! Samples for the scene optimizer, from a read-back analysis pass or from
//! plain world-space points.

use glam::{DMat2, DVec3};

use crate::caster_bounds::CasterBounds;
use crate::error::{LixelError, Result};
use crate::light::LightFrame;
use crate::matrix::LightMatrix;
use crate::optimize::objective::BoundarySample;
use crate::problem::ShadowProblem;
use crate::workspace::with_workspace;

use super::extract::{check_readback, extract, faces_light, SampleWorkspace};

/// A low-resolution readback of the camera's analysis pass, as an engine
/// reads it: row-major, laid out as [`layout`](Self::layout) says.
#[derive(Clone, Copy, Debug)]
pub struct Readback<'a> {
    /// Width in pixels (of the readback, not the screen).
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Depth values, in the convention of [`ReadbackLayout::depth`].
    pub depth: &'a [f32],
    /// Bit `i` set: the pixel is in light `i`'s shadow.
    pub shadow_bits: &'a [u32],
    /// Optional world-space normals (need not be unit length).
    pub normals: Option<&'a [[f32; 3]]>,
    /// Depth convention, row order and covered part of the viewport.
    pub layout: ReadbackLayout,
}

/// What a readback's depth values are.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum ReadbackDepth {
    /// lixel's own depth of the normalised camera (the `z` of
    /// [`Camera::screen_from_world`](crate::Camera::screen_from_world)):
    /// `[0, 1]` growing away from the eye, `1` = nothing. What lixel's
    /// renderer and [`SyntheticScene`](crate::synthetic::SyntheticScene)
    /// write; for a wgpu-convention camera (such as
    /// [`Camera::look_at`](crate::Camera::look_at)) the same as [`Window`](Self::Window).
    #[default]
    Lixel,
    /// The depth buffer of the engine's `[0, 1]` clip-depth projection,
    /// forward: NDC depth, `1` (the cleared far plane) = nothing.
    Window,
    /// The depth buffer of a reverse-Z `[0, 1]` projection: `0` = nothing.
    WindowReversed,
    /// OpenGL window depth of a `[-1, 1]` projection (`glDepthRange(0, 1)`):
    /// `(z_ndc + 1) / 2`, `1` = nothing.
    GlWindow,
    /// Linear distance in front of the eye along the view direction, in
    /// world units; non-finite = nothing.
    LinearView,
}

/// Row order of a readback.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum RowOrder {
    /// Row 0 is the top of the screen (wgpu, Direct3D, Vulkan, Metal).
    #[default]
    TopDown,
    /// Row 0 is the bottom (OpenGL's `glReadPixels`).
    BottomUp,
}

/// A rectangle of the viewport in full-resolution pixels; `y` counts rows
/// in the readback's [`RowOrder`] (from the bottom for `BottomUp`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct PixelRect {
    /// First column.
    pub x: u32,
    /// First row.
    pub y: u32,
    /// Width.
    pub width: u32,
    /// Height.
    pub height: u32,
}

/// How a [`Readback`] is laid out. The default is lixel's own: lixel depth,
/// top-down rows, the whole viewport.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct ReadbackLayout {
    /// What the depth values are.
    pub depth: ReadbackDepth,
    /// Row order.
    pub rows: RowOrder,
    /// The part of the viewport the readback covers; `None` is all of it.
    pub rect: Option<PixelRect>,
}

/// How [`Samples::from_readback`] classifies pixels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SampleOptions {
    /// A depth second difference above `curvature_ratio · |first difference|`
    /// (plus [`depth_epsilon`](Self::depth_epsilon)) marks a depth
    /// discontinuity: no reliable derivative there. Planes have zero second
    /// difference (depth-buffer values are affine in screen space on a
    /// plane). Default `0.5`.
    pub curvature_ratio: f64,
    /// Absolute slack on the second-difference test, in depth-buffer units.
    /// Default `1e-6` (a few f32 ulps near 1).
    pub depth_epsilon: f64,
    /// A boundary receiver must face the light with at least this cosine.
    /// Default `0.0`.
    pub min_light_cosine: f64,
}

impl Default for SampleOptions {
    fn default() -> Self {
        Self { curvature_ratio: 0.5, depth_epsilon: 1e-6, min_light_cosine: 0.0 }
    }
}

/// Counts from building [`Samples`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SampleCounts {
    /// Pixels (or points) with geometry.
    pub covered: usize,
    /// Shadowed pixels.
    pub shadowed: usize,
    /// Pixels next to both shadowed and lit pixels.
    pub boundary_candidates: usize,
    /// Candidates dropped for a depth discontinuity or missing neighbours.
    pub rejected_discontinuity: usize,
    /// Candidates dropped because the receiver faces away from the light.
    pub rejected_back_facing: usize,
    /// Inputs dropped for non-finite values or positions behind the camera.
    pub rejected_invalid: usize,
}

/// The samples of one light for [`optimize_light_matrix`](crate::optimize_light_matrix):
/// *boundary* samples drive the objective, *relevant* samples (every
/// shadowed pixel plus the boundary samples) must all be in the map.
#[derive(Clone, Debug)]
pub struct Samples {
    pub(crate) problem: ShadowProblem,
    /// The focused matrix (the optimizer's fallback and a starting point).
    pub(crate) focused: Result<LightMatrix>,
    pub(crate) frame: LightFrame,
    pub(crate) boundary: Vec<BoundarySample>,
    /// World position of every boundary sample (for debug views).
    pub(crate) boundary_world: Vec<DVec3>,
    /// `X~` of every relevant sample.
    pub(crate) relevant: Vec<DVec3>,
    /// World position of every relevant sample (the optimizer checks its
    /// answer on them, as a renderer evaluates it).
    pub(crate) relevant_world: Vec<DVec3>,
    /// World points whose depth the map must cover besides the relevant
    /// samples (`relevant_world`, which follow them in the depth fold): the
    /// vertices of the visible receivers' body.
    pub(crate) depth_points: Vec<DVec3>,
    /// The casters of the visible receivers' body, whose depth the map must
    /// cover too.
    pub(crate) casters: CasterBounds,
    pub(crate) counts: SampleCounts,
}

impl Samples {
    fn empty(problem: &ShadowProblem) -> Self {
        let mut samples = Self {
            problem: problem.clone(),
            focused: Err(LixelError::UnusableSamples { reason: "not computed" }),
            frame: LightFrame::new(problem.light(), glam::DVec3::NEG_Y),
            boundary: Vec::new(),
            boundary_world: Vec::new(),
            relevant: Vec::new(),
            relevant_world: Vec::new(),
            depth_points: Vec::new(),
            casters: CasterBounds::default(),
            counts: SampleCounts::default(),
        };
        samples.reset(problem);
        samples
    }

    /// Makes these the samples of `problem` with no points yet: its visible
    /// receivers' body and casters (depth points), light frame and focused
    /// matrix, keeping the buffers.
    fn reset(&mut self, problem: &ShadowProblem) {
        with_workspace(|ws| {
            let mut focus = ws.take_body();
            problem.visible_receiver_body_into(&mut focus, ws);
            self.frame = problem.frame_towards(&focus);
            problem.caster_bounds_into(&focus, &mut self.casters, ws);
            self.focused = crate::methods::focused::from_bodies(problem, &focus, &self.casters, ws);
            self.depth_points.clear();
            self.depth_points.extend_from_slice(focus.vertices());
            ws.put_body(focus);
        });
        self.problem = problem.clone();
        self.boundary.clear();
        self.boundary_world.clear();
        self.relevant.clear();
        self.relevant_world.clear();
        self.counts = SampleCounts::default();
    }

    /// The boundary samples (light coordinates and surface derivatives).
    #[must_use]
    pub fn boundary(&self) -> &[BoundarySample] {
        &self.boundary
    }

    /// World positions of the [`boundary`](Self::boundary) samples, in the
    /// same order (for debug views: where the optimizer looked).
    #[must_use]
    pub fn boundary_world(&self) -> &[DVec3] {
        &self.boundary_world
    }

    /// Number of relevant samples.
    #[must_use]
    pub fn relevant_count(&self) -> usize {
        self.relevant.len()
    }

    /// What happened to the input.
    #[must_use]
    pub fn counts(&self) -> SampleCounts {
        self.counts
    }

    /// The problem (camera, light, bounds, map size) the samples belong to.
    #[must_use]
    pub fn problem(&self) -> &ShadowProblem {
        &self.problem
    }

    /// The light frame the samples are expressed in.
    #[must_use]
    pub fn frame(&self) -> &LightFrame {
        &self.frame
    }

    /// Samples from world-space points: `relevant` must all be in the map;
    /// `boundary` (point, surface normal) drive the objective and are
    /// relevant too. Non-finite points, points behind the camera and boundary
    /// points seen edge-on are dropped (counted in
    /// [`SampleCounts::rejected_invalid`]); boundary points facing away from
    /// the light are dropped from the objective but stay relevant.
    #[must_use]
    pub fn from_points(problem: &ShadowProblem, relevant: &[DVec3], boundary: &[(DVec3, DVec3)]) -> Self {
        let mut samples = Self::empty(problem);
        let camera = *problem.camera();
        let screen = camera.screen_from_world();
        let light = *problem.light();
        for &p in relevant {
            samples.push_relevant(p, &camera);
        }
        for &(p, n) in boundary {
            if !samples.push_relevant(p, &camera) {
                continue;
            }
            samples.counts.boundary_candidates += 1;
            let Some(n) = n.try_normalize() else {
                samples.counts.rejected_invalid += 1;
                continue;
            };
            if !faces_light(&light, p, n, 0.0) {
                samples.counts.rejected_back_facing += 1;
                continue;
            }
            // d(pixel)/d(surface) in a tangent basis, inverted: d(surface)/d(pixel).
            let (t1, t2) = n.any_orthonormal_pair();
            let clip = screen * p.extend(1.0);
            let px = glam::DVec2::new(clip.x, clip.y) / clip.w;
            let column = |t: DVec3| {
                let d = screen * t.extend(0.0);
                (glam::DVec2::new(d.x, d.y) - px * d.w) / clip.w
            };
            let ds = DMat2::from_cols(column(t1), column(t2));
            // Seen (nearly) edge-on: the tangent images are (nearly) parallel.
            let sine = ds.determinant().abs() / (ds.x_axis.length() * ds.y_axis.length());
            if !(sine > problem.tolerances().min_view_sine) {
                samples.counts.rejected_invalid += 1;
                continue;
            }
            let inv = ds.inverse();
            let dp_dx = t1 * inv.x_axis.x + t2 * inv.x_axis.y;
            let dp_dy = t1 * inv.y_axis.x + t2 * inv.y_axis.y;
            let light_dir = |v: DVec3| samples.frame.homogeneous4(v.extend(0.0));
            samples.boundary.push(BoundarySample {
                light: samples.frame.homogeneous(p),
                d_dx: light_dir(dp_dx),
                d_dy: light_dir(dp_dy),
            });
            samples.boundary_world.push(p);
        }
        samples
    }

    /// Adds a relevant world point; `false` if it was rejected.
    fn push_relevant(&mut self, p: DVec3, camera: &crate::Camera) -> bool {
        self.counts.covered += 1;
        if !p.is_finite()
            || p.abs().max_element() > crate::MAX_COORDINATE
            || !((camera.clip_from_world() * p.extend(1.0)).w > 0.0)
        {
            self.counts.rejected_invalid += 1;
            return false;
        }
        let x = self.frame.homogeneous(p);
        if x.length_squared() == 0.0 {
            self.counts.rejected_invalid += 1;
            return false;
        }
        self.relevant.push(x);
        self.relevant_world.push(p);
        true
    }

    /// Samples of light `light_index` (bit in [`Readback::shadow_bits`]) from
    /// a low-resolution readback of the camera view.
    ///
    /// Boundary samples: pixels whose 3x3 neighbourhood holds both shadowed
    /// and lit pixels, on receivers facing the light, where the depth has a
    /// reliable derivative (see [`SampleOptions`]); derivatives come from the
    /// read-back normals when given, else from central differences of depth.
    /// Relevant samples: every shadowed pixel plus the boundary samples.
    ///
    /// The readback may be in the engine's own layout ([`ReadbackLayout`]):
    /// its depth convention, row order and sub-rectangle are brought to
    /// lixel's first, so every layout of the same image gives the same samples.
    ///
    /// # Errors
    /// [`LixelError::UnusableSamples`] when the buffer sizes do not match
    /// `width x height`, `light_index >= 32`, the rectangle is empty or
    /// outside the viewport, or the declared depth direction contradicts the
    /// camera's projection.
    pub fn from_readback(
        problem: &ShadowProblem,
        readback: &Readback<'_>,
        light_index: u32,
        options: &SampleOptions,
    ) -> Result<Self> {
        let mut workspace = SampleWorkspace::default();
        Self::check_one(problem, readback, light_index, &mut workspace)?;
        let mut all = [Self::empty(problem)];
        extract(&mut all, &mut workspace, readback, options);
        let [samples] = all;
        Ok(samples)
    }

    /// [`Self::from_readback`] into `self` (a previous call's samples, of any
    /// light), reusing its buffers and `workspace`'s: once they have grown,
    /// this allocates nothing. On an error `self` is left unchanged.
    ///
    /// # Errors
    /// As [`Self::from_readback`].
    pub fn from_readback_into(
        &mut self,
        problem: &ShadowProblem,
        readback: &Readback<'_>,
        light_index: u32,
        options: &SampleOptions,
        workspace: &mut SampleWorkspace,
    ) -> Result<()> {
        Self::check_one(problem, readback, light_index, workspace)?;
        self.reset(problem);
        extract(std::slice::from_mut(self), workspace, readback, options);
        Ok(())
    }

    /// Checks one light's readback and brings it into `workspace`.
    fn check_one(
        problem: &ShadowProblem,
        readback: &Readback<'_>,
        light_index: u32,
        workspace: &mut SampleWorkspace,
    ) -> Result<()> {
        check_readback(readback)?;
        if light_index as usize >= crate::MAX_LIGHTS {
            return Err(LixelError::UnusableSamples { reason: "light index must be below 32" });
        }
        workspace.grid.fill(problem.camera(), readback)?;
        workspace.bits.clear();
        workspace.bits.push(light_index);
        Ok(())
    }

    /// The samples of every light at once: `problems[i]` is light `i` (bit
    /// `i` of [`Readback::shadow_bits`]). One pass over the readback serves
    /// all lights (their bits share a `u32`, and a pixel's world position and
    /// surface derivatives are computed once); each light's samples equal
    /// [`Self::from_readback`]'s for its bit. With the `rayon` feature the
    /// lights' bodies and focused matrices, the pixels' work (in bands of
    /// rows) and the lights' samples are computed in parallel.
    ///
    /// # Errors
    /// [`LixelError::UnusableSamples`] when the buffer sizes do not match
    /// `width x height` or there are more than 32 problems.
    pub fn from_readback_all(
        problems: &[ShadowProblem],
        readback: &Readback<'_>,
        options: &SampleOptions,
    ) -> Result<Vec<Self>> {
        let mut all = Vec::new();
        Self::from_readback_all_into(problems, readback, options, &mut all, &mut SampleWorkspace::default())?;
        Ok(all)
    }

    /// [`Self::from_readback_all`] into `out` (a previous call's samples),
    /// reusing their buffers and `workspace`'s: once they have grown to the
    /// readback and the lights' sample counts, this allocates nothing (but
    /// for what rayon's scheduling allocates with the `rayon` feature). On
    /// an error `out` is left unchanged.
    ///
    /// # Errors
    /// As [`Self::from_readback_all`].
    pub fn from_readback_all_into(
        problems: &[ShadowProblem],
        readback: &Readback<'_>,
        options: &SampleOptions,
        out: &mut Vec<Self>,
        workspace: &mut SampleWorkspace,
    ) -> Result<()> {
        check_readback(readback)?;
        if problems.len() > crate::MAX_LIGHTS {
            return Err(LixelError::UnusableSamples { reason: "at most 32 lights share a readback" });
        }
        let Some(first) = problems.first() else {
            out.clear();
            return Ok(());
        };
        if problems.iter().any(|p| p.camera() != first.camera()) {
            return Err(LixelError::UnusableSamples { reason: "lights sharing a readback must share its camera" });
        }
        workspace.grid.fill(first.camera(), readback)?;
        workspace.bits.clear();
        workspace.bits.extend(0..problems.len() as u32);
        out.truncate(problems.len());
        let reused = out.len();
        #[cfg(feature = "rayon")]
        {
            use rayon::prelude::*;
            // One job into rayon's pool for the whole call (its parallel
            // steps then split from a worker thread): each job sent from
            // outside the pool takes a slot of its queue, whose blocks are
            // allocated as it fills.
            rayon::scope(|_| {
                out.par_iter_mut().zip(&problems[..reused]).for_each(|(samples, problem)| samples.reset(problem));
                let fresh: Vec<Self> = problems[reused..].par_iter().map(Self::empty).collect();
                out.extend(fresh);
                extract(out, workspace, readback, options);
            });
        }
        #[cfg(not(feature = "rayon"))]
        {
            for (samples, problem) in out.iter_mut().zip(problems) {
                samples.reset(problem);
            }
            out.extend(problems[reused..].iter().map(Self::empty));
            extract(out, workspace, readback, options);
        }
        Ok(())
    }
}
