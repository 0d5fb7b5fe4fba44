//! The misclassification experiment of Chong & Gortler 2006, section 3
//! (their Table 1), made a tool: for many light positions, render the shadow
//! of every method at the same map resolution and count the screen pixels
//! whose shadow bit differs from exact ground truth.
//!
//! One configuration (a light position) runs:
//!
//! 1. ground truth: a ray from every visible pixel's surface point to the
//!    light against all triangles ([`RayCaster`](crate::mesh::RayCaster)), and/or the paper's
//!    focused 4000² map;
//! 2. every method's matrix (scene-optimized ones through the frame loop at
//!    the fixed configuration until the optimizer stops switching);
//! 3. the camera pass's full-resolution masks; a pixel counts when it is
//!    visible, on a receiver facing the light, and its bit differs from the
//!    truth. One bias policy ([`ShadowBias`](crate::render::ShadowBias)'s
//!    default) serves every method.

mod batch;
mod cascades;
mod coverage;
mod finish;
pub mod framing;
mod guard;
mod identity;
mod images;
mod merge;
mod method;
mod plots;
mod report;
mod rows;
mod rundir;
mod runner;
mod shard;
pub mod stability;
mod stages;
mod timing;
mod workers;

use std::path::PathBuf;
use std::time::Instant;

use glam::{DVec3, UVec2};

use crate::mesh::{LoadReport, Scene, SceneOptions};
use crate::render::{LoopError, RenderError};
use crate::{Camera, Light, LixelError};

pub use cascades::{check_cascades, fold_cascade_masks, large_scene};
pub use coverage::{facet_reference, facet_reference_words, Coverage, VisibilityError};
pub use identity::{Identity, RESULT_NEUTRAL_SETTINGS};
pub use images::error_overlay;
pub use merge::{merge, MergeOptions};
pub use method::{CascadeMethod, MethodSpec, Search};
pub use report::{markdown, MethodSummary, Summary};
pub use rows::ConfigRow;
pub use rundir::{report_dir, write_atomic};
use runner::nearest_view_depth;
pub use runner::{experiment_renderer_options, ConfigOutcome, Counts, MethodResult, Runner};
pub use shard::{Shard, ShardError};
pub use stages::{RunStage, RunStages};
pub use timing::{run_timing, timing_markdown, RatioEstimate, StageTimes, TimingOptions, TimingRow, PIPELINES};
pub use workers::default_jobs;

/// Which ground truth the counts use.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Truth {
    /// Exact ray casting (independent of every method). The default.
    #[value(name = "raytrace")]
    RayCast,
    /// The paper's reference: a focused 4000x4000 map.
    Focused4000,
    /// Count against ray casting and also report how often the two disagree.
    Both,
}

/// Point lights on a distant hemisphere, or directional lights from it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum LightKind {
    /// Point lights (the paper's setting).
    Point,
    /// Directional lights (sun-like).
    Directional,
}

/// Where the scene comes from.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum SceneSource {
    /// The procedural scene with this triangle budget.
    Builtin {
        /// Triangle budget.
        triangles: usize,
    },
    /// The large view's procedural scene ([`large_scene`]): 40×40 objects
    /// over a 2000-unit floor, for cascades (`--preset large`).
    Large {
        /// Triangle budget.
        triangles: usize,
    },
    /// A scene file (OBJ, glTF 2.0) with how to orient, scale and floor it.
    File {
        /// The file.
        path: PathBuf,
        /// Up axis, scale, floor.
        options: SceneOptions,
    },
}

