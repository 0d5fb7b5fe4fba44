//! Shadow lookup modes: how the camera and analysis passes decide that a
//! point is in a light's shadow, together with the map format and the
//! shadow pass that lookup needs.
//!
//! The lookup is a value ([`ShadowLookup`], chosen per frame in
//! [`Frame::lookup`](super::Frame::lookup)) so that a new mode is one
//! variant here, its WGSL files and its map format, while the frame loop,
//! the scheduler and the experiment's counting stay as they are: every mode
//! ends in the same per-light shadow bit (`in_shadow` in its lookup WGSL),
//! which the camera pass writes into the masks and the analysis pass into
//! the readback the optimizer reads. A mode's pipelines and maps are built
//! the first time a frame asks for it. See ARCHITECTURE.md, "Lookup modes".

use std::borrow::Cow;

use super::passes::{storage_entry, AnalysisPass, CameraPass, SceneLayouts, DEPTH_FORMAT, MAX_SHADOW_SLOTS};
use super::sgsm::gpu::{SgsmMaps, SweepPass};
use super::sgsm::{self, SgsmOptions};
use super::spsm::{self, SpsmOptions};
use super::subpixel::AaSamples;
use super::uniforms::{ShadowPassRaw, VertexRaw, SHADOW_SLOT_STRIDE};

/// How the camera and analysis passes look a point up in a light's map.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum ShadowLookup {
    /// The standard hard shadow test: one linear light depth per texel
    /// (`shaders/shadow.wgsl`), compared at the texel the point falls in
    /// (`shaders/lookup_depth_compare.wgsl`).
    #[default]
    DepthCompare,
    /// Sub-pixel shadow maps (Lecocq et al. 2014; see [`spsm`](super::spsm)):
    /// conservatively rasterized maps holding the closest triangle per texel
    /// (`shaders/spsm_pass.wgsl`), looked up with the triangles' planes and
    /// the paper's silhouette recovery (`shaders/spsm_lookup.wgsl`).
    Spsm(SpsmOptions),
    /// Sub-geometry shadow maps (see [`sgsm`](super::sgsm)): SPSM's maps
    /// plus each triangle's slopes, a compute sweep recognising the
    /// triangles at each texel's four corners, and a lookup on the plane
    /// of the one containing the point (`shaders/sgsm_lookup.wgsl`), SPSM's
    /// lookup where the pattern is not recognised.
    Sgsm(SgsmOptions),
    /// Sub-pixel antialiased shadows (Pan et al. 2009; see
    /// [`subpixel`](super::subpixel)): the depth compare's maps and shadow
    /// bit, plus compute passes after the camera pass that give every pixel
    /// an occlusion word and a validity word over the pattern's sub-samples
    /// ([`Renderer::read_occlusion`](super::Renderer::read_occlusion),
    /// [`Renderer::read_validity`](super::Renderer::read_validity)).
    SubPixelAa(AaSamples),
    /// Brute-force supersampling of the standard lookup, the baseline the
    /// antialiased lookup is measured against (see
    /// [`subpixel::supersample`](super::subpixel::supersample)): the depth
    /// compare's maps and bit, plus one more camera pass per sub-sample of
    /// the pattern, jittered to that sub-sample's position, whose shadow
    /// and facing bits are gathered into per-pixel words
    /// ([`Renderer::read_supersampled`](super::Renderer::read_supersampled)).
    Supersampled(AaSamples),
}

impl ShadowLookup {
    /// Every lookup mode (SPSM and SGSM with their default options, the
    /// antialiased lookup and supersampling with each sample count).
    pub const ALL: [ShadowLookup; 9] = [
        ShadowLookup::DepthCompare,
        ShadowLookup::Spsm(SpsmOptions::PAPER),
        ShadowLookup::Sgsm(SgsmOptions::PAPER),
        ShadowLookup::SubPixelAa(AaSamples::X8),
        ShadowLookup::SubPixelAa(AaSamples::X16),
        ShadowLookup::SubPixelAa(AaSamples::X32),
        ShadowLookup::Supersampled(AaSamples::X8),
        ShadowLookup::Supersampled(AaSamples::X16),
        ShadowLookup::Supersampled(AaSamples::X32),
    ];

