//! A wgpu renderer for lixel's light matrices (feature `render`).
//!
//! One frame ([`Renderer::render`]) is, in order:
//!
//! 1. **Shadow passes** (`shaders/shadow.wgsl` for the default
//!    [`ShadowLookup`]): one per light, into one layer each of a
//!    `Depth32Float` array (plus the lookup mode's own per-texel data, if
//!    any); each map is sized by its [`LightMatrix::map_size`], storing
//!    *linear* light depth (distance along the light's rays, normalized to
//!    [`LightMatrix::light_distance`]), which grows away from the light for
//!    every matrix, so the ordinary depth test serves all of them; with
//!    unclipped depth when [`LightMatrix::needs_unclipped_depth`] is set and the device has
//!    `DEPTH_CLIP_CONTROL`. Bias: [`ShadowBias`], the same for every method.
//! 2. **Camera pass** (`shaders/camera.wgsl`): the camera's view with hard
//!    shadows of up to 32 lights (points outside a map count as lit), looked
//!    up as [`Frame::lookup`] says;
//!    optionally the full-resolution per-pixel masks (depth, one shadow bit
//!    and one light-facing bit per light, normal) for the experiments.
//! 3. **Analysis pass** (`shaders/analysis.wgsl`, when asked for): the same
//!    view at low resolution (180x180 by default) writing only the masks,
//!    optionally looked up in a different set of maps (the periodic focused
//!    analysis of the paper's section 2.4), copied into a [`ReadbackRing`]
//!    slot. By default ([`AnalysisSource::CameraDepth`]) it is a full-screen
//!    pass over the camera pass's depth buffer, so the scene is drawn only
//!    once per frame; [`AnalysisSource::Geometry`] draws it again.
//!    [`Renderer::try_take_analysis`] hands it back frames later without
//!    ever waiting; when every slot is in flight the frame skips its analysis
//!    instead of stalling.
//!
//! GPU timestamps of the three stages come back the same way
//! ([`Renderer::try_take_gpu_times`]) when the device has `TIMESTAMP_QUERY`.
//!
//! The renderer takes a `&wgpu::Device` and `&wgpu::Queue`; choosing an
//! adapter, windows and files are the application's business.
//! [`Renderer::optional_features`] lists the features worth requesting.

mod analysis;
mod capture;
mod cascade_loop;
mod culling;
mod depth_copy;
pub mod device;
mod encode;
mod frame_loop;
mod lookup;
mod options;
mod output;
pub(crate) mod passes;
pub mod readback;
mod reuse;
pub mod sgsm;
pub mod spsm;
pub mod subpixel;
mod timing;
mod uniforms;

use std::time::Instant;

use glam::Vec3;
use wgpu::util::DeviceExt;

use crate::mesh::{MeshError, Scene};
use crate::{Camera, LightMatrix};

pub use analysis::{AnalysisMeta, AnalysisReadback};
pub use cascade_loop::{sun_bits, CascadeMatrices, CascadePolicy, SplitPlacement};
pub use device::Gpu;
pub use frame_loop::{
    FirstFrame, LoopError, LoopFrame, LoopOptions, LoopPolicy, LoopView, ReadbackInfo, Settled, ShadowLoop,
};
pub use lookup::ShadowLookup;
pub use options::{AnalysisSource, RendererOptions, ShadowBias, ShadowFaces};
pub use output::{masks_image, shadow_map_image, DepthImage};
pub use readback::{Readback, ReadbackLatency, ReadbackRing, RingStats};
pub use sgsm::{SgsmCounts, SgsmOptions};
pub use spsm::{SpsmOptions, StandardFallback};
pub use timing::GpuFrameTimes;
pub use uniforms::MAX_LIGHTS;

use encode::CameraOutput;
use lookup::LookupState;
use passes::{CameraTargets, SceneLayouts, Target, MASKS_FORMAT, MAX_SHADOW_SLOTS};
use timing::GpuTimer;
use uniforms::{CameraRaw, LightRaw, LightsRaw, ShadowPassRaw, VertexRaw};

/// The next `f32` above a finite `x`.
/// What a frame's full-resolution masks were rendered for
/// ([`Renderer::has_masks_of`]).
#[derive(Clone, Debug, PartialEq)]
struct MasksKey {
    camera: Camera,
    lights: Vec<LightMatrix>,
    lookup: ShadowLookup,
    cascades: Vec<Option<CascadeSlot>>,
}

/// Light slot of a cascade ([`Renderer::set_cascades`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct CascadeSlot {
    /// View depths where its mask bits apply, `[start, end)`.
    pub(crate) owned: (f32, f32),
    /// Weight ramps: (fade-in start, fade-in end, fade-out start, fade-out end).
    pub(crate) ramps: [f32; 4],
    /// The sun's first cascade.
    pub(crate) first: bool,
}

