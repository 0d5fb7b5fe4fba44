//! A wgpu renderer for lixel's light matrices (feature `render`).
//!
//! One frame ([`Renderer::render`]) is, in order:
//!
//! 1. **Shadow passes** (`shaders/shadow.wgsl`): depth only, one per light,
//!    into one layer each of a `Depth32Float` array; each map is sized by its
//!    [`LightMatrix::map_size`], storing *linear* light depth (distance
//!    along the light's rays, normalized to
//!    [`LightMatrix::light_distance`]), which grows away from the light for
//!    every matrix, so the ordinary depth test serves all of them
//!    ([`LightMatrix::reverse_depth_test`] does not apply); with unclipped
//!    depth when [`LightMatrix::needs_unclipped_depth`] is set and the device has
//!    `DEPTH_CLIP_CONTROL`. Bias: [`ShadowBias`], the same for every method.
//! 2. **Camera pass** (`shaders/camera.wgsl`): the camera's view with hard
//!    shadows of up to 32 lights (points outside a map count as lit);
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
mod culling;
mod output;
mod passes;
pub mod readback;
pub mod spsm;
mod timing;
mod uniforms;

use std::time::Instant;

use glam::Vec3;
use wgpu::util::DeviceExt;

use crate::mesh::{MeshError, Scene};
use crate::{Camera, LightMatrix};

pub use analysis::{AnalysisMeta, AnalysisReadback};
pub use output::{masks_image, shadow_map_image, DepthImage};
pub use readback::{Readback, ReadbackLatency, ReadbackRing, RingStats};
pub use spsm::{ShadowLookup, SpsmOptions};
pub use timing::GpuFrameTimes;
pub use uniforms::MAX_LIGHTS;

use passes::{CameraTargets, ScenePasses, ShadowMaps, ShadowPass, Target, MASKS_FORMAT, MAX_SHADOW_SLOTS};
use timing::GpuTimer;
use uniforms::{CameraRaw, LightRaw, LightsRaw, ShadowPassRaw, VertexRaw, SHADOW_SLOT_STRIDE};

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
}

/// The depth bias of every shadow map, the same for every method.
///
/// Shadow maps store *linear* light depth (distance along the light's rays,
/// normalized to the matrix's [`LightDistance`](crate::LightDistance) range;
/// see `shaders/shadow.wgsl`), and `fs_shadow` adds
/// `slope_scale · m + constant · 2⁻²⁴` to it, where
/// `m = max(|∂z/∂x|, |∂z/∂y|)` is the stored depth's slope per texel,
/// clamped to `clamp` when that is non-zero. A receiver looked up at most half
/// a texel from a texel centre differs from the stored depth by at most `m`
/// on a plane, so `slope_scale >= 1` prevents self-shadowing of planar
/// surfaces; `2` leaves room. Because the depth is linear, `m` depends only
/// on the surface's angle to the light rays and the texel's size, never on
/// how a warped map spends its projective depth. No normal offset is used at
/// lookup, so the only method-dependent effect is each map's own texel size.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadowBias {
    /// In units of the smallest depth step `r`.
    pub constant: i32,
    /// Multiple of the depth slope per texel.
    pub slope_scale: f32,
    /// Largest bias in depth units; 0 for none.
    pub clamp: f32,
}

impl Default for ShadowBias {
    fn default() -> Self {
        Self { constant: 16, slope_scale: 2.0, clamp: 0.0 }
    }
}

/// Which faces the shadow pass draws.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ShadowFaces {
    /// Every triangle (works for open and inconsistently wound meshes; needs
    /// the slope-scaled [`ShadowBias`] against self-shadowing).
    #[default]
    Both,
    /// Only triangles facing away from the light ("second-depth" shadow
    /// maps, Wang & Molnar 1994): lit surfaces are compared with the far side
    /// of their occluders, so no slope-scaled bias is needed and edge-on
    /// casters are never pushed behind their receivers. Needs closed meshes
    /// wound counter-clockwise seen from outside (the procedural scene's).
    /// Mirrored light matrices are detected (`det(clip_from_world) < 0`) and
    /// cull the other winding.
    AwayFromLight,
}

