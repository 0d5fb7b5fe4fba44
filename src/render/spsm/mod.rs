//! Sub-pixel shadow maps (SPSM, Lecocq et al. 2014) as a shadow lookup of
//! the renderer, for every [`LightMatrix`](crate::LightMatrix).
//!
//! Why: a standard map answers every lookup with one depth per texel, so its
//! error is bounded by texels whatever the matrix. SPSM stores, per texel,
//! the closest triangle that *touches* the texel (conservative
//! rasterization) and rebuilds shadow edges below texel size.
//!
//! It is the lookup mode [`ShadowLookup::Spsm`](super::ShadowLookup::Spsm):
//!
//! - The **SPSM pass** (`shaders/spsm_pass.wgsl`) is the mode's shadow
//!   pass: conservative rasterization done in the shader (no
//!   `CONSERVATIVE_RASTERIZATION` on lavapipe or GL; the vertex stage pulls
//!   whole triangles from the scene's buffers), the paper's consistent
//!   minimum depth in the depth buffer and the packed triangle in the
//!   mode's `Rgba32Uint` texel array ([`packing`] mirrors the format on the
//!   CPU).
//! - The **lookup** (`shaders/spsm_lookup.wgsl`) is the mode's `in_shadow`
//!   in the camera and analysis shaders, so masks, colour and the
//!   optimizer's analysis bits all come from the same lookup.
//!
//! All of it works in the matrix's post-projective space (`z / w`), where
//! triangles stay planar; lixel's standard maps store linear light depth,
//! which is not planar for point lights (see `shaders/spsm_common.wgsl`).

pub(crate) mod adjacency;
pub mod packing;

use std::hash::{Hash, Hasher};

pub use packing::GradientCode;

/// Format of the SPSM texels (the mode's colour array).
pub(crate) const TEXEL_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Uint;

/// Settings of the SPSM lookup.
///
/// Compared and hashed by the bits of its fields (the renderer keeps one
/// set of pipelines per distinct value).
#[derive(Clone, Copy, Debug)]
pub struct SpsmOptions {
    /// How the texel holds the plane's depth derivatives: the paper's
    /// power quantization (eq. 3, [`GradientCode::Power`]) or the log-polar
    /// code (the default since issue 16, session 6; see [`GradientCode`]).
    pub gradient_code: GradientCode,
    /// Constant depth bias of every plane test, in units of the `[0, 1]`
    /// post-projective depth range (the paper: 1e-5).
    pub bias: f32,
    /// Also allow, in each plane test, the packing's own error bound: half a
    /// quantization step of each decoded derivative times the distance the
    /// plane is extrapolated (zero where the code is exact). Off: the plain
    /// constant bias, where the 8-bit derivatives show as acne.
    pub packing_tolerance: bool,
    /// Thin-caster rules (issue 16, s16): the neighbours' "p lies on a
    /// stored receiver" shortcut only when the own texel's triangle is not
    /// an occluder in front of p (without them also when p lies beyond one
    /// facet width of a small own triangle, session 4), and the silhouette
    /// recovery tests both sides of a thin blocked band (four directions
    /// for a blob). Keeps sub-texel wires' shadows (276 of 279 pixels
    /// against 68 without, in `tests/render_spsm.rs`) but adds false shadow
    /// along edges on the experiment's scene (session 2, quick preset:
    /// focused+spsm 434.8 against 296.7 misclassified), hence off in
    /// [`Self::PAPER`].
    pub thin_casters: bool,
    /// Where the lookup takes the standard lookup's verdict instead of its
    /// own (issue 16, session 5; see [`StandardFallback`]).
    pub standard_fallback: StandardFallback,
    /// Inner-edge continuation (issue 16, sessions 7 and 9): the pass
    /// finds each stored triangle's inner edges (the mesh continues across
    /// them on the light's side; from the scene's edge adjacency) and, for
    /// a small facet, stores where each neighbour's opposite vertex lies
    /// (the texel's compact format, `shaders/spsm_common.wgsl`); a receiver
    /// outside the facet but inside a neighbour (grown to 3x its height
    /// over the edge on curved meshes, 2x on flat ones), far enough behind
    /// the facet's plane, is shadowed: a tessellated curved caster's thin
    /// outer facets, which lose every texel to the facet nearer the light,
    /// then still cast their shadow edges. On in [`Self::PAPER`] since
    /// session 9 (default preset, first 20 lights: `focused+spsm` 1338 to
    /// 1240 misclassified, `optimized+spsm` 692 to 616; session 7's
    /// unbounded continuation lost: 2074 and 739).
    pub inner_edges: bool,
}

