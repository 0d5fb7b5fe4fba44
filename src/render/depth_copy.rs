//! Shadow-map readback through a colour target.
//!
//! Why: the GL backend cannot copy depth textures to buffers, and R32Float
//! is not renderable there. A full-screen pass reads one layer of the
//! shadow-map array (bound as an unfilterable float texture) and writes each
//! texel's f32 bits into an R32Uint target, which any backend can copy. The
//! bits are the stored depth exactly, so every backend takes this one path.
//! Used only by blocking reads ([`Renderer::read_shadow_map`](super::Renderer::read_shadow_map)),
//! never by the frame loop; the pipeline is built on first use.

use std::borrow::Cow;

use wgpu::util::DeviceExt;

use super::passes::{full_screen_pipeline, Target};

const SHADER: &str = r"
@group(0) @binding(0) var depth: texture_2d_array<f32>;
@group(0) @binding(1) var<uniform> layer: vec4<u32>;

@vertex
fn vs_fullscreen(@builtin(vertex_index) index: u32) -> @builtin(position) vec4<f32> {
    let corner = vec2<f32>(f32((index << 1u) & 2u), f32(index & 2u));
    return vec4<f32>(corner * 2.0 - 1.0, 0.0, 1.0);
}

@fragment
fn fs_copy(@builtin(position) frag: vec4<f32>) -> @location(0) u32 {
    return bitcast<u32>(textureLoad(depth, vec2<i32>(frag.xy), layer.x, 0).x);
}
";

/// Format the depth bits are written to.
pub(crate) const BITS_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R32Uint;

/// The copy pipeline and its layout.
pub(crate) struct DepthCopy {
    layout: wgpu::BindGroupLayout,
    pipeline: wgpu::RenderPipeline,
}

impl DepthCopy {
    pub(crate) fn new(device: &wgpu::Device) -> Self {
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("lixel depth copy shader"),
            source: wgpu::ShaderSource::Wgsl(Cow::Borrowed(SHADER)),
        });
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("lixel depth copy bind group layout"),
            entries: &[
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Float { filterable: false },
                        view_dimension: wgpu::TextureViewDimension::D2Array,
                        multisampled: false,
                    },
                    count: None,
                },
                wgpu::BindGroupLayoutEntry {
                    binding: 1,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: false,
                        min_binding_size: None,
                    },
                    count: None,
                },
            ],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("lixel depth copy pipeline layout"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = full_screen_pipeline(
            device,
            "lixel depth copy pipeline",
            &pipeline_layout,
            &module,
            ["vs_fullscreen", "fs_copy"],
            &[Some(wgpu::ColorTargetState::from(BITS_FORMAT))],
            None,
        );
        Self { layout, pipeline }
    }

    /// Encodes the copy of `layer` of the shadow-map array `maps` (its
    /// top-left `width x height` texels) into a new R32Uint target, returned
    /// for reading back. The whole array is bound and the layer passed in a
    /// uniform: GL has no views of one array layer as a 2D texture.
    pub(crate) fn encode(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        maps: &wgpu::TextureView,
        layer: u32,
        width: u32,
        height: u32,
    ) -> Target {
        let uniform = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("lixel depth copy layer"),
            contents: bytemuck::cast_slice(&[layer, 0, 0, 0]),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("lixel depth copy bind group"),
            layout: &self.layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(maps) },
                wgpu::BindGroupEntry { binding: 1, resource: uniform.as_entire_binding() },
            ],
        });
        let target = Target::new(device, "lixel depth copy target", BITS_FORMAT, width, height);
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("lixel depth copy pass"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &target.view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: None,
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &bind_group, &[]);
        pass.draw(0..3, 0..1);
        drop(pass);
        target
    }
}