/// Why the renderer refused a request.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RenderError {
    /// More lights than the 32 bits of the shadow masks.
    #[error("{count} lights requested; at most {MAX_LIGHTS} are supported")]
    TooManyLights {
        /// Lights requested.
        count: usize,
    },
    /// A shadow map is empty or larger than the device allows.
    #[error("light {light}: shadow map {width}x{height} outside 1..={max} texels per side")]
    BadMapSize {
        /// Index of the light.
        light: usize,
        /// Requested width.
        width: u32,
        /// Requested height.
        height: u32,
        /// The device's `max_texture_dimension_2d`.
        max: u32,
    },
    /// A light matrix holds NaN or infinity.
    #[error("light {light}: non-finite light matrix")]
    NonFiniteMatrix {
        /// Index of the light.
        light: usize,
    },
    /// The camera's viewport or the analysis size exceeds the device's limit.
    #[error("target {width}x{height} exceeds the device limit {max}")]
    TargetTooLarge {
        /// Requested width.
        width: u32,
        /// Requested height.
        height: u32,
        /// The device's `max_texture_dimension_2d`.
        max: u32,
    },
    /// The scene cannot be uploaded.
    #[error("invalid scene: {0}")]
    Scene(#[from] MeshError),
    /// Something was read back before any frame was rendered.
    #[error("nothing rendered yet")]
    NothingRendered,
    /// A light index past the last frame's lights.
    #[error("no light {light} in the last frame ({count} lights)")]
    NoSuchLight {
        /// Requested index.
        light: usize,
        /// Lights of the last frame.
        count: usize,
    },
    /// Mapping a buffer for a blocking read failed.
    #[error("buffer mapping failed: {0}")]
    Map(#[from] wgpu::BufferAsyncError),
    /// Waiting for the device failed (device lost, timeout).
    #[error("device poll failed: {0}")]
    Poll(#[from] wgpu::PollError),
    /// No backend offered an adapter ([`Gpu::open`]).
    #[error(
        "no GPU adapter ({tried}); install mesa-vulkan-drivers (Vulkan through lavapipe) or libegl-mesa0 (GL through \
         llvmpipe)"
    )]
    NoAdapter {
        /// Each backend tried and why it failed.
        tried: String,
    },
    /// The device reported a validation, out-of-memory or internal error.
    #[error("{pass} failed on {backend} adapter {adapter:?}: {message}{}", hint.map(|h| format!(" (hint: {h})")).unwrap_or_default())]
    Device {
        /// The wgpu backend (`vulkan`, `gl`, ...).
        backend: String,
        /// The adapter's name.
        adapter: String,
        /// What the renderer was doing.
        pass: &'static str,
        /// wgpu's description of the error.
        message: String,
        /// What might help, where known.
        hint: Option<&'static str>,
    },
}

/// An analysis pass to render this frame.
#[derive(Clone, Copy, Debug, Default)]
pub struct AnalysisRequest<'a> {
    /// Maps to look shadows up in; `None`: the frame's own. The paper
    /// periodically uses standard (focused) maps here so that shadows that
    /// moved into view are not missed by maps optimized for the old view.
    /// A matrix equal to the frame's light of the same index reuses that
    /// light's map; only the others cost a shadow pass.
    pub lights: Option<&'a [LightMatrix]>,
    /// A number handed back with the readback (e.g. which maps were used).
    pub tag: u32,
}

/// What to render in one frame.
#[derive(Clone, Copy, Debug)]
pub struct Frame<'a> {
    /// The viewer; its viewport is the camera pass's resolution.
    pub camera: &'a Camera,
    /// One shadow map per light (at most [`MAX_LIGHTS`]).
    pub lights: &'a [LightMatrix],
    /// Also write the full-resolution masks ([`Renderer::read_masks`]).
    pub masks: bool,
    /// Render the low-resolution analysis pass and queue its readback.
    pub analysis: Option<AnalysisRequest<'a>>,
    /// How the camera and analysis passes look shadows up (and so which
    /// maps the shadow passes write).
    pub lookup: ShadowLookup,
}

impl<'a> Frame<'a> {
    /// A frame of `lights` seen by `camera` with the default lookup, no
    /// full-resolution masks and no analysis pass.
    #[must_use]
    pub fn new(camera: &'a Camera, lights: &'a [LightMatrix]) -> Self {
        Self { camera, lights, masks: false, analysis: None, lookup: ShadowLookup::default() }
    }
}

/// What [`Renderer::render`] did.
#[derive(Clone, Debug)]
pub struct FrameReport {
    /// Index of the frame (0, 1, 2, ...).
    pub frame: u64,
    /// The queue submission of the frame.
    pub submission: wgpu::SubmissionIndex,
    /// An analysis pass was requested but every readback slot was in
    /// flight, so it was skipped (the frame did not wait).
    pub analysis_skipped: bool,
    /// An analysis readback was queued.
    pub analysis_queued: bool,
    /// Lights that needed unclipped depth the device could not provide.
    pub unclipped_unavailable: u32,
    /// Shadow passes rendered: one per light, plus one per analysis matrix
    /// that differs from the frame's light of the same index.
    pub shadow_passes: u32,
    /// Triangles drawn by the shadow passes, all together (fewer than
    /// `shadow_passes` x the scene's when objects were culled).
    pub shadow_triangles: u64,
    /// Triangles drawn by the camera pass.
    pub camera_triangles: u64,
    /// Shadow passes skipped because their layer already held their map
    /// ([`RendererOptions::reuse_maps`]); not counted in `shadow_passes`.
    pub maps_reused: u32,
    /// CPU time spent encoding and submitting.
    pub cpu_time: std::time::Duration,
}

/// The scene on the GPU.
struct GpuScene {
    vertices: wgpu::Buffer,
    /// The vertices' positions alone, tightly packed (12 bytes a vertex):
    /// the depth-only shadow passes read nothing else, and a lean stream
    /// costs a software rasterizer's vertex fetch less than every third
    /// float of [`VertexRaw`].
    positions: wgpu::Buffer,
    indices: wgpu::Buffer,
    /// Per index slot, the slot of the vertex across the edge starting at
    /// that corner (`spsm::adjacency`), for the SPSM pass's silhouette edges;
    /// built with the first lookup that pulls vertices
    /// ([`Renderer::pulled_scene`]), so other renderers never pay for it.
    adjacent: Option<wgpu::Buffer>,
    /// Each object's index slots and vertices, in upload order (edges are
    /// matched within an object).
    object_slots: Vec<(std::ops::Range<u32>, std::ops::Range<u32>)>,
    index_count: u32,
    /// Per-object index ranges and bounds, for culling.
    objects: Vec<culling::ObjectBounds>,
}

/// The camera pass's lights and its group-0 bind group.
struct CameraBindings {
    lights: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
}

