//! Samples for the scene optimizer, from a read-back analysis pass or from
//! plain world-space points.

use glam::{DMat2, DVec3, DVec4};

use crate::error::{LixelError, Result};
use crate::light::{Light, LightFrame};
use crate::matrix::LightMatrix;
use crate::optimize::objective::BoundarySample;
use crate::problem::ShadowProblem;

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

/// A readback brought to lixel's convention: top-down rows, lixel depth
/// (non-finite where nothing was drawn), screen placement.
struct Grid {
    width: usize,
    height: usize,
    depth: Vec<f64>,
    bits: Vec<u32>,
    normals: Option<Vec<[f32; 3]>>,
    /// Screen position of the readback's top-left corner, full-resolution pixels.
    origin: glam::DVec2,
    /// Full-resolution pixels per readback pixel.
    step: glam::DVec2,
}

impl Grid {
    fn new(camera: &crate::Camera, readback: &Readback<'_>) -> Result<Self> {
        use crate::conventions::DepthDirection;
        let (w, h) = (readback.width as usize, readback.height as usize);
        let layout = readback.layout;
        let viewport = camera.viewport();
        let rect = layout.rect.unwrap_or(PixelRect { x: 0, y: 0, width: viewport.x, height: viewport.y });
        let inside = rect.width > 0
            && rect.height > 0
            && u64::from(rect.x) + u64::from(rect.width) <= u64::from(viewport.x)
            && u64::from(rect.y) + u64::from(rect.height) <= u64::from(viewport.y);
        if !inside {
            return Err(LixelError::UnusableSamples { reason: "readback rectangle is empty or outside the viewport" });
        }
        let reverse = camera.conventions().depth == DepthDirection::Reverse;
        match layout.depth {
            ReadbackDepth::WindowReversed if !reverse => {
                return Err(LixelError::UnusableSamples {
                    reason: "readback depth is reverse-Z but the camera's projection is forward-Z",
                })
            }
            ReadbackDepth::Window | ReadbackDepth::GlWindow if reverse => {
                return Err(LixelError::UnusableSamples {
                    reason: "readback depth is forward-Z but the camera's projection is reverse-Z",
                })
            }
            _ => {}
        }
        let top = match layout.rows {
            RowOrder::TopDown => rect.y,
            RowOrder::BottomUp => viewport.y - rect.y - rect.height,
        };
        let to_lixel = |v: f32| -> f64 {
            let v = f64::from(v);
            if !v.is_finite() {
                return f64::NAN;
            }
            let lixel = match layout.depth {
                ReadbackDepth::Lixel => v,
                ReadbackDepth::Window if v >= 1.0 => f64::NAN,
                ReadbackDepth::WindowReversed if v <= 0.0 => f64::NAN,
                ReadbackDepth::GlWindow if v >= 1.0 => f64::NAN,
                ReadbackDepth::Window | ReadbackDepth::WindowReversed => {
                    camera.depth_at_distance(camera.distance_at_source_depth(v))
                }
                ReadbackDepth::GlWindow => camera.depth_at_distance(camera.distance_at_source_depth(2.0 * v - 1.0)),
                ReadbackDepth::LinearView => camera.depth_at_distance(v),
            };
            if lixel.is_finite() && (0.0..1.0).contains(&lixel) {
                lixel
            } else {
                f64::NAN
            }
        };
        let source_row = |y: usize| match layout.rows {
            RowOrder::TopDown => y,
            RowOrder::BottomUp => h - 1 - y,
        };
        let rows = |y: usize| source_row(y) * w..source_row(y) * w + w;
        Ok(Self {
            width: w,
            height: h,
            depth: (0..h).flat_map(|y| readback.depth[rows(y)].iter().map(|&v| to_lixel(v))).collect(),
            bits: (0..h).flat_map(|y| readback.shadow_bits[rows(y)].iter().copied()).collect(),
            normals: readback.normals.map(|n| (0..h).flat_map(|y| n[rows(y)].iter().copied()).collect()),
            origin: glam::DVec2::new(f64::from(rect.x), f64::from(top)),
            step: glam::DVec2::new(f64::from(rect.width) / w as f64, f64::from(rect.height) / h as f64),
        })
    }
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
    /// World points whose depth the map must cover: the visible receivers'
    /// body and its casters, and every relevant sample.
    pub(crate) depth_points: Vec<DVec3>,
    pub(crate) counts: SampleCounts,
}

