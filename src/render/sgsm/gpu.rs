//! The SGSM sweep on the GPU: the compute pipeline, its per-map uniforms,
//! the maps' extra arrays (slopes written by the pass, mask words written
//! by the sweep) and the lookup's path counters.

use std::borrow::Cow;

use super::{SgsmCounts, SgsmOptions};
use crate::render::passes::MAX_SHADOW_SLOTS;
use crate::render::RenderError;

/// Format of the conservative pass's slope words.
pub(crate) const NORMAL_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R32Uint;
/// Format of the sweep's mask words.
pub(crate) const MASK_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R32Uint;
/// Uniform slot stride (the minimum uniform offset alignment).
const SLOT_STRIDE: u64 = 256;
/// Rows per workgroup (`@workgroup_size` in `sgsm_sweep.wgsl`).
const WORKGROUP: u32 = 64;
/// Texels of a row per invocation (`SGSM_SEGMENT` in `sgsm_sweep.wgsl`):
/// the CPU backends' loop limit (65 535 iterations per invocation) cut a
/// whole row's sweep at 1024-texel maps. Workgroups: rows / 64 by
/// columns / 128, at most 128 × 64 for an 8192² map.
const SEGMENT: u32 = 128;

/// The sweep pipeline and the lookup's counters.
pub(crate) struct SweepPass {
    pipeline: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
    uniforms: wgpu::Buffer,
    /// The path counters, when counting.
    pub(crate) counters: Option<wgpu::Buffer>,
}

/// The SGSM arrays of one set of maps.
pub(crate) struct SgsmMaps {
    pub(crate) normals: wgpu::Texture,
    pub(crate) normal_layers: Vec<wgpu::TextureView>,
    pub(crate) masks: wgpu::Texture,
    pub(crate) masks_view: wgpu::TextureView,
    bind_group: wgpu::BindGroup,
}

