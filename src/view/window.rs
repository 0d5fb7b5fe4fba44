//! The viewer's window: winit (X11) and a wgpu surface, keys and mouse
//! turned into [`Viewer`] calls. Everything else — the frame, the overlays,
//! the HUD — is the [`Viewer`]'s, shared with the offscreen screenshots.

use std::collections::HashSet;
use std::sync::Arc;
use std::time::{Duration, Instant};

use glam::{DVec3, UVec2};
use winit::application::ApplicationHandler;
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::keyboard::{Key, KeyCode, NamedKey, PhysicalKey};
use winit::window::{Window, WindowId};

use super::{CameraPath, ViewConfig, ViewError, Viewer};
use crate::experiment::MethodSpec;

/// What the window does besides showing the view.
#[derive(Clone, Debug, Default)]
pub struct WindowOptions {
    /// Close after this many frames (scripts, tests, frame-rate figures).
    pub frames: Option<u64>,
    /// Move the camera along this path.
    pub path: Option<CameraPath>,
    /// Turn the lights about the vertical axis (degrees per second).
    pub animate_degrees_per_second: f64,
}

/// What a window session measured.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct WindowSummary {
    /// Frames presented.
    pub frames: u64,
    /// Wall time from the first presented frame to the last.
    pub elapsed: Duration,
}

impl WindowSummary {
    /// Mean frames per second after the first frame (0 for fewer than two).
    #[must_use]
    pub fn fps(&self) -> f64 {
        if self.frames < 2 || self.elapsed.is_zero() {
            return 0.0;
        }
        (self.frames - 1) as f64 / self.elapsed.as_secs_f64()
    }
}

/// Opens a window on the view of `config` and runs until it is closed (or
/// `options.frames` were presented).
///
/// # Errors
/// [`ViewError::NoDisplay`] without a display (the message names
/// `--screenshot`); [`ViewError::Window`] when the window or its surface
/// cannot be made; the [`Viewer`]'s errors.
pub fn run_window(config: ViewConfig, options: WindowOptions) -> Result<WindowSummary, ViewError> {
    if cfg!(all(unix, not(target_os = "macos"))) && std::env::var_os("DISPLAY").is_none_or(|d| d.is_empty()) {
        let reason = if std::env::var_os("WAYLAND_DISPLAY").is_some() {
            "DISPLAY is not set; this build speaks X11 only (run XWayland)"
        } else {
            "DISPLAY is not set"
        };
        return Err(ViewError::NoDisplay { reason: reason.into() });
    }
    let event_loop = EventLoop::new().map_err(|e| ViewError::NoDisplay { reason: e.to_string() })?;
    event_loop.set_control_flow(ControlFlow::Poll);
    let mut app = App { config: Some(config), options, state: None, error: None, summary: WindowSummary::default() };
    event_loop.run_app(&mut app).map_err(|e| ViewError::Window(e.to_string()))?;
    match app.error {
        Some(e) => Err(e),
        None => Ok(app.summary),
    }
}

struct WindowState {
    window: Arc<Window>,
    surface: wgpu::Surface<'static>,
    surface_config: wgpu::SurfaceConfiguration,
    device: wgpu::Device,
    queue: wgpu::Queue,
    viewer: Viewer,
    held: HashSet<KeyCode>,
    drag: Option<MouseButton>,
    cursor: Option<(f64, f64)>,
    orbit: bool,
    animate: bool,
    last: Instant,
    first_frame: Option<Instant>,
}

struct App {
    config: Option<ViewConfig>,
    options: WindowOptions,
    state: Option<WindowState>,
    error: Option<ViewError>,
    summary: WindowSummary,
}

impl App {
    fn fail(&mut self, event_loop: &ActiveEventLoop, error: ViewError) {
        self.error.get_or_insert(error);
        event_loop.exit();
    }
}

