//! The viewer's state and its frame, independent of any window: the scene
//! on the GPU, the [`ShadowLoop`] of the chosen method, the camera, the
//! lights and the overlays. [`Viewer::render_to`] renders one frame into any
//! texture view; the window and [`Viewer::screenshot`] both call it.

use std::time::{Duration, Instant};

use glam::UVec2;

use super::composite::{Composite, CompositeRaw, Slot};
use super::truth::{self, ErrorCounts};
use super::{hud, CameraPath, FlyCamera, LightRig, Overlays, ViewConfig, ViewError, MAP_SIZES};
use crate::experiment::{self, MethodSpec};
use crate::mesh::RayCaster;
use crate::optimize::{OptimizeOptions, ScheduleOptions};
use crate::render::{
    shadow_map_image, Frame, GpuFrameTimes, LoopOptions, LoopPolicy, LoopView, ReadbackInfo, Renderer, RendererOptions,
    ShadowLookup, ShadowLoop,
};
use crate::{LightMatrix, SceneBounds, ShadowMapSize};

/// The format of [`Viewer::screenshot`]'s target (and so of a viewer made
/// for screenshots).
pub const SCREENSHOT_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;

/// What one frame did, for the HUD and for scripts.
#[derive(Clone, Debug, Default)]
pub struct FrameStats {
    /// Frames rendered so far (this one included).
    pub frames: u64,
    /// Wall time between this frame and the previous one (smoothed).
    pub frame_time: Duration,
    /// CPU time of solving and optimizing this frame's matrices.
    pub solve_and_optimize: Duration,
    /// The newest readback consumed (latency in frames and time).
    pub readback: Option<ReadbackInfo>,
    /// The newest GPU timestamps, where the device has them.
    pub gpu: Option<GpuFrameTimes>,
    /// Bit `i`: light `i` was optimized this frame.
    pub optimized: u32,
    /// The error overlay's counts, while it is valid.
    pub error: Option<ErrorCounts>,
}

/// An error overlay and the view it was computed for.
struct ErrorState {
    counts: ErrorCounts,
    frame: u64,
    key: ViewKey,
    image: image::RgbaImage,
}

/// What an error overlay depends on: the camera, the lights, the method and
/// the map (not the optimizer's later moves at the same view).
#[derive(Clone, Debug, PartialEq)]
struct ViewKey {
    camera: FlyCamera,
    size: UVec2,
    lights: Vec<crate::Light>,
    method: MethodSpec,
    map: u32,
}

/// The interactive viewer without its window. See the [module docs](super).
pub struct Viewer {
    device: wgpu::Device,
    queue: wgpu::Queue,
    config: ViewConfig,
    scene: crate::mesh::Scene,
    bounds: SceneBounds,
    renderer: Renderer,
    shadows: ShadowLoop,
    composite: Composite,
    caster: Option<RayCaster>,
    /// The camera; move it freely between frames.
    pub camera: FlyCamera,
    rig: LightRig,
    size: UVec2,
    map: u32,
    method: MethodSpec,
    overlays: Overlays,
    selected: usize,
    error_requested: bool,
    error: Option<ErrorState>,
    /// World positions of each light's boundary samples from the last
    /// readback the loop consumed.
    boundary: Vec<Vec<glam::DVec3>>,
    /// The screen overlay texture holds the samples (not only the error).
    samples_drawn: bool,
    matrices: Vec<LightMatrix>,
    stats: FrameStats,
    last_frame: Option<Instant>,
    last_submission: Option<wgpu::SubmissionIndex>,
}

impl std::fmt::Debug for Viewer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Viewer")
            .field("method", &self.method)
            .field("map", &self.map)
            .field("size", &self.size)
            .field("overlays", &self.overlays)
            .finish_non_exhaustive()
    }
}