/// Which SPSM verdicts are replaced by the standard lookup's: the verdict
/// of a plain depth compare against a centre-sampled depth (the nearest
/// triangle covering the texel centre, biased as a standard map), which the
/// conservative pass keeps beside each texel's triangle
/// (`spsm_store_centre` in `shaders/spsm_pass.wgsl`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum StandardFallback {
    /// SPSM's own verdict everywhere (the paper's lookup).
    Off,
    /// The hybrid lookup, the default: where p lies on none of the stored
    /// triangles of its 3x3 neighbourhood (the paper's "uncertain" pixels:
    /// a uniform or mixed depth-test pattern, the silhouette recovery's
    /// domain) the standard verdict decides; verdicts from a stored
    /// triangle containing p, or from p's own plane, stay SPSM's. Measured
    /// per path on the default preset (issue-16 note, session 5): the
    /// recovery's and the uniform patterns' verdicts were worse than the
    /// standard's, the triangle paths' better. Also the depth-only texels
    /// (triangles crossing the light's `w = 0` plane, e.g. a floor under a
    /// PSM-like warp; session 6): their 16-bit `z / w` with a constant
    /// bias showed as acne (quick preset, configuration 1: `psm+spsm`
    /// 3137 misclassified, mostly false shadow, against `psm`'s 373).
    #[default]
    Uncertain,
    /// The standard verdict everywhere: the standard lookup computed from
    /// SPSM's maps (for tests and diagnosis; it matches
    /// [`ShadowLookup::DepthCompare`](super::ShadowLookup::DepthCompare)
    /// up to the depth space, `z / w` instead of linear light depth).
    Always,
}

impl StandardFallback {
    /// The paths of `in_shadow` in `shaders/spsm_lookup.wgsl` (and SGSM's
    /// plane paths) whose verdict the standard lookup gives: a mask of the
    /// shader's `SPSM_PATH_*` bits.
    fn paths(self) -> u32 {
        match self {
            Self::Off => 0,
            // SPSM_PATH_UNIFORM | SPSM_PATH_RECOVER | SPSM_PATH_DEPTH_ONLY
            Self::Uncertain => 16 | 32 | 256,
            Self::Always => 0xffff,
        }
    }
}

impl SpsmOptions {
    /// The default: the paper's bias (1e-5) with the packing tolerance,
    /// the log-polar derivative code ([`GradientCode::LogPolar`]; the
    /// paper's power code lost whole shadows under scene-optimized
    /// matrices, see [`GradientCode`]), the hybrid
    /// [`StandardFallback::Uncertain`] and the
    /// [`inner_edges`](Self::inner_edges) continuation.
    pub const PAPER: Self = Self {
        gradient_code: GradientCode::LogPolar,
        bias: 1e-5,
        packing_tolerance: true,
        thin_casters: false,
        standard_fallback: StandardFallback::Uncertain,
        inner_edges: true,
    };

    /// [`Self::PAPER`] without the [`standard_fallback`](Self::standard_fallback)
    /// ([`StandardFallback::Off`]):
    /// the paper's lookup alone, silhouette recovery included.
    pub const SUBPIXEL_ONLY: Self = Self { standard_fallback: StandardFallback::Off, ..Self::PAPER };

    /// [`Self::SUBPIXEL_ONLY`] with [`thin_casters`](Self::thin_casters)
    /// (the thin-band recovery is what keeps sub-texel wires; the
    /// fallback would hand those pixels to the standard lookup).
    pub const THIN_CASTERS: Self = Self { thin_casters: true, ..Self::SUBPIXEL_ONLY };
}

impl Default for SpsmOptions {
    fn default() -> Self {
        Self::PAPER
    }
}

impl PartialEq for SpsmOptions {
    fn eq(&self, other: &Self) -> bool {
        code_key(self.gradient_code) == code_key(other.gradient_code)
            && self.bias.to_bits() == other.bias.to_bits()
            && self.packing_tolerance == other.packing_tolerance
            && self.thin_casters == other.thin_casters
            && self.standard_fallback == other.standard_fallback
            && self.inner_edges == other.inner_edges
    }
}

impl Eq for SpsmOptions {}

impl Hash for SpsmOptions {
    fn hash<H: Hasher>(&self, state: &mut H) {
        (
            code_key(self.gradient_code),
            self.bias.to_bits(),
            self.packing_tolerance,
            self.thin_casters,
            self.standard_fallback,
            self.inner_edges,
        )
            .hash(state);
    }
}

/// The bits a [`GradientCode`] is compared and hashed by.
fn code_key(code: GradientCode) -> (u8, u32) {
    match code {
        GradientCode::Power { exponent } => (0, exponent.to_bits()),
        GradientCode::LogPolar => (1, 0),
    }
}