/// The window, its surface and a device that can present to it.
fn open(event_loop: &ActiveEventLoop, config: ViewConfig) -> Result<WindowState, ViewError> {
    let size = config.experiment.screen;
    let attributes = Window::default_attributes()
        .with_title("lixel view")
        .with_inner_size(winit::dpi::PhysicalSize::new(size, size));
    let window = Arc::new(event_loop.create_window(attributes).map_err(|e| ViewError::Window(e.to_string()))?);
    let descriptor =
        wgpu::InstanceDescriptor::new_with_display_handle_from_env(Box::new(event_loop.owned_display_handle()));
    let instance = wgpu::Instance::new(descriptor);
    let surface = instance.create_surface(window.clone()).map_err(|e| ViewError::Window(e.to_string()))?;
    let adapter =
        pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            compatible_surface: Some(&surface),
            ..Default::default()
        }))
        .map_err(|e| crate::render::RenderError::NoAdapter { tried: e.to_string() })?;
    let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
        label: Some("lixel view"),
        required_features: adapter.features() & crate::render::Renderer::optional_features(),
        required_limits: wgpu::Limits {
            max_texture_dimension_2d: adapter.limits().max_texture_dimension_2d,
            ..wgpu::Limits::default()
        },
        ..Default::default()
    }))
    .map_err(|e| ViewError::Window(format!("device: {e}")))?;
    let inner = window.inner_size();
    let caps = surface.get_capabilities(&adapter);
    let format = caps.formats.iter().copied().find(wgpu::TextureFormat::is_srgb).or(caps.formats.first().copied());
    let mut surface_config = surface
        .get_default_config(&adapter, inner.width.max(1), inner.height.max(1))
        .ok_or_else(|| ViewError::Window("the adapter cannot present to this window".into()))?;
    surface_config.format = format.unwrap_or(surface_config.format);
    surface_config.present_mode = wgpu::PresentMode::AutoNoVsync;
    surface.configure(&device, &surface_config);
    let mut viewer = Viewer::new(&device, &queue, config, surface_config.format)?;
    viewer.resize(UVec2::new(surface_config.width, surface_config.height));
    Ok(WindowState {
        window,
        surface,
        surface_config,
        device,
        queue,
        viewer,
        held: HashSet::new(),
        drag: None,
        cursor: None,
        orbit: false,
        animate: false,
        last: Instant::now(),
        first_frame: None,
    })
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        let Some(config) = self.config.take() else { return };
        match open(event_loop, config) {
            Ok(state) => {
                state.window.request_redraw();
                self.state = Some(state);
            }
            Err(e) => self.fail(event_loop, e),
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        let Some(state) = self.state.as_mut() else { return };
        let result = match event {
            WindowEvent::CloseRequested => {
                event_loop.exit();
                Ok(())
            }
            WindowEvent::Resized(size) if size.width > 0 && size.height > 0 => {
                state.surface_config.width = size.width;
                state.surface_config.height = size.height;
                state.surface.configure(&state.device, &state.surface_config);
                state.viewer.resize(UVec2::new(size.width, size.height));
                Ok(())
            }
            WindowEvent::KeyboardInput { event, .. } => {
                if let PhysicalKey::Code(code) = event.physical_key {
                    match event.state {
                        ElementState::Pressed => state.held.insert(code),
                        ElementState::Released => state.held.remove(&code),
                    };
                }
                if event.state == ElementState::Pressed && !event.repeat {
                    if event.logical_key == Key::Named(NamedKey::Escape) {
                        event_loop.exit();
                        Ok(())
                    } else {
                        press(state, &event.logical_key)
                    }
                } else {
                    Ok(())
                }
            }
            WindowEvent::MouseInput { state: button_state, button, .. } => {
                state.drag = (button_state == ElementState::Pressed).then_some(button);
                Ok(())
            }
            WindowEvent::CursorMoved { position, .. } => {
                let (x, y) = (position.x, position.y);
                if let (Some(button), Some((px, py))) = (state.drag, state.cursor) {
                    let (dx, dy) = ((x - px) * 0.004, (y - py) * 0.004);
                    if state.orbit || button == MouseButton::Right {
                        state.viewer.camera.orbit(-dx, dy);
                    } else {
                        state.viewer.camera.turn(-dx, -dy);
                    }
                }
                state.cursor = Some((x, y));
                Ok(())
            }
            WindowEvent::MouseWheel { delta, .. } => {
                let lines = match delta {
                    MouseScrollDelta::LineDelta(_, y) => f64::from(y),
                    MouseScrollDelta::PixelDelta(p) => p.y / 40.0,
                };
                state.viewer.camera.zoom(0.1 * lines);
                Ok(())
            }
            WindowEvent::RedrawRequested => redraw(state, &self.options, &mut self.summary).map(|done| {
                if done {
                    event_loop.exit();
                }
            }),
            _ => Ok(()),
        };
        if let Err(e) = result {
            self.fail(event_loop, e);
        }
    }

    fn about_to_wait(&mut self, _event_loop: &ActiveEventLoop) {
        if let Some(state) = &self.state {
            state.window.request_redraw();
        }
    }
}