impl Viewer {
    /// Loads the scene, uploads it and builds the passes for targets of
    /// `format` ([`SCREENSHOT_FORMAT`] for screenshots).
    ///
    /// # Errors
    /// [`ViewError::Experiment`] for an unreadable scene or a degenerate
    /// camera; [`ViewError::Render`] for device errors;
    /// [`ViewError::Config`] for more than 32 lights or a zero map size.
    pub fn new(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        config: ViewConfig,
        format: wgpu::TextureFormat,
    ) -> Result<Self, ViewError> {
        if config.lights == 0 || config.lights > crate::MAX_LIGHTS {
            return Err(ViewError::Config(format!(
                "{} lights; 1 to {} are supported",
                config.lights,
                crate::MAX_LIGHTS
            )));
        }
        if config.experiment.map == 0 || config.experiment.screen == 0 {
            return Err(ViewError::Config("map and screen sizes must be positive".into()));
        }
        let scene = experiment::load_scene(&config.experiment.scene)?;
        let start = experiment::camera_for(&config.experiment, &scene)?;
        let bounds = scene.bounds();
        let centre = bounds.scene().center();
        let target = start.eye() + start.view_direction() * (centre - start.eye()).length().max(start.z_near() * 10.0);
        let mut camera =
            FlyCamera::look_at(start.eye(), target, config.experiment.fov_y_degrees.to_radians(), start.z_far());
        camera.near = start.z_near();
        let renderer = Renderer::new(device, queue, &scene, RendererOptions::default())?;
        let rig = LightRig::new(&config.experiment, &scene, config.lights);
        let shadows = new_loop(config.method, config.lights, config.schedule)?;
        Ok(Self {
            device: device.clone(),
            queue: queue.clone(),
            composite: Composite::new(device, queue, format)?,
            bounds,
            renderer,
            shadows,
            caster: None,
            camera,
            rig,
            size: UVec2::splat(config.experiment.screen),
            map: config.experiment.map,
            method: config.method,
            overlays: config.overlays,
            selected: 0,
            error_requested: config.overlays.error,
            error: None,
            boundary: Vec::new(),
            samples_drawn: false,
            matrices: Vec::new(),
            stats: FrameStats::default(),
            last_frame: None,
            last_submission: None,
            scene,
            config,
        })
    }

    /// The overlays drawn.
    #[must_use]
    pub fn overlays(&self) -> Overlays {
        self.overlays
    }

    /// Sets the overlays; turning the error overlay on computes it at the
    /// next frame.
    pub fn set_overlays(&mut self, overlays: Overlays) {
        if overlays.error && !self.overlays.error {
            self.error_requested = true;
        }
        self.overlays = overlays;
    }

    /// Computes the error overlay against the ray-cast truth at the next
    /// frame (and shows it).
    pub fn request_error(&mut self) {
        self.overlays.error = true;
        self.error_requested = true;
    }

    /// The method every light uses.
    #[must_use]
    pub fn method(&self) -> MethodSpec {
        self.method
    }

    /// Switches every light to `method`, its lookup included (a new frame
    /// loop: a scene-optimized loop starts from focused matrices).
    ///
    /// # Errors
    /// [`ViewError::Config`] when the loop cannot be made.
    pub fn set_method(&mut self, method: MethodSpec) -> Result<(), ViewError> {
        self.method = method;
        self.restart_loop()
    }

    /// Keeps the matrix method and steps to the next lookup mode of
    /// [`ShadowLookup::ALL`].
    ///
    /// # Errors
    /// As [`set_method`](Self::set_method).
    pub fn next_lookup(&mut self) -> Result<(), ViewError> {
        let all = ShadowLookup::ALL;
        let i = all.iter().position(|&l| l == self.method.lookup()).unwrap_or(0);
        self.set_method(self.method.with_lookup(all[(i + 1) % all.len()]))
    }

    /// The square map size.
    #[must_use]
    pub fn map_size(&self) -> u32 {
        self.map
    }

    /// Steps the map size through [`MAP_SIZES`] (`up`: larger).
    ///
    /// # Errors
    /// As [`set_method`](Self::set_method).
    pub fn step_map_size(&mut self, up: bool) -> Result<(), ViewError> {
        let next = if up {
            MAP_SIZES.iter().copied().find(|&s| s > self.map)
        } else {
            MAP_SIZES.iter().rev().copied().find(|&s| s < self.map)
        };
        if let Some(size) = next {
            self.map = size;
            self.restart_loop()?;
        }
        Ok(())
    }