/// Everything an experiment run depends on. Serialized (without `out`,
/// `resume` and `force`) as the `settings` of `settings.json`, the run's
/// identity ([`Identity`]).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ExperimentConfig {
    /// The scene.
    pub scene: SceneSource,
    /// Eye position; `None`: for the built-in scene a little above the floor
    /// at the scene's edge, for a file [`framing`] around the model.
    pub eye: Option<DVec3>,
    /// Look-at point; `None`: the scene centre, slightly above the floor
    /// (built-in scene) or the model's bounding-sphere centre (files).
    pub target: Option<DVec3>,
    /// Vertical field of view in degrees.
    pub fov_y_degrees: f64,
    /// Light kind.
    pub light: LightKind,
    /// Radius of the light hemisphere, in scene diagonals.
    pub light_distance: f64,
    /// Number of configurations (light positions).
    pub configs: usize,
    /// Seed of the light positions.
    pub seed: u64,
    /// Square screen resolution.
    pub screen: u32,
    /// Square shadow-map resolution (of each cascade when `cascades` > 0;
    /// see [`single_map`](Self::single_map)).
    pub map: u32,
    /// Cascades per sun of the cascade methods ([`CascadeMethod`]; 0: none).
    /// At equal total texels: each cascade has `map²` texels, the methods
    /// with one map per light [`single_map`](Self::single_map)`²` =
    /// `(map·√cascades)²`. Needs directional lights. Runs from before the
    /// field read as 0 (and a run without cascades records none).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub cascades: usize,
    /// Methods to compare.
    pub methods: Vec<MethodSpec>,
    /// Ground truth.
    pub truth: Truth,
    /// Most frames the scene-optimized frame loop may take to settle.
    pub max_optimize_frames: usize,
    /// Resolution equivalence on the first this-many configurations (0: off).
    pub equivalence_configs: usize,
    /// Focused map resolutions tried for the equivalence.
    pub equivalence_ladder: Vec<u32>,
    /// Sub-samples per pixel of the coverage truth behind
    /// `mean_visibility_error` (8, 16 or 32; 0: off, the default but for the
    /// quick preset: it costs 15-25 times the centre-sample truth). Needs the
    /// ray-cast truth. Runs from before the field read as 0.
    #[serde(default)]
    pub coverage_samples: u32,
    /// Run only the configurations `k` with `k mod count = index`; the
    /// report goes to `out/shard-I-of-N` (see [`Shard`]).
    pub shard: Option<Shard>,
    /// Report directory.
    #[serde(skip)]
    pub out: PathBuf,
    /// Continue an interrupted run.
    #[serde(skip)]
    pub resume: bool,
    /// Move a previous report in `out` aside (into `out/replaced-N/`) instead
    /// of refusing to start.
    #[serde(skip)]
    pub force: bool,
    /// Configurations run at once, each by a worker with its own device and
    /// renderer (the scene, ray caster and primary rays shared); 0: as many
    /// as [`default_jobs`] says. Changes no result: rows, `summary.csv`
    /// and the report's figures are the same for every value (see
    /// `workers.rs`). Not recorded in the run's identity.
    #[serde(skip)]
    pub jobs: usize,
}

/// `serde`'s `skip_serializing_if` for counts that default to 0.
#[allow(clippy::trivially_copy_pass_by_ref)]
fn is_zero(n: &usize) -> bool {
    *n == 0
}

/// Named presets.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Preset {
    /// Small enough for CI (well under two minutes).
    Quick,
    /// The main job: minutes on a 2-core machine.
    Default,
    /// The paper's setting: 1.1M triangles, 500 point lights, 750² screen, 400² maps.
    Paper,
    /// Cascaded suns on a large view: the eye 1.7 units above a 2000-unit
    /// floor, far plane 1500 ([`SceneSource::Large`]); 6 directional
    /// lights, 4 cascades of 1024² against one 2048² map, the cascade
    /// methods with focused and LiSPSM.
    Large,
}

impl ExperimentConfig {
    /// The configuration of a preset.
    #[must_use]
    pub fn preset(preset: Preset) -> Self {
        let base = Self {
            scene: SceneSource::Builtin { triangles: 200_000 },
            eye: None,
            target: None,
            fov_y_degrees: 60.0,
            light: LightKind::Point,
            light_distance: 5.0,
            configs: 40,
            seed: 2006,
            screen: 512,
            map: 400,
            methods: MethodSpec::ALL.to_vec(),
            cascades: 0,
            truth: Truth::Both,
            max_optimize_frames: 12,
            equivalence_configs: 10,
            equivalence_ladder: vec![400, 500, 640, 800, 1000, 1250, 1600, 2000, 2500, 3200, 4000],
            coverage_samples: 0,
            shard: None,
            out: PathBuf::from("report"),
            resume: false,
            force: false,
            jobs: 0,
        };
        match preset {
            Preset::Default => base,
            Preset::Quick => Self {
                scene: SceneSource::Builtin { triangles: 8_000 },
                configs: 6,
                screen: 192,
                map: 256,
                truth: Truth::Both,
                max_optimize_frames: 6,
                equivalence_configs: 2,
                equivalence_ladder: vec![256, 512, 1024],
                coverage_samples: 32,
                ..base
            },
            Preset::Paper => Self {
                scene: SceneSource::Builtin { triangles: 1_137_772 },
                configs: 500,
                screen: 750,
                map: 400,
                truth: Truth::RayCast,
                equivalence_configs: 50,
                ..base
            },
            Preset::Large => Self {
                scene: SceneSource::Large { triangles: 300_000 },
                light: LightKind::Directional,
                configs: 6,
                screen: 512,
                map: 1024,
                cascades: 4,
                methods: [MethodSpec::FOCUSED, MethodSpec::LISPSM].into_iter().chain(MethodSpec::CASCADED).collect(),
                truth: Truth::RayCast,
                equivalence_configs: 0,
                ..base
            },
        }
    }