/// The winding cull that keeps only faces turned away from the light of `m`:
/// a small triangle facing the light is projected by `m`, and by a standard
/// camera a triangle facing that camera (whose front faces are
/// counter-clockwise in wgpu); the same sign of their signed areas means the
/// light sees its facing triangles as front faces, which are then culled.
/// (The 4x4 determinant does not decide this: the depth row's sign enters it
/// but not the 2D winding.)
fn away_from_light_cull(m: &LightMatrix) -> wgpu::Face {
    let centre = m.clip_from_world.inverse().project_point3(glam::DVec3::new(0.0, 0.0, 0.5));
    let towards_light = match m.frame {
        crate::LightFrame::Perspective { position, .. } => position - centre,
        crate::LightFrame::Orthographic { rotation } => -rotation.row(2),
    };
    let light = facing_winding(&m.clip_from_world, centre, towards_light);
    let view = glam::dcamera::rh::view::look_at_mat4(glam::DVec3::Z, glam::DVec3::ZERO, glam::DVec3::Y);
    let proj = glam::dcamera::rh::proj::directx::perspective(1.0, 1.0, 0.1, 10.0);
    let reference = facing_winding(&(proj * view), glam::DVec3::ZERO, glam::DVec3::Z);
    if light * reference > 0.0 {
        wgpu::Face::Front
    } else {
        wgpu::Face::Back
    }
}

/// Signed NDC area of a small triangle at `p` whose counter-clockwise
/// (outward) side faces `towards`, projected by `m`.
fn facing_winding(m: &glam::DMat4, p: glam::DVec3, towards: glam::DVec3) -> f64 {
    let n = towards.normalize_or(glam::DVec3::Y);
    let (t1, t2) = n.any_orthonormal_pair();
    // (t1, t2, n) right-handed, so p, p + t1, p + t2 is CCW seen from n.
    let (t1, t2) = if t1.cross(t2).dot(n) > 0.0 { (t1, t2) } else { (t2, t1) };
    let size = 1e-3 * p.length().max(1.0);
    let project = |q: glam::DVec3| m.project_point3(q).truncate();
    let (a, b, c) = (project(p), project(p + t1 * size), project(p + t2 * size));
    (b - a).perp_dot(c - a)
}

/// Where the analysis pass gets the visible surface from.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum AnalysisSource {
    /// A full-screen pass over the camera pass's depth buffer and masks (no
    /// second geometry pass; its cost does not grow with the scene). Each
    /// analysis pixel stands for the full-resolution point at its scaled
    /// centre: the depth there is extrapolated from the nearest
    /// full-resolution pixel along the one-sided depth differences that
    /// continue its surface (exact on planes, where screen-space depth is
    /// affine). Lights whose analysis map is the frame's own take that
    /// pixel's shadow and facing bits from the camera pass, which then writes
    /// its masks on analysis frames; others (the periodic focused maps) are
    /// looked up at the world point reconstructed from the 32-bit depth, with
    /// the camera pass's interpolated normal.
    #[default]
    CameraDepth,
    /// Draws the scene again at the analysis resolution, with interpolated
    /// positions and vertex normals. Exact, but on a software rasterizer it
    /// costs a good part of a camera pass.
    Geometry,
}

/// Settings fixed when the renderer is created.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RendererOptions {
    /// Resolution of the analysis pass (the paper: 180x180 for 1150² screens).
    pub analysis_size: (u32, u32),
    /// Where the analysis pass gets the visible surface from.
    pub analysis_source: AnalysisSource,
    /// Staging buffers of the analysis readback ring (the paper used 2).
    pub readback_slots: usize,
    /// Shadow-map depth bias.
    pub bias: ShadowBias,
    /// Which faces the shadow pass rasterizes.
    pub shadow_faces: ShadowFaces,
    /// Light that reaches every surface regardless of shadows, in `[0, 1]`.
    pub ambient: f32,
    /// Clear colour of the camera pass (linear RGB).
    pub background: Vec3,
    /// Record GPU timestamps when the device supports them.
    pub timestamps: bool,
    /// Leave out of each scene pass the objects whose bounding box lies
    /// outside its clip volume (the output is the same; see
    /// [`FrameReport::shadow_triangles`]).
    pub cull_objects: bool,
    /// How the camera and analysis passes look shadows up (the shadow
    /// passes follow: SPSM lookups get SPSM passes, see [`spsm`]).
    pub lookup: ShadowLookup,
}