    /// A short stable name (for file names, CSV and logs).
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::DepthCompare => "depth-compare",
            Self::Spsm(_) => "spsm",
            Self::Sgsm(_) => "sgsm",
            Self::SubPixelAa(AaSamples::X8) => "aa8",
            Self::SubPixelAa(AaSamples::X16) => "aa16",
            Self::SubPixelAa(AaSamples::X32) => "aa32",
            Self::Supersampled(AaSamples::X8) => "ss8",
            Self::Supersampled(AaSamples::X16) => "ss16",
            Self::Supersampled(AaSamples::X32) => "ss32",
        }
    }

    /// Parses [`name`](Self::name) (a mode of [`ALL`](Self::ALL), with its
    /// default options).
    #[must_use]
    pub fn parse(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|l| l.name() == name)
    }

    /// The three parts a mode provides.
    /// Whether this lookup's shadow pass pulls whole triangles (SPSM,
    /// SGSM), so it needs the scene's buffers and edge adjacency bound.
    pub(crate) fn pulls_vertices(self) -> bool {
        self.spec().pulls_vertices
    }

    fn spec(self) -> LookupSpec {
        match self {
            // The antialiased and supersampled modes' bit is the depth
            // compare's; their sub-pixel work runs after the camera pass
            // (subpixel::gpu, subpixel::supersample).
            Self::DepthCompare | Self::SubPixelAa(_) | Self::Supersampled(_) => LookupSpec {
                map_color: None,
                shadow_wgsl: Cow::Borrowed(include_str!("../../shaders/shadow.wgsl")),
                lookup_wgsl: Cow::Borrowed(include_str!("../../shaders/lookup_depth_compare.wgsl")),
                pulls_vertices: false,
                sgsm: None,
            },
            Self::Spsm(options) => LookupSpec {
                map_color: Some(spsm::TEXEL_FORMAT),
                shadow_wgsl: Cow::Owned(spsm::pass_source(&options)),
                lookup_wgsl: Cow::Owned(spsm::lookup_source(&options)),
                pulls_vertices: true,
                sgsm: None,
            },
            Self::Sgsm(options) => LookupSpec {
                map_color: Some(spsm::TEXEL_FORMAT),
                shadow_wgsl: Cow::Owned(sgsm::pass_source(&options)),
                lookup_wgsl: Cow::Owned(sgsm::lookup_source(&options)),
                pulls_vertices: true,
                sgsm: Some(options),
            },
        }
    }
}

/// What a lookup mode adds to the renderer.
struct LookupSpec {
    /// The map format: every mode has a `Depth32Float` array (the shadow
    /// pass's depth test and [`Renderer::read_shadow_map`](super::Renderer::read_shadow_map));
    /// a mode that stores more per texel (e.g. a triangle) names the format
    /// of a colour array written next to it (shadow-pass target 0, bound at
    /// group 1 binding 1 of the camera and analysis passes).
    map_color: Option<wgpu::TextureFormat>,
    /// The shadow pass: `vs_shadow` and `fs_shadow`, after
    /// `shaders/light_depth.wgsl`, reading `ShadowPass` (uniforms.rs) at
    /// group 0 binding 0 with one dynamic-offset slot per map.
    shadow_wgsl: Cow<'static, str>,
    /// The lookup: its group-1 bindings and `fn in_shadow(light: Light,
    /// world: vec3<f32>) -> bool`, together with `shaders/common.wgsl`.
    lookup_wgsl: Cow<'static, str>,
    /// The shadow pass pulls whole triangles itself: no vertex buffer, the
    /// scene's vertex words and indices as read-only storage buffers at
    /// group 0 bindings 1 and 2, non-indexed draws whose `vertex_index` is
    /// the index slot, no face culling (conservative rasterization).
    pulls_vertices: bool,
    /// SGSM: a second shadow-pass target (the slopes), the sweep after the
    /// shadow passes, its mask array at group 1 binding 2 and, when
    /// counting, the path counters at binding 3.
    sgsm: Option<SgsmOptions>,
}

