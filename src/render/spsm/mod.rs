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

pub mod packing;

use std::hash::{Hash, Hasher};

/// Format of the SPSM texels (the mode's colour array).
pub(crate) const TEXEL_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Uint;

/// Settings of the SPSM lookup.
///
/// Compared and hashed by the bits of its fields (the renderer keeps one
/// set of pipelines per distinct value).
#[derive(Clone, Copy, Debug)]
pub struct SpsmOptions {
    /// Exponent `n` of the paper's power quantization of the depth
    /// derivatives (eq. 3); the paper uses 5, 1 is linear.
    pub exponent: f32,
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
    /// an occluder in front of p, and the silhouette recovery tests both
    /// sides of a thin blocked band (four directions for a blob). Keeps
    /// sub-texel wires' shadows (277 of 279 pixels against 82 without, in
    /// `tests/render_spsm.rs`) but adds false shadow along edges on the
    /// experiment's scene (quick preset: focused+spsm 434.8 against 296.7
    /// misclassified), hence off in [`Self::PAPER`].
    pub thin_casters: bool,
}

impl SpsmOptions {
    /// The paper's settings (exponent 5, bias 1e-5) with the packing
    /// tolerance; the default.
    pub const PAPER: Self = Self { exponent: 5.0, bias: 1e-5, packing_tolerance: true, thin_casters: false };

    /// [`Self::PAPER`] with [`thin_casters`](Self::thin_casters).
    pub const THIN_CASTERS: Self = Self { thin_casters: true, ..Self::PAPER };
}

impl Default for SpsmOptions {
    fn default() -> Self {
        Self::PAPER
    }
}

impl PartialEq for SpsmOptions {
    fn eq(&self, other: &Self) -> bool {
        self.exponent.to_bits() == other.exponent.to_bits()
            && self.bias.to_bits() == other.bias.to_bits()
            && self.packing_tolerance == other.packing_tolerance
            && self.thin_casters == other.thin_casters
    }
}

impl Eq for SpsmOptions {}

impl Hash for SpsmOptions {
    fn hash<H: Hasher>(&self, state: &mut H) {
        (self.exponent.to_bits(), self.bias.to_bits(), self.packing_tolerance, self.thin_casters).hash(state);
    }
}

/// WGSL constants the SPSM shaders expect before `spsm_common.wgsl`.
fn constants(options: &SpsmOptions) -> String {
    // A non-positive or non-finite exponent would make the code
    // meaningless; the paper's 5 stands in.
    let exponent = if options.exponent.is_finite() && options.exponent > 0.0 { options.exponent } else { 5.0 };
    let bias = if options.bias.is_finite() { options.bias } else { 0.0 };
    format!(
        "const SPSM_EXPONENT: f32 = {exponent:?};\nconst SPSM_BIAS: f32 = {bias:?};\nconst SPSM_TOLERANCE: f32 = {:?};\nconst SPSM_THIN: bool = {};\n",
        if options.packing_tolerance { 1.0f32 } else { 0.0 },
        options.thin_casters
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
