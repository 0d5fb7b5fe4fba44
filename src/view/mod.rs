//! `lixel view`: every method live, with the overlays that show where a
//! method spends its texels and where it errs (feature `view`).
//!
//! Why a module of its own: the viewer is an application of the library —
//! it drives [`ShadowLoop`](crate::render::ShadowLoop) like an engine would,
//! and adds what only a person looking at the picture needs — but the same
//! frame code must also run without a display, so that scripts and tests can
//! drive it. So the frame ([`Viewer::render_to`]) is rendered into any
//! texture view: the window's surface ([`run_window`], winit) or an offscreen
//! texture ([`Viewer::screenshot`]).
//!
//! One frame:
//!
//! ```text
//! FlyCamera (keys, mouse, or a --path file) ─▶ Camera
//! ShadowLoop::frame (matrices of the chosen method; analysis + optimizer for scene-optimized)
//! composite pass (shaders/view_composite.wgsl) over the camera pass's colour and depth:
//!     texel density  b = ‖J‖²/det(J)², J = ∂texel/∂pixel per pixel (score::badness on the GPU)
//!     texel grid     the shadow map's texel boundaries on the surfaces
//!     error          false shadow / false light against the ray-cast truth (on demand)
//!     shadow map     the selected light's map in a corner
//!     HUD            text rasterized on the CPU (ab_glyph), with the density legend
//! ```
//!
//! Nothing here panics on a wgpu or windowing error: they come back as
//! [`ViewError`].

mod camera;
mod composite;
mod hud;
mod lights;
mod path;
mod truth;
mod viewer;
mod window;

use std::path::PathBuf;

pub use camera::FlyCamera;
pub use hud::density_color;
pub use lights::LightRig;
pub use path::{CameraKey, CameraPath};
pub use truth::ErrorCounts;
pub use viewer::{FrameStats, Viewer, SCREENSHOT_FORMAT};
pub use window::{run_window, WindowOptions, WindowSummary};

use crate::experiment::{ExperimentConfig, ExperimentError, MethodSpec, Preset};
use crate::optimize::ScheduleOptions;
use crate::render::RenderError;

/// Why the viewer stopped.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ViewError {
    /// No display to open a window on.
    #[error(
        "no display to open a window on ({reason}); run it on an X11 display (or under Xvfb: `xvfb-run lixel view`), \
         or render offscreen with `--screenshot FILE --frames N`"
    )]
    NoDisplay {
        /// What was missing or what failed.
        reason: String,
    },
    /// The window or its surface could not be created.
    #[error("window: {0}")]
    Window(String),
    /// The renderer or the device failed.
    #[error("renderer: {0}")]
    Render(#[from] RenderError),
    /// The scene, the camera or a light is invalid, or a matrix could not be
    /// solved.
    #[error("{0}")]
    Experiment(#[from] ExperimentError),
    /// A camera path file is unreadable or malformed.
    #[error("camera path {path}: {reason}")]
    Path {
        /// The file.
        path: PathBuf,
        /// What is wrong (with the line number).
        reason: String,
    },
    /// A setting is out of range.
    #[error("{0}")]
    Config(String),
    /// Writing the screenshot failed.
    #[error("screenshot {path}: {reason}")]
    Screenshot {
        /// The file.
        path: PathBuf,
        /// The cause.
        reason: String,
    },
}

impl From<crate::render::LoopError> for ViewError {
    fn from(e: crate::render::LoopError) -> Self {
        match e {
            crate::render::LoopError::Render(e) => Self::Render(e),
            other => Self::Experiment(ExperimentError::Config(other.to_string())),
        }
    }
}

impl From<crate::LixelError> for ViewError {
    fn from(e: crate::LixelError) -> Self {
        Self::Experiment(ExperimentError::Solver(e))
    }
}

/// Which overlays are drawn over the camera picture.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Overlays {
    /// Each pixel coloured by its badness (screen pixels per texel, squared).
    pub density: bool,
    /// The shadow map's texel boundaries on the surfaces.
    pub grid: bool,
    /// False shadow / false light against the ray-cast truth (computed for
    /// the frame it was asked on; dropped when the view changes).
    pub error: bool,
    /// The selected light's shadow map in the bottom-right corner.
    pub shadow_map: bool,
    /// The text HUD (frame time, readback latency, optimizer report, keys).
    pub hud: bool,
    /// The boundary samples the optimizer used for the selected light (at
    /// their world positions, from the last readback), as magenta crosses.
    pub samples: bool,
}

impl Overlays {
    /// Parses a comma-separated list: `density`, `grid`, `error`, `map`,
    /// `hud`, `samples` (`none` for nothing).
    ///
    /// # Errors
    /// [`ViewError::Config`] naming an unknown overlay.
    pub fn parse(list: &str) -> Result<Self, ViewError> {
        let mut o = Self::default();
        for name in list.split(',').map(str::trim).filter(|n| !n.is_empty()) {
            match name {
                "density" => o.density = true,
                "grid" => o.grid = true,
                "error" => o.error = true,
                "map" => o.shadow_map = true,
                "hud" => o.hud = true,
                "samples" => o.samples = true,
                "none" => {}
                other => {
                    return Err(ViewError::Config(format!(
                        "unknown overlay {other:?}; valid: density, grid, error, map, hud, samples, none"
                    )))
                }
            }
        }
        Ok(o)
    }
}

/// Everything the viewer starts from.
#[derive(Clone, Debug)]
pub struct ViewConfig {
    /// Scene, default camera (eye, target, field of view), light kind and
    /// seed, window size (`screen`) and map size (`map`): as the experiment's
    /// preset gives them.
    pub experiment: ExperimentConfig,
    /// Lights: the experiment's configurations `0..lights` (at most 32).
    pub lights: usize,
    /// The method every light uses, with its shadow lookup.
    pub method: MethodSpec,
    /// Overlays drawn at the start.
    pub overlays: Overlays,
    /// Cadence of the analysis passes (scene-optimized).
    pub schedule: ScheduleOptions,
}

impl ViewConfig {
    /// The viewer on `preset`: one light, scene-optimized, the HUD on.
    #[must_use]
    pub fn preset(preset: Preset) -> Self {
        Self {
            experiment: ExperimentConfig::preset(preset),
            lights: 1,
            method: MethodSpec::OPTIMIZED,
            overlays: Overlays { hud: true, ..Overlays::default() },
            schedule: ScheduleOptions::default(),
        }
    }
}

/// Map sizes the `[` and `]` keys step through.
pub const MAP_SIZES: [u32; 8] = [128, 256, 400, 512, 1024, 2048, 4096, 8192];
