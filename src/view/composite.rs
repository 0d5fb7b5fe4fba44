//! The composite pass (`shaders/view_composite.wgsl`): the camera pass's
//! picture plus the overlays, written into the window's surface or an
//! offscreen texture. The camera colour is copied into a texture of our own
//! (the renderer's target is not bindable); its depth is bound directly.
//! The error, shadow-map and HUD pictures are uploaded from the CPU when
//! they change.

use bytemuck::{Pod, Zeroable};
use glam::Mat4;

use crate::render::passes::full_screen_pipeline;
use crate::render::RenderError;

/// Format of the uploaded pictures (error, shadow map, HUD) and of the
/// colour copy: sRGB bytes, read back as linear colour.
const PICTURE_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;

/// `View` in `view_composite.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub(crate) struct CompositeRaw {
    pub(crate) world_from_clip: [[f32; 4]; 4],
    pub(crate) light_clip_from_world: [[f32; 4]; 4],
    pub(crate) sizes: [f32; 4],
    pub(crate) flags: [u32; 4],
    pub(crate) map_rect: [f32; 4],
    pub(crate) hud_rect: [f32; 4],
}

impl CompositeRaw {
    pub(crate) fn new(world_from_clip: Mat4, light: Mat4) -> Self {
        Self {
            world_from_clip: world_from_clip.to_cols_array_2d(),
            light_clip_from_world: light.to_cols_array_2d(),
            sizes: [1.0; 4],
            flags: [0; 4],
            map_rect: [0.0; 4],
            hud_rect: [0.0; 4],
        }
    }
}

/// A picture uploaded from the CPU.
struct Picture {
    texture: wgpu::Texture,
    view: wgpu::TextureView,
}

impl Picture {
    fn new(device: &wgpu::Device, label: &str, width: u32, height: u32, usage: wgpu::TextureUsages) -> Self {
        let texture = device.create_texture(&wgpu::TextureDescriptor {
            label: Some(label),
            size: wgpu::Extent3d { width: width.max(1), height: height.max(1), depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: PICTURE_FORMAT,
            usage: wgpu::TextureUsages::TEXTURE_BINDING | usage,
            view_formats: &[],
        });
        let view = texture.create_view(&wgpu::TextureViewDescriptor::default());
        Self { texture, view }
    }

    fn size(&self) -> (u32, u32) {
        (self.texture.width(), self.texture.height())
    }
}

/// Which uploaded picture.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Slot {
    Error,
    Map,
    Hud,
}

/// The composite pass for one target format.
pub(crate) struct Composite {
    device: wgpu::Device,
    queue: wgpu::Queue,
    layout: wgpu::BindGroupLayout,
    pipeline: wgpu::RenderPipeline,
    /// Whether the shader encodes sRGB itself (non-sRGB target).
    encode_srgb: bool,
    uniforms: wgpu::Buffer,
    color: Picture,
    pictures: [Picture; 3],
}

impl Composite {
    /// The pass writing into targets of `format`.
    ///
    /// # Errors
    /// [`RenderError::Device`] when the device refuses the pipeline.
    pub(crate) fn new(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        format: wgpu::TextureFormat,
    ) -> Result<Self, RenderError> {
        crate::render::device::capture(device, "viewer composite pipeline", || {
            let texture = |binding| wgpu::BindGroupLayoutEntry {
                binding,
                visibility: wgpu::ShaderStages::FRAGMENT,
                ty: wgpu::BindingType::Texture {
                    sample_type: wgpu::TextureSampleType::Float { filterable: false },
                    view_dimension: wgpu::TextureViewDimension::D2,
                    multisampled: false,
                },
                count: None,
            };
            let uniform = wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::FRAGMENT,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            };
            let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("lixel view composite layout"),
                entries: &[uniform, texture(1), texture(2), texture(3), texture(4), texture(5)],
            });
            let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("lixel view composite pipeline layout"),
                bind_group_layouts: &[Some(&layout)],
                immediate_size: 0,
            });
            let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some("lixel view composite shader"),
                source: wgpu::ShaderSource::Wgsl(include_str!("../../shaders/view_composite.wgsl").into()),
            });
            let pipeline = full_screen_pipeline(
                device,
                "lixel view composite pipeline",
                &pipeline_layout,
                &module,
                ["vs_composite", "fs_composite"],
                &[Some(wgpu::ColorTargetState::from(format))],
                None,
            );
            let uniforms = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("lixel view composite uniforms"),
                size: std::mem::size_of::<CompositeRaw>() as u64,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            let empty = |label| Picture::new(device, label, 1, 1, wgpu::TextureUsages::COPY_DST);
            Self {
                device: device.clone(),
                queue: queue.clone(),
                layout,
                pipeline,
                encode_srgb: !format.is_srgb(),
                uniforms,
                color: Picture::new(device, "lixel view colour copy", 1, 1, wgpu::TextureUsages::COPY_DST),
                pictures: [empty("lixel view error"), empty("lixel view shadow map"), empty("lixel view HUD")],
            }
        })
    }

    /// Uploads a picture (reallocating its texture when the size changed).
    pub(crate) fn upload(&mut self, slot: Slot, picture: &image::RgbaImage) {
        let (w, h) = picture.dimensions();
        if w == 0 || h == 0 {
            return;
        }
        let i = slot as usize;
        if self.pictures[i].size() != (w, h) {
            self.pictures[i] = Picture::new(&self.device, "lixel view picture", w, h, wgpu::TextureUsages::COPY_DST);
        }
        self.queue.write_texture(
            self.pictures[i].texture.as_image_copy(),
            picture.as_raw(),
            wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(4 * w), rows_per_image: Some(h) },
            wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 },
        );
    }

    /// Encodes the pass: copies the camera colour, then draws into `target`.
    /// `raw`'s flags `w` is set here from the target format.
    pub(crate) fn encode(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        target: &wgpu::TextureView,
        camera_color: &wgpu::Texture,
        camera_depth: &wgpu::TextureView,
        mut raw: CompositeRaw,
    ) {
        let (w, h) = (camera_color.width(), camera_color.height());
        if self.color.size() != (w, h) {
            self.color = Picture::new(&self.device, "lixel view colour copy", w, h, wgpu::TextureUsages::COPY_DST);
        }
        encoder.copy_texture_to_texture(
            camera_color.as_image_copy(),
            self.color.texture.as_image_copy(),
            wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 },
        );
        raw.flags[3] = u32::from(self.encode_srgb);
        self.queue.write_buffer(&self.uniforms, 0, bytemuck::bytes_of(&raw));
        let view = |binding, view| wgpu::BindGroupEntry { binding, resource: wgpu::BindingResource::TextureView(view) };
        let bind_group = self.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("lixel view composite bind group"),
            layout: &self.layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: self.uniforms.as_entire_binding() },
                view(1, &self.color.view),
                view(2, camera_depth),
                view(3, &self.pictures[Slot::Error as usize].view),
                view(4, &self.pictures[Slot::Map as usize].view),
                view(5, &self.pictures[Slot::Hud as usize].view),
            ],
        });
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("lixel view composite pass"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: target,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations { load: wgpu::LoadOp::Clear(wgpu::Color::BLACK), store: wgpu::StoreOp::Store },
            })],
            depth_stencil_attachment: None,
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &bind_group, &[]);
        pass.draw(0..3, 0..1);
    }

    /// Size of an uploaded picture.
    pub(crate) fn picture_size(&self, slot: Slot) -> (u32, u32) {
        self.pictures[slot as usize].size()
    }
}