/// A frame's shadow maps: the frame's lights, then the analysis pass's own.
struct MapSlots<'f> {
    /// The matrix of each slot (array layer).
    maps: Vec<&'f LightMatrix>,
    /// The layer of each analysis light.
    analysis_layers: Vec<u32>,
    /// Index into [`Renderer::lookups`].
    lookup: usize,
}

/// Shadows for many lights, a camera pass and asynchronous low-resolution
/// readback. See the [module docs](self).
pub struct Renderer {
    device: wgpu::Device,
    queue: wgpu::Queue,
    options: RendererOptions,
    max_texture: u32,
    unclipped_available: bool,
    /// SPSM and SGSM passes use the rasterizer's conservative mode
    /// ([`RendererOptions::hardware_conservative`] and the device has it).
    hardware_conservative: bool,
    scene: GpuScene,
    layouts: SceneLayouts,
    /// Pipelines and maps of each lookup mode used so far.
    lookups: Vec<LookupState>,
    camera_uniforms: wgpu::Buffer,
    camera_bindings: CameraBindings,
    analysis_lights: wgpu::Buffer,
    /// Refers to the camera targets; `None` after they changed.
    analysis_bind_group: Option<wgpu::BindGroup>,
    camera_targets: Option<CameraTargets>,
    analysis_masks: Target,
    /// Depth buffer of [`AnalysisSource::Geometry`].
    analysis_depth: Option<Target>,
    ring: ReadbackRing<AnalysisMeta>,
    timer: Option<GpuTimer>,
    /// Device errors no scope caught (wgpu would otherwise panic).
    errors: device::DeviceErrors,
    /// Built on the first [`Renderer::read_shadow_map`].
    depth_copy: std::sync::OnceLock<depth_copy::DepthCopy>,
    frame: u64,
    /// Lights of the last frame (for reading maps back).
    last_lights: Vec<LightMatrix>,
    /// The lookup mode of the last frame (index into `lookups`).
    last_lookup: Option<usize>,
    /// What the last frame's full-resolution masks were rendered for, when
    /// it wrote them ([`Renderer::has_masks_of`]).
    last_masks: Option<MasksKey>,
    /// Light `i` is a cascade when `cascades[i]` is set
    /// ([`Renderer::set_cascades`]).
    cascades: Vec<Option<CascadeSlot>>,
    /// The antialiased lookup's passes, built on its first frame (from the
    /// scene buffers read back) with blocker bias `aa_bias` (world units).
    aa: Option<subpixel::gpu::AaPass>,
    aa_bias: f32,
    /// The supersampled mode's gather pass, built on its first frame.
    ss: Option<subpixel::supersample::SupersamplePass>,
    /// The view drawn once by [`Renderer::capture_view`].
    capture: Option<capture::ViewCapture>,
}

impl std::fmt::Debug for Renderer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Renderer")
            .field("options", &self.options)
            .field("frame", &self.frame)
            .field("triangles", &(self.scene.index_count / 3))
            .field("unclipped_available", &self.unclipped_available)
            .field("hardware_conservative", &self.hardware_conservative)
            .field("timestamps", &self.timer.is_some())
            .field("ring", &self.ring)
            .finish_non_exhaustive()
    }
}

impl Renderer {
    /// Features the renderer uses when the device has them:
    /// `DEPTH_CLIP_CONTROL` (unclipped depth) and `TIMESTAMP_QUERY`.
    #[must_use]
    pub fn optional_features() -> wgpu::Features {
        wgpu::Features::DEPTH_CLIP_CONTROL
            | wgpu::Features::TIMESTAMP_QUERY
            | wgpu::Features::CONSERVATIVE_RASTERIZATION
    }

