//! Pipelines and GPU resources of the three passes, one small struct each.

use std::borrow::Cow;

use super::spsm::ShadowLookup;
use super::uniforms::{ShadowPassRaw, VertexRaw, MAX_LIGHTS, SHADOW_SLOT_STRIDE};

/// Depth format of shadow maps and camera depth buffers.
pub(crate) const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
/// Colour format of the camera pass: the shaders write linear colour.
pub(crate) const COLOR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;
/// Format of the per-pixel words (depth bits, shadow, facing, normal).
pub(crate) const MASKS_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Uint;

/// Shadow maps of one frame: at most the frame's lights plus the analysis
/// pass's own lights.
pub(crate) const MAX_SHADOW_SLOTS: usize = 2 * MAX_LIGHTS;

fn scene_shader(device: &wgpu::Device, label: &str, source: Cow<'static, str>) -> wgpu::ShaderModule {
    device.create_shader_module(wgpu::ShaderModuleDescriptor { label: Some(label), source: wgpu::ShaderSource::Wgsl(source) })
}

/// The depth-only pass: twelve pipelines (depth test normal/reversed x depth
/// clipped/unclipped x faces culled: none, front, back) sharing one uniform
/// buffer with a slot per light.
pub(crate) struct ShadowPass {
    /// Indexed by `cull * 4 + reversed as usize * 2 + unclipped as usize`
    /// (`cull`: 0 none, 1 front, 2 back); `None` for unclipped variants when
    /// the device lacks `DEPTH_CLIP_CONTROL`.
    pipelines: [Option<wgpu::RenderPipeline>; 12],
    pub(crate) uniforms: wgpu::Buffer,
    pub(crate) bind_group: wgpu::BindGroup,
}

impl ShadowPass {
    pub(crate) fn new(device: &wgpu::Device, unclipped_available: bool) -> Self {
        let module = scene_shader(
            device,
            "lixel shadow shader",
            Cow::Borrowed(concat!(
                include_str!("../../shaders/light_depth.wgsl"),
                include_str!("../../shaders/shadow.wgsl")
            )),
        );
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("lixel shadow bind group layout"),
            entries: &[wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: true,
                    min_binding_size: wgpu::BufferSize::new(std::mem::size_of::<ShadowPassRaw>() as u64),
                },
                count: None,
            }],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("lixel shadow pipeline layout"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let uniforms = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("lixel shadow pass uniforms"),
            size: SHADOW_SLOT_STRIDE * MAX_SHADOW_SLOTS as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("lixel shadow bind group"),
            layout: &layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                    buffer: &uniforms,
                    offset: 0,
                    size: wgpu::BufferSize::new(std::mem::size_of::<ShadowPassRaw>() as u64),
                }),
            }],
        });
        let pipelines = std::array::from_fn(|k| {
            let (cull, reversed, unclipped) = (k / 4, (k / 2) % 2 == 1, k % 2 == 1);
            let cull_mode = [None, Some(wgpu::Face::Front), Some(wgpu::Face::Back)][cull];
            (!unclipped || unclipped_available).then(|| {
                let label = format!(
                    "lixel shadow pipeline ({}, {}, cull {cull_mode:?})",
                    if reversed { "reversed depth" } else { "depth" },
                    if unclipped { "unclipped" } else { "clipped" }
                );
                device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                    label: Some(&label),
                    layout: Some(&pipeline_layout),
                    vertex: wgpu::VertexState {
                        module: &module,
                        entry_point: Some("vs_shadow"),
                        compilation_options: Default::default(),
                        buffers: &[Some(VertexRaw::position_layout())],
                    },
                    primitive: wgpu::PrimitiveState {
                        // `ShadowFaces::Both` (no culling) by default: meshes from
                        // OBJ files need not be closed or consistently wound.
                        cull_mode,
                        unclipped_depth: unclipped,
                        ..Default::default()
                    },
                    depth_stencil: Some(wgpu::DepthStencilState {
                        format: DEPTH_FORMAT,
                        depth_write_enabled: Some(true),
                        // Reversed: greater is closer to the light.
                        depth_compare: Some(if reversed {
                            wgpu::CompareFunction::Greater
                        } else {
                            wgpu::CompareFunction::Less
                        }),
                        stencil: wgpu::StencilState::default(),
                        // The bias is applied in fs_shadow, on linear depth.
                        bias: wgpu::DepthBiasState::default(),
                    }),
                    multisample: wgpu::MultisampleState::default(),
                    fragment: Some(wgpu::FragmentState {
                        module: &module,
                        entry_point: Some("fs_shadow"),
                        compilation_options: Default::default(),
                        targets: &[],
                    }),
                    multiview_mask: None,
                    cache: None,
                })
            })
        });
        Self { pipelines, uniforms, bind_group }
    }

    /// The pipeline for a light; `unclipped` falls back to clipped when
    /// the device cannot do it (the returned flag says which was used).
    pub(crate) fn pipeline(
        &self,
        reversed: bool,
        unclipped: bool,
        cull: Option<wgpu::Face>,
    ) -> (&wgpu::RenderPipeline, bool) {
        let cull = match cull {
            None => 0,
            Some(wgpu::Face::Front) => 1,
            Some(wgpu::Face::Back) => 2,
        };
        let base = cull * 4 + usize::from(reversed) * 2;
        match &self.pipelines[base + usize::from(unclipped)] {
            Some(p) => (p, unclipped),
            None => (self.pipelines[base].as_ref().expect("clipped pipelines always exist"), false),
        }
    }
}