/// Whether a shadow pass clips depth at the light's near and far planes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum DepthClip {
    /// The usual clipping (and the only mode without `DEPTH_CLIP_CONTROL`).
    Clipped,
    /// Casters nearer than the near plane rasterize, clamped to depth 0.
    Unclipped,
}

/// One lookup mode's pipelines and maps.
pub(crate) struct LookupState {
    pub(crate) lookup: ShadowLookup,
    pub(crate) shadow: ShadowPass,
    pub(crate) camera: CameraPass,
    pub(crate) analysis: AnalysisPass,
    maps_layout: wgpu::BindGroupLayout,
    map_color: Option<wgpu::TextureFormat>,
    pub(crate) maps: ShadowMaps,
    /// See [`LookupSpec::pulls_vertices`].
    pub(crate) pulls_vertices: bool,
    /// The SGSM sweep (and counters), for that mode.
    pub(crate) sweep: Option<SweepPass>,
}

impl LookupState {
    pub(crate) fn new(
        device: &wgpu::Device,
        lookup: ShadowLookup,
        layouts: &SceneLayouts,
        unclipped_available: bool,
        hardware_conservative: bool,
        pulled: Option<(&wgpu::Buffer, &wgpu::Buffer, &wgpu::Buffer)>,
    ) -> Self {
        let spec = lookup.spec();
        let hardware_conservative = hardware_conservative && spec.pulls_vertices;
        // Depth bound as unfilterable float: naga cannot translate
        // `textureLoad` from a `texture_depth_*` to GLSL (the GL backend).
        let mut entries = vec![map_entry(0, wgpu::TextureSampleType::Float { filterable: false })];
        if let Some(format) = spec.map_color {
            let sample_type = format.sample_type(None, None).unwrap_or(wgpu::TextureSampleType::Uint);
            entries.push(map_entry(1, sample_type));
        }
        if spec.pulls_vertices {
            // SPSM's centre-sampled depths (CentreDepths), read by the lookup.
            entries.push(storage_entry(4, wgpu::ShaderStages::FRAGMENT, true, false));
        }
        let sweep = spec.sgsm.map(|options| SweepPass::new(device, &options));
        if let Some(sweep) = &sweep {
            entries.push(map_entry(2, wgpu::TextureSampleType::Uint));
            if sweep.counters.is_some() {
                entries.push(storage_entry(3, wgpu::ShaderStages::FRAGMENT, false, false));
            }
        }
        let maps_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some(&format!("lixel {} maps layout", lookup.name())),
            entries: &entries,
        });
        let scene_source = |pass: &str| {
            // WGSL has no includes: the shared declarations are prepended.
            let source = format!(
                "{}{}{}{pass}",
                include_str!("../../shaders/light_depth.wgsl"),
                include_str!("../../shaders/common.wgsl"),
                &spec.lookup_wgsl
            );
            wgpu::ShaderSource::Wgsl(Cow::Owned(source))
        };
        let module = |label: String, source| {
            device.create_shader_module(wgpu::ShaderModuleDescriptor { label: Some(&label), source })
        };
        let camera_module = module(
            format!("lixel camera shader ({})", lookup.name()),
            scene_source(include_str!("../../shaders/camera.wgsl")),
        );
        let analysis_module = module(
            format!("lixel analysis shader ({})", lookup.name()),
            scene_source(include_str!("../../shaders/analysis.wgsl")),
        );
        // spsm_pass.wgsl's vertex stage emits the true triangle when the
        // rasterizer is conservative (unused by the other passes).
        let shadow_source = format!(
            "const SPSM_HARDWARE_CONSERVATIVE: bool = {hardware_conservative};\n{}{}",
            include_str!("../../shaders/light_depth.wgsl"),
            &spec.shadow_wgsl
        );
        let shadow_module = module(
            format!("lixel shadow shader ({})", lookup.name()),
            wgpu::ShaderSource::Wgsl(Cow::Owned(shadow_source)),
        );
        let shadow = ShadowPass::new(
            device,
            &shadow_module,
            spec.map_color,
            sweep.is_some(),
            unclipped_available,
            hardware_conservative,
            pulled.filter(|_| spec.pulls_vertices),
        );
        let maps_spec = MapsSpec {
            layout: &maps_layout,
            color: spec.map_color,
            sweep: sweep.as_ref(),
            centre: shadow.centre_layout.as_ref(),
        };
        let maps = ShadowMaps::new(device, &maps_spec, 1, 1, 1);
        Self {
            lookup,
            shadow,
            camera: CameraPass::new(device, &layouts.camera, &maps_layout, &camera_module),
            analysis: AnalysisPass::new(device, &layouts.analysis, &maps_layout, &analysis_module),
            maps,
            maps_layout,
            map_color: spec.map_color,
            pulls_vertices: spec.pulls_vertices,
            sweep,
        }
    }

    /// Replaces the maps by the smallest; frames grow them again on demand.
    pub(crate) fn release_maps(&mut self, device: &wgpu::Device) {
        self.maps = ShadowMaps::new(device, &self.maps_spec(), 1, 1, 1);
    }

    /// What the maps are built with.
    fn maps_spec(&self) -> MapsSpec<'_> {
        MapsSpec {
            layout: &self.maps_layout,
            color: self.map_color,
            sweep: self.sweep.as_ref(),
            centre: self.shadow.centre_layout.as_ref(),
        }
    }

    /// Builds the view-capture pipelines of this mode's camera shader.
    pub(crate) fn ensure_deferred(&mut self, device: &wgpu::Device, layouts: &SceneLayouts) {
        self.camera.deferred(device, layouts, &self.maps_layout);
    }

    /// Grows the maps to hold `layers` maps of up to `width x height`.
    pub(crate) fn ensure_maps(&mut self, device: &wgpu::Device, width: u32, height: u32, layers: u32) {
        let maps = &self.maps;
        if width > maps.width || height > maps.height || layers > maps.layers() {
            self.maps = ShadowMaps::new(
                device,
                &self.maps_spec(),
                width.max(maps.width),
                height.max(maps.height),
                layers.max(maps.layers()),
            );
        }
    }
}