impl Samples {
    fn empty(problem: &ShadowProblem) -> Self {
        let focus = problem.visible_receiver_body();
        let frame = problem.frame_towards(&focus);
        let casters = problem.caster_body(&focus);
        let focused = crate::methods::focused::from_bodies(problem, &focus, &casters);
        let mut depth_points = casters.vertices().to_vec();
        depth_points.extend_from_slice(focus.vertices());
        Self {
            problem: problem.clone(),
            focused,
            frame,
            boundary: Vec::new(),
            boundary_world: Vec::new(),
            relevant: Vec::new(),
            relevant_world: Vec::new(),
            depth_points,
            counts: SampleCounts::default(),
        }
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
        self.depth_points.push(p);
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
        check_readback(readback)?;
        if light_index as usize >= crate::MAX_LIGHTS {
            return Err(LixelError::UnusableSamples { reason: "light index must be below 32" });
        }
        let grid = Grid::new(problem.camera(), readback)?;
        let mut all = vec![Self::empty(problem)];
        extract(&mut all, &[light_index], &grid, options);
        Ok(all.pop().expect("one light"))
    }

    /// The samples of every light at once: `problems[i]` is light `i` (bit
    /// `i` of [`Readback::shadow_bits`]). One pass over the readback serves
    /// all lights (their bits share a `u32`, and a pixel's world position and
    /// surface derivatives are computed once); each light's samples equal
    /// [`Self::from_readback`]'s for its bit. With the `rayon` feature the
    /// lights' bodies and focused matrices are computed in parallel.
    ///
    /// # Errors
    /// [`LixelError::UnusableSamples`] when the buffer sizes do not match
    /// `width x height` or there are more than 32 problems.
    pub fn from_readback_all(
        problems: &[ShadowProblem],
        readback: &Readback<'_>,
        options: &SampleOptions,
    ) -> Result<Vec<Self>> {
        check_readback(readback)?;
        if problems.len() > crate::MAX_LIGHTS {
            return Err(LixelError::UnusableSamples { reason: "at most 32 lights share a readback" });
        }
        let Some(first) = problems.first() else {
            return Ok(Vec::new());
        };
        if problems.iter().any(|p| p.camera() != first.camera()) {
            return Err(LixelError::UnusableSamples { reason: "lights sharing a readback must share its camera" });
        }
        let grid = Grid::new(first.camera(), readback)?;
        #[cfg(feature = "rayon")]
        let mut all: Vec<Self> = {
            use rayon::prelude::*;
            problems.par_iter().map(Self::empty).collect()
        };
        #[cfg(not(feature = "rayon"))]
        let mut all: Vec<Self> = problems.iter().map(Self::empty).collect();
        let bits: Vec<u32> = (0..problems.len() as u32).collect();
        extract(&mut all, &bits, &grid, options);
        Ok(all)
    }
}

/// The buffers match the readback's size.
fn check_readback(readback: &Readback<'_>) -> Result<()> {
    let n = readback.width as usize * readback.height as usize;
    if readback.depth.len() != n
        || readback.shadow_bits.len() != n
        || readback.normals.is_some_and(|normals| normals.len() != n)
    {
        return Err(LixelError::UnusableSamples { reason: "readback buffers do not match its size" });
    }
    Ok(())
}

