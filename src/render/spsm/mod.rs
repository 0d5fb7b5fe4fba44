//! Sub-pixel shadow maps (SPSM, Lecocq et al. 2014) as a shadow lookup of
//! the renderer, for every [`LightMatrix`](crate::LightMatrix).
//!
//! Why: a standard map answers every lookup with one depth per texel, so its
//! error is bounded by texels whatever the matrix. SPSM stores, per texel,
//! the closest triangle that *touches* the texel (conservative
//! rasterization) and rebuilds shadow edges below texel size.
//!
//! - The **SPSM pass** (`shaders/spsm_pass.wgsl`) replaces the depth-only
//!   shadow pass: conservative rasterization done in the shader (no
//!   `CONSERVATIVE_RASTERIZATION` on lavapipe or GL), the paper's consistent
//!   minimum depth in the depth buffer and the packed triangle in an
//!   `Rgba32Uint` texel array ([`packing`] mirrors the format on the CPU).
//! - The **lookup** (`shaders/spsm_lookup.wgsl`) replaces `in_shadow` in
//!   the camera and analysis shaders, so masks, colour and the optimizer's
//!   analysis bits all come from the same lookup.
//!
//! All of it works in the matrix's post-projective space (`z / w`), where
//! triangles stay planar; lixel's standard maps store linear light depth,
//! which is not planar for point lights (see `shaders/spsm_common.wgsl`).

pub mod packing;

use std::borrow::Cow;

use bytemuck::{Pod, Zeroable};

use super::passes::DEPTH_FORMAT;
use crate::LightMatrix;

/// Format of the SPSM texels.
pub(crate) const TEXEL_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Uint;

/// Settings of the SPSM lookup.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpsmOptions {
    /// Exponent `n` of the paper's power quantization of the depth
    /// derivatives (eq. 3); the paper uses 5, 1 is linear.
    pub exponent: f32,
    /// Constant depth bias of every plane test, in units of the `[0, 1]`
    /// post-projective depth range (the paper: 1e-5).
    pub bias: f32,
    /// Also allow, in each plane test, the packing's own error bound: half a
    /// quantization step of each decoded derivative times the distance the
    /// plane is extrapolated. Off: the plain constant bias (acne from the
    /// 8-bit derivatives shows).
    pub packing_tolerance: bool,
}

impl Default for SpsmOptions {
    fn default() -> Self {
        Self { exponent: 5.0, bias: 1e-5, packing_tolerance: true }
    }
}

/// How the camera and analysis passes look shadows up.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum ShadowLookup {
    /// One depth compare per lookup against a standard depth map.
    #[default]
    Standard,
    /// Sub-pixel shadow maps.
    Spsm(SpsmOptions),
}

impl ShadowLookup {
    /// The SPSM options, if this is the SPSM lookup.
    #[must_use]
    pub fn spsm(&self) -> Option<&SpsmOptions> {
        match self {
            Self::Standard => None,
            Self::Spsm(options) => Some(options),
        }
    }
}

/// WGSL constants the SPSM shaders expect before `spsm_common.wgsl`.
fn constants(options: &SpsmOptions) -> String {
    format!(
        "const SPSM_EXPONENT: f32 = {:?};\nconst SPSM_BIAS: f32 = {:?};\nconst SPSM_TOLERANCE: f32 = {:?};\n",
        options.exponent,
        options.bias,
        if options.packing_tolerance { 1.0f32 } else { 0.0 }
    )
}

/// The 3x3 pattern table of the lookup as a WGSL constant.
fn tangent_table() -> String {
    let mut s = String::from("const SPSM_TANGENTS = array<vec2<f32>, 512>(\n");
    for n in packing::silhouette_normals() {
        s.push_str(&format!("    vec2<f32>({:?}, {:?}),\n", n[0], n[1]));
    }
    s.push_str(");\n");
    s
}

/// Source of the SPSM pass.
pub(crate) fn pass_source(options: &SpsmOptions) -> String {
    constants(options) + include_str!("../../../shaders/spsm_common.wgsl") + include_str!("../../../shaders/spsm_pass.wgsl")
}

/// A camera or analysis shader (`light_depth` + `common` + `pass`) with the
/// SPSM lookup in place of the standard `in_shadow`.
pub(crate) fn scene_source(options: &SpsmOptions, common: &str, pass: &str) -> String {
    let light_depth = include_str!("../../../shaders/light_depth.wgsl");
    let common = common.replacen("fn in_shadow(", "fn in_shadow_standard(", 1);
    let spsm = constants(options)
        + include_str!("../../../shaders/spsm_common.wgsl")
        + &tangent_table()
        + include_str!("../../../shaders/spsm_lookup.wgsl");
    format!("{light_depth}{common}{spsm}{pass}")
}

/// `SpsmPass` in `spsm_pass.wgsl`, padded to its dynamic-offset slot.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub(crate) struct SpsmPassRaw {
    clip_from_world: [[f32; 4]; 4],
    map: [f32; 4],
    _pad: [f32; 44],
}

