//! Pipelines and targets of the camera and analysis passes, one small
//! struct per pass (the shadow pass and the maps depend on the lookup mode:
//! `lookup.rs`).

use super::capture::{self, DeferredPipelines};
use super::uniforms::{VertexRaw, MAX_LIGHTS};

/// Depth format of shadow maps and camera depth buffers.
pub(crate) const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
/// Colour format of the camera pass: the shaders write linear colour.
pub(crate) const COLOR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;
/// Format of the per-pixel words (depth bits, shadow, facing, normal).
pub(crate) const MASKS_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Uint;

/// Shadow maps of one frame: at most the frame's lights plus the analysis
/// pass's own lights.
pub(crate) const MAX_SHADOW_SLOTS: usize = 2 * MAX_LIGHTS;

/// The group-0 layouts of the camera and analysis passes (the same for
/// every lookup mode; the maps are group 1, see `lookup.rs`): camera
/// uniforms (binding 0) and lights (binding 1); the analysis layout adds the
/// camera pass's depth (binding 3) and masks (binding 4).
pub(crate) struct SceneLayouts {
    pub(crate) camera: wgpu::BindGroupLayout,
    pub(crate) analysis: wgpu::BindGroupLayout,
    /// A view capture's targets (group 2 of the deferred camera pass).
    pub(crate) capture: wgpu::BindGroupLayout,
}

impl SceneLayouts {
    pub(crate) fn new(device: &wgpu::Device) -> Self {
        let uniform = |binding| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::VERTEX | wgpu::ShaderStages::FRAGMENT,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        };
        let texture = |binding, sample_type| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::FRAGMENT,
            // Depth bound as unfilterable float: `textureLoad` from a
            // `texture_depth_*` has no GLSL translation (GL backend).
            ty: wgpu::BindingType::Texture {
                sample_type,
                view_dimension: wgpu::TextureViewDimension::D2,
                multisampled: false,
            },
            count: None,
        };
        Self {
            camera: device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("lixel camera bind group layout"),
                entries: &[uniform(0), uniform(1)],
            }),
            analysis: device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("lixel analysis bind group layout"),
                entries: &[
                    uniform(0),
                    uniform(1),
                    texture(3, wgpu::TextureSampleType::Float { filterable: false }),
                    texture(4, wgpu::TextureSampleType::Uint),
                ],
            }),
            capture: capture::layout(device),
        }
    }
}

fn pipeline_layout(
    device: &wgpu::Device,
    label: &str,
    scene: &wgpu::BindGroupLayout,
    maps: &wgpu::BindGroupLayout,
) -> wgpu::PipelineLayout {
    device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some(label),
        bind_group_layouts: &[Some(scene), Some(maps)],
        immediate_size: 0,
    })
}

/// A pipeline drawing the scene from the camera (`vs_main` in common.wgsl)
/// with the usual depth test.
pub(crate) fn scene_pipeline(
    device: &wgpu::Device,
    label: &str,
    layout: &wgpu::PipelineLayout,
    module: &wgpu::ShaderModule,
    entry: &str,
    targets: &[Option<wgpu::ColorTargetState>],
) -> wgpu::RenderPipeline {
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(label),
        layout: Some(layout),
        vertex: wgpu::VertexState {
            module,
            entry_point: Some("vs_main"),
            compilation_options: Default::default(),
            buffers: &[Some(VertexRaw::layout())],
        },
        // No culling, as in the shadow pass and the ray caster.
        primitive: wgpu::PrimitiveState { cull_mode: None, ..Default::default() },
        depth_stencil: Some(wgpu::DepthStencilState {
            format: DEPTH_FORMAT,
            depth_write_enabled: Some(true),
            depth_compare: Some(wgpu::CompareFunction::Less),
            stencil: wgpu::StencilState::default(),
            bias: wgpu::DepthBiasState::default(),
        }),
        multisample: wgpu::MultisampleState::default(),
        fragment: Some(wgpu::FragmentState {
            module,
            entry_point: Some(entry),
            compilation_options: Default::default(),
            targets,
        }),
        multiview_mask: None,
        cache: None,
    })
}

/// A storage-buffer entry of a bind group layout, seen by `visibility`.
pub(crate) fn storage_entry(
    binding: u32,
    visibility: wgpu::ShaderStages,
    read_only: bool,
    has_dynamic_offset: bool,
) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset,
            min_binding_size: None,
        },
        count: None,
    }
}

/// A pipeline drawing one full-screen triangle without vertex buffers
/// (`entries`: the vertex and fragment entry points of `module`, e.g.
/// `vs_fullscreen` in common.wgsl), writing `targets` and, with
/// `depth_stencil`, a depth target.
pub(crate) fn full_screen_pipeline(
    device: &wgpu::Device,
    label: &str,
    layout: &wgpu::PipelineLayout,
    module: &wgpu::ShaderModule,
    [vertex, fragment]: [&str; 2],
    targets: &[Option<wgpu::ColorTargetState>],
    depth_stencil: Option<wgpu::DepthStencilState>,
) -> wgpu::RenderPipeline {
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(label),
        layout: Some(layout),
        vertex: wgpu::VertexState {
            module,
            entry_point: Some(vertex),
            compilation_options: Default::default(),
            buffers: &[],
        },
        primitive: wgpu::PrimitiveState::default(),
        depth_stencil,
        multisample: wgpu::MultisampleState::default(),
        fragment: Some(wgpu::FragmentState {
            module,
            entry_point: Some(fragment),
            compilation_options: Default::default(),
            targets,
        }),
        multiview_mask: None,
        cache: None,
    })
}