/// OR of `src` over each pixel's 3x3 neighbourhood (clamped at the edges),
/// separably.
fn or_3x3<T: Copy + Default + std::ops::BitOr<Output = T>>(src: &[T], w: usize, h: usize) -> Vec<T> {
    let mut tmp = vec![T::default(); src.len()];
    for (s, t) in src.chunks_exact(w).zip(tmp.chunks_exact_mut(w)) {
        for x in 0..w {
            t[x] = s[x.saturating_sub(1)] | s[x] | s[(x + 1).min(w - 1)];
        }
    }
    let mut dst = vec![T::default(); src.len()];
    for y in 0..h {
        let (above, here, below) =
            (&tmp[y.saturating_sub(1) * w..][..w], &tmp[y * w..][..w], &tmp[(y + 1).min(h - 1) * w..][..w]);
        for (x, cell) in dst[y * w..][..w].iter_mut().enumerate() {
            *cell = above[x] | here[x] | below[x];
        }
    }
    dst
}

/// Per pixel and light slot `k` (the `k`-th light extracted): shadowed, and
/// lit, over covered pixels; and the OR of both over the 3x3 neighbourhood,
/// so a slot both shadowed and lit nearby marks a shadow boundary. One light
/// packs into a byte (bit 0 shadowed, bit 1 lit); up to 32 into a `u64`
/// (shadowed slots in the low half, lit in the high half), so one pass
/// serves every light.
enum Classes {
    One { class: Vec<u8>, near: Vec<u8> },
    Many { class: Vec<u64>, near: Vec<u64> },
}

impl Classes {
    fn new(grid: &Grid, bits: &[u32]) -> Self {
        let (w, h) = (grid.width, grid.height);
        let valid = |d: f64| d.is_finite();
        let pixels = grid.depth.iter().zip(&grid.bits);
        if let [bit] = *bits {
            let class: Vec<u8> = pixels
                .map(|(&d, &b)| match (valid(d), b >> bit & 1 != 0) {
                    (false, _) => 0,
                    (true, true) => 1,
                    (true, false) => 2,
                })
                .collect();
            let near = or_3x3(&class, w, h);
            return Self::One { class, near };
        }
        let class: Vec<u64> = pixels
            .map(|(&d, &b)| {
                if !valid(d) {
                    return 0;
                }
                bits.iter()
                    .enumerate()
                    .fold(0u64, |c, (k, &bit)| c | if b >> bit & 1 != 0 { 1 << k } else { 1 << (k + 32) })
            })
            .collect();
        let near = or_3x3(&class, w, h);
        Self::Many { class, near }
    }

    /// Slots shadowed at pixel `i`, and slots with a shadow boundary there.
    fn at(&self, i: usize) -> (u32, u32) {
        match self {
            Self::One { class, near } => (u32::from(class[i] & 1), u32::from(near[i] & (near[i] >> 1) & 1)),
            Self::Many { class, near } => (class[i] as u32, near[i] as u32 & (near[i] >> 32) as u32),
        }
    }
}