/// Stride between the per-light slots of the pass's uniform buffer.
pub(crate) const SLOT_STRIDE: u64 = 256;
const _: () = assert!(std::mem::size_of::<SpsmPassRaw>() as u64 == SLOT_STRIDE);

impl SpsmPassRaw {
    pub(crate) fn to_raw(matrix: &LightMatrix) -> Self {
        Self {
            clip_from_world: matrix.clip_from_world_f32().to_cols_array_2d(),
            map: [matrix.map_size.width as f32, matrix.map_size.height as f32, 0.0, 0.0],
            _pad: [0.0; 44],
        }
    }
}

/// The SPSM pass's pipeline, uniforms and bind group (scene buffers bound
/// as storage for vertex pulling).
pub(crate) struct SpsmPass {
    pub(crate) pipeline: wgpu::RenderPipeline,
    pub(crate) uniforms: wgpu::Buffer,
    pub(crate) bind_group: wgpu::BindGroup,
}

impl SpsmPass {
    pub(crate) fn new(
        device: &wgpu::Device,
        options: &SpsmOptions,
        vertices: &wgpu::Buffer,
        indices: &wgpu::Buffer,
        slots: usize,
        unclipped: bool,
    ) -> Self {
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("lixel spsm pass shader"),
            source: wgpu::ShaderSource::Wgsl(Cow::Owned(pass_source(options))),
        });
        let storage = |binding| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::VERTEX,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Storage { read_only: true },
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        };
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("lixel spsm bind group layout"),
            entries: &[
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: true,
                        min_binding_size: wgpu::BufferSize::new(SLOT_STRIDE),
                    },
                    count: None,
                },
                storage(1),
                storage(2),
            ],
        });
        let uniforms = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("lixel spsm pass uniforms"),
            size: SLOT_STRIDE * slots as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("lixel spsm bind group"),
            layout: &layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                        buffer: &uniforms,
                        offset: 0,
                        size: wgpu::BufferSize::new(SLOT_STRIDE),
                    }),
                },
                wgpu::BindGroupEntry { binding: 1, resource: vertices.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 2, resource: indices.as_entire_binding() },
            ],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("lixel spsm pipeline layout"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("lixel spsm pipeline"),
            layout: Some(&pipeline_layout),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs_spsm"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive: wgpu::PrimitiveState { cull_mode: None, unclipped_depth: unclipped, ..Default::default() },
            depth_stencil: Some(wgpu::DepthStencilState {
                format: DEPTH_FORMAT,
                depth_write_enabled: Some(true),
                depth_compare: Some(wgpu::CompareFunction::Less),
                stencil: wgpu::StencilState::default(),
                bias: wgpu::DepthBiasState::default(),
            }),
            multisample: wgpu::MultisampleState::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs_spsm"),
                compilation_options: Default::default(),
                targets: &[Some(wgpu::ColorTargetState::from(TEXEL_FORMAT))],
            }),
            multiview_mask: None,
            cache: None,
        });
        Self { pipeline, uniforms, bind_group }
    }
}

/// The SPSM texels of every light: a layer each, like the depth maps.
pub(crate) struct SpsmTexels {
    pub(crate) texture: wgpu::Texture,
    pub(crate) array_view: wgpu::TextureView,
    pub(crate) layer_views: Vec<wgpu::TextureView>,
}

impl SpsmTexels {
    pub(crate) fn new(device: &wgpu::Device, width: u32, height: u32, layers: u32) -> Self {
        let texture = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("lixel spsm texels"),
            size: wgpu::Extent3d { width, height, depth_or_array_layers: layers },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: TEXEL_FORMAT,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT
                | wgpu::TextureUsages::TEXTURE_BINDING
                | wgpu::TextureUsages::COPY_SRC,
            view_formats: &[],
        });
        let array_view = texture.create_view(&wgpu::TextureViewDescriptor {
            label: Some("lixel spsm texels array view"),
            dimension: Some(wgpu::TextureViewDimension::D2Array),
            ..Default::default()
        });
        let layer_views = (0..layers)
            .map(|layer| {
                texture.create_view(&wgpu::TextureViewDescriptor {
                    label: Some(&format!("lixel spsm texels layer {layer}")),
                    dimension: Some(wgpu::TextureViewDimension::D2),
                    base_array_layer: layer,
                    array_layer_count: Some(1),
                    ..Default::default()
                })
            })
            .collect();
        Self { texture, array_view, layer_views }
    }
}

/// The texel every SPSM layer is cleared to: no triangle, empty.
pub(crate) fn empty_clear() -> wgpu::Color {
    let all = f64::from(u32::MAX);
    wgpu::Color { r: all, g: all, b: all, a: f64::from(0xffff_ffffu32) }
}

/// The bind-group-layout entry of the texels in the camera and analysis passes.
pub(crate) fn texels_layout_entry() -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding: 5,
        visibility: wgpu::ShaderStages::FRAGMENT,
        ty: wgpu::BindingType::Texture {
            sample_type: wgpu::TextureSampleType::Uint,
            view_dimension: wgpu::TextureViewDimension::D2Array,
            multisampled: false,
        },
        count: None,
    }
}