    /// The square map of a method with one map per light: `map` without
    /// cascades, else the size with the texels of `cascades` maps of
    /// `map²`, `round(map·√cascades)`.
    #[must_use]
    pub fn single_map(&self) -> u32 {
        if self.cascades == 0 {
            return self.map;
        }
        (f64::from(self.map) * (self.cascades as f64).sqrt()).round() as u32
    }
}

/// Why an experiment stopped.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ExperimentError {
    /// The scene could not be loaded.
    #[error("scene: {0}")]
    Scene(String),
    /// The renderer failed.
    #[error("renderer: {0}")]
    Render(#[from] RenderError),
    /// Reading or writing the report failed.
    #[error("report {path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// A configuration is invalid.
    #[error("configuration: {0}")]
    Config(String),
    /// The camera or a light is invalid.
    #[error("solver: {0}")]
    Solver(#[from] LixelError),
    /// `out` holds a report and neither `resume` nor `force` was given.
    #[error(
        "{} already holds a report; pass --resume to continue it, --force to move it aside (into {}/replaced-N/), or another --out",
        dir.display(), dir.display()
    )]
    ReportExists {
        /// The report directory.
        dir: PathBuf,
    },
    /// Another run holds the report directory's lock.
    #[error("{} is in use by another lixel run ({}); wait for it or choose another --out", dir.display(), pid.map_or_else(|| "PID unknown".to_string(), |p| format!("PID {p}")))]
    Locked {
        /// The report directory.
        dir: PathBuf,
        /// The holder's process id, when it recorded one.
        pid: Option<u32>,
    },
    /// `--resume` or `merge` met a report made with different, result-changing settings.
    #[error("{context}: {setting} differs: recorded {recorded}, now {now}")]
    SettingsDiffer {
        /// What was being checked (a directory and the operation).
        context: String,
        /// The setting (and its flag).
        setting: String,
        /// The value recorded in `settings.json`.
        recorded: String,
        /// The value of this run.
        now: String,
    },
    /// A size is beyond what the device or the machine's memory allows.
    #[error("{flag} {value} is too large: {limit}")]
    TooLarge {
        /// The flag (or setting) at fault.
        flag: &'static str,
        /// Its value.
        value: String,
        /// The limit, with its source.
        limit: String,
    },
    /// No configuration counted a single pixel: the camera sees no lit receiver.
    #[error(
        "all {configs} configurations counted 0 pixels (no visible receiver faces the light): the camera sees nothing of the scene; aim it with --eye x,y,z and --target x,y,z"
    )]
    NothingCounted {
        /// Configurations run.
        configs: usize,
    },
    /// A cascade method, or `--cascades`, in a run that cannot cascade.
    #[error("{what}: {reason}")]
    Cascades {
        /// The method or flag at fault.
        what: String,
        /// Why.
        reason: &'static str,
    },
    /// `merge` found configurations missing or run by more than one shard.
    #[error("merge: {}{}{}", list("missing configurations", missing), if !missing.is_empty() && !duplicated.is_empty() { "; " } else { "" }, list("configurations in more than one directory", duplicated))]
    Incomplete {
        /// Configurations no directory holds.
        missing: Vec<usize>,
        /// Configurations more than one directory holds.
        duplicated: Vec<usize>,
    },
}

/// "what: 1, 2, 3" (at most 20 shown), or nothing for an empty list.
fn list(what: &str, items: &[usize]) -> String {
    if items.is_empty() {
        return String::new();
    }
    let shown: Vec<String> = items.iter().take(20).map(ToString::to_string).collect();
    let more = if items.len() > 20 { format!(" and {} more", items.len() - 20) } else { String::new() };
    format!("{what} {}{more}", shown.join(", "))
}

impl From<LoopError> for ExperimentError {
    fn from(e: LoopError) -> Self {
        match e {
            LoopError::Render(e) => Self::Render(e),
            LoopError::Solve(e) => Self::Solver(e),
        }
    }
}