/// Fills `all[k]` (already [`Samples::empty`]) from the readback for light
/// bit `bits[k]` (at most 32 lights), in one pass over the pixels.
fn extract(all: &mut [Samples], bits: &[u32], grid: &Grid, options: &SampleOptions) {
    let (w, h) = (grid.width, grid.height);
    let n = w * h;
    if n == 0 || all.is_empty() {
        return;
    }
    // Every light's problem shares the camera (the readback is its view).
    let camera = *all[0].problem.camera();
    let world_from_screen = camera.screen_from_world().inverse();
    let step = grid.step;
    // Lixel depth, non-finite where nothing was drawn (see `Grid`).
    let depth_at = |x: usize, y: usize| -> Option<f64> {
        let d = grid.depth[y * w + x];
        d.is_finite().then_some(d)
    };
    // Homogeneous world point of screen (x1, x2, depth), scaled to w > 0.
    let unproject = |sx: f64, sy: f64, d: f64| -> DVec4 {
        let v = world_from_screen * DVec4::new(sx, sy, d, 1.0);
        if v.w < 0.0 {
            -v
        } else {
            v
        }
    };
    let classes = Classes::new(grid, bits);
    for y in 0..h {
        for x in 0..w {
            let i = y * w + x;
            if !grid.depth[i].is_finite() {
                continue;
            }
            let (shadowed_bits, mixed_bits) = classes.at(i);
            for (bit, samples) in all.iter_mut().enumerate() {
                samples.counts.covered += 1;
                samples.counts.shadowed += (shadowed_bits >> bit & 1) as usize;
            }
            let active = shadowed_bits | mixed_bits;
            if active == 0 {
                continue;
            }
            let d = grid.depth[i];
            let sx = grid.origin.x + (x as f64 + 0.5) * step.x;
            let sy = grid.origin.y + (y as f64 + 0.5) * step.y;
            let here = unproject(sx, sy, d);
            if !(here.w > 0.0) || !here.is_finite() {
                for (bit, samples) in all.iter_mut().enumerate() {
                    samples.counts.rejected_invalid += (active >> bit & 1) as usize;
                }
                continue;
            }
            let world = here.truncate() / here.w;
            // Light-independent surface derivatives, computed on first use.
            let mut surface: Option<Option<Surface>> = None;
            for (bit, samples) in all.iter_mut().enumerate() {
                if active >> bit & 1 == 0 {
                    continue;
                }
                let frame = samples.frame;
                let x_light = frame.homogeneous4(here);
                samples.relevant.push(x_light);
                samples.relevant_world.push(world);
                samples.depth_points.push(world);
                if mixed_bits >> bit & 1 == 0 {
                    continue;
                }
                samples.counts.boundary_candidates += 1;
                let found = *surface.get_or_insert_with(|| {
                    surface_at(
                        grid,
                        &world_from_screen,
                        &camera,
                        options,
                        (x, y),
                        (sx, sy, d),
                        here,
                        world,
                        step,
                        &depth_at,
                    )
                });
                let Some(found) = found else {
                    samples.counts.rejected_discontinuity += 1;
                    continue;
                };
                let sample = match found {
                    Surface::Given { tx, ty, .. } => {
                        let along = |t: DVec3| frame.homogeneous4(t.extend(0.0));
                        BoundarySample { light: frame.homogeneous(world), d_dx: along(tx), d_dy: along(ty) }
                    }
                    Surface::Depth { dx4, dy4, .. } => {
                        BoundarySample { light: x_light, d_dx: frame.homogeneous4(dx4), d_dy: frame.homogeneous4(dy4) }
                    }
                };
                if !faces_light(samples.problem.light(), world, found.normal(), options.min_light_cosine) {
                    samples.counts.rejected_back_facing += 1;
                    continue;
                }
                samples.boundary.push(sample);
                samples.boundary_world.push(world);
            }
        }
    }
}

/// A boundary pixel's surface: world tangents from a read-back normal, or
/// homogeneous derivatives from depth differences.
#[derive(Clone, Copy)]
enum Surface {
    Given { tx: DVec3, ty: DVec3, normal: DVec3 },
    Depth { dx4: DVec4, dy4: DVec4, normal: DVec3 },
}

impl Surface {
    fn normal(self) -> DVec3 {
        match self {
            Self::Given { normal, .. } | Self::Depth { normal, .. } => normal,
        }
    }
}