fn map_entry(binding: u32, sample_type: wgpu::TextureSampleType) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::FRAGMENT,
        ty: wgpu::BindingType::Texture {
            sample_type,
            view_dimension: wgpu::TextureViewDimension::D2Array,
            multisampled: false,
        },
        count: None,
    }
}

/// The shadow pass of one lookup mode: six pipelines (depth clipped or
/// unclipped x faces culled: none, front, back) sharing one uniform buffer
/// with a slot per map.
pub(crate) struct ShadowPass {
    /// Indexed by `cull * 2 + unclipped` (`cull`: 0 none, 1 front, 2 back);
    /// `None` for unclipped variants when the device lacks
    /// `DEPTH_CLIP_CONTROL`.
    pipelines: [Option<wgpu::RenderPipeline>; 6],
    pub(crate) uniforms: wgpu::Buffer,
    pub(crate) bind_group: wgpu::BindGroup,
    /// SPSM and SGSM: group 1 of the pass, the centre-sampled depths
    /// ([`CentreDepths`]) at a dynamic offset per map.
    pub(crate) centre_layout: Option<wgpu::BindGroupLayout>,
}

impl ShadowPass {
    fn new(
        device: &wgpu::Device,
        module: &wgpu::ShaderModule,
        map_color: Option<wgpu::TextureFormat>,
        sgsm_slopes: bool,
        unclipped_available: bool,
        conservative: bool,
        pulled: Option<(&wgpu::Buffer, &wgpu::Buffer, &wgpu::Buffer)>,
    ) -> Self {
        let storage = |binding| storage_entry(binding, wgpu::ShaderStages::VERTEX, true, false);
        let mut layout_entries = vec![wgpu::BindGroupLayoutEntry {
            binding: 0,
            visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: true,
                min_binding_size: wgpu::BufferSize::new(std::mem::size_of::<ShadowPassRaw>() as u64),
            },
            count: None,
        }];
        if pulled.is_some() {
            layout_entries.extend([storage(1), storage(2), storage(3)]);
        }
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("lixel shadow bind group layout"),
            entries: &layout_entries,
        });
        let centre_layout = pulled.is_some().then(|| {
            device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("lixel spsm centre depths layout"),
                entries: &[storage_entry(0, wgpu::ShaderStages::FRAGMENT, false, true)],
            })
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("lixel shadow pipeline layout"),
            bind_group_layouts: &[Some(&layout), centre_layout.as_ref()],
            immediate_size: 0,
        });
        let uniforms = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("lixel shadow pass uniforms"),
            size: SHADOW_SLOT_STRIDE * MAX_SHADOW_SLOTS as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut entries = vec![wgpu::BindGroupEntry {
            binding: 0,
            resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                buffer: &uniforms,
                offset: 0,
                size: wgpu::BufferSize::new(std::mem::size_of::<ShadowPassRaw>() as u64),
            }),
        }];
        if let Some((vertices, indices, adjacent)) = pulled {
            entries.push(wgpu::BindGroupEntry { binding: 1, resource: vertices.as_entire_binding() });
            entries.push(wgpu::BindGroupEntry { binding: 2, resource: indices.as_entire_binding() });
            entries.push(wgpu::BindGroupEntry { binding: 3, resource: adjacent.as_entire_binding() });
        }
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("lixel shadow bind group"),
            layout: &layout,
            entries: &entries,
        });
        let vertex_buffers = [Some(VertexRaw::position_layout())];
        let vertex_buffers: &[Option<wgpu::VertexBufferLayout<'_>>] =
            if pulled.is_some() { &[] } else { &vertex_buffers };
        let targets = [map_color.map(wgpu::ColorTargetState::from), Some(sgsm::gpu::NORMAL_FORMAT.into())];
        let targets: &[Option<wgpu::ColorTargetState>] = match (map_color.is_some(), sgsm_slopes) {
            (true, true) => &targets,
            (true, false) => &targets[..1],
            (false, _) => &[],
        };
        let pipelines = std::array::from_fn(|k| {
            let (cull, unclipped) = (k / 2, k % 2 == 1);
            let cull_mode = [None, Some(wgpu::Face::Front), Some(wgpu::Face::Back)][cull];
            (!unclipped || unclipped_available).then(|| {
                let clip = if unclipped { "unclipped" } else { "clipped" };
                device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                    label: Some(&format!("lixel shadow pipeline ({clip}, cull {cull_mode:?})")),
                    layout: Some(&pipeline_layout),
                    vertex: wgpu::VertexState {
                        module,
                        entry_point: Some("vs_shadow"),
                        compilation_options: Default::default(),
                        buffers: vertex_buffers,
                    },
                    primitive: wgpu::PrimitiveState {
                        // `ShadowFaces::Both` (no culling) by default: meshes from
                        // OBJ files need not be closed or consistently wound.
                        cull_mode,
                        unclipped_depth: unclipped,
                        conservative,
                        ..Default::default()
                    },
                    depth_stencil: Some(wgpu::DepthStencilState {
                        format: DEPTH_FORMAT,
                        depth_write_enabled: Some(true),
                        // Linear light depth grows away from the light for
                        // every matrix, so the ordinary test always applies.
                        depth_compare: Some(wgpu::CompareFunction::Less),
                        stencil: wgpu::StencilState::default(),
                        // The bias is applied in fs_shadow, on linear depth.
                        bias: wgpu::DepthBiasState::default(),
                    }),
                    multisample: wgpu::MultisampleState::default(),
                    fragment: Some(wgpu::FragmentState {
                        module,
                        entry_point: Some("fs_shadow"),
                        compilation_options: Default::default(),
                        targets,
                    }),
                    multiview_mask: None,
                    cache: None,
                })
            })
        });
        Self { pipelines, uniforms, bind_group, centre_layout }
    }

    /// The pipeline for a map; unclipped depth falls back to clipped when
    /// the device cannot do it (the returned value says which was used).
    pub(crate) fn pipeline(&self, clip: DepthClip, cull: Option<wgpu::Face>) -> (&wgpu::RenderPipeline, DepthClip) {
        let cull = match cull {
            None => 0,
            Some(wgpu::Face::Front) => 1,
            Some(wgpu::Face::Back) => 2,
        };
        let clipped = self.pipelines[cull * 2].as_ref().expect("clipped pipelines always exist");
        match (clip, &self.pipelines[cull * 2 + 1]) {
            (DepthClip::Unclipped, Some(p)) => (p, DepthClip::Unclipped),
            _ => (clipped, DepthClip::Clipped),
        }
    }
}