    /// Uploads `scene` and builds the pipelines.
    ///
    /// # Errors
    /// [`RenderError::Scene`] for an invalid or empty scene;
    /// [`RenderError::TargetTooLarge`] for an analysis size past the device
    /// limit.
    pub fn new(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        scene: &Scene,
        options: RendererOptions,
    ) -> Result<Self, RenderError> {
        scene.validate()?;
        let errors = device::DeviceErrors::install(device);
        let max_texture = device.limits().max_texture_dimension_2d;
        let (aw, ah) = options.analysis_size;
        check_target(aw, ah, max_texture)?;
        let features = device.features();
        let unclipped_available = features.contains(wgpu::Features::DEPTH_CLIP_CONTROL);
        let hardware_conservative =
            options.hardware_conservative && features.contains(wgpu::Features::CONSERVATIVE_RASTERIZATION);
        let timer = (options.timestamps && features.contains(wgpu::Features::TIMESTAMP_QUERY))
            .then(|| GpuTimer::new(device, queue));

        let mut vertices = Vec::with_capacity(scene.vertex_count());
        let mut indices = Vec::with_capacity(3 * scene.triangle_count());
        let mut object_slots = Vec::with_capacity(scene.objects.len());
        let mut objects = Vec::with_capacity(scene.objects.len());
        for object in &scene.objects {
            let base = vertices.len() as u32;
            let first = indices.len() as u32;
            let count = object.mesh.indices.len() as u32;
            objects.extend(culling::ObjectBounds::new(
                first..first + count,
                object.mesh.positions.iter().map(|p| p.as_dvec3()),
            ));
            let albedo = (object.albedo.clamp(Vec3::ZERO, Vec3::ONE) * 255.0).round().as_uvec3();
            let albedo = [albedo.x as u8, albedo.y as u8, albedo.z as u8, 255];
            vertices.extend(object.mesh.positions.iter().zip(&object.mesh.normals).map(|(p, n)| VertexRaw {
                position: p.to_array(),
                normal: n.to_array(),
                albedo,
            }));
            indices.extend(object.mesh.indices.iter().map(|i| i + base));
            object_slots.push((first..first + count, base..base + object.mesh.positions.len() as u32));
        }
        let aa_bias = (1e-4
            * scene
                .objects
                .iter()
                .filter_map(|o| o.mesh.bounds())
                .reduce(|a, b| a.union(&b))
                .map_or(1.0, |b| b.diagonal())) as f32;
        let gpu_scene = device::capture(device, "scene upload", || GpuScene {
            vertices: device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("lixel scene vertices"),
                contents: bytemuck::cast_slice(&vertices),
                // Storage: the SPSM pass pulls whole triangles; copy: the
                // antialiased lookup reads the positions back once.
                usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            }),
            positions: device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("lixel scene positions"),
                contents: bytemuck::cast_slice(&vertices.iter().map(|v| v.position).collect::<Vec<_>>()),
                usage: wgpu::BufferUsages::VERTEX,
            }),
            indices: device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("lixel scene indices"),
                contents: bytemuck::cast_slice(&indices),
                usage: wgpu::BufferUsages::INDEX | wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            }),
            adjacent: None,
            object_slots,
            index_count: indices.len() as u32,
            objects,
        })?;
        let camera_uniforms = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("lixel camera uniforms"),
            size: std::mem::size_of::<CameraRaw>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let lights_buffer = |label| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: std::mem::size_of::<LightsRaw>() as u64,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        };
        let layouts = device::capture(device, "camera and analysis layouts", || SceneLayouts::new(device))?;
        let camera_lights = lights_buffer("lixel camera pass lights");
        let camera_bindings = CameraBindings {
            bind_group: device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("lixel camera bind group"),
                layout: &layouts.camera,
                entries: &[
                    wgpu::BindGroupEntry { binding: 0, resource: camera_uniforms.as_entire_binding() },
                    wgpu::BindGroupEntry { binding: 1, resource: camera_lights.as_entire_binding() },
                ],
            }),
            lights: camera_lights,
        };
        // The default lookup is built now, so that the first frame does not
        // pay for its pipelines.
        // (It pulls no vertices, so it needs no edge adjacency.)
        let lookups = vec![device::capture(device, "shadow, camera and analysis pipelines", || {
            LookupState::new(device, ShadowLookup::default(), &layouts, unclipped_available, false, None)
        })?];
        let ring = ReadbackRing::new(
            device,
            "lixel analysis readback",
            options.readback_slots,
            analysis::padded_row_bytes(aw) * u64::from(ah),
        );
        let renderer = Self {
            device: device.clone(),
            queue: queue.clone(),
            max_texture,
            unclipped_available,
            hardware_conservative,
            scene: gpu_scene,
            layouts,
            lookups,
            camera_uniforms,
            camera_bindings,
            analysis_lights: lights_buffer("lixel analysis pass lights"),
            analysis_bind_group: None,
            camera_targets: None,
            analysis_masks: Target::new(device, "lixel analysis masks", MASKS_FORMAT, aw, ah),
            analysis_depth: (options.analysis_source == AnalysisSource::Geometry)
                .then(|| Target::new(device, "lixel analysis depth", passes::DEPTH_FORMAT, aw, ah)),
            ring,
            timer,
            frame: 0,
            last_lights: Vec::new(),
            last_lookup: None,
            last_masks: None,
            cascades: Vec::new(),
            aa: None,
            aa_bias,
            ss: None,
            capture: None,
            options,
            errors,
            depth_copy: std::sync::OnceLock::new(),
        };
        renderer.errors.take(device, "renderer buffers and targets")?;
        Ok(renderer)
    }

    /// Makes lights cascades from the next frame on: light `first + k` is
    /// cascade `k` of `splits`. Frame `lights` hold the cascades' matrices
    /// at those indices. Per pixel at view depth `d`, as
    /// [`Splits::choose`](crate::cascade::Splits::choose) says:
    ///
    /// - colour: cascade `k` lights with weight `1 - blend` and, inside the
    ///   blend band at its end, cascade `k + 1` with weight `blend` (the
    ///   visibility of the two lookups blended);
    /// - masks (shadow and facing bits, camera and analysis passes): only
    ///   the cascade of [`CascadeChoice::bit_owner`](crate::cascade::CascadeChoice::bit_owner)
    ///   sets its bits — `k`, or `k + 1` from the middle of the band on —
    ///   so the bit is the blended visibility rounded (ties to `k + 1`), at
    ///   most one bit per sun is set, and the sun's bit is the OR of its
    ///   cascades' bits.
    ///
    /// Depths nearer than the first split belong to the first cascade and
    /// depths beyond the last split to the last one (where `choose` says
    /// `None`): splits placed from an earlier readback (SDSM) lag a moving
    /// camera, and a surface the camera has come closer to than the
    /// readback's nearest depth, or sees beyond its farthest, is looked up
    /// in the nearest cascade (outside its map: lit) rather than left
    /// without the sun.
    ///
    /// A cascaded sun counts as one light in the split of light intensity.
    /// Other lights are unaffected; `None` for a `splits` clears the lights
    /// from `first` on.
    pub fn set_cascades(&mut self, first: usize, splits: Option<&crate::cascade::Splits>) {
        self.cascades.truncate(first);
        let Some(splits) = splits else { return };
        self.cascades.resize(first, None);
        let b = splits.boundaries();
        let n = splits.count();
        // The f64 midpoints of the bands, cast once, are shared by both
        // neighbours: the ownership ranges partition the depths exactly.
        // The end cascades reach past the splits (-f32::MAX, f32::MAX): see above.
        let mid = |k: usize| {
            if k == 0 {
                -f32::MAX
            } else if k == n {
                f32::MAX
            } else {
                (b[k] - 0.5 * splits.band(k - 1)) as f32
            }
        };
        for k in 0..n {
            let start = if k == 0 { -f32::MAX } else { b[k] as f32 };
            let fade_in = if k == 0 { -f32::MAX } else { (b[k] - splits.band(k - 1)) as f32 };
            let end = if k + 1 == n { f32::MAX } else { b[k + 1] as f32 };
            let fade_out = if splits.band(k) > 0.0 && k + 1 < n { (b[k + 1] - splits.band(k)) as f32 } else { end };
            let ramps = [fade_in, start, fade_out, end];
            self.cascades.push(Some(CascadeSlot { owned: (mid(k), mid(k + 1)), ramps, first: k == 0 }));
        }
    }

    /// The adapter the device was opened on.
    #[must_use]
    pub fn adapter_info(&self) -> wgpu::AdapterInfo {
        self.device.adapter_info()
    }

    /// The options it was created with.
    #[must_use]
    pub fn options(&self) -> &RendererOptions {
        &self.options
    }

    /// Whether lights needing unclipped depth get it on this device.
    #[must_use]
    pub fn unclipped_depth_available(&self) -> bool {
        self.unclipped_available
    }

    /// Whether SPSM and SGSM passes use the rasterizer's conservative mode
    /// ([`RendererOptions::hardware_conservative`] set and the device has
    /// `CONSERVATIVE_RASTERIZATION`) rather than the shader's padded triangles.
    #[must_use]
    pub fn hardware_conservative(&self) -> bool {
        self.hardware_conservative
    }

    /// Whether GPU timestamps are recorded.
    #[must_use]
    pub fn timestamps_enabled(&self) -> bool {
        self.timer.is_some()
    }

    /// Triangles of the uploaded scene.
    #[must_use]
    pub fn triangle_count(&self) -> usize {
        self.scene.index_count as usize / 3
    }

    /// Index the next frame will get.
    #[must_use]
    pub fn next_frame(&self) -> u64 {
        self.frame
    }

    /// The analysis readback ring (for its statistics).
    #[must_use]
    pub fn readback_ring(&self) -> &ReadbackRing<AnalysisMeta> {
        &self.ring
    }

    /// The last frame's camera colour texture and depth view (the viewer's
    /// overlays read them on the GPU); `None` before the first frame.
    #[cfg(feature = "view")]
    pub(crate) fn camera_textures(&self) -> Option<(&wgpu::Texture, &wgpu::TextureView)> {
        self.camera_targets.as_ref().map(|t| (&t.color.texture, &t.depth.view))
    }

    /// Whether the last frame wrote the full-resolution masks that `frame`
    /// would write — the same camera, lights, lookup and cascades, the masks
    /// written (a frame with [`Frame::masks`], or one whose analysis pass
    /// reads them) — so that [`read_masks`](Self::read_masks) gives
    /// `frame`'s masks without rendering it. `false` after a failed frame
    /// and after the captured view changed.
    #[must_use]
    pub fn has_masks_of(&self, frame: &Frame<'_>) -> bool {
        self.last_masks.as_ref().is_some_and(|k| *k == self.masks_key(frame))
    }

    /// What the camera pass's masks of `frame` depend on besides the
    /// renderer's fixed scene and options.
    fn masks_key(&self, frame: &Frame<'_>) -> MasksKey {
        MasksKey {
            camera: *frame.camera,
            lights: frame.lights.to_vec(),
            lookup: frame.lookup,
            cascades: self.cascades.clone(),
        }
    }

    /// Draws the scene from `camera` once into a view capture and waits for
    /// it. Until [`release_view`](Self::release_view) or the next capture,
    /// frames whose camera equals `camera` (bit for bit) do not draw the
    /// scene for their camera pass: one full-screen pass shades the capture
    /// with the frame's lights and lookup instead. For runs of many frames
    /// from one viewpoint (the experiment: every light and method through
    /// one camera); the shadow passes are drawn as before.
    ///
    /// The shadow, facing and normal words of the masks are bit-identical to
    /// a drawn camera pass (the depth test keeps the same fragments, and
    /// their interpolated position and normal are stored as f32); the
    /// colour is shaded with an 8-bit albedo. Such frames report
    /// `camera_triangles` 0. The capture costs 32 bytes per pixel.
    ///
    /// # Errors
    /// [`RenderError::TargetTooLarge`] for a viewport beyond the device's
    /// limit; device errors.
    pub fn capture_view(&mut self, camera: &Camera) -> Result<(), RenderError> {
        self.errors.take(&self.device, "an earlier device call")?;
        self.capture = None;
        self.last_masks = None;
        let frame = Frame::new(camera, &[]);
        let slots = self.prepare(&frame)?;
        self.write_uniforms(&frame, &slots);
        let capture = capture::ViewCapture::new(&self.device, &self.layouts.capture, *camera);
        let state = &mut self.lookups[slots.lookup];
        state.ensure_deferred(&self.device, &self.layouts);
        let mut encoder =
            self.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("lixel view capture") });
        self.encode_capture_pass(&mut encoder, &self.lookups[slots.lookup], &capture);
        let submission = self.queue.submit([encoder.finish()]);
        self.errors.take(&self.device, "capturing a view")?;
        self.wait_for(&submission)?;
        self.capture = Some(capture);
        Ok(())
    }

    /// Drops every lookup mode's shadow maps; the next frame allocates what
    /// it needs. Maps only grow otherwise (in size and in layers), so frames
    /// with large maps after a frame of many lights would keep, and clear
    /// on first use, as many large layers.
    pub fn release_maps(&mut self) {
        for state in &mut self.lookups {
            state.release_maps(&self.device);
        }
    }

    /// Drops the view capture: every frame draws its camera pass again.
    pub fn release_view(&mut self) {
        self.capture = None;
        self.last_masks = None;
    }

    /// The camera of the current view capture, if any.
    #[must_use]
    pub fn captured_view(&self) -> Option<&Camera> {
        self.capture.as_ref().map(|c| &c.camera)
    }

    /// Renders and submits one frame. Never waits for the GPU.
    ///
    /// # Errors
    /// [`RenderError::TooManyLights`], [`RenderError::BadMapSize`],
    /// [`RenderError::NonFiniteMatrix`] or [`RenderError::TargetTooLarge`]
    /// for bad input; nothing is rendered then.
    pub fn render(&mut self, frame: &Frame<'_>) -> Result<FrameReport, RenderError> {
        let started = Instant::now();
        self.last_masks = None;
        self.errors.take(&self.device, "an earlier device call")?;
        let slots = self.prepare(frame)?;
        let shadow_raw = self.write_uniforms(frame, &slots);

        let mut encoder = self.device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some(&format!("lixel frame {}", self.frame)),
        });
        let timer = self.timer.as_mut().and_then(GpuTimer::begin_frame);
        // A full ring skips the analysis (never waits for a slot).
        let analysis_staging = frame.analysis.and_then(|_| self.ring.acquire().map(|(slot, b)| (slot, b.clone())));
        // A frame from the captured viewpoint shades the capture.
        let deferred = self.capture.as_ref().is_some_and(|c| c.camera == *frame.camera);
        if deferred {
            self.lookups[slots.lookup].ensure_deferred(&self.device, &self.layouts);
        }
        let state = &self.lookups[slots.lookup];
        let reuse = if self.options.reuse_maps && timer.is_none() && state.sweep.is_none() {
            state.maps.drawn.reusable(&slots.maps, &shadow_raw)
        } else {
            vec![false; slots.maps.len()]
        };
        let shadow = self.encode_shadow_passes(&mut encoder, state, &slots.maps, &reuse, timer.as_ref());
        // The depth analysis and the antialiased passes read the camera pass's masks.
        let aa = match frame.lookup {
            ShadowLookup::SubPixelAa(samples) => Some(samples),
            _ => None,
        };
        let camera_output = if frame.masks
            || aa.is_some()
            || (analysis_staging.is_some() && self.options.analysis_source == AnalysisSource::CameraDepth)
        {
            CameraOutput::ColorAndMasks
        } else {
            CameraOutput::Color
        };
        let capture = if deferred { self.capture.as_ref() } else { None };
        let camera_triangles =
            self.encode_camera_pass(&mut encoder, state, frame.camera, camera_output, capture, timer.as_ref());
        if let (Some(samples), Some(pass), Some(targets)) = (aa, self.aa.as_mut(), self.camera_targets.as_ref()) {
            pass.encode(
                &self.device,
                &self.queue,
                &mut encoder,
                (&self.camera_uniforms, &self.camera_bindings.lights),
                (&self.scene.vertices, &self.scene.indices, self.scene.index_count / 3),
                (&targets.masks.view, &state.maps.depth_array),
                &self.options.bias,
                (targets.width, targets.height),
                frame.lights,
                samples,
            );
        }
        if let ShadowLookup::Supersampled(samples) = frame.lookup {
            self.encode_supersampled(&mut encoder, slots.lookup, frame.camera, frame.lights.len(), samples);
        }
        let state = &self.lookups[slots.lookup];
        if let Some((_, buffer)) = &analysis_staging {
            self.encode_analysis_pass(&mut encoder, state, frame.camera, buffer, timer.as_ref());
        }
        if let (Some(t), Some(timer)) = (timer.as_ref(), self.timer.as_ref()) {
            timer.resolve(&mut encoder, t);
        }
        let submission = self.queue.submit([encoder.finish()]);
        let drawn = &mut self.lookups[slots.lookup].maps.drawn;
        if let Err(e) = self.errors.take(&self.device, "rendering a frame") {
            drawn.forget();
            return Err(e);
        }
        drawn.record(&slots.maps, &shadow_raw);

        let analysis_slot = analysis_staging.map(|(slot, _)| slot);
        if let (Some(slot), Some(request)) = (analysis_slot, frame.analysis) {
            let (w, h) = self.options.analysis_size;
            let lights = request.lights.unwrap_or(frame.lights).to_vec();
            let meta = AnalysisMeta { camera: *frame.camera, lights, width: w, height: h, tag: request.tag };
            self.ring.submitted(slot, self.frame, meta);
        }
        if let (Some(t), Some(timer)) = (timer, self.timer.as_mut()) {
            timer.submitted(t, self.frame, !slots.maps.is_empty(), analysis_slot.is_some());
        }
        self.last_lights = frame.lights.to_vec();
        self.last_lookup = Some(slots.lookup);
        if camera_output == CameraOutput::ColorAndMasks {
            self.last_masks = Some(self.masks_key(frame));
        }
        let report = FrameReport {
            frame: self.frame,
            submission,
            analysis_skipped: frame.analysis.is_some() && analysis_slot.is_none(),
            analysis_queued: analysis_slot.is_some(),
            unclipped_unavailable: shadow.unclipped_unavailable,
            shadow_passes: shadow.passes,
            shadow_triangles: shadow.triangles,
            camera_triangles,
            maps_reused: slots.maps.len() as u32 - shadow.passes,
            cpu_time: started.elapsed(),
        };
        self.frame += 1;
        Ok(report)
    }

    /// Validates `frame`, assigns its shadow-map slots and makes sure the
    /// lookup mode's pipelines, the maps and the targets exist.
    fn prepare<'f>(&mut self, frame: &Frame<'f>) -> Result<MapSlots<'f>, RenderError> {
        let analysis_lights = frame.analysis.and_then(|a| a.lights);
        self.validate(frame.lights)?;
        if let Some(lights) = analysis_lights {
            self.validate(lights)?;
        }
        let viewport = frame.camera.viewport();
        check_target(viewport.x, viewport.y, self.max_texture)?;

        // Shadow-map slots: the frame's lights, then the analysis pass's own
        // where they differ from the frame's light of the same index.
        let mut maps: Vec<&LightMatrix> = frame.lights.iter().collect();
        let mut analysis_layers = Vec::new();
        for (i, m) in analysis_lights.into_iter().flatten().enumerate() {
            if frame.lights.get(i) == Some(m) {
                analysis_layers.push(i as u32);
            } else {
                analysis_layers.push(maps.len() as u32);
                maps.push(m);
            }
        }
        debug_assert!(maps.len() <= MAX_SHADOW_SLOTS);
        let lookup = self.lookup_state(frame.lookup)?;
        if matches!(frame.lookup, ShadowLookup::SubPixelAa(_)) {
            self.ensure_aa()?;
        }
        if matches!(frame.lookup, ShadowLookup::Supersampled(_)) {
            self.ensure_supersample()?;
        }
        self.ensure_resources(lookup, &maps, viewport.x, viewport.y);
        Ok(MapSlots { maps, analysis_layers, lookup })
    }

    /// The index of `lookup`'s pipelines and maps, built on first use.
    fn lookup_state(&mut self, lookup: ShadowLookup) -> Result<usize, RenderError> {
        if let Some(i) = self.lookups.iter().position(|s| s.lookup == lookup) {
            return Ok(i);
        }
        if lookup.pulls_vertices() {
            self.ensure_adjacency()?;
        }
        let scene = &self.scene;
        let pulled = scene.adjacent.as_ref().map(|adjacent| (&scene.vertices, &scene.indices, adjacent));
        let state = device::capture(&self.device, "shadow, camera and analysis pipelines", || {
            LookupState::new(
                &self.device,
                lookup,
                &self.layouts,
                self.unclipped_available,
                self.hardware_conservative,
                pulled,
            )
        })?;
        self.lookups.push(state);
        Ok(self.lookups.len() - 1)
    }

    /// Builds the scene's edge adjacency (`spsm::adjacency`) from the
    /// uploaded vertices and indices, once: only lookups that pull vertices
    /// (SPSM, SGSM) read it, and no CPU copy of the scene is kept.
    fn ensure_adjacency(&mut self) -> Result<(), RenderError> {
        if self.scene.adjacent.is_some() {
            return Ok(());
        }
        let words = self.read_buffer_words(&self.scene.vertices, 0, self.scene.vertices.size() / 4)?;
        let words_per_vertex = std::mem::size_of::<VertexRaw>() / 4;
        let positions: Vec<Vec3> = words
            .chunks_exact(words_per_vertex)
            .map(|v| Vec3::new(f32::from_bits(v[0]), f32::from_bits(v[1]), f32::from_bits(v[2])))
            .collect();
        let indices = self.read_buffer_words(&self.scene.indices, 0, u64::from(self.scene.index_count))?;
        let mut adjacent = Vec::with_capacity(indices.len());
        for (slots, vertices) in &self.scene.object_slots {
            let (Some(own), Some(own_positions)) = (
                indices.get(slots.start as usize..slots.end as usize),
                positions.get(vertices.start as usize..vertices.end as usize),
            ) else {
                // The read-back is the uploaded size; shorter means it failed.
                return Err(RenderError::Map(wgpu::BufferAsyncError));
            };
            // Object-local indices, as the object's mesh holds them.
            let local: Vec<u32> = own.iter().map(|&i| i.wrapping_sub(vertices.start)).collect();
            adjacent.extend(spsm::adjacency::opposite_slots(own_positions, &local, slots.start));
        }
        let buffer = device::capture(&self.device, "scene edge adjacency", || {
            self.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("lixel scene edge adjacency"),
                // Never empty: a zero-sized storage binding is invalid.
                contents: bytemuck::cast_slice(if adjacent.is_empty() {
                    &[spsm::adjacency::NO_NEIGHBOUR]
                } else {
                    &adjacent[..]
                }),
                usage: wgpu::BufferUsages::STORAGE,
            })
        })?;
        self.scene.adjacent = Some(buffer);
        Ok(())
    }

    /// Camera, lights of both scene passes and the shadow passes' slots
    /// (returned). Light intensity is split so that n lights add up to 1.
    fn write_uniforms(&self, frame: &Frame<'_>, slots: &MapSlots<'_>) -> Vec<ShadowPassRaw> {
        let light_color = |n: usize| Vec3::splat((1.0 - self.options.ambient) / n.max(1) as f32);
        let cascade = |i: usize| self.cascades.get(i).and_then(Option::as_ref);
        // The SPSM pass and lookup (SGSM builds on both) compare in a depth of their own (see
        // spsm::depth_matrix).
        let spsm = matches!(frame.lookup, ShadowLookup::Spsm(_) | ShadowLookup::Sgsm(_));
        let for_lookup = |m: &LightMatrix| {
            if spsm {
                LightMatrix { clip_from_world: spsm::depth_matrix(m), ..*m }
            } else {
                *m
            }
        };
        let raw_lights = |lights: &[LightMatrix], layer: &dyn Fn(usize) -> u32| -> Vec<LightRaw> {
            // A sun's cascades count once.
            let suns = (0..lights.len()).filter(|&i| cascade(i).is_none_or(|c| c.first)).count();
            let color = light_color(suns);
            lights
                .iter()
                .enumerate()
                .map(|(i, m)| {
                    let raw = LightRaw::to_raw(&for_lookup(m), layer(i), color);
                    cascade(i).map_or(raw, |c| raw.with_cascade(c))
                })
                .collect()
        };
        self.queue.write_buffer(
            &self.camera_uniforms,
            0,
            bytemuck::bytes_of(&CameraRaw::to_raw(frame.camera, self.options.ambient, self.options.analysis_size)),
        );
        self.queue.write_buffer(
            &self.camera_bindings.lights,
            0,
            bytemuck::bytes_of(&LightsRaw::to_raw(&raw_lights(frame.lights, &|i| i as u32))),
        );
        if let Some(request) = frame.analysis {
            let layers = &slots.analysis_layers;
            let (raw, layer): (_, &dyn Fn(usize) -> u32) = match request.lights {
                Some(lights) => (raw_lights(lights, &|i| layers[i]), &|i| layers[i]),
                None => (raw_lights(frame.lights, &|i| i as u32), &|i| i as u32),
            };
            // The depth analysis takes the camera pass's bits of a light whose
            // map is the frame's own (the camera pass then writes its masks).
            let camera_bits = match self.options.analysis_source {
                AnalysisSource::CameraDepth => (0..raw.len().min(frame.lights.len()))
                    .filter(|&i| layer(i) == i as u32)
                    .fold(0u32, |bits, i| bits | 1 << i),
                AnalysisSource::Geometry => 0,
            };
            let lights = LightsRaw::with_camera_bits(&raw, camera_bits);
            self.queue.write_buffer(&self.analysis_lights, 0, bytemuck::bytes_of(&lights));
        }
        let shadow_raw: Vec<ShadowPassRaw> =
            slots.maps.iter().map(|m| ShadowPassRaw::to_raw(&for_lookup(m), &self.options.bias)).collect();
        if !shadow_raw.is_empty() {
            let state = &self.lookups[slots.lookup];
            self.queue.write_buffer(&state.shadow.uniforms, 0, bytemuck::cast_slice(&shadow_raw));
        }
        shadow_raw
    }

    /// The newest analysis readback that has arrived, without waiting (one
    /// non-blocking device poll). `None` while nothing new has arrived: keep
    /// using the current matrices.
    pub fn try_take_analysis(&mut self) -> Option<AnalysisReadback> {
        // The frame that would consume it is the next one to be rendered.
        let readback = self.ring.try_take(&self.device, self.frame)?;
        Some(AnalysisReadback::decode(readback))
    }

    /// Drops every analysis readback that has arrived (for example when the
    /// scene or the lights change, so that a new [`ShadowLoop`] does not
    /// optimize from the old ones); returns how many.
    pub fn discard_analyses(&mut self) -> usize {
        std::iter::from_fn(|| self.try_take_analysis()).count()
    }

    /// GPU times of the newest frame whose timestamps have arrived, without
    /// waiting. `None` without `TIMESTAMP_QUERY` or while nothing arrived.
    pub fn try_take_gpu_times(&mut self) -> Option<GpuFrameTimes> {
        let frame = self.frame;
        self.timer.as_mut()?.try_take(&self.device, frame)
    }

    /// Blocks until every submitted frame has finished on the GPU.
    ///
    /// # Errors
    /// [`RenderError::Poll`] when the device is lost.
    pub fn wait_idle(&self) -> Result<(), RenderError> {
        self.device.poll(wgpu::PollType::wait_indefinitely())?;
        Ok(())
    }

    /// Blocks until `submission` has finished (frame pacing: wait for frame
    /// `n - k` to keep at most `k` frames in flight).
    ///
    /// # Errors
    /// [`RenderError::Poll`] when the device is lost.
    pub fn wait_for(&self, submission: &wgpu::SubmissionIndex) -> Result<(), RenderError> {
        self.device.poll(wgpu::PollType::Wait { submission_index: Some(submission.clone()), timeout: None })?;
        Ok(())
    }

    fn validate(&self, lights: &[LightMatrix]) -> Result<(), RenderError> {
        if lights.len() > MAX_LIGHTS {
            return Err(RenderError::TooManyLights { count: lights.len() });
        }
        for (light, m) in lights.iter().enumerate() {
            let (width, height) = (m.map_size.width, m.map_size.height);
            if width == 0 || height == 0 || width > self.max_texture || height > self.max_texture {
                return Err(RenderError::BadMapSize { light, width, height, max: self.max_texture });
            }
            if !m.clip_from_world_f32().is_finite() {
                return Err(RenderError::NonFiniteMatrix { light });
            }
        }
        Ok(())
    }

    /// Grows the lookup mode's maps and the camera targets as needed and
    /// (re)creates the analysis bind group, which refers to the latter.
    fn ensure_resources(&mut self, lookup: usize, maps: &[&LightMatrix], width: u32, height: u32) {
        let need_w = maps.iter().map(|m| m.map_size.width).max().unwrap_or(1);
        let need_h = maps.iter().map(|m| m.map_size.height).max().unwrap_or(1);
        let need_layers = (maps.len() as u32).max(1);
        self.lookups[lookup].ensure_maps(&self.device, need_w, need_h, need_layers);
        if self.camera_targets.as_ref().is_none_or(|t| t.width != width || t.height != height) {
            self.camera_targets = Some(CameraTargets::new(&self.device, "lixel camera", width, height));
            // It binds the camera depth.
            self.analysis_bind_group = None;
        }
        if self.analysis_bind_group.is_none() {
            let camera = self.camera_targets.as_ref().expect("created above");
            let texture =
                |binding, view| wgpu::BindGroupEntry { binding, resource: wgpu::BindingResource::TextureView(view) };
            self.analysis_bind_group = Some(self.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("lixel analysis bind group"),
                layout: &self.layouts.analysis,
                entries: &[
                    wgpu::BindGroupEntry { binding: 0, resource: self.camera_uniforms.as_entire_binding() },
                    wgpu::BindGroupEntry { binding: 1, resource: self.analysis_lights.as_entire_binding() },
                    texture(3, &camera.depth.view),
                    texture(4, &camera.masks.view),
                ],
            }));
        }
    }
}

fn check_target(width: u32, height: u32, max: u32) -> Result<(), RenderError> {
    if width == 0 || height == 0 || width > max || height > max {
        return Err(RenderError::TargetTooLarge { width, height, max });
    }
    Ok(())
}
