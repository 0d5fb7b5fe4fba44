//! GPU-side layouts of the uniforms in `shaders/*.wgsl`, each built from its
//! domain type with `to_raw`.

use bytemuck::{Pod, Zeroable};
use glam::Vec3;

use crate::{Camera, LightFrame, LightMatrix};

/// Lights a camera or analysis pass can look up (the bit width of the masks).
pub use crate::tolerance::MAX_LIGHTS;

/// Stride between the per-light slots of the shadow pass's uniform buffer:
/// wgpu's default `min_uniform_buffer_offset_alignment`.
pub(crate) const SHADOW_SLOT_STRIDE: u64 = 256;

/// `Camera` in `common.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub(crate) struct CameraRaw {
    clip_from_world: [[f32; 4]; 4],
    world_from_clip: [[f32; 4]; 4],
    eye: [f32; 4],
    /// (ambient, analysis width, analysis height, 0).
    params: [f32; 4],
    /// View depth row: `dot(view_depth, (world, 1))` is the distance along
    /// the view direction (the cascade choice, `shaders/common.wgsl`).
    view_depth: [f32; 4],
}

impl CameraRaw {
    pub(crate) fn to_raw(camera: &Camera, ambient: f32, analysis_size: (u32, u32)) -> Self {
        Self::with_clip(camera, camera.clip_from_world(), ambient, analysis_size)
    }

    /// [`to_raw`](Self::to_raw) with another clip matrix (a jittered one).
    pub(crate) fn with_clip(
        camera: &Camera,
        clip_from_world: glam::DMat4,
        ambient: f32,
        analysis_size: (u32, u32),
    ) -> Self {
        Self {
            clip_from_world: clip_from_world.as_mat4().to_cols_array_2d(),
            // Inverted in f64: an f32 inverse loses ~far/near of precision.
            world_from_clip: clip_from_world.inverse().as_mat4().to_cols_array_2d(),
            eye: camera.eye().as_vec3().extend(1.0).to_array(),
            params: [ambient, analysis_size.0 as f32, analysis_size.1 as f32, 0.0],
            view_depth: {
                let row = -camera.view_from_world().row(2);
                row.as_vec4().to_array()
            },
        }
    }
}

/// `Light` in `common.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub(crate) struct LightRaw {
    clip_from_world: [[f32; 4]; 4],
    position: [f32; 4],
    color: [f32; 4],
    map_size: [f32; 2],
    layer: u32,
    flags: u32,
    /// Linear depth: (min distance, 1 / (max - min), 0, 0).
    depth: [f32; 4],
    /// A spot light's cone: (unit axis, cos half-angle); w = -2 for no cone.
    spot: [f32; 4],
    /// A cascade's weight ramps (`flags` bit 0): (fade-in start, fade-in
    /// end, fade-out start, fade-out end) in view depth.
    cascade: [f32; 4],
}

impl LightRaw {
    /// The light of `matrix`, whose map is in array layer `layer`.
    pub(crate) fn to_raw(matrix: &LightMatrix, layer: u32, color: Vec3) -> Self {
        let position = light_position(matrix);
        Self {
            clip_from_world: matrix.clip_from_world_f32().to_cols_array_2d(),
            position: position.to_array(),
            color: color.extend(0.0).to_array(),
            map_size: [matrix.map_size.width as f32, matrix.map_size.height as f32],
            layer,
            // Reserved.
            flags: 0,
            depth: {
                let [min, inv_span] = linear_depth_range(matrix);
                [min, inv_span, 0.0, 0.0]
            },
            spot: match matrix.light.cone() {
                Some((axis, cos)) => axis.as_vec3().extend(cos as f32).to_array(),
                None => [0.0, 0.0, 0.0, -2.0],
            },
            cascade: [0.0; 4],
        }
    }

    /// Makes this light a cascade (`flags` bit 0) that owns the mask bits
    /// at view depths `[start, end)` (in `depth.zw`; `cascade_owns` in
    /// `shaders/common.wgsl`) and lights with weights ramping up over
    /// `ramps[0]..ramps[1]`, 1 to `ramps[2]`, down to 0 at `ramps[3]`
    /// (`cascade_weight`).
    pub(crate) fn with_cascade(mut self, slot: &super::CascadeSlot) -> Self {
        self.flags |= 1;
        self.depth[2] = slot.owned.0;
        self.depth[3] = slot.owned.1;
        self.cascade = slot.ramps;
        self
    }
}

/// `Lights` in `common.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub(crate) struct LightsRaw {
    count: u32,
    /// Analysis pass: bit i set when light i's bits come from the camera pass.
    camera_bits: u32,
    /// Analysis pass: how many lights it looks up itself ...
    lookup_count: u32,
    _pad: u32,
    /// ... and their indices, four per vector.
    lookup: [[u32; 4]; MAX_LIGHTS / 4],
    items: [LightRaw; MAX_LIGHTS],
}