/// One key press.
fn press(state: &mut WindowState, key: &Key) -> Result<(), ViewError> {
    let viewer = &mut state.viewer;
    let mut overlays = viewer.overlays();
    let Key::Character(text) = key else {
        return Ok(());
    };
    match text.to_lowercase().as_str() {
        digit @ ("1" | "2" | "3" | "4" | "5" | "6" | "7" | "8") => {
            let i: usize = digit.parse().unwrap_or(1);
            // A digit picks the matrix method and keeps the lookup.
            viewer.set_method(MethodSpec::ALL[i - 1].with_lookup(viewer.method().lookup()))?;
        }
        "k" => viewer.next_lookup()?,
        "[" => viewer.step_map_size(false)?,
        "]" => viewer.step_map_size(true)?,
        "," => viewer.set_cadence(viewer.cadence().saturating_sub(1))?,
        "." => viewer.set_cadence(viewer.cadence() + 1)?,
        "t" => overlays.density = !overlays.density,
        "g" => overlays.grid = !overlays.grid,
        "m" => overlays.shadow_map = !overlays.shadow_map,
        "b" => overlays.samples = !overlays.samples,
        "h" => overlays.hud = !overlays.hud,
        "x" => {
            overlays.error = !overlays.error;
            if overlays.error {
                viewer.request_error();
                return Ok(());
            }
        }
        "l" => viewer.next_light(),
        "o" => state.orbit = !state.orbit,
        " " => state.animate = !state.animate,
        _ => return Ok(()),
    }
    viewer.set_overlays(overlays);
    Ok(())
}

/// Moves the camera and the lights for the time since the last frame,
/// renders and presents. Returns whether the frame budget is used up.
fn redraw(state: &mut WindowState, options: &WindowOptions, summary: &mut WindowSummary) -> Result<bool, ViewError> {
    let now = Instant::now();
    let dt = (now - state.last).as_secs_f64().min(0.25);
    state.last = now;
    let held = |code| state.held.contains(&code);
    let axis = |plus, minus| f64::from(u8::from(held(plus))) - f64::from(u8::from(held(minus)));
    let step = state.viewer.camera.speed * dt * if held(KeyCode::ShiftLeft) { 4.0 } else { 1.0 };
    let fly = DVec3::new(
        axis(KeyCode::KeyD, KeyCode::KeyA),
        axis(KeyCode::KeyE, KeyCode::KeyQ),
        axis(KeyCode::KeyW, KeyCode::KeyS),
    );
    if fly != DVec3::ZERO {
        state.viewer.camera.fly(fly * step);
    }
    let turn = (axis(KeyCode::ArrowRight, KeyCode::ArrowLeft), axis(KeyCode::ArrowUp, KeyCode::ArrowDown));
    let spin = if state.animate { options.animate_degrees_per_second.max(10.0).to_radians() * dt } else { 0.0 };
    if turn != (0.0, 0.0) || spin != 0.0 {
        state.viewer.rotate_lights(turn.0 * dt + spin, turn.1 * dt * 0.5)?;
    }
    if let Some(path) = &options.path {
        let (eye, target) = path.at(summary.frames);
        state.viewer.camera.eye = eye;
        state.viewer.camera.look_towards(target);
    }
    let frame = match state.surface.get_current_texture() {
        wgpu::CurrentSurfaceTexture::Success(t) | wgpu::CurrentSurfaceTexture::Suboptimal(t) => t,
        wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
            state.surface.configure(&state.device, &state.surface_config);
            return Ok(false);
        }
        wgpu::CurrentSurfaceTexture::Timeout | wgpu::CurrentSurfaceTexture::Occluded => return Ok(false),
        wgpu::CurrentSurfaceTexture::Validation => {
            return Err(ViewError::Window("the surface texture failed validation".into()));
        }
    };
    let view = frame.texture.create_view(&wgpu::TextureViewDescriptor::default());
    state.viewer.render_to(&view)?;
    state.window.pre_present_notify();
    state.queue.present(frame);
    let first = *state.first_frame.get_or_insert(now);
    summary.frames += 1;
    summary.elapsed = Instant::now() - first;
    Ok(options.frames.is_some_and(|n| summary.frames >= n))
}
