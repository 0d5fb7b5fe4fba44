//! View capture and deferred camera passes ([`Renderer::capture_view`]).
//!
//! An experiment sees every light and every method through one camera, yet a
//! camera pass draws the whole scene (a million triangles on the paper
//! preset) for each of them. A capture draws the scene once into two
//! `Rgba32Uint` targets — per pixel the interpolated world position, the
//! depth-buffer value, the interpolated normal (all f32 bits) and an 8-bit
//! albedo — and later frames with exactly that camera shade the capture with
//! one full-screen triangle (`fs_deferred_*` in `shaders/camera.wgsl`). The
//! depth test kept the same fragment and the lookups see the same inputs,
//! so masks are bit-identical to a drawn pass; the colour sees the 8-bit
//! albedo. The deferred pass writes the depth buffer too (`frag_depth`), so
//! the depth analysis pass and the antialiased passes read what a drawn
//! pass would have left.
//!
//! [`Renderer::capture_view`]: super::Renderer::capture_view

use super::passes::{full_screen_pipeline, scene_pipeline, Target, COLOR_FORMAT, DEPTH_FORMAT, MASKS_FORMAT};
use crate::Camera;

/// Format of both capture targets (f32 bits in integer channels: R32Float
/// targets are not renderable everywhere, e.g. on GL).
const CAPTURE_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Uint;

/// The bind-group layout of a capture (group 2 of the deferred pipelines).
pub(crate) fn layout(device: &wgpu::Device) -> wgpu::BindGroupLayout {
    let texture = |binding| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::FRAGMENT,
        ty: wgpu::BindingType::Texture {
            sample_type: wgpu::TextureSampleType::Uint,
            view_dimension: wgpu::TextureViewDimension::D2,
            multisampled: false,
        },
        count: None,
    };
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("lixel view capture layout"),
        entries: &[texture(0), texture(1)],
    })
}

/// One captured view: the camera it was drawn from and its two targets.
pub(crate) struct ViewCapture {
    pub(crate) camera: Camera,
    pub(crate) surface: Target,
    pub(crate) normal: Target,
    pub(crate) bind_group: wgpu::BindGroup,
}

impl ViewCapture {
    pub(crate) fn new(device: &wgpu::Device, layout: &wgpu::BindGroupLayout, camera: Camera) -> Self {
        let size = camera.viewport();
        let target = |label: &str| {
            Target::with_usage(device, label, CAPTURE_FORMAT, size.x, size.y, wgpu::TextureUsages::TEXTURE_BINDING)
        };
        let surface = target("lixel view capture (surface)");
        let normal = target("lixel view capture (normal)");
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("lixel view capture bind group"),
            layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(&surface.view) },
                wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::TextureView(&normal.view) },
            ],
        });
        Self { camera, surface, normal, bind_group }
    }

    /// The capture pass's colour attachments, cleared to "background"
    /// (depth 1.0's bits in the surface word).
    pub(crate) fn attachments(&self) -> [Option<wgpu::RenderPassColorAttachment<'_>>; 2] {
        let clear = |view, r| {
            Some(wgpu::RenderPassColorAttachment {
                view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color { r: 0.0, g: 0.0, b: 0.0, a: r }),
                    store: wgpu::StoreOp::Store,
                },
            })
        };
        // Integer targets take their clear value through f64; 1.0f32's bits are exact.
        [clear(&self.surface.view, f64::from(1.0f32.to_bits())), clear(&self.normal.view, 0.0)]
    }
}

/// The pipelines of captures for one lookup mode's camera shader, built on
/// the first captured frame of that mode.
pub(crate) struct DeferredPipelines {
    /// Draws the scene into a capture.
    pub(crate) capture: wgpu::RenderPipeline,
    /// Full-screen shading of a capture: colour only, and colour and masks.
    pub(crate) color: wgpu::RenderPipeline,
    pub(crate) color_masks: wgpu::RenderPipeline,
}

impl DeferredPipelines {
    pub(crate) fn new(
        device: &wgpu::Device,
        layouts: [&wgpu::BindGroupLayout; 3],
        module: &wgpu::ShaderModule,
    ) -> Self {
        let [camera, maps, capture] = layouts;
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("lixel deferred camera pipeline layout"),
            bind_group_layouts: &[Some(camera), Some(maps), Some(capture)],
            immediate_size: 0,
        });
        let capture_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("lixel view capture pipeline layout"),
            bind_group_layouts: &[Some(camera)],
            immediate_size: 0,
        });
        let capture_target = Some(wgpu::ColorTargetState::from(CAPTURE_FORMAT));
        // As the camera pass: no culling, depth test "less".
        let capture = scene_pipeline(
            device,
            "lixel view capture pipeline",
            &capture_layout,
            module,
            "fs_capture",
            &[capture_target.clone(), capture_target],
        );
        let full_screen = |label: &str, entry: &str, targets: &[Option<wgpu::ColorTargetState>]| {
            // Every covered pixel writes its captured depth.
            let depth = wgpu::DepthStencilState {
                format: DEPTH_FORMAT,
                depth_write_enabled: Some(true),
                depth_compare: Some(wgpu::CompareFunction::Always),
                stencil: wgpu::StencilState::default(),
                bias: wgpu::DepthBiasState::default(),
            };
            full_screen_pipeline(device, label, &layout, module, ["vs_fullscreen", entry], targets, Some(depth))
        };
        let color_target = Some(wgpu::ColorTargetState::from(COLOR_FORMAT));
        let masks_target = Some(wgpu::ColorTargetState::from(MASKS_FORMAT));
        Self {
            capture,
            color: full_screen(
                "lixel deferred camera pipeline",
                "fs_deferred_color",
                std::slice::from_ref(&color_target),
            ),
            color_masks: full_screen(
                "lixel deferred camera pipeline with masks",
                "fs_deferred_color_masks",
                &[color_target, masks_target],
            ),
        }
    }
}