/// Every map of one frame: one layer each of a depth texture array (plus
/// the mode's colour array, if any) whose layers are as large as the
/// largest map (each map uses the top-left `width x height` texels of its
/// layer), and the group-1 bind group of the camera and analysis passes.
pub(crate) struct ShadowMaps {
    pub(crate) depth_array: wgpu::TextureView,
    /// The mode's colour array, if any.
    pub(crate) color: Option<wgpu::Texture>,
    pub(crate) depth_layers: Vec<wgpu::TextureView>,
    pub(crate) color_layers: Vec<wgpu::TextureView>,
    /// SGSM's slopes and masks.
    pub(crate) sgsm: Option<SgsmMaps>,
    /// SPSM and SGSM: the centre-sampled depths.
    pub(crate) centre: Option<CentreDepths>,
    pub(crate) bind_group: wgpu::BindGroup,
    pub(crate) width: u32,
    pub(crate) height: u32,
    /// What each layer holds (`reuse.rs`).
    pub(crate) drawn: super::reuse::MapRecords,
}

impl ShadowMaps {
    fn new(device: &wgpu::Device, spec: &MapsSpec<'_>, width: u32, height: u32, layers: u32) -> Self {
        let MapsSpec { layout, color, sweep, centre } = *spec;
        // At least two layers and never six: the GL backend makes a one-layer
        // texture a plain 2D texture and a six-layer one a cube map, which
        // then read wrongly through the array view (six lights' masks were
        // all shadow).
        let layers = match layers.max(2) {
            6 => 7,
            n => n,
        };
        let array = |label: &str, format| {
            let texture = device.create_texture(&wgpu::TextureDescriptor {
                label: Some(label),
                size: wgpu::Extent3d { width, height, depth_or_array_layers: layers },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage: wgpu::TextureUsages::RENDER_ATTACHMENT
                    | wgpu::TextureUsages::TEXTURE_BINDING
                    | wgpu::TextureUsages::COPY_SRC,
                view_formats: &[],
            });
            let array_view = texture.create_view(&wgpu::TextureViewDescriptor {
                label: Some(&format!("{label} array view")),
                dimension: Some(wgpu::TextureViewDimension::D2Array),
                ..Default::default()
            });
            let layer_views = (0..layers)
                .map(|layer| {
                    texture.create_view(&wgpu::TextureViewDescriptor {
                        label: Some(&format!("{label} layer {layer}")),
                        dimension: Some(wgpu::TextureViewDimension::D2),
                        base_array_layer: layer,
                        array_layer_count: Some(1),
                        ..Default::default()
                    })
                })
                .collect::<Vec<_>>();
            (texture, array_view, layer_views)
        };
        let (_, depth_array, depth_layers) = array("lixel shadow maps", DEPTH_FORMAT);
        let color = color.map(|format| array("lixel shadow map words", format));
        let mut entries =
            vec![wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(&depth_array) }];
        if let Some((_, view, _)) = &color {
            entries.push(wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::TextureView(view) });
        }
        let sgsm = sweep.zip(color.as_ref()).map(|(s, (_, view, _))| s.maps(device, view, width, height, layers));
        if let Some(maps) = &sgsm {
            entries.push(wgpu::BindGroupEntry {
                binding: 2,
                resource: wgpu::BindingResource::TextureView(&maps.masks_view),
            });
        }
        if let Some(counters) = sweep.and_then(|s| s.counters.as_ref()) {
            entries.push(wgpu::BindGroupEntry { binding: 3, resource: counters.as_entire_binding() });
        }
        let centre = centre.map(|pass_layout| CentreDepths::new(device, pass_layout, width, height, layers));
        if let Some(c) = &centre {
            entries.push(wgpu::BindGroupEntry { binding: 4, resource: c.buffer.as_entire_binding() });
        }
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("lixel shadow maps bind group"),
            layout,
            entries: &entries,
        });
        let (color, color_layers) = match color {
            Some((texture, _, layers)) => (Some(texture), layers),
            None => (None, Vec::new()),
        };
        Self {
            depth_array,
            color,
            depth_layers,
            color_layers,
            sgsm,
            centre,
            bind_group,
            width,
            height,
            drawn: Default::default(),
        }
    }

    pub(crate) fn layers(&self) -> u32 {
        self.depth_layers.len() as u32
    }
}