impl SweepPass {
    pub(crate) fn new(device: &wgpu::Device, options: &SgsmOptions) -> Self {
        let texture = |binding| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Texture {
                sample_type: wgpu::TextureSampleType::Uint,
                view_dimension: wgpu::TextureViewDimension::D2Array,
                multisampled: false,
            },
            count: None,
        };
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("lixel sgsm sweep layout"),
            entries: &[
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::COMPUTE,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: true,
                        min_binding_size: wgpu::BufferSize::new(16),
                    },
                    count: None,
                },
                texture(1),
                texture(2),
                wgpu::BindGroupLayoutEntry {
                    binding: 3,
                    visibility: wgpu::ShaderStages::COMPUTE,
                    ty: wgpu::BindingType::StorageTexture {
                        access: wgpu::StorageTextureAccess::WriteOnly,
                        format: MASK_FORMAT,
                        view_dimension: wgpu::TextureViewDimension::D2Array,
                    },
                    count: None,
                },
            ],
        });
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("lixel sgsm sweep shader"),
            source: wgpu::ShaderSource::Wgsl(Cow::Owned(super::sweep_source(options))),
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("lixel sgsm sweep pipeline layout"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("lixel sgsm sweep"),
            layout: Some(&pipeline_layout),
            module: &module,
            entry_point: Some("sgsm_sweep"),
            compilation_options: Default::default(),
            cache: None,
        });
        let uniforms = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("lixel sgsm sweep uniforms"),
            size: SLOT_STRIDE * MAX_SHADOW_SLOTS as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let counters = options.count_paths.then(|| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("lixel sgsm path counters"),
                size: (SgsmCounts::LEN * 4) as u64,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        });
        Self { pipeline, layout, uniforms, counters }
    }

    /// The arrays for maps of `width x height x layers`; `texels` is the
    /// SPSM texel array view.
    pub(crate) fn maps(
        &self,
        device: &wgpu::Device,
        texels: &wgpu::TextureView,
        width: u32,
        height: u32,
        layers: u32,
    ) -> SgsmMaps {
        let array = |label: &str, format, usage| {
            let texture = device.create_texture(&wgpu::TextureDescriptor {
                label: Some(label),
                size: wgpu::Extent3d { width, height, depth_or_array_layers: layers },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage: usage | wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_SRC,
                view_formats: &[],
            });
            let view = texture.create_view(&wgpu::TextureViewDescriptor {
                label: Some(label),
                dimension: Some(wgpu::TextureViewDimension::D2Array),
                ..Default::default()
            });
            (texture, view)
        };
        let (normals, normals_view) = array("lixel sgsm slopes", NORMAL_FORMAT, wgpu::TextureUsages::RENDER_ATTACHMENT);
        let (masks, masks_view) = array("lixel sgsm masks", MASK_FORMAT, wgpu::TextureUsages::STORAGE_BINDING);
        let normal_layers = (0..layers)
            .map(|layer| {
                normals.create_view(&wgpu::TextureViewDescriptor {
                    label: Some("lixel sgsm slopes layer"),
                    dimension: Some(wgpu::TextureViewDimension::D2),
                    base_array_layer: layer,
                    array_layer_count: Some(1),
                    ..Default::default()
                })
            })
            .collect();
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("lixel sgsm sweep bind group"),
            layout: &self.layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                        buffer: &self.uniforms,
                        offset: 0,
                        size: wgpu::BufferSize::new(16),
                    }),
                },
                wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::TextureView(texels) },
                wgpu::BindGroupEntry { binding: 2, resource: wgpu::BindingResource::TextureView(&normals_view) },
                wgpu::BindGroupEntry { binding: 3, resource: wgpu::BindingResource::TextureView(&masks_view) },
            ],
        });
        SgsmMaps { normals, normal_layers, masks, masks_view, bind_group }
    }

    /// Sweeps maps `0..sizes.len()` (sizes in texels), one dispatch each: an
    /// invocation per row segment of [`SEGMENT`] texels.
    pub(crate) fn encode(
        &self,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        maps: &SgsmMaps,
        sizes: &[(u32, u32)],
        timestamp_writes: Option<wgpu::ComputePassTimestampWrites<'_>>,
    ) {
        if sizes.is_empty() {
            return;
        }
        let mut raw = vec![0u32; sizes.len() * SLOT_STRIDE as usize / 4];
        for (i, (w, h)) in sizes.iter().enumerate() {
            let at = i * SLOT_STRIDE as usize / 4;
            raw[at..at + 3].copy_from_slice(&[*w, *h, i as u32]);
        }
        queue.write_buffer(&self.uniforms, 0, bytemuck::cast_slice(&raw));
        let mut pass = encoder
            .begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some("lixel sgsm sweep"), timestamp_writes });
        pass.set_pipeline(&self.pipeline);
        for (i, (w, h)) in sizes.iter().enumerate() {
            pass.set_bind_group(0, &maps.bind_group, &[(i as u64 * SLOT_STRIDE) as u32]);
            pass.dispatch_workgroups(h.div_ceil(WORKGROUP), w.div_ceil(SEGMENT), 1);
        }
    }
}

/// Reads a small buffer of `u32` and clears it.
pub(crate) fn read_and_clear(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    buffer: &wgpu::Buffer,
) -> Result<Vec<u32>, RenderError> {
    let staging = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("lixel sgsm counters readback"),
        size: buffer.size(),
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut encoder =
        device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("lixel sgsm counters") });
    encoder.copy_buffer_to_buffer(buffer, 0, &staging, 0, buffer.size());
    encoder.clear_buffer(buffer, 0, None);
    queue.submit([encoder.finish()]);
    let (sender, receiver) = std::sync::mpsc::channel();
    staging.map_async(wgpu::MapMode::Read, .., move |r| {
        let _ = sender.send(r);
    });
    device.poll(wgpu::PollType::wait_indefinitely())?;
    receiver.recv().map_err(|_| RenderError::Map(wgpu::BufferAsyncError))??;
    let words = {
        let view = staging.get_mapped_range(..).map_err(|_| RenderError::Map(wgpu::BufferAsyncError))?;
        bytemuck::cast_slice::<u8, u32>(&view).to_vec()
    };
    staging.unmap();
    Ok(words)
}