impl Default for RendererOptions {
    fn default() -> Self {
        Self {
            analysis_size: (180, 180),
            analysis_source: AnalysisSource::CameraDepth,
            readback_slots: 3,
            bias: ShadowBias::default(),
            shadow_faces: ShadowFaces::Both,
            ambient: 0.25,
            background: Vec3::new(0.55, 0.68, 0.85),
            timestamps: true,
            cull_objects: true,
            lookup: ShadowLookup::Standard,
        }
    }
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
    /// CPU time spent encoding and submitting.
    pub cpu_time: std::time::Duration,
}

/// The scene on the GPU.
struct GpuScene {
    vertices: wgpu::Buffer,
    indices: wgpu::Buffer,
    index_count: u32,
    /// Per-object index ranges and bounds, for culling.
    objects: Vec<culling::ObjectBounds>,
}

/// Per-frame uniforms and bind group of one scene pass (camera or analysis).
struct SceneBindings {
    lights: wgpu::Buffer,
    bind_group: Option<wgpu::BindGroup>,
}

/// Shadows for many lights, a camera pass and asynchronous low-resolution
/// readback. See the [module docs](self).
pub struct Renderer {
    device: wgpu::Device,
    queue: wgpu::Queue,
    options: RendererOptions,
    max_texture: u32,
    unclipped_available: bool,
    scene: GpuScene,
    shadow: ShadowPass,
    passes: ScenePasses,
    camera_uniforms: wgpu::Buffer,
    camera_bindings: SceneBindings,
    analysis_bindings: SceneBindings,
    shadow_maps: ShadowMaps,
    camera_targets: Option<CameraTargets>,
    analysis_masks: Target,
    /// Depth buffer of [`AnalysisSource::Geometry`].
    analysis_depth: Option<Target>,
    ring: ReadbackRing<AnalysisMeta>,
    timer: Option<GpuTimer>,
    /// The SPSM pass and texels, with the SPSM lookup.
    spsm: Option<(spsm::SpsmPass, spsm::SpsmTexels)>,
    frame: u64,
    /// Lights of the last frame (for reading maps back).
    last_lights: Vec<LightMatrix>,
}