    /// The analysis cadence (frames between analysis passes).
    #[must_use]
    pub fn cadence(&self) -> u32 {
        self.config.schedule.optimize_every
    }

    /// Sets the analysis cadence (1 to 60 frames).
    ///
    /// # Errors
    /// As [`set_method`](Self::set_method).
    pub fn set_cadence(&mut self, every: u32) -> Result<(), ViewError> {
        self.config.schedule.optimize_every = every.clamp(1, 60);
        self.restart_loop()
    }

    /// Selects the next light for the density, grid and shadow-map overlays.
    pub fn next_light(&mut self) {
        self.selected = (self.selected + 1) % self.rig.len().max(1);
    }

    /// Moves every light over its hemisphere (radians).
    ///
    /// # Errors
    /// As [`set_method`](Self::set_method).
    pub fn rotate_lights(&mut self, azimuth: f64, elevation: f64) -> Result<(), ViewError> {
        self.rig.rotate(azimuth, elevation);
        // Optimized matrices belong to the old light positions.
        self.restart_loop()
    }

    /// The viewport in pixels.
    #[must_use]
    pub fn size(&self) -> UVec2 {
        self.size
    }

    /// Sets the viewport (the window's size); zero sizes are ignored.
    pub fn resize(&mut self, size: UVec2) {
        if size.x > 0 && size.y > 0 {
            self.size = size;
        }
    }

    /// The matrices of the last frame, one per light.
    #[must_use]
    pub fn matrices(&self) -> &[LightMatrix] {
        &self.matrices
    }

    /// The last frame's statistics.
    #[must_use]
    pub fn stats(&self) -> &FrameStats {
        &self.stats
    }

    /// The renderer (for its adapter and statistics).
    #[must_use]
    pub fn renderer(&self) -> &Renderer {
        &self.renderer
    }

    fn restart_loop(&mut self) -> Result<(), ViewError> {
        self.shadows = new_loop(self.method, self.rig.len(), self.config.schedule)?;
        self.renderer.discard_analyses();
        self.boundary.clear();
        Ok(())
    }

    fn key(&self) -> ViewKey {
        ViewKey { camera: self.camera, size: self.size, lights: self.rig.lights(), method: self.method, map: self.map }
    }

