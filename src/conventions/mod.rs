//! Engine conventions: what a camera's matrices mean, how a readback stores
//! depth, and how an engine's shadow pass wants its light matrix.
//!
//! Inside, lixel works in one convention (wgpu's: clip depth `[0, 1]` growing
//! away from the eye, NDC `y` up, view space looking down `-z`). An engine
//! brings its own: OpenGL's `[-1, 1]` clip depth, reverse-Z with an infinite
//! far plane, a Vulkan `y`-down projection, a left-handed view, an
//! orthographic or jittered projection. [`Camera::from_matrices`] reads which
//! one it was given ([`CameraConventions`]) and normalises once, so the
//! methods never see the difference; [`LightMatrix::in_convention`] converts
//! the answer back for the engine's shadow pass ([`ShadowPassConvention`]).
//!
//! # What a matrix can and cannot tell
//! A perspective projection states its handedness (the sign of its `w` row),
//! its depth direction (depth grows or shrinks with distance), whether far is
//! infinite, and its centre offset. It does **not** always state its clip
//! depth range: every forward-Z OpenGL projection is also a valid `[0, 1]`
//! projection with a near plane about twice as far, and the other way round.
//! When both readings are valid lixel takes the one with the larger frustum
//! (`[-1, 1]` for forward-Z: nothing the engine can see is lost; a `[0, 1]`
//! camera read this way only gains a sliver between `n/2` and `n`), and says
//! so in [`CameraConventions::clip_depth_inferred`]. Reverse-Z is read as
//! `[0, 1]` (reverse-Z only gains precision with `[0, 1]` clip depth, so
//! that is how engines use it). [`ProjectionHints`] states the range, and
//! [`Camera::look_at`] always does.
//!
//! An orthographic projection cannot tell forward-Z looking down `-z` from
//! reverse-Z looking down `+z` (same matrix); lixel assumes a right-handed
//! view space unless [`ProjectionHints::orthographic_view`] says otherwise.
//! Only the viewing direction depends on it, which no method uses for an
//! orthographic camera (PSM and LiSPSM reduce to the focused map there).
//!
//! [`Camera::from_matrices`]: crate::Camera::from_matrices
//! [`Camera::look_at`]: crate::Camera::look_at
//! [`LightMatrix::in_convention`]: crate::LightMatrix::in_convention

mod projection;
mod shadow;

pub(crate) use projection::{analyse, SourceDepth};
pub use shadow::{DepthCompare, EngineLightMatrix, ShadowPassConvention, TextureY};

/// Clip-space depth range of a projection (before the perspective divide).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ClipDepth {
    /// `0 <= z <= w`: Direct3D, Vulkan, Metal, wgpu, and OpenGL with
    /// `glClipControl(.., GL_ZERO_TO_ONE)`.
    ZeroToOne,
    /// `-w <= z <= w`: OpenGL and WebGL by default (three.js, many GL engines).
    NegativeOneToOne,
}

/// Whether depth grows with distance from the eye.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum DepthDirection {
    /// Near maps to the low end of the range, far to the high end (depth
    /// test `Less`).
    Forward,
    /// Near maps to the high end, far to the low end (reverse-Z: Bevy,
    /// Unreal, Godot 4.3+; depth test `Greater`).
    Reverse,
}

/// Perspective or orthographic.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ProjectionKind {
    /// `w` is the distance along the view direction.
    Perspective,
    /// `w` is constant (editors, CAD, top-down and isometric views).
    Orthographic,
}

/// Where the projection's centre lies on the screen.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Centring {
    /// The view axis hits the screen centre.
    Symmetric,
    /// Off by less than [`ProjectionTolerances::jitter_pixels`] pixels: a
    /// temporal anti-aliasing jitter.
    Jittered,
    /// Off by more: an off-centre frustum (VR eyes, tiled or oblique screens).
    OffCentre,
}

/// Handedness of view space.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Handedness {
    /// The camera looks down `-z` (OpenGL, glam's `rh`, Bevy, Godot, three.js).
    Right,
    /// The camera looks down `+z` (Direct3D's `lh` builders, Unreal).
    Left,
}

/// Which way NDC `y` points.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ClipY {
    /// NDC `y = +1` is the top of the screen (OpenGL, Direct3D, wgpu, Metal).
    Up,
    /// NDC `y = +1` is the bottom (Vulkan without a flipped viewport; glam's
    /// `vulkan` builders).
    Down,
}