/// The camera and analysis passes: the camera pass and the geometry
/// analysis share the vertex stage; the depth analysis draws one full-screen
/// triangle. The analysis layout adds the camera pass's depth (binding 3)
/// and masks (binding 4). With the SPSM lookup both layouts add the SPSM
/// texels (binding 5) and the shaders use `spsm_lookup.wgsl`'s `in_shadow`.
pub(crate) struct ScenePasses {
    pub(crate) camera_layout: wgpu::BindGroupLayout,
    pub(crate) analysis_layout: wgpu::BindGroupLayout,
    pub(crate) color: wgpu::RenderPipeline,
    pub(crate) color_masks: wgpu::RenderPipeline,
    pub(crate) analysis_geometry: wgpu::RenderPipeline,
    pub(crate) analysis_depth: wgpu::RenderPipeline,
}

impl ScenePasses {
    pub(crate) fn new(device: &wgpu::Device, lookup: &ShadowLookup) -> Self {
        // WGSL has no includes: the shared declarations are prepended.
        let source = |pass: &'static str| -> Cow<'static, str> {
            let common = include_str!("../../shaders/common.wgsl");
            match lookup.spsm() {
                None => Cow::Owned(format!("{}{common}{pass}", include_str!("../../shaders/light_depth.wgsl"))),
                Some(options) => Cow::Owned(super::spsm::scene_source(options, common, pass)),
            }
        };
        let camera_source = source(include_str!("../../shaders/camera.wgsl"));
        let analysis_source = source(include_str!("../../shaders/analysis.wgsl"));
        let camera_module = scene_shader(device, "lixel camera shader", camera_source);
        let analysis_module = scene_shader(device, "lixel analysis shader", analysis_source);
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
        let depth_texture = |binding, view_dimension| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::FRAGMENT,
            ty: wgpu::BindingType::Texture {
                sample_type: wgpu::TextureSampleType::Depth,
                view_dimension,
                multisampled: false,
            },
            count: None,
        };
        let scene_entries = [uniform(0), uniform(1), depth_texture(2, wgpu::TextureViewDimension::D2Array)];
        let spsm_entry = lookup.spsm().map(|_| super::spsm::texels_layout_entry());
        let camera_entries: Vec<_> = scene_entries.iter().copied().chain(spsm_entry).collect();
        let camera_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("lixel camera bind group layout"),
            entries: &camera_entries,
        });
        let analysis_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("lixel analysis bind group layout"),
            entries: &[
                scene_entries[0],
                scene_entries[1],
                scene_entries[2],
                depth_texture(3, wgpu::TextureViewDimension::D2),
                wgpu::BindGroupLayoutEntry {
                    binding: 4,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Uint,
                        view_dimension: wgpu::TextureViewDimension::D2,
                        multisampled: false,
                    },
                    count: None,
                },
            ]
            .into_iter()
            .chain(spsm_entry)
            .collect::<Vec<_>>(),
        });
        let pipeline_layout = |label, layout| {
            device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some(label),
                bind_group_layouts: &[Some(layout)],
                immediate_size: 0,
            })
        };
        let camera_pipeline_layout = pipeline_layout("lixel camera pipeline layout", &camera_layout);
        let analysis_pipeline_layout = pipeline_layout("lixel analysis pipeline layout", &analysis_layout);
        let depth_test = Some(wgpu::DepthStencilState {
            format: DEPTH_FORMAT,
            depth_write_enabled: Some(true),
            depth_compare: Some(wgpu::CompareFunction::Less),
            stencil: wgpu::StencilState::default(),
            bias: wgpu::DepthBiasState::default(),
        });
        let scene_pipeline = |label: &str,
                              layout: &wgpu::PipelineLayout,
                              module: &wgpu::ShaderModule,
                              entry: &str,
                              targets: &[Option<wgpu::ColorTargetState>]| {
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
                depth_stencil: depth_test.clone(),
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
        };
        let color_target = Some(wgpu::ColorTargetState::from(COLOR_FORMAT));
        let masks_target = Some(wgpu::ColorTargetState::from(MASKS_FORMAT));
        let analysis_depth = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("lixel analysis pipeline (camera depth)"),
            layout: Some(&analysis_pipeline_layout),
            vertex: wgpu::VertexState {
                module: &analysis_module,
                entry_point: Some("vs_fullscreen"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive: wgpu::PrimitiveState::default(),
            depth_stencil: None,
            multisample: wgpu::MultisampleState::default(),
            fragment: Some(wgpu::FragmentState {
                module: &analysis_module,
                entry_point: Some("fs_analysis_depth"),
                compilation_options: Default::default(),
                targets: std::slice::from_ref(&masks_target),
            }),
            multiview_mask: None,
            cache: None,
        });
        Self {
            color: scene_pipeline(
                "lixel camera pipeline",
                &camera_pipeline_layout,
                &camera_module,
                "fs_color",
                std::slice::from_ref(&color_target),
            ),
            color_masks: scene_pipeline(
                "lixel camera pipeline with masks",
                &camera_pipeline_layout,
                &camera_module,
                "fs_color_masks",
                &[color_target, masks_target.clone()],
            ),
            analysis_geometry: scene_pipeline(
                "lixel analysis pipeline (geometry)",
                &analysis_pipeline_layout,
                &analysis_module,
                "fs_analysis_geometry",
                &[masks_target],
            ),
            analysis_depth,
            camera_layout,
            analysis_layout,
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

/// Every light's shadow map: one layer each of a depth texture array whose
/// layers are as large as the largest map (each map uses the top-left
/// `width x height` texels of its layer).
pub(crate) struct ShadowMaps {
    pub(crate) texture: wgpu::Texture,
    pub(crate) array_view: wgpu::TextureView,
    pub(crate) layer_views: Vec<wgpu::TextureView>,
    pub(crate) width: u32,
    pub(crate) height: u32,
}

impl ShadowMaps {
    pub(crate) fn new(device: &wgpu::Device, width: u32, height: u32, layers: u32) -> Self {
        let texture = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("lixel shadow maps"),
            size: wgpu::Extent3d { width, height, depth_or_array_layers: layers },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: DEPTH_FORMAT,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT
                | wgpu::TextureUsages::TEXTURE_BINDING
                | wgpu::TextureUsages::COPY_SRC,
            view_formats: &[],
        });
        let array_view = texture.create_view(&wgpu::TextureViewDescriptor {
            label: Some("lixel shadow maps array view"),
            dimension: Some(wgpu::TextureViewDimension::D2Array),
            ..Default::default()
        });
        let layer_views = (0..layers)
            .map(|layer| {
                texture.create_view(&wgpu::TextureViewDescriptor {
                    label: Some(&format!("lixel shadow map layer {layer}")),
                    dimension: Some(wgpu::TextureViewDimension::D2),
                    base_array_layer: layer,
                    array_layer_count: Some(1),
                    ..Default::default()
                })
            })
            .collect();
        Self { texture, array_view, layer_views, width, height }
    }

    pub(crate) fn layers(&self) -> u32 {
        self.layer_views.len() as u32
    }
}
