//! # lixel — a lixel for every pixel
//!
//! Shadow maps alias because a light's texels land unevenly on screen. A
//! shadow map's 4x4 light matrix has free parameters that decide where its
//! texels go; lixel computes them.
//!
//! Every light matrix is a planar homography `G = [g1; g2; j]` of the light
//! coordinates `X~` ([`LightFrame`]) plus a depth row: the optical axis `j`
//! is the projective freedom, `g1, g2` (given `j`) the affine one. The
//! methods differ only in how they choose `j` and the region the map must
//! hold; one shared affine fit ([`fit`]: minimum-area rectangle) and one depth
//! policy ([`DepthRange`]) finish every matrix, and one scorer ([`score`])
//! measures them all.
//!
//! ## Methods
//!
//! | [`Parameterization`] | what it computes | reference |
//! |---|---|---|
//! | `Normal` | uniform map around every receiver the light reaches | — |
//! | `Focused` | uniform map around the receivers the view frustum sees | Brabec et al. 2002 |
//! | `FocusedSnapped` | the focused map with world-fixed axes, texel size on a ladder, origin snapped to whole texels (engines' anti-shimmer) | Unity/Bevy practice |
//! | `Psm` | uniform in the camera's post-perspective space, with hull `H = conv(V ∪ l) ∩ S ∩ L` and virtual camera shift | Stamminger & Drettakis 2002 |
//! | `LiSpsm` | perspective frustum in light space along the projected view direction, simple or general `n_opt` | Wimmer, Scherzer & Purgathofer 2004 |
//! | `PlaneOptimal` | exactly uniform sampling on one receiver plane | Chong & Gortler 2004 |
//!
//! Start with [`ShadowProblem`]. Sun lights over long views: [`cascade`]
//! (one problem per depth slice of the view, each solved by any method).
//!
//! ## Conventions
//! Inside, wgpu's: right-handed view space, clip depth in `[0, 1]`, NDC `y`
//! up, framebuffer row 0 at the top. In: [`Camera::from_matrices`] reads an
//! engine's own matrices (GL `[-1, 1]` depth, reverse-Z, infinite far,
//! orthographic, jittered, left-handed, `y`-down) and
//! [`optimize::ReadbackLayout`] its readback; out:
//! [`LightMatrix::in_convention`] gives the matrix for the engine's shadow
//! pass. See [`conventions`]. All solver arithmetic is in `f64`;
//! [`LightMatrix::clip_from_world_f32`] converts for upload.
//!
//! ## Features
//! `render` (default) adds the wgpu renderer and its frame loop
//! (`render::ShadowLoop`); without it the crate is the solver alone (glam,
//! thiserror, robust, argmin). `cli` (default) adds the `lixel` binary and
//! the experiment harness behind it (`lixel::experiment`, with clap and
//! indicatif); an engine needs only `render`.

// `unsafe` only to call `#[target_feature]` functions: the SSE2 pack of the
// sample extraction (`optimize::extract`, where SSE2 is part of the build's
// target), and the optimizer's loops compiled for AVX where the CPU has it
// (`optimize::objective`, `optimize::holds`, `optimize::project_onto_plane`,
// `matrix::range_of`: each through `avx_or_portable!` below, behind
// `is_x86_feature_detected!("avx")`, the same Rust as the portable loop it
// stands for).
#![deny(unsafe_code)]
#![warn(missing_docs)]

/// `$avx` (a call of a `#[target_feature(enable = "avx")]` function) where
/// this x86-64 CPU has AVX, else `$portable`: the one place the optimizer's
/// AVX loops are dispatched. Each such function wraps the `#[inline(always)]`
/// portable body that `$portable` calls, so both give the same bits.
#[cfg(target_arch = "x86_64")]
macro_rules! avx_or_portable {
    ($avx:expr, $portable:expr $(,)?) => {
        if std::arch::is_x86_feature_detected!("avx") {
            #[allow(unsafe_code)]
            // SAFETY: the callee's only requirement is the AVX target
            // feature (its `#[target_feature]`), and this CPU has it
            // (detected just above); its arguments and memory accesses are
            // safe Rust.
            unsafe {
                $avx
            }
        } else {
            $portable
        }
    };
}

/// Other targets: `$portable` (the AVX functions do not exist there).
#[cfg(not(target_arch = "x86_64"))]
macro_rules! avx_or_portable {
    ($avx:expr, $portable:expr $(,)?) => {
        $portable
    };
}

mod camera;
pub mod cascade;
mod caster_bounds;
pub mod conventions;
mod error;
#[cfg(feature = "cli")]
pub mod experiment;
pub mod fit;
pub mod geometry;
mod light;
mod matrix;
#[cfg(feature = "render")]
pub mod mesh;
mod methods;
pub mod optimize;
mod problem;
#[cfg(feature = "render")]
pub mod render;
mod scene;
pub mod score;
pub mod synthetic;
#[cfg(test)]
mod test_rng;
mod tolerance;
#[cfg(feature = "view")]
pub mod view;
mod workspace;

pub use camera::{Camera, INFINITE_FAR_CORNER_RATIO};
pub use error::{LixelError, Result};
pub use light::{Light, LightFrame};
pub use matrix::{light_distance, DepthRange, Fallback, LightDistance, LightMatrix, Method};
pub use methods::{
    psm_light_case, FocusedSnappedOptions, LiSpsmOptions, NOpt, Parameterization, PlaneOptimalOptions, PsmLightCase,
    PsmOptions,
};
pub use optimize::{optimize_light_matrix, OptimizeOptions, OptimizeReport, Optimized, Optimizer, Samples};
pub use problem::ShadowProblem;
pub use scene::{Aabb, SceneBounds, ShadowMapSize};
pub use tolerance::{Tolerances, MAX_COORDINATE, MAX_LIGHTS};
pub use workspace::SolveWorkspace;