/// What [`ShadowMaps::new`] builds besides the depth array.
#[derive(Clone, Copy)]
struct MapsSpec<'a> {
    /// The camera and analysis passes' group-1 layout.
    layout: &'a wgpu::BindGroupLayout,
    /// [`LookupSpec::map_color`].
    color: Option<wgpu::TextureFormat>,
    sweep: Option<&'a SweepPass>,
    /// [`ShadowPass::centre_layout`].
    centre: Option<&'a wgpu::BindGroupLayout>,
}

/// SPSM's centre-sampled depths (issue 16, session 5): per texel, the
/// depth a standard shadow pass would store (`spsm_store_centre` in
/// `shaders/spsm_pass.wgsl`, an atomic per covering fragment), which the
/// lookup falls back to where its own silhouette recovery is unsure. One
/// block of [`stride`](Self::stride) bytes per layer; the pass binds its
/// map's block at a dynamic offset, the lookup the whole buffer.
pub(crate) struct CentreDepths {
    pub(crate) buffer: wgpu::Buffer,
    pub(crate) pass_bind_group: wgpu::BindGroup,
    /// Bytes per layer: the layer's texel count times 4, rounded up to the
    /// 256-byte storage offset alignment.
    pub(crate) stride: u64,
}

impl CentreDepths {
    fn new(device: &wgpu::Device, pass_layout: &wgpu::BindGroupLayout, width: u32, height: u32, layers: u32) -> Self {
        let stride = (u64::from(width) * u64::from(height) * 4).div_ceil(256) * 256;
        let limits = device.limits();
        let wanted = stride * u64::from(layers);
        // Beyond the device's limits a 256-byte buffer stands in: the pass
        // writes nothing into it (a map has more texels) and the lookup sees
        // it too small and keeps SPSM's own verdicts (spsm_standard).
        let fits = wanted <= limits.max_storage_buffer_binding_size && wanted <= limits.max_buffer_size;
        let (size, stride) = if fits { (wanted, stride) } else { (256, 0) };
        let buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("lixel spsm centre depths"),
            size,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let pass_bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("lixel spsm centre depths (pass)"),
            layout: pass_layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                    buffer: &buffer,
                    offset: 0,
                    size: wgpu::BufferSize::new(if fits { stride } else { 256 }),
                }),
            }],
        });
        Self { buffer, pass_bind_group, stride }
    }
}