/// The camera pass: colour only, or colour and the full-resolution masks;
/// the view-capture pipelines of the same shader on first use.
pub(crate) struct CameraPass {
    pub(crate) color: wgpu::RenderPipeline,
    pub(crate) color_masks: wgpu::RenderPipeline,
    module: wgpu::ShaderModule,
    deferred: Option<DeferredPipelines>,
}

impl CameraPass {
    pub(crate) fn new(
        device: &wgpu::Device,
        scene: &wgpu::BindGroupLayout,
        maps: &wgpu::BindGroupLayout,
        module: &wgpu::ShaderModule,
    ) -> Self {
        let layout = pipeline_layout(device, "lixel camera pipeline layout", scene, maps);
        let color_target = Some(wgpu::ColorTargetState::from(COLOR_FORMAT));
        let masks_target = Some(wgpu::ColorTargetState::from(MASKS_FORMAT));
        Self {
            color: scene_pipeline(
                device,
                "lixel camera pipeline",
                &layout,
                module,
                "fs_color",
                std::slice::from_ref(&color_target),
            ),
            color_masks: scene_pipeline(
                device,
                "lixel camera pipeline with masks",
                &layout,
                module,
                "fs_color_masks",
                &[color_target, masks_target],
            ),
            module: module.clone(),
            deferred: None,
        }
    }

    /// The view-capture and deferred pipelines, built on the first call.
    pub(crate) fn deferred(
        &mut self,
        device: &wgpu::Device,
        layouts: &SceneLayouts,
        maps: &wgpu::BindGroupLayout,
    ) -> &DeferredPipelines {
        self.deferred.get_or_insert_with(|| {
            DeferredPipelines::new(device, [&layouts.camera, maps, &layouts.capture], &self.module)
        })
    }

    /// The deferred pipelines when built.
    pub(crate) fn deferred_built(&self) -> Option<&DeferredPipelines> {
        self.deferred.as_ref()
    }
}

/// The analysis pass, from either source: the geometry version shares the
/// camera pass's vertex stage; the depth version draws one full-screen
/// triangle over the camera pass's depth and masks.
pub(crate) struct AnalysisPass {
    pub(crate) geometry: wgpu::RenderPipeline,
    pub(crate) depth: wgpu::RenderPipeline,
}

impl AnalysisPass {
    pub(crate) fn new(
        device: &wgpu::Device,
        scene: &wgpu::BindGroupLayout,
        maps: &wgpu::BindGroupLayout,
        module: &wgpu::ShaderModule,
    ) -> Self {
        let layout = pipeline_layout(device, "lixel analysis pipeline layout", scene, maps);
        let masks_target = Some(wgpu::ColorTargetState::from(MASKS_FORMAT));
        let depth = full_screen_pipeline(
            device,
            "lixel analysis pipeline (camera depth)",
            &layout,
            module,
            ["vs_fullscreen", "fs_analysis_depth"],
            std::slice::from_ref(&masks_target),
            None,
        );
        Self {
            geometry: scene_pipeline(
                device,
                "lixel analysis pipeline (geometry)",
                &layout,
                module,
                "fs_analysis_geometry",
                &[masks_target],
            ),
            depth,
        }
    }
}

/// A 2D texture with a default view.
pub(crate) struct Target {
    pub(crate) texture: wgpu::Texture,
    pub(crate) view: wgpu::TextureView,
}

impl Target {
    pub(crate) fn new(
        device: &wgpu::Device,
        label: &str,
        format: wgpu::TextureFormat,
        width: u32,
        height: u32,
    ) -> Self {
        Self::with_usage(device, label, format, width, height, wgpu::TextureUsages::empty())
    }

    /// A target that can also be used as `extra` (e.g. bound as a texture).
    pub(crate) fn with_usage(
        device: &wgpu::Device,
        label: &str,
        format: wgpu::TextureFormat,
        width: u32,
        height: u32,
        extra: wgpu::TextureUsages,
    ) -> Self {
        let texture = device.create_texture(&wgpu::TextureDescriptor {
            label: Some(label),
            size: wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC | extra,
            view_formats: &[],
        });
        let view = texture
            .create_view(&wgpu::TextureViewDescriptor { label: Some(&format!("{label} view")), ..Default::default() });
        Self { texture, view }
    }
}

/// The camera pass's targets at one resolution.
pub(crate) struct CameraTargets {
    pub(crate) width: u32,
    pub(crate) height: u32,
    pub(crate) color: Target,
    pub(crate) masks: Target,
    pub(crate) depth: Target,
}

impl CameraTargets {
    pub(crate) fn new(device: &wgpu::Device, label: &str, width: u32, height: u32) -> Self {
        Self {
            width,
            height,
            color: Target::new(device, &format!("{label} colour"), COLOR_FORMAT, width, height),
            // Both bound as textures by the depth analysis pass.
            masks: Target::with_usage(
                device,
                &format!("{label} masks"),
                MASKS_FORMAT,
                width,
                height,
                wgpu::TextureUsages::TEXTURE_BINDING,
            ),
            depth: Target::with_usage(
                device,
                &format!("{label} depth"),
                DEPTH_FORMAT,
                width,
                height,
                wgpu::TextureUsages::TEXTURE_BINDING,
            ),
        }
    }
}