/// WGSL constants the SPSM shaders expect before `spsm_common.wgsl`.
fn constants(options: &SpsmOptions) -> String {
    // A non-positive or non-finite exponent would make the power code
    // meaningless; the paper's 5 stands in.
    let (kind, exponent) = match options.gradient_code {
        GradientCode::Power { exponent } if exponent.is_finite() && exponent > 0.0 => (0u32, exponent),
        GradientCode::Power { .. } => (0, 5.0),
        GradientCode::LogPolar => (1, 5.0),
    };
    let bias = if options.bias.is_finite() { options.bias } else { 0.0 };
    let fallback = options.standard_fallback.paths();
    format!(
        "const SPSM_GRADIENT_CODE: u32 = {kind}u;\nconst SPSM_LOG_MIN: f32 = {:?};\nconst SPSM_LOG_STEP: f32 = {:?};\nconst SPSM_EXPONENT: f32 = {exponent:?};\nconst SPSM_BIAS: f32 = {bias:?};\nconst SPSM_TOLERANCE: f32 = {:?};\nconst SPSM_THIN: bool = {};\nconst SPSM_FALLBACK: u32 = {fallback}u;\nconst SPSM_INNER_EDGES: bool = {};\n",
        packing::LOG_MIN as f32,
        ((packing::LOG_MAX / packing::LOG_MIN).ln() / 253.0) as f32,
        if options.packing_tolerance { 1.0f32 } else { 0.0 },
        options.thin_casters,
        options.inner_edges
    )
}

/// The constants and `spsm_common.wgsl` (also for the SGSM shaders).
pub(crate) fn common_source(options: &SpsmOptions) -> String {
    constants(options) + include_str!("../../../shaders/spsm_common.wgsl")
}

/// The mode's shadow-pass WGSL (after `light_depth.wgsl`).
pub(crate) fn pass_source(options: &SpsmOptions) -> String {
    constants(options)
        + include_str!("../../../shaders/spsm_common.wgsl")
        + include_str!("../../../shaders/spsm_pass.wgsl")
}

/// The mode's lookup WGSL (after `light_depth.wgsl` and `common.wgsl`).
pub(crate) fn lookup_source(options: &SpsmOptions) -> String {
    constants(options)
        + include_str!("../../../shaders/spsm_common.wgsl")
        + include_str!("../../../shaders/spsm_lookup.wgsl")
}

/// The matrix the SPSM pass and lookup work with: `matrix` itself, except
/// for a point or spot light whose near plane was clamped
/// ([`LightMatrix::needs_unclipped_depth`](crate::LightMatrix::needs_unclipped_depth)),
/// where the depth row is rebuilt with a near plane of its own.
///
/// Why (issue 16, session 3): SPSM compares in `zeta = z / w = a + b / w`.
/// A scene-optimized warp can put a caster-body point at a grazing angle to
/// the optical axis `j`, so that the smallest `w = j·X` over the depth
/// points is tiny and the solver clamps `near` to `far · 1e-4`. Then every
/// receiver lands within ~1e-3 of `zeta = 1`, caster and receiver differ by
/// ~1e-5 there (below the 16-bit centre-depth step and the constant bias),
/// and the lookup misses the shadow (quick preset, configuration 1:
/// `optimized+spsm` 3445 of 3441 shadowed pixels false-lit). The standard
/// lookup stores linear light distance and is immune.
///
/// Every point the map holds lies within the matrix's
/// [`light_distance`](crate::LightMatrix::light_distance) of the light and
/// inside the map, whose rays make at most the angle of its farthest
/// corner with `j`; so `w >= light_distance.min · cos(that angle)` there.
/// That bound (when larger than the clamped `near`) is the SPSM near plane:
/// `zeta` stays affine in `1 / w` (planar on triangles), monotone along
/// rays, and receivers spread over `[0, 1]` again. Anything nearer (not a
/// caster of the map's receivers) gets `zeta < 0`, which the pass and the
/// lookup order correctly.
#[must_use]
pub fn depth_matrix(matrix: &crate::LightMatrix) -> glam::DMat4 {
    use glam::{DVec4, Vec4Swizzles};
    let m = matrix.clip_from_world;
    let (crate::DepthRange::Perspective { near, far }, Some(position)) = (matrix.depth, matrix.light.position()) else {
        return m;
    };
    if !matrix.needs_unclipped_depth {
        return m;
    }
    let w_row = m.row(3);
    let world_from_clip = m.inverse();
    let mut cos_min = f64::INFINITY;
    for (x, y) in [(-1.0, -1.0), (1.0, -1.0), (-1.0, 1.0), (1.0, 1.0)] {
        let p = world_from_clip * DVec4::new(x, y, 0.5, 1.0);
        if !(p.w.abs() > 0.0) {
            return m;
        }
        let p = p.xyz() / p.w;
        let r = (p - position).length();
        cos_min = cos_min.min(w_row.dot(p.extend(1.0)) / r);
    }
    let w_lo = matrix.light_distance.min * cos_min;
    if !(w_lo.is_finite() && w_lo > near && w_lo < far) {
        return m;
    }
    let a = far / (far - w_lo);
    let b = -w_lo * far / (far - w_lo);
    let z_row = w_row * a + DVec4::W * b;
    glam::DMat4::from_cols(m.row(0), m.row(1), z_row, w_row).transpose()
}