/// The surface at boundary pixel `(x, y)`; `None` at a depth discontinuity
/// or where the derivatives are not finite.
#[allow(clippy::too_many_arguments)]
fn surface_at(
    grid: &Grid,
    world_from_screen: &glam::DMat4,
    camera: &crate::Camera,
    options: &SampleOptions,
    (x, y): (usize, usize),
    (sx, sy, d): (f64, f64, f64),
    here: DVec4,
    world: DVec3,
    step: glam::DVec2,
    depth_at: &impl Fn(usize, usize) -> Option<f64>,
) -> Option<Surface> {
    let (w, h) = (grid.width, grid.height);
    // Depth slope along each screen axis (full-resolution units).
    let slope = |dx: isize, dy: isize| -> Option<f64> {
        let (x0, y0) = (x.checked_add_signed(-dx)?, y.checked_add_signed(-dy)?);
        let (x1, y1) = (x + dx as usize, y + dy as usize);
        if x1 >= w || y1 >= h {
            return None;
        }
        let (d0, d1) = (depth_at(x0, y0)?, depth_at(x1, y1)?);
        let first = 0.5 * (d1 - d0);
        let second = d1 - 2.0 * d + d0;
        (second.abs() <= options.curvature_ratio * first.abs() + options.depth_epsilon)
            .then_some(first / if dx != 0 { step.x } else { step.y })
    };
    let normal_given = grid.normals.as_ref().map(|normals| {
        let [nx, ny, nz] = normals[y * w + x];
        DVec3::new(f64::from(nx), f64::from(ny), f64::from(nz))
    });
    match normal_given.and_then(DVec3::try_normalize) {
        Some(normal) => {
            // Derivatives of the surface point along the tangent plane.
            let (tx, ty) = plane_derivatives(world_from_screen, sx, sy, world, normal)?;
            Some(Surface::Given { tx, ty, normal })
        }
        None => {
            let (zx, zy) = (slope(1, 0)?, slope(0, 1)?);
            let dx4 = *world_from_screen * DVec4::new(1.0, 0.0, zx, 0.0);
            let dy4 = *world_from_screen * DVec4::new(0.0, 1.0, zy, 0.0);
            let (dx4, dy4) = if here.w < 0.0 { (-dx4, -dy4) } else { (dx4, dy4) };
            // World tangents (derivative of the dehomogenised point).
            let tx = (dx4.truncate() - world * dx4.w) / here.w;
            let ty = (dy4.truncate() - world * dy4.w) / here.w;
            let mut normal = tx.cross(ty).normalize_or_zero();
            if normal.dot(camera.towards_viewer(world)) < 0.0 {
                normal = -normal;
            }
            // Homogeneous point and its homogeneous derivatives: one scale.
            Some(Surface::Depth { dx4, dy4, normal })
        }
    }
}

/// World-space derivatives, per full-resolution pixel along x and y, of the
/// point where the pixel's ray meets the plane through `world` with `normal`.
fn plane_derivatives(
    world_from_screen: &glam::DMat4,
    sx: f64,
    sy: f64,
    world: DVec3,
    normal: DVec3,
) -> Option<(DVec3, DVec3)> {
    // Move one pixel along x (or y) and intersect that pixel's ray with the plane.
    let hit = |px: f64, py: f64| -> Option<DVec3> {
        let a = world_from_screen.project_point3(DVec3::new(px, py, 0.0));
        // Depth 0.5, not 1: an infinite far plane's depth 1 is at infinity.
        let b = world_from_screen.project_point3(DVec3::new(px, py, 0.5));
        let denom = normal.dot(b - a);
        if denom.abs() <= f64::EPSILON * (b - a).length() {
            return None;
        }
        Some(a + (b - a) * (normal.dot(world - a) / denom))
    };
    let (xp, xm) = (hit(sx + 0.5, sy)?, hit(sx - 0.5, sy)?);
    let (yp, ym) = (hit(sx, sy + 0.5)?, hit(sx, sy - 0.5)?);
    Some((xp - xm, yp - ym)).filter(|(a, b)| a.is_finite() && b.is_finite())
}

/// Whether a receiver at `p` with unit normal `n` faces the light.
fn faces_light(light: &Light, p: DVec3, n: DVec3, min_cosine: f64) -> bool {
    let to_light = match *light {
        Light::Directional { direction } => -direction,
        Light::Point { position } | Light::Spot { position, .. } => (position - p).normalize_or_zero(),
    };
    n.dot(to_light) > min_cosine
}
