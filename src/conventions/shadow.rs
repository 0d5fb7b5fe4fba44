//! [`LightMatrix`] in an engine's shadow-pass convention.
//!
//! lixel's matrices use wgpu's: clip depth `[0, 1]` growing away from the
//! light, NDC `y` up, texel row 0 at NDC `y = +1`. An engine's shadow pass
//! may want `[-1, 1]` clip depth (OpenGL), reverse-Z depth, or texture
//! coordinates with row 0 at the bottom (OpenGL's `t = 0`). Each is a fixed
//! remap of clip space, applied after lixel's matrix, so the map covers
//! exactly the same region and stores the same occlusion order.

use glam::{DMat4, DVec4};

use super::ClipDepth;
use crate::matrix::LightMatrix;

/// Which way the rows of the shadow texture run, for the lookup matrix.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum TextureY {
    /// Texel row 0 holds NDC `y = +1` (wgpu, Direct3D, Vulkan, Metal: `v = 0`
    /// at the top).
    Down,
    /// Texel row 0 holds NDC `y = -1` (OpenGL: `t = 0` at the bottom).
    Up,
}

/// The depth comparison the shadow pass and the lookup use.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum DepthCompare {
    /// Smaller is closer to the light.
    Less,
    /// Larger is closer to the light (reverse-Z).
    Greater,
}

/// How an engine's shadow pass stores depth and addresses its texture.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct ShadowPassConvention {
    /// Clip depth range of the shadow pass's projection.
    pub clip_depth: ClipDepth,
    /// Reverse-Z: the depth buffer holds `1` at the light's near end.
    pub reverse_z: bool,
    /// Row order of the texture, for [`EngineLightMatrix::texel_from_world`].
    pub texture_y: TextureY,
}

impl ShadowPassConvention {
    /// wgpu, Direct3D, Metal: `[0, 1]`, forward, row 0 at the top (lixel's own).
    pub const WGPU: Self = Self { clip_depth: ClipDepth::ZeroToOne, reverse_z: false, texture_y: TextureY::Down };
    /// OpenGL and WebGL defaults: `[-1, 1]`, forward, row 0 at the bottom.
    pub const OPENGL: Self =
        Self { clip_depth: ClipDepth::NegativeOneToOne, reverse_z: false, texture_y: TextureY::Up };
    /// Reverse-Z `[0, 1]`, row 0 at the top (Bevy, Unreal, Godot 4.3+ on Vulkan/D3D).
    pub const REVERSE_Z: Self = Self { clip_depth: ClipDepth::ZeroToOne, reverse_z: true, texture_y: TextureY::Down };
}

/// A light matrix expressed in an engine's [`ShadowPassConvention`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EngineLightMatrix {
    /// World to the shadow pass's clip space.
    pub clip_from_world: DMat4,
    /// World to (texel x, texel y, stored depth), homogeneous: texel centres
    /// at half-integers, `y` in the convention's row order, depth as the
    /// depth buffer holds it (window depth in `[0, 1]`).
    pub texel_from_world: DMat4,
    /// The depth test of the shadow pass and the comparison of the lookup.
    pub depth_compare: DepthCompare,
    /// The convention.
    pub convention: ShadowPassConvention,
}

impl EngineLightMatrix {
    /// `clip_from_world` in single precision, for uploading to a GPU.
    #[must_use]
    pub fn clip_from_world_f32(&self) -> glam::Mat4 {
        self.clip_from_world.as_mat4()
    }
}

impl LightMatrix {
    /// This matrix in an engine's shadow-pass convention. The covered region
    /// and the occlusion order are unchanged; [`needs_unclipped_depth`]
    /// still applies (in OpenGL: `GL_DEPTH_CLAMP`).
    ///
    /// [`needs_unclipped_depth`]: LightMatrix::needs_unclipped_depth
    #[must_use]
    pub fn in_convention(&self, convention: ShadowPassConvention) -> EngineLightMatrix {
        // lixel's clip z is in [0, w]; the window depth it stores is z/w.
        // Rows: x, y, z, w of the remap applied after lixel's clip space.
        let window = match convention.reverse_z {
            false => DVec4::new(0.0, 0.0, 1.0, 0.0),
            true => DVec4::new(0.0, 0.0, -1.0, 1.0),
        };
        let clip_z = match convention.clip_depth {
            // [0, 1] window depth is the clip depth itself.
            ClipDepth::ZeroToOne => window,
            // OpenGL: window = (z_ndc + 1) / 2, so z_clip = 2·window - w.
            ClipDepth::NegativeOneToOne => window * 2.0 - DVec4::W,
        };
        let remap = DMat4::from_cols(DVec4::X, DVec4::Y, clip_z, DVec4::W).transpose();
        let (w, h) = (f64::from(self.map_size.width), f64::from(self.map_size.height));
        let y_sign = match convention.texture_y {
            TextureY::Down => -1.0,
            TextureY::Up => 1.0,
        };
        // lixel clip -> (texel x, texel y, window depth).
        let texel_from_clip = DMat4::from_cols(
            DVec4::new(0.5 * w, 0.0, 0.0, 0.0),
            DVec4::new(0.0, 0.5 * h * y_sign, 0.0, 0.0),
            DVec4::new(0.0, 0.0, window.z, 0.0),
            DVec4::new(0.5 * w, 0.5 * h, window.w, 1.0),
        );
        // lixel's shadow pass keeps the nearest depth (`Less`); reversed z
        // flips the comparison.
        let depth_compare = if convention.reverse_z { DepthCompare::Greater } else { DepthCompare::Less };
        EngineLightMatrix {
            clip_from_world: remap * self.clip_from_world,
            texel_from_world: texel_from_clip * self.clip_from_world,
            depth_compare,
            convention,
        }
    }
}