/// Progress of a run, for a progress bar.
#[derive(Clone, Copy, Debug)]
pub struct Progress {
    /// Configurations finished (resumed ones included).
    pub done: usize,
    /// Configurations in total (of this shard, when sharded).
    pub total: usize,
    /// The configuration just finished counted 0 pixels (a warning: the
    /// camera saw no visible receiver facing that light).
    pub zero_pixels: Option<usize>,
}

/// Loads the configured scene.
///
/// # Errors
/// [`ExperimentError::Scene`] for an unreadable or invalid scene file.
pub fn load_scene(source: &SceneSource) -> Result<Scene, ExperimentError> {
    Ok(load_scene_with_report(source)?.0)
}

/// Loads the configured scene and, for a file, says what was loaded.
///
/// # Errors
/// [`ExperimentError::Scene`] for an unreadable or invalid scene file.
pub fn load_scene_with_report(source: &SceneSource) -> Result<(Scene, Option<LoadReport>), ExperimentError> {
    match source {
        SceneSource::Builtin { triangles } => {
            Ok((crate::mesh::ProceduralScene { triangle_budget: *triangles, ..Default::default() }.build(), None))
        }
        SceneSource::Large { triangles } => Ok((large_scene(*triangles).build(), None)),
        SceneSource::File { path, options } => crate::mesh::load_scene_file(path, options)
            .map(|(scene, report)| (scene, Some(report)))
            .map_err(|e| ExperimentError::Scene(e.to_string())),
    }
}

/// The fixed camera of the experiment for `scene`.
///
/// # Errors
/// [`ExperimentError::Solver`] for a degenerate camera.
pub fn camera_for(config: &ExperimentConfig, scene: &Scene) -> Result<Camera, ExperimentError> {
    if matches!(config.scene, SceneSource::File { .. }) {
        let f = framing::frame_model(scene, config.eye, config.target, config.fov_y_degrees.to_radians());
        return Ok(Camera::look_at(
            f.eye,
            f.target,
            world_up(f.eye, f.target),
            config.fov_y_degrees.to_radians(),
            UVec2::splat(config.screen),
            f.near,
            f.far,
        )?);
    }
    if matches!(config.scene, SceneSource::Large { .. }) {
        // 1.7 units above the floor, 240 units inside its front edge,
        // looking across it: near 0.1, far 1500.
        let eye = config.eye.unwrap_or(DVec3::new(3.0, 1.7, 760.0));
        let target = config.target.unwrap_or(eye + DVec3::new(0.05, -0.04, -1.0));
        let fov = config.fov_y_degrees.to_radians();
        return Ok(Camera::look_at(eye, target, world_up(eye, target), fov, UVec2::splat(config.screen), 0.1, 1500.0)?);
    }
    let bounds = scene.bounds().scene();
    let center = bounds.center();
    let extent = bounds.max - bounds.min;
    let floor = bounds.min.y;
    // A little above the floor near the scene's front edge, looking across it.
    let eye = config.eye.unwrap_or(DVec3::new(center.x, floor + 0.025 * extent.x.max(extent.z), bounds.max.z * 0.95));
    let target = config.target.unwrap_or(DVec3::new(center.x, floor + 0.01 * extent.x.max(extent.z), center.z));
    let far = 2.0 * bounds.diagonal().max(1e-6);
    Ok(Camera::look_at(
        eye,
        target,
        world_up(eye, target),
        config.fov_y_degrees.to_radians(),
        UVec2::splat(config.screen),
        far * 1e-3,
        far,
    )?)
}

/// The camera's up vector: the world's `+y`, or `-z` when the view looks
/// straight up or down (a top-down `--eye`/`--target`), where `+y` leaves the
/// image's orientation undefined.
fn world_up(eye: DVec3, target: DVec3) -> DVec3 {
    let dir = (target - eye).normalize_or_zero();
    if dir.cross(DVec3::Y).length() < 1e-6 {
        DVec3::NEG_Z
    } else {
        DVec3::Y
    }
}

