//! Sub-geometry shadow maps (SGSM, the paper in
//! `shared/papers/sgsm-sub-geometry-shadow-maps.txt`) as a shadow lookup of
//! the renderer, for every [`LightMatrix`](crate::LightMatrix).
//!
//! Why: SPSM ([`super::spsm`]) keeps only the closest triangle per
//! texel; where several triangles share a texel (tessellated curved
//! casters, creases) a sample on another triangle's part of the texel is
//! rebuilt on the wrong plane. SGSM finds the triangles at the texel's four
//! corners and rebuilds depth on the one that contains the sample.
//!
//! It is the lookup mode [`ShadowLookup::Sgsm`](super::ShadowLookup::Sgsm):
//!
//! - **Pass** (`shaders/sgsm_pass.wgsl`): SPSM's conservative pass plus a
//!   second `R32Uint` target with the stored triangle's plane slopes (two
//!   f16; the normal in the matrix's post-projective space).
//! - **Sweep** (`sgsm/gpu.rs`, `shaders/sgsm_sweep.wgsl`): a compute pass, one
//!   invocation per map row, stepping along it one texel at a time; per
//!   texel it finds each corner's triangle among the four texels around the
//!   corner, groups the corners by plane and writes a mask word
//!   ([`pattern::MaskWord`]: participating 3x3 slots, status, pattern,
//!   corner slots) into an `R32Uint` array. CPU reference: [`sweep`].
//! - **Lookup** (`shaders/sgsm_lookup.wgsl`): own triangle, else the plane
//!   the word names (one plane) or the pattern's corner triangle that
//!   contains the sample, else SPSM's lookup. With
//!   [`SgsmOptions::count_paths`] each path taken is counted
//!   ([`Renderer::take_sgsm_counts`](super::Renderer::take_sgsm_counts)).
//!
//! Memory per texel: SPSM's 128-bit texel, 32 bits of slopes (read by the
//! sweep only) and the 32-bit mask word (31 bits used), besides the
//! `Depth32Float` every mode has: 192 bits of colour against SPSM's 128 and
//! none for a standard map (32 bits of depth each).

pub(crate) mod gpu;
pub mod overlap;
pub mod pattern;
pub mod sweep;

use super::spsm::{self, SpsmOptions};
use super::{RenderError, Renderer};

/// Settings of the SGSM lookup.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct SgsmOptions {
    /// The SPSM settings of the pass and of the fallback lookup.
    pub spsm: SpsmOptions,
    /// Count the lookup paths taken (atomic counters in a storage buffer;
    /// costs time, for tests and reports).
    pub count_paths: bool,
}

impl SgsmOptions {
    /// SPSM's paper settings, no counting; the default.
    pub const PAPER: Self = Self { spsm: SpsmOptions::PAPER, count_paths: false };

    /// [`Self::PAPER`] with [`count_paths`](Self::count_paths).
    pub const COUNTED: Self = Self { count_paths: true, ..Self::PAPER };
}

/// How often each path of the SGSM lookup was taken (camera and analysis
/// lookups together, every fragment shaded, since the last
/// [`Renderer::take_sgsm_counts`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SgsmCounts {
    /// Outside the map or behind the light: lit.
    pub outside: u64,
    /// Empty texel: lit.
    pub empty: u64,
    /// Depth-only texel: standard test.
    pub depth_only: u64,
    /// Inside the own stored triangle: its plane.
    pub own: u64,
    /// The texel lies on one plane (all corners): that plane.
    pub full: u64,
    /// A recognised pattern's corner triangle contains the sample.
    pub pattern: u64,
    /// Not recognised: SPSM's lookup.
    pub fallback: u64,
}

impl SgsmCounts {
    /// Number of counters in the buffer.
    pub(crate) const LEN: usize = 8;

    fn from_words(w: &[u32]) -> Self {
        let at = |i: usize| u64::from(w.get(i).copied().unwrap_or(0));
        Self {
            outside: at(0),
            empty: at(1),
            depth_only: at(2),
            own: at(3),
            full: at(4),
            pattern: at(5),
            fallback: at(6),
        }
    }

    /// Lookups that reached a texel with a triangle (own, full, pattern,
    /// fallback).
    #[must_use]
    pub fn on_triangles(&self) -> u64 {
        self.own + self.full + self.pattern + self.fallback
    }
}

/// One light's SGSM words ([`Renderer::read_sgsm_words`]), row-major.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SgsmWords {
    /// The conservative pass's slope words (two f16 slopes per map extent;
    /// [`sweep::decode_normal`]).
    pub normals: Vec<u32>,
    /// The sweep's mask words ([`pattern::MaskWord`]).
    pub masks: Vec<u32>,
}