/// Whether a convention was read off the matrices or assumed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Inferred {
    /// Only one reading of the matrix is a valid camera.
    FromMatrix,
    /// Given by [`ProjectionHints`] (or by [`Camera::look_at`](crate::Camera::look_at)).
    Stated,
    /// Several readings are valid; lixel took the one with the larger
    /// frustum (see the [module docs](self)).
    Assumed,
}

/// What [`Camera::from_matrices`](crate::Camera::from_matrices) found the
/// engine's matrices to mean ([`Camera::conventions`](crate::Camera::conventions)).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraConventions {
    /// Perspective or orthographic.
    pub projection: ProjectionKind,
    /// The clip depth range the camera was read with.
    pub clip_depth: ClipDepth,
    /// How [`clip_depth`](Self::clip_depth) was decided.
    pub clip_depth_inferred: Inferred,
    /// Forward or reverse Z.
    pub depth: DepthDirection,
    /// `true` for an infinite far plane (far distance `f64::INFINITY`).
    pub infinite_far: bool,
    /// Symmetric, jittered or off-centre.
    pub centring: Centring,
    /// Where the view axis hits the screen, in NDC (`y` up): `(0, 0)` when
    /// symmetric, the jitter when jittered.
    pub centre_offset_ndc: glam::DVec2,
    /// View-space handedness.
    pub view: Handedness,
    /// Which way NDC `y` points.
    pub clip_y: ClipY,
}

/// Overrides for [`Camera::from_matrices_with`](crate::Camera::from_matrices_with):
/// what the matrices cannot say by themselves.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ProjectionHints {
    /// The clip depth range; `None` infers it (see the [module docs](self)).
    pub clip_depth: Option<ClipDepth>,
    /// View-space handedness for an orthographic projection; `None` assumes
    /// [`Handedness::Right`]. Ignored for perspective projections, whose `w`
    /// row states it.
    pub orthographic_view: Option<Handedness>,
    /// The numeric tolerances of the analysis.
    pub tolerances: ProjectionTolerances,
}

impl ProjectionHints {
    /// Hints that state the clip depth range.
    #[must_use]
    pub fn clip_depth(clip_depth: ClipDepth) -> Self {
        Self { clip_depth: Some(clip_depth), ..Self::default() }
    }
}

/// Tolerances of the projection analysis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProjectionTolerances {
    /// `|RᵀR - I|` (entry-wise) allowed for the view matrix's rotation.
    /// Default `1e-5` (single-precision matrices pass).
    pub rigid: f64,
    /// Entries that must vanish (the `w` row's `x`, `y`; the depth row's
    /// `x`, `y`) may be this large relative to the row. Default `1e-6`.
    pub structure: f64,
    /// A depth row whose limit at infinity is within this of the range's
    /// far end has an infinite far plane. Default `4 · f32::EPSILON` (a
    /// single-precision `perspective_infinite*` matrix passes; a finite far
    /// beyond about `2·10⁶ · near` is read as infinite, which only enlarges
    /// the frustum).
    pub infinite_far: f64,
    /// Centre offsets below this many pixels count as jitter. Default `2`.
    pub jitter_pixels: f64,
}

impl Default for ProjectionTolerances {
    fn default() -> Self {
        Self { rigid: 1e-5, structure: 1e-6, infinite_far: 4.0 * f64::from(f32::EPSILON), jitter_pixels: 2.0 }
    }
}

/// The camera property [`LixelError::InvalidProjection`](crate::LixelError::InvalidProjection)
/// found wrong.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum CameraProperty {
    /// The viewport has zero width or height.
    Viewport,
    /// `view_from_world` is not a rotation (or reflection) plus translation.
    RigidView,
    /// The projection's `w` row is neither `±z` (perspective) nor constant
    /// (orthographic).
    ProjectionKind,
    /// The depth row depends on view `x` or `y` (an oblique near plane), is
    /// constant, or puts the near plane behind the eye.
    DepthRow,
    /// The stated clip depth range gives no valid near/far for this matrix.
    ClipDepth,
    /// NDC `x` decreases to the right (a mirrored projection).
    Mirrored,
    /// `clip_from_world` is singular.
    Singular,
}

impl std::fmt::Display for CameraProperty {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::Viewport => "viewport",
            Self::RigidView => "rigid view",
            Self::ProjectionKind => "projection kind",
            Self::DepthRow => "depth row",
            Self::ClipDepth => "clip depth range",
            Self::Mirrored => "mirroring",
            Self::Singular => "singularity",
        })
    }
}