    /// Renders one frame into `target` (a view of a texture of the format
    /// the viewer was made for, at [`size`](Self::size)), keeping at most one
    /// frame in flight.
    ///
    /// # Errors
    /// [`ViewError::Render`] for device errors; [`ViewError::Experiment`]
    /// when a matrix cannot be solved (a camera inside degenerate bounds).
    pub fn render_to(&mut self, target: &wgpu::TextureView) -> Result<&FrameStats, ViewError> {
        let camera = self.camera.camera(self.size)?;
        let lights = self.rig.lights();
        let view =
            LoopView { camera: &camera, lights: &lights, bounds: self.bounds, map: ShadowMapSize::square(self.map) };
        let done = self.shadows.frame(&mut self.renderer, &view)?;
        self.matrices.clone_from(&done.matrices);
        self.stats.solve_and_optimize = done.solve_time + done.optimize_time;
        self.stats.optimized = done.optimized;
        if done.readback.is_some() {
            self.stats.readback = done.readback;
            self.boundary.clone_from(&done.boundary_samples);
        }
        if let Some(times) = self.renderer.try_take_gpu_times() {
            self.stats.gpu = Some(times);
        }
        let key = self.key();
        if self.error.as_ref().is_some_and(|e| e.key != key) {
            self.error = None;
        }
        if self.error_requested {
            self.error_requested = false;
            self.compute_error(&camera, &lights, key)?;
        }
        self.selected = self.selected.min(self.matrices.len().saturating_sub(1));
        let screen_overlay = self.upload_screen_overlay(&camera);
        let map_rect = self.upload_shadow_map()?;
        let hud_rect = self.upload_hud();
        let (color, depth) = self.renderer.camera_textures().ok_or(crate::render::RenderError::NothingRendered)?;
        let light = self.matrices.get(self.selected).map_or(glam::Mat4::ZERO, LightMatrix::clip_from_world_f32);
        let mut raw = CompositeRaw::new(camera.clip_from_world().inverse().as_mat4(), light);
        let map = self.matrices.get(self.selected).map_or((1, 1), |m| (m.map_size.width, m.map_size.height));
        raw.sizes = [self.size.x as f32, self.size.y as f32, map.0 as f32, map.1 as f32];
        raw.flags = [u32::from(self.overlays.density), u32::from(self.overlays.grid), u32::from(screen_overlay), 0];
        raw.map_rect = map_rect;
        raw.hud_rect = hud_rect;
        let mut encoder =
            self.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("lixel view composite") });
        let (color, depth) = (color.clone(), depth.clone());
        let submission = crate::render::device::capture(&self.device, "viewer composite pass", || {
            self.composite.encode(&mut encoder, target, &color, &depth, raw);
            self.queue.submit([encoder.finish()])
        })?;
        // At most one frame in flight: wait for the previous one.
        if let Some(previous) = self.last_submission.replace(submission) {
            self.renderer.wait_for(&previous)?;
        }
        let now = Instant::now();
        if let Some(last) = self.last_frame.replace(now) {
            let dt = now - last;
            let smoothed = self.stats.frame_time;
            self.stats.frame_time = if smoothed.is_zero() { dt } else { smoothed.mul_f64(0.9) + dt.mul_f64(0.1) };
        }
        self.stats.frames += 1;
        self.stats.error = self.error.as_ref().map(|e| e.counts);
        Ok(&self.stats)
    }

    /// Renders the frame again with masks and compares them with the
    /// ray-cast truth (blocks: the BVH is built on first use).
    fn compute_error(
        &mut self,
        camera: &crate::Camera,
        lights: &[crate::Light],
        key: ViewKey,
    ) -> Result<(), ViewError> {
        let report = self.renderer.render(&Frame {
            camera,
            lights: &self.matrices,
            masks: true,
            analysis: None,
            lookup: self.method.lookup(),
        })?;
        self.renderer.wait_for(&report.submission)?;
        let masks = self.renderer.read_masks()?;
        let caster = self.caster.get_or_insert_with(|| RayCaster::new(&self.scene));
        let truth = truth::truth(caster, camera, lights);
        let (image, counts) = truth::compare(&masks, &truth, lights.len());
        self.composite.upload(Slot::Error, &image);
        self.samples_drawn = false;
        self.error = Some(ErrorState { counts, frame: self.stats.frames + 1, key, image });
        Ok(())
    }

    /// The boundary samples of each light from the last readback the loop
    /// consumed (world positions; empty before the first, or for methods
    /// without analysis).
    #[must_use]
    pub fn boundary_samples(&self) -> &[Vec<glam::DVec3>] {
        &self.boundary
    }

    /// Uploads the screen-sized overlay (the error picture, the boundary
    /// samples drawn over it) when either is on; returns whether one is shown.
    fn upload_screen_overlay(&mut self, camera: &crate::Camera) -> bool {
        let error = self.error.as_ref().filter(|_| self.overlays.error);
        if !self.overlays.samples {
            if self.samples_drawn {
                // Put the plain error picture back.
                if let Some(e) = error {
                    self.composite.upload(Slot::Error, &e.image);
                }
                self.samples_drawn = false;
            }
            return error.is_some();
        }
        let mut picture = match error {
            Some(e) => e.image.clone(),
            None => image::RgbaImage::new(self.size.x, self.size.y),
        };
        let screen_from_world = camera.screen_from_world();
        let points = self.boundary.get(self.selected).map_or(&[][..], Vec::as_slice);
        for &p in points {
            let v = screen_from_world * p.extend(1.0);
            if !(v.w > 0.0) {
                continue;
            }
            draw_cross(&mut picture, v.x / v.w, v.y / v.w);
        }
        self.composite.upload(Slot::Error, &picture);
        self.samples_drawn = true;
        true
    }

    /// Uploads the selected light's map when that overlay is on; returns its
    /// rectangle in the bottom-right corner (width 0: off).
    fn upload_shadow_map(&mut self) -> Result<[f32; 4], ViewError> {
        if !self.overlays.shadow_map || self.matrices.is_empty() {
            return Ok([0.0; 4]);
        }
        let map = self.renderer.read_shadow_map(self.selected)?;
        self.composite.upload(Slot::Map, &shadow_map_image(&map));
        let side = (0.3 * self.size.x.min(self.size.y) as f32).max(16.0);
        let (w, h) = (map.width as f32, map.height as f32);
        let scale = side / w.max(h);
        let (rw, rh) = ((w * scale).round().max(1.0), (h * scale).round().max(1.0));
        Ok([self.size.x as f32 - rw - 8.0, self.size.y as f32 - rh - 8.0, rw, rh])
    }

    /// The HUD's lines.
    #[must_use]
    pub fn hud_lines(&self) -> Vec<String> {
        let s = &self.stats;
        let ms = |d: Duration| d.as_secs_f64() * 1e3;
        let fps = if s.frame_time.is_zero() { 0.0 } else { 1.0 / s.frame_time.as_secs_f64() };
        let n = self.rig.len();
        let mut lines = vec![
            format!("{} map {}² light {}/{n}", self.method, self.map, self.selected),
            format!(
                "frame {}: {:.1} ms ({fps:.1} fps) cpu {:.1} ms",
                s.frames,
                ms(s.frame_time),
                ms(s.solve_and_optimize)
            ),
        ];
        if let Some(gpu) = &s.gpu {
            let part = |d: Option<Duration>| d.map_or_else(|| "-".to_string(), |d| format!("{:.1}", ms(d)));
            lines.push(format!(
                "GPU ms: shadow {} camera {} analysis {}",
                part(gpu.shadow),
                part(gpu.camera),
                part(gpu.analysis)
            ));
        }
        if self.shadows.policy().analyses() {
            lines.push(match &s.readback {
                Some(r) => format!(
                    "readback {} fr, {:.1} ms | analysis every {}",
                    r.latency.frames,
                    ms(r.latency.ready),
                    self.cadence()
                ),
                None => format!("readback: none yet | analysis every {}", self.cadence()),
            });
            match self.shadows.scheduler().last_report(self.selected) {
                Some(r) => {
                    lines.push(format!(
                        "optimizer: {} median b {:.3} (prev {})",
                        if r.accepted { "accepted" } else { "kept" },
                        r.median_new,
                        r.median_prev.map_or_else(|| "-".to_string(), |p| format!("{p:.3}")),
                    ));
                    if let Some(f) = &r.fallback {
                        lines.push(format!("  fallback {f:?}"));
                    }
                }
                None => lines.push("optimizer: no report yet (focused)".to_string()),
            }
        }
        if self.overlays.error {
            lines.push(match &self.error {
                Some(e) => format!(
                    "error f{}: {} false shadow, {} false light / {}",
                    e.frame, e.counts.false_shadow, e.counts.false_light, e.counts.counted
                ),
                None => "error: view changed, press X".to_string(),
            });
        }
        lines.push("1-8 method K lookup [ ] map , . cadence L light".to_string());
        lines.push("T density G grid X error B samples M map H hud O orbit".to_string());
        lines.push("WASD QE fly, drag look, wheel zoom, arrows light".to_string());
        lines
    }

    /// Uploads the HUD when it is on; returns its rectangle (width 0: off).
    fn upload_hud(&mut self) -> [f32; 4] {
        if !self.overlays.hud {
            return [0.0; 4];
        }
        let picture = hud::render(&self.hud_lines(), self.overlays.density);
        self.composite.upload(Slot::Hud, &picture);
        let (w, h) = self.composite.picture_size(Slot::Hud);
        [8.0, 8.0, w.min(self.size.x) as f32, h.min(self.size.y) as f32]
    }

    /// Renders `frames` frames offscreen (the camera following `path` when
    /// given, frame by frame) and returns the last one. Needs no display.
    /// The viewer must have been made for [`SCREENSHOT_FORMAT`].
    ///
    /// # Errors
    /// As [`render_to`](Self::render_to); [`ViewError::Config`] for zero
    /// frames.
    pub fn screenshot(&mut self, frames: u64, path: Option<&CameraPath>) -> Result<image::RgbaImage, ViewError> {
        if frames == 0 {
            return Err(ViewError::Config("--frames must be at least 1".into()));
        }
        let (w, h) = (self.size.x, self.size.y);
        let texture = crate::render::device::capture(&self.device, "viewer screenshot target", || {
            self.device.create_texture(&wgpu::TextureDescriptor {
                label: Some("lixel view screenshot"),
                size: wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: SCREENSHOT_FORMAT,
                usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
                view_formats: &[],
            })
        })?;
        let view = texture.create_view(&wgpu::TextureViewDescriptor::default());
        for frame in 0..frames {
            if let Some(path) = path {
                let (eye, target) = path.at(frame);
                self.camera.eye = eye;
                self.camera.look_towards(target);
            }
            self.render_to(&view)?;
            // Each frame finishes before the next: readbacks arrive at the
            // same frames on every run.
            self.renderer.wait_idle()?;
        }
        read_texture(&self.device, &self.queue, &texture)
    }
}