impl std::fmt::Debug for Renderer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Renderer")
            .field("options", &self.options)
            .field("frame", &self.frame)
            .field("triangles", &(self.scene.index_count / 3))
            .field("unclipped_available", &self.unclipped_available)
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
        wgpu::Features::DEPTH_CLIP_CONTROL | wgpu::Features::TIMESTAMP_QUERY
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
        let max_texture = device.limits().max_texture_dimension_2d;
        let (aw, ah) = options.analysis_size;
        check_target(aw, ah, max_texture)?;
        let features = device.features();
        let unclipped_available = features.contains(wgpu::Features::DEPTH_CLIP_CONTROL);
        let timer = (options.timestamps && features.contains(wgpu::Features::TIMESTAMP_QUERY))
            .then(|| GpuTimer::new(device, queue));

        let mut vertices = Vec::with_capacity(scene.vertex_count());
        let mut indices = Vec::with_capacity(3 * scene.triangle_count());
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
        }
        let gpu_scene = GpuScene {
            vertices: device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("lixel scene vertices"),
                contents: bytemuck::cast_slice(&vertices),
                // Storage: the SPSM pass pulls whole triangles.
                usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::STORAGE,
            }),
            indices: device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("lixel scene indices"),
                contents: bytemuck::cast_slice(&indices),
                usage: wgpu::BufferUsages::INDEX | wgpu::BufferUsages::STORAGE,
            }),
            index_count: indices.len() as u32,
            objects,
        };
        let camera_uniforms = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("lixel camera uniforms"),
            size: std::mem::size_of::<CameraRaw>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let lights_buffer = |label| SceneBindings {
            lights: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: std::mem::size_of::<LightsRaw>() as u64,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            bind_group: None,
        };
        let ring = ReadbackRing::new(
            device,
            "lixel analysis readback",
            options.readback_slots,
            analysis::padded_row_bytes(aw) * u64::from(ah),
        );
        let spsm = options.lookup.spsm().map(|o| {
            let pass = spsm::SpsmPass::new(
                device,
                o,
                &gpu_scene.vertices,
                &gpu_scene.indices,
                MAX_SHADOW_SLOTS,
                unclipped_available,
            );
            (pass, spsm::SpsmTexels::new(device, 1, 1, 1))
        });
        Ok(Self {
            device: device.clone(),
            queue: queue.clone(),
            max_texture,
            unclipped_available,
            scene: gpu_scene,
            shadow: ShadowPass::new(device, unclipped_available),
            passes: ScenePasses::new(device, &options.lookup),
            camera_uniforms,
            camera_bindings: lights_buffer("lixel camera pass lights"),
            analysis_bindings: lights_buffer("lixel analysis pass lights"),
            shadow_maps: ShadowMaps::new(device, 1, 1, 1),
            camera_targets: None,
            analysis_masks: Target::new(device, "lixel analysis masks", MASKS_FORMAT, aw, ah),
            analysis_depth: (options.analysis_source == AnalysisSource::Geometry)
                .then(|| Target::new(device, "lixel analysis depth", passes::DEPTH_FORMAT, aw, ah)),
            ring,
            timer,
            spsm,
            frame: 0,
            last_lights: Vec::new(),
            options,
        })
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

    /// Renders and submits one frame. Never waits for the GPU.
    ///
    /// # Errors
    /// [`RenderError::TooManyLights`], [`RenderError::BadMapSize`],
    /// [`RenderError::NonFiniteMatrix`] or [`RenderError::TargetTooLarge`]
    /// for bad input; nothing is rendered then.
    pub fn render(&mut self, frame: &Frame<'_>) -> Result<FrameReport, RenderError> {
        let started = Instant::now();
        let analysis_lights = frame.analysis.and_then(|a| a.lights);
        self.validate(frame.lights)?;
        if let Some(lights) = analysis_lights {
            self.validate(lights)?;
        }
        let viewport = frame.camera.viewport();
        check_target(viewport.x, viewport.y, self.max_texture)?;

        // Shadow-map slots: the frame's lights, then the analysis pass's own
        // where they differ from the frame's light of the same index.
        let mut slots: Vec<&LightMatrix> = frame.lights.iter().collect();
        let mut analysis_layers = Vec::new();
        for (i, m) in analysis_lights.into_iter().flatten().enumerate() {
            if frame.lights.get(i) == Some(m) {
                analysis_layers.push(i as u32);
            } else {
                analysis_layers.push(slots.len() as u32);
                slots.push(m);
            }
        }
        debug_assert!(slots.len() <= MAX_SHADOW_SLOTS);
        self.ensure_resources(&slots, viewport.x, viewport.y);

        // Uniforms. Light intensity is split so that n lights add up to 1.
        let light_color = |n: usize| Vec3::splat((1.0 - self.options.ambient) / n.max(1) as f32);
        let raw_lights = |lights: &[LightMatrix], layer: &dyn Fn(usize) -> u32| -> Vec<LightRaw> {
            let color = light_color(lights.len());
            lights.iter().enumerate().map(|(i, m)| LightRaw::to_raw(m, layer(i), color)).collect()
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
        if frame.analysis.is_some() {
            let (raw, layers): (_, &dyn Fn(usize) -> u32) = match analysis_lights {
                Some(lights) => (raw_lights(lights, &|i| analysis_layers[i]), &|i| analysis_layers[i]),
                None => (raw_lights(frame.lights, &|i| i as u32), &|i| i as u32),
            };
            // The depth analysis takes the camera pass's bits of a light whose
            // map is the frame's own (the camera pass then writes its masks).
            let camera_bits = match self.options.analysis_source {
                AnalysisSource::CameraDepth => (0..raw.len().min(frame.lights.len()))
                    .filter(|&i| layers(i) == i as u32)
                    .fold(0u32, |bits, i| bits | 1 << i),
                AnalysisSource::Geometry => 0,
            };
            let lights = LightsRaw::with_camera_bits(&raw, camera_bits);
            self.queue.write_buffer(&self.analysis_bindings.lights, 0, bytemuck::bytes_of(&lights));
        }
        let shadow_raw: Vec<ShadowPassRaw> =
            slots.iter().map(|m| ShadowPassRaw::to_raw(m, &self.options.bias)).collect();
        if !shadow_raw.is_empty() {
            self.queue.write_buffer(&self.shadow.uniforms, 0, bytemuck::cast_slice(&shadow_raw));
        }
        if let Some((pass, _)) = &self.spsm {
            let raw: Vec<spsm::SpsmPassRaw> = slots.iter().map(|m| spsm::SpsmPassRaw::to_raw(m)).collect();
            self.queue.write_buffer(&pass.uniforms, 0, bytemuck::cast_slice(&raw));
        }

        let mut encoder = self.device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some(&format!("lixel frame {}", self.frame)),
        });
        let timer = self.timer.as_mut().and_then(GpuTimer::begin_frame);
        // A full ring skips the analysis (never waits for a slot).
        let analysis_staging = frame.analysis.and_then(|_| self.ring.acquire().map(|(slot, b)| (slot, b.clone())));
        let analysis_skipped = frame.analysis.is_some() && analysis_staging.is_none();
        let (unclipped_unavailable, shadow_triangles) = self.encode_shadow_passes(&mut encoder, &slots, timer.as_ref());
        // The depth analysis reads the camera pass's masks.
        let camera_masks =
            frame.masks || (analysis_staging.is_some() && self.options.analysis_source == AnalysisSource::CameraDepth);
        let camera_triangles = self.encode_camera_pass(&mut encoder, frame.camera, camera_masks, timer.as_ref());
        let analysis_slot = analysis_staging.map(|(slot, buffer)| {
            self.encode_analysis_pass(&mut encoder, frame.camera, &buffer, timer.as_ref());
            slot
        });
        if let (Some(t), Some(timer)) = (timer.as_ref(), self.timer.as_ref()) {
            timer.resolve(&mut encoder, t);
        }
        let submission = self.queue.submit([encoder.finish()]);

        if let (Some(slot), Some(request)) = (analysis_slot, frame.analysis) {
            let (w, h) = self.options.analysis_size;
            let lights = analysis_lights.unwrap_or(frame.lights).to_vec();
            let meta = AnalysisMeta { camera: *frame.camera, lights, width: w, height: h, tag: request.tag };
            self.ring.submitted(slot, self.frame, meta);
        }
        if let (Some(t), Some(timer)) = (timer, self.timer.as_mut()) {
            timer.submitted(t, self.frame, !slots.is_empty(), analysis_slot.is_some());
        }
        self.last_lights = frame.lights.to_vec();
        let report = FrameReport {
            frame: self.frame,
            submission,
            analysis_skipped,
            analysis_queued: analysis_slot.is_some(),
            unclipped_unavailable,
            shadow_passes: slots.len() as u32,
            shadow_triangles,
            camera_triangles,
            cpu_time: started.elapsed(),
        };
        self.frame += 1;
        Ok(report)
    }

    /// The newest analysis readback that has arrived, without waiting (one
    /// non-blocking device poll). `None` while nothing new has arrived: keep
    /// using the current matrices.
    pub fn try_take_analysis(&mut self) -> Option<AnalysisReadback> {
        // The frame that would consume it is the next one to be rendered.
        let readback = self.ring.try_take(&self.device, self.frame)?;
        Some(AnalysisReadback::decode(readback))
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

    /// Grows the shadow-map array and the camera targets as needed and
    /// (re)creates the bind groups that refer to them.
    fn ensure_resources(&mut self, slots: &[&LightMatrix], width: u32, height: u32) {
        let need_w = slots.iter().map(|m| m.map_size.width).max().unwrap_or(1);
        let need_h = slots.iter().map(|m| m.map_size.height).max().unwrap_or(1);
        let need_layers = (slots.len() as u32).max(1);
        let maps = &self.shadow_maps;
        if need_w > maps.width || need_h > maps.height || need_layers > maps.layers() {
            self.shadow_maps = ShadowMaps::new(
                &self.device,
                need_w.max(maps.width),
                need_h.max(maps.height),
                need_layers.max(maps.layers()),
            );
            self.camera_bindings.bind_group = None;
            self.analysis_bindings.bind_group = None;
            if let Some((_, texels)) = &mut self.spsm {
                let maps = &self.shadow_maps;
                *texels = spsm::SpsmTexels::new(&self.device, maps.width, maps.height, maps.layers());
            }
        }
        if self.camera_targets.as_ref().is_none_or(|t| t.width != width || t.height != height) {
            self.camera_targets = Some(CameraTargets::new(&self.device, "lixel camera", width, height));
            // It binds the camera depth.
            self.analysis_bindings.bind_group = None;
        }
        let camera = self.camera_targets.as_ref().expect("created above");
        let camera_views = Some((&camera.depth.view, &camera.masks.view));
        for (bindings, layout, views, label) in [
            (&mut self.camera_bindings, &self.passes.camera_layout, None, "lixel camera bind group"),
            (&mut self.analysis_bindings, &self.passes.analysis_layout, camera_views, "lixel analysis bind group"),
        ] {
            if bindings.bind_group.is_none() {
                let mut entries = vec![
                    wgpu::BindGroupEntry { binding: 0, resource: self.camera_uniforms.as_entire_binding() },
                    wgpu::BindGroupEntry { binding: 1, resource: bindings.lights.as_entire_binding() },
                    wgpu::BindGroupEntry {
                        binding: 2,
                        resource: wgpu::BindingResource::TextureView(&self.shadow_maps.array_view),
                    },
                ];
                if let Some((_, texels)) = &self.spsm {
                    entries.push(wgpu::BindGroupEntry {
                        binding: 5,
                        resource: wgpu::BindingResource::TextureView(&texels.array_view),
                    });
                }
                if let Some((depth, masks)) = views {
                    entries
                        .push(wgpu::BindGroupEntry { binding: 3, resource: wgpu::BindingResource::TextureView(depth) });
                    entries
                        .push(wgpu::BindGroupEntry { binding: 4, resource: wgpu::BindingResource::TextureView(masks) });
                }
                bindings.bind_group = Some(self.device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some(label),
                    layout,
                    entries: &entries,
                }));
            }
        }
    }

    /// One depth-only pass per slot; returns how many lights wanted
    /// unclipped depth the device lacks.
    fn encode_shadow_passes(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        slots: &[&LightMatrix],
        timer: Option<&timing::FrameQueries>,
    ) -> (u32, u64) {
        let mut unavailable = 0;
        let mut triangles = 0;
        let last = slots.len().saturating_sub(1);
        if let Some((pass, texels)) = &self.spsm {
            return self.encode_spsm_passes(encoder, slots, timer, pass, texels);
        }
        for (i, m) in slots.iter().enumerate() {
            // Linear light depth grows away from the light whatever the
            // matrix's own depth row does, so the ordinary test always applies.
            let reversed = false;
            let cull = match self.options.shadow_faces {
                ShadowFaces::Both => None,
                ShadowFaces::AwayFromLight => Some(away_from_light_cull(m)),
            };
            let (pipeline, unclipped) = self.shadow.pipeline(reversed, m.needs_unclipped_depth, cull);
            if m.needs_unclipped_depth && !unclipped {
                unavailable += 1;
            }
            let timestamp_writes = self
                .timer
                .as_ref()
                .zip(timer)
                .and_then(|(t, q)| t.pass_writes(q, timing::Stage::Shadow, i == 0, i == last));
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some(&format!("lixel shadow pass {i}")),
                color_attachments: &[],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &self.shadow_maps.layer_views[i],
                    // Far is 1 (0 under a reversed test): nothing blocks.
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(if reversed { 0.0 } else { 1.0 }),
                        store: wgpu::StoreOp::Store,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            let (w, h) = (m.map_size.width, m.map_size.height);
            // Only the light's own rectangle at the top-left of the layer.
            pass.set_viewport(0.0, 0.0, w as f32, h as f32, 0.0, 1.0);
            pass.set_scissor_rect(0, 0, w, h);
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, &self.shadow.bind_group, &[(i as u64 * SHADOW_SLOT_STRIDE) as u32]);
            triangles += self.draw_scene(&mut pass, &m.clip_from_world, !unclipped);
        }
        (unavailable, triangles)
    }

    /// The SPSM passes (instead of the depth-only ones): one per slot,
    /// conservative, into the slot's depth layer and SPSM texel layer.
    fn encode_spsm_passes(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        slots: &[&LightMatrix],
        timer: Option<&timing::FrameQueries>,
        pass_data: &spsm::SpsmPass,
        texels: &spsm::SpsmTexels,
    ) -> (u32, u64) {
        let mut triangles = 0;
        let last = slots.len().saturating_sub(1);
        for (i, m) in slots.iter().enumerate() {
            let timestamp_writes = self
                .timer
                .as_ref()
                .zip(timer)
                .and_then(|(t, q)| t.pass_writes(q, timing::Stage::Shadow, i == 0, i == last));
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some(&format!("lixel spsm pass {i}")),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &texels.layer_views[i],
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations { load: wgpu::LoadOp::Clear(spsm::empty_clear()), store: wgpu::StoreOp::Store },
                })],
                depth_stencil_attachment: Some(depth_attachment(&self.shadow_maps.layer_views[i])),
                timestamp_writes,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            let (w, h) = (m.map_size.width, m.map_size.height);
            pass.set_viewport(0.0, 0.0, w as f32, h as f32, 0.0, 1.0);
            pass.set_scissor_rect(0, 0, w, h);
            pass.set_pipeline(&pass_data.pipeline);
            pass.set_bind_group(0, &pass_data.bind_group, &[(i as u64 * spsm::SLOT_STRIDE) as u32]);
            // Vertex pulling: vertex_index is the index slot. Depth is the
            // pass's own (never clipped), so culling ignores near and far; an
            // object outside the map's xy touches none of its texels.
            if self.options.cull_objects {
                for range in culling::visible_ranges(&self.scene.objects, &m.clip_from_world, false) {
                    triangles += u64::from(range.len() as u32 / 3);
                    pass.draw(range, 0..1);
                }
            } else {
                pass.draw(0..self.scene.index_count, 0..1);
                triangles += u64::from(self.scene.index_count / 3);
            }
        }
        (0, triangles)
    }

    /// Draws the scene, less the objects outside the clip volume of
    /// `clip_from_world` (with `clip_depth: false` for unclipped depth) when
    /// [`RendererOptions::cull_objects`] is set; returns the triangles drawn.
    fn draw_scene(&self, pass: &mut wgpu::RenderPass<'_>, clip_from_world: &glam::DMat4, clip_depth: bool) -> u64 {
        pass.set_vertex_buffer(0, self.scene.vertices.slice(..));
        pass.set_index_buffer(self.scene.indices.slice(..), wgpu::IndexFormat::Uint32);
        if !self.options.cull_objects {
            pass.draw_indexed(0..self.scene.index_count, 0, 0..1);
            return u64::from(self.scene.index_count / 3);
        }
        let mut triangles = 0;
        for range in culling::visible_ranges(&self.scene.objects, clip_from_world, clip_depth) {
            triangles += u64::from(range.len() as u32 / 3);
            pass.draw_indexed(range, 0, 0..1);
        }
        triangles
    }

    fn encode_camera_pass(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        camera: &Camera,
        masks: bool,
        timer: Option<&timing::FrameQueries>,
    ) -> u64 {
        let targets = self.camera_targets.as_ref().expect("created by ensure_resources");
        let bg = self.options.background.as_dvec3();
        let mut color_attachments = vec![Some(wgpu::RenderPassColorAttachment {
            view: &targets.color.view,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations {
                load: wgpu::LoadOp::Clear(wgpu::Color { r: bg.x, g: bg.y, b: bg.z, a: 1.0 }),
                store: wgpu::StoreOp::Store,
            },
        })];
        if masks {
            color_attachments.push(Some(masks_attachment(&targets.masks.view)));
        }
        let timestamp_writes =
            self.timer.as_ref().zip(timer).and_then(|(t, q)| t.pass_writes(q, timing::Stage::Camera, true, true));
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("lixel camera pass"),
            color_attachments: &color_attachments,
            depth_stencil_attachment: Some(depth_attachment(&targets.depth.view)),
            timestamp_writes,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(if masks { &self.passes.color_masks } else { &self.passes.color });
        pass.set_bind_group(0, self.camera_bindings.bind_group.as_ref(), &[]);
        self.draw_scene(&mut pass, &camera.clip_from_world(), true)
    }

    fn encode_analysis_pass(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        camera: &Camera,
        staging: &wgpu::Buffer,
        timer: Option<&timing::FrameQueries>,
    ) {
        let timestamp_writes =
            self.timer.as_ref().zip(timer).and_then(|(t, q)| t.pass_writes(q, timing::Stage::Analysis, true, true));
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("lixel analysis pass"),
                color_attachments: &[Some(masks_attachment(&self.analysis_masks.view))],
                depth_stencil_attachment: self.analysis_depth.as_ref().map(|t| depth_attachment(&t.view)),
                timestamp_writes,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_bind_group(0, self.analysis_bindings.bind_group.as_ref(), &[]);
            match self.options.analysis_source {
                AnalysisSource::CameraDepth => {
                    pass.set_pipeline(&self.passes.analysis_depth);
                    pass.draw(0..3, 0..1);
                }
                AnalysisSource::Geometry => {
                    pass.set_pipeline(&self.passes.analysis_geometry);
                    self.draw_scene(&mut pass, &camera.clip_from_world(), true);
                }
            }
        }
        let (w, h) = self.options.analysis_size;
        encoder.copy_texture_to_buffer(
            self.analysis_masks.texture.as_image_copy(),
            wgpu::TexelCopyBufferInfo {
                buffer: staging,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(analysis::padded_row_bytes(w) as u32),
                    rows_per_image: Some(h),
                },
            },
            wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 },
        );
    }
}

/// Masks attachment cleared to "background": depth 1.0's bits, no bits set.
fn masks_attachment(view: &wgpu::TextureView) -> wgpu::RenderPassColorAttachment<'_> {
    wgpu::RenderPassColorAttachment {
        view,
        depth_slice: None,
        resolve_target: None,
        ops: wgpu::Operations {
            // Integer targets take their clear value through f64; 1.0f32's
            // bits (0x3f80_0000) are exact in f64.
            load: wgpu::LoadOp::Clear(wgpu::Color { r: f64::from(1.0f32.to_bits()), g: 0.0, b: 0.0, a: 0.0 }),
            store: wgpu::StoreOp::Store,
        },
    }
}

fn depth_attachment(view: &wgpu::TextureView) -> wgpu::RenderPassDepthStencilAttachment<'_> {
    wgpu::RenderPassDepthStencilAttachment {
        view,
        depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Clear(1.0), store: wgpu::StoreOp::Store }),
        stencil_ops: None,
    }
}

fn check_target(width: u32, height: u32, max: u32) -> Result<(), RenderError> {
    if width == 0 || height == 0 || width > max || height > max {
        return Err(RenderError::TargetTooLarge { width, height, max });
    }
    Ok(())
}