/// The light of configuration `index`: uniform on the upper hemisphere around
/// the scene centre (seeded per index, so any subset is reproducible).
#[must_use]
pub fn light_for(config: &ExperimentConfig, scene: &Scene, index: usize) -> Light {
    let bounds = scene.bounds().scene();
    let mut state = config.seed ^ (index as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    let mut next = || {
        // SplitMix64.
        state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    };
    // Uniform on the hemisphere: y uniform in (0, 1], azimuth uniform.
    let y = 1.0 - next();
    let phi = std::f64::consts::TAU * next();
    let r = (1.0 - y * y).max(0.0).sqrt();
    let dir = DVec3::new(r * phi.cos(), y.max(1e-3), r * phi.sin()).normalize();
    match config.light {
        LightKind::Point => Light::point(bounds.center() + dir * (config.light_distance * bounds.diagonal())),
        LightKind::Directional => Light::directional(-dir),
    }
}

/// Runs (or resumes) the whole experiment and writes the report.
///
/// Before any work: the sizes are checked against the device and the
/// machine's memory, the report directory is locked, a previous report in
/// it is refused (or moved aside with `force`), and `resume` checks the
/// recorded identity. With a [`Shard`], only its configurations run and the
/// report directory holds them for [`merge`]. [`ExperimentConfig::jobs`]
/// configurations run at once, the further workers on devices opened on
/// `device`'s adapter; the report is the same for any number.
///
/// # Errors
/// Scene, renderer and I/O failures; every refusal above; and
/// [`ExperimentError::NothingCounted`] when no configuration counted a pixel.
pub fn run(
    config: &ExperimentConfig,
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    progress: &mut dyn FnMut(Progress),
) -> Result<Summary, ExperimentError> {
    let started = Instant::now();
    guard::check(config, &device.limits(), guard::available_memory())?;
    let identity = Identity::of(config)?;
    let dir = rundir::RunDir::prepare(config, &identity)?;
    let mut warnings: Vec<String> = dir
        .resumed_with
        .iter()
        .map(|d| format!("resumed a run that differs in a setting that changes no row: {d}"))
        .collect();
    if let Some(moved) = &dir.moved_to {
        warnings.push(format!("--force: the previous report was moved to {}", moved.display()));
    }
    let indices: Vec<usize> = shard::indices(config).collect();
    let jobs = guard::workers(config, indices.len(), guard::available_memory())?;
    let mut runners = workers::runners(config, device, queue, jobs, &mut warnings)?;
    let mut writer = rows::ConfigWriter::open(config, &dir, &identity)?;
    let todo: Vec<usize> = indices.iter().copied().filter(|i| !writer.done().contains(i)).collect();
    // A resume with fewer configurations left than workers: drop the idle ones.
    runners.truncate(todo.len().max(1));
    let done_here = |w: &rows::ConfigWriter| indices.iter().filter(|i| w.done().contains(i)).count();
    progress(Progress { done: done_here(&writer), total: indices.len(), zero_pixels: None });
    let loop_start = Instant::now();
    // Rows go to the journal in configuration order, whatever the workers.
    workers::for_each(&mut runners, &todo, Runner::run_config, |&index, outcome: ConfigOutcome| {
        writer.append(index, &outcome)?;
        let counted = outcome.results.iter().filter_map(|(_, r)| r.counts).map(|c| c.counted).max();
        let zero_pixels = (counted == Some(0)).then_some(index);
        progress(Progress { done: done_here(&writer), total: indices.len(), zero_pixels });
        Ok(())
    })?;
    workers::gather_stages(&mut runners, loop_start.elapsed());
    let rows = writer.rows().to_vec();
    finish::check_counted(&rows, &mut warnings)?;
    let completeness =
        finish::Completeness { adapter: crate::render::device::describe(&device.adapter_info()), ..Default::default() };
    finish::finish(&mut runners, config, dir.path(), &rows, &completeness, warnings, started)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A top-down `--eye`/`--target` (straight down, or up) is a camera, not
    /// "up is parallel to the view direction"; the screen's up is then `-z`.
    #[test]
    fn top_down_views_get_a_camera() {
        for (eye, target) in [
            (DVec3::new(0.0, 5.0, 0.0), DVec3::ZERO),
            (DVec3::new(1.0, -3.0, 2.0), DVec3::new(1.0, 4.0, 2.0)),
            (DVec3::new(0.3, 30.0, 0.3), DVec3::new(0.3, 0.0, 0.3 + 1e-9)),
        ] {
            let config = ExperimentConfig {
                eye: Some(eye),
                target: Some(target),
                screen: 32,
                ..ExperimentConfig::preset(Preset::Quick)
            };
            let scene = crate::mesh::ProceduralScene { triangle_budget: 200, ..Default::default() }.build();
            let camera = camera_for(&config, &scene).unwrap_or_else(|e| panic!("{eye} -> {target}: {e}"));
            assert!(camera.eye().distance(eye) < 1e-12);
        }
        assert_eq!(world_up(DVec3::ZERO, DVec3::new(0.0, 0.0, -1.0)), DVec3::Y);
        assert_eq!(world_up(DVec3::Y, DVec3::ZERO), DVec3::NEG_Z);
    }
}