/// The frame loop of `method` for `lights` lights.
fn new_loop(method: MethodSpec, lights: usize, schedule: ScheduleOptions) -> Result<ShadowLoop, ViewError> {
    if method.cascade().is_some() {
        return Err(ViewError::Config(format!("{method}: the viewer does not draw cascaded suns yet")));
    }
    let policy = method.parameterization(None).map_or(LoopPolicy::Optimized, LoopPolicy::Fixed);
    let strategy = method.search().strategy();
    let optimize = OptimizeOptions { strategy, ..Default::default() };
    let options = LoopOptions { schedule, optimize, lookup: method.lookup() };
    ShadowLoop::new(policy, lights, options).map_err(|e| ViewError::Config(e.to_string()))
}

/// Reads an RGBA8 texture back (rows padded to 256 bytes for the copy).
fn read_texture(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    texture: &wgpu::Texture,
) -> Result<image::RgbaImage, ViewError> {
    let (w, h) = (texture.width(), texture.height());
    let row = (4 * w).div_ceil(256) * 256;
    let buffer = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("lixel view screenshot readback"),
        size: u64::from(row) * u64::from(h),
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    let mut encoder =
        device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("lixel view screenshot") });
    encoder.copy_texture_to_buffer(
        texture.as_image_copy(),
        wgpu::TexelCopyBufferInfo {
            buffer: &buffer,
            layout: wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(row), rows_per_image: Some(h) },
        },
        wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 },
    );
    queue.submit([encoder.finish()]);
    let slice = buffer.slice(..);
    let (sender, receiver) = std::sync::mpsc::channel();
    slice.map_async(wgpu::MapMode::Read, move |r| {
        let _ = sender.send(r);
    });
    device.poll(wgpu::PollType::wait_indefinitely()).map_err(crate::render::RenderError::from)?;
    receiver
        .recv()
        .map_err(|_| ViewError::Config("screenshot readback was dropped".into()))?
        .map_err(crate::render::RenderError::from)?;
    let mapped = slice.get_mapped_range().map_err(|e| ViewError::Config(format!("screenshot readback: {e}")))?;
    let mut pixels = Vec::with_capacity((4 * w * h) as usize);
    for y in 0..h as usize {
        let start = y * row as usize;
        pixels.extend_from_slice(&mapped[start..start + 4 * w as usize]);
    }
    drop(mapped);
    buffer.unmap();
    image::RgbaImage::from_raw(w, h, pixels).ok_or_else(|| ViewError::Config("screenshot size mismatch".into()))
}

/// A magenta cross (5 pixels wide) centred on screen position `(x, y)`
/// (pixels, rows top-down as the masks); the parts off the picture are
/// skipped.
fn draw_cross(picture: &mut image::RgbaImage, x: f64, y: f64) {
    if !(x.is_finite() && y.is_finite()) {
        return;
    }
    let (cx, cy) = (x.floor() as i64, y.floor() as i64);
    for d in -2..=2i64 {
        for (px, py) in [(cx + d, cy), (cx, cy + d)] {
            if px >= 0 && py >= 0 && px < i64::from(picture.width()) && py < i64::from(picture.height()) {
                picture.put_pixel(px as u32, py as u32, image::Rgba([255, 0, 255, 255]));
            }
        }
    }
}