impl LightsRaw {
    /// Up to [`MAX_LIGHTS`] lights (the caller checks the count), every one
    /// looked up by the pass itself.
    pub(crate) fn to_raw(lights: &[LightRaw]) -> Self {
        Self::with_camera_bits(lights, 0)
    }

    /// As [`to_raw`](Self::to_raw), but lights in the `camera_bits` mask take
    /// their bits from the camera pass (analysis pass only).
    pub(crate) fn with_camera_bits(lights: &[LightRaw], camera_bits: u32) -> Self {
        let mut raw = Self::zeroed();
        let n = lights.len().min(MAX_LIGHTS);
        raw.count = n as u32;
        raw.items[..n].copy_from_slice(&lights[..n]);
        raw.camera_bits = camera_bits;
        for i in (0..n).filter(|&i| camera_bits >> i & 1 == 0) {
            let k = raw.lookup_count as usize;
            raw.lookup[k / 4][k % 4] = i as u32;
            raw.lookup_count += 1;
        }
        raw
    }
}

/// `ShadowPass` in `shadow.wgsl`, padded to its dynamic-offset slot.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub(crate) struct ShadowPassRaw {
    clip_from_world: [[f32; 4]; 4],
    /// Homogeneous light position: (p, 1) or (-d, 0).
    position: [f32; 4],
    /// Linear depth: (min distance, 1 / (max - min), constant bias, slope scale).
    depth: [f32; 4],
    /// (bias clamp, map width, map height, 0).
    clamp: [f32; 4],
    _pad: [f32; 36],
}

impl ShadowPassRaw {
    pub(crate) fn to_raw(matrix: &LightMatrix, bias: &crate::render::ShadowBias) -> Self {
        Self {
            clip_from_world: matrix.clip_from_world_f32().to_cols_array_2d(),
            position: light_position(matrix).to_array(),
            depth: {
                let [min, inv_span] = linear_depth_range(matrix);
                // Constant bias in units of 2^-24, the float spacing just below 1.
                [min, inv_span, bias.constant as f32 * 2f32.powi(-24), bias.slope_scale]
            },
            // yz: the map's size (the SPSM pass works in texels).
            clamp: [bias.clamp, matrix.map_size.width as f32, matrix.map_size.height as f32, 0.0],
            _pad: [0.0; 36],
        }
    }
}

/// `(min distance, 1 / (max - min))` of the matrix's light distances: the
/// `range` of `linear_light_depth` in `shaders/light_depth.wgsl`.
fn linear_depth_range(matrix: &LightMatrix) -> [f32; 2] {
    let d = matrix.light_distance;
    [d.min as f32, (1.0 / (d.max - d.min)) as f32]
}

/// The point the light comes from, homogeneous: (p, 1) or (-d, 0).
fn light_position(matrix: &LightMatrix) -> glam::Vec4 {
    match matrix.frame {
        LightFrame::Perspective { position, .. } => position.as_vec3().extend(1.0),
        LightFrame::Orthographic { rotation } => (-rotation.row(2).as_vec3()).extend(0.0),
    }
}

/// One vertex of the scene buffer: position, normal, albedo (sRGB-agnostic
/// linear bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub(crate) struct VertexRaw {
    pub(crate) position: [f32; 3],
    pub(crate) normal: [f32; 3],
    pub(crate) albedo: [u8; 4],
}

impl VertexRaw {
    pub(crate) const ATTRIBUTES: [wgpu::VertexAttribute; 3] =
        wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Unorm8x4];

    /// The layout with all three attributes (camera and analysis passes).
    pub(crate) fn layout() -> wgpu::VertexBufferLayout<'static> {
        wgpu::VertexBufferLayout {
            array_stride: std::mem::size_of::<Self>() as u64,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &Self::ATTRIBUTES,
        }
    }

    /// The layout of the packed positions buffer (shadow pass): the
    /// position attribute alone, 12 bytes a vertex.
    pub(crate) fn position_layout() -> wgpu::VertexBufferLayout<'static> {
        wgpu::VertexBufferLayout {
            array_stride: std::mem::size_of::<[f32; 3]>() as u64,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &Self::ATTRIBUTES[..1],
        }
    }
}

const _: () = assert!(std::mem::size_of::<ShadowPassRaw>() as u64 == SHADOW_SLOT_STRIDE);
const _: () = assert!(std::mem::size_of::<LightRaw>() == 160);
const _: () = assert!(std::mem::size_of::<VertexRaw>() == 28);