/// Replaces `from` (which must occur) by `to` in a shader source.
fn renamed(source: &str, from: &str, to: &str) -> String {
    debug_assert!(source.contains(from), "shader text changed: {from:?} not found");
    source.replacen(from, to, 1)
}

/// The mode's shadow-pass WGSL (after `light_depth.wgsl`).
pub(crate) fn pass_source(options: &SgsmOptions) -> String {
    let spsm_pass = renamed(
        include_str!("../../../shaders/spsm_pass.wgsl"),
        "@fragment\nfn fs_shadow(in: SpsmVertex) -> SpsmOutput",
        "fn spsm_fragment(in: SpsmVertex) -> SpsmOutput",
    );
    spsm::common_source(&options.spsm) + &spsm_pass + include_str!("../../../shaders/sgsm_pass.wgsl")
}

/// The WGSL the sweep and the lookup share (SPSM's texel format, the
/// pattern tables, `shaders/sgsm_common.wgsl`): for shader tests, which
/// append their own entry point.
#[must_use]
pub fn common_wgsl(options: &SgsmOptions) -> String {
    spsm::common_source(&options.spsm) + &pattern::wgsl_tables() + include_str!("../../../shaders/sgsm_common.wgsl")
}

/// The sweep's compute WGSL.
pub(crate) fn sweep_source(options: &SgsmOptions) -> String {
    common_wgsl(options) + include_str!("../../../shaders/sgsm_sweep.wgsl")
}

/// The mode's lookup WGSL (after `light_depth.wgsl` and `common.wgsl`).
pub(crate) fn lookup_source(options: &SgsmOptions) -> String {
    let spsm_lookup = renamed(&spsm::lookup_source(&options.spsm), "fn in_shadow(", "fn spsm_in_shadow(");
    let count = if options.count_paths {
        "@group(1) @binding(3) var<storage, read_write> sgsm_counters: array<atomic<u32>, 8>;\n\
         fn sgsm_count(path: u32) {\n    atomicAdd(&sgsm_counters[path], 1u);\n}\n"
    } else {
        "fn sgsm_count(path: u32) {}\n"
    };
    spsm_lookup
        + &pattern::wgsl_tables()
        + include_str!("../../../shaders/sgsm_common.wgsl")
        + count
        + include_str!("../../../shaders/sgsm_lookup.wgsl")
}

impl Renderer {
    /// Light `light`'s SGSM words from the last frame: the conservative
    /// pass's slope words and the sweep's mask words, row-major. `Ok(None)` when the last frame's
    /// mode is not SGSM. Blocks until the GPU is done.
    ///
    /// # Errors
    /// [`RenderError::NoSuchLight`]; [`RenderError::NothingRendered`];
    /// mapping or polling failures.
    pub fn read_sgsm_words(&self, light: usize) -> Result<Option<SgsmWords>, RenderError> {
        let matrix =
            self.last_lights.get(light).ok_or(RenderError::NoSuchLight { light, count: self.last_lights.len() })?;
        let maps = &self.lookups[self.last_lookup.ok_or(RenderError::NothingRendered)?].maps;
        let Some(extra) = &maps.sgsm else { return Ok(None) };
        let (w, h) = (matrix.map_size.width, matrix.map_size.height);
        let read = |t| {
            self.read_texture(t, wgpu::TextureAspect::All, light as u32, w, h, 4)
                .map(|b| bytemuck::cast_slice::<u8, u32>(&b).to_vec())
        };
        Ok(Some(SgsmWords { normals: read(&extra.normals)?, masks: read(&extra.masks)? }))
    }

    /// The SGSM lookup's path counters since the last call (reset to zero
    /// by this call); `Ok(None)` unless the last frame's mode is SGSM with
    /// [`SgsmOptions::count_paths`]. Blocks until the GPU is done.
    ///
    /// # Errors
    /// [`RenderError::NothingRendered`]; mapping or polling failures.
    pub fn take_sgsm_counts(&self) -> Result<Option<SgsmCounts>, RenderError> {
        let state = &self.lookups[self.last_lookup.ok_or(RenderError::NothingRendered)?];
        let Some(counters) = state.sweep.as_ref().and_then(|s| s.counters.as_ref()) else { return Ok(None) };
        let words = gpu::read_and_clear(&self.device, &self.queue, counters)?;
        Ok(Some(SgsmCounts::from_words(&words)))
    }
}
