//! Temporal stability ("shimmer"): `lixel experiment --stability`.
//!
//! Shadow edges that crawl while the camera moves are what users of real
//! engines complain about most, and a per-frame misclassification count does
//! not see them. Here the camera follows a scripted slow walk and turn
//! through a static scene with one static light; per method and frame the
//! camera masks are compared with the ray-cast truth of the same frame, and
//! consecutive frames with each other:
//!
//! - **flicker** of frame `f`: among the pixels counted in both frames `f-1`
//!   and `f` (visible and light-facing in the truth) whose truth shadow bit
//!   did *not* change, the share whose method bit did change. Truth flips are
//!   real motion and are left out, so a perfect method has zero flicker;
//! - **misclassified** of frame `f`: as in the main experiment ([`Counts`]).
//!
//! The scene-optimized method runs the real frame loop ([`ShadowLoop`],
//! analysis every few frames, readbacks consumed as they arrive); it is
//! settled at the first view before the path starts, so the figures are its
//! steady behaviour, not its warm-up. Outputs: `stability.csv`,
//! `stability.md`, `stability_tradeoff.svg` (x = misclassified, y =
//! flicker) and `stability_frames.svg` (flicker per frame per method).

use std::fmt::Write as _;
use std::path::Path;

use glam::{DQuat, DVec3};

use super::{write_atomic, Counts, ExperimentConfig, ExperimentError, MethodSpec, Preset, Runner, Truth};
use crate::mesh::{Flicker, ShadowMasks};
use crate::optimize::{AcceptMeasure, OptimizeOptions, TexelSnap};
use crate::render::{LoopOptions, LoopPolicy, LoopView, ShadowLoop};
use crate::{Camera, ShadowMapSize};

/// The scripted camera path.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraPath {
    /// Frames along the path (at least 2 for any flicker figure).
    pub frames: usize,
    /// Distance walked along the view direction over the whole path, in
    /// scene diagonals.
    pub walk: f64,
    /// Turn (yaw about +y) over the whole path, degrees.
    pub turn_degrees: f64,
}

impl CameraPath {
    /// The path of a preset: 120 frames at the default preset (a slow walk of
    /// 4 % of the scene's diagonal while turning 12°), 12 at the quick one.
    #[must_use]
    pub fn preset(preset: Preset) -> Self {
        let frames = match preset {
            Preset::Quick => 12,
            Preset::Default | Preset::Paper => 120,
            Preset::Large => 60,
        };
        Self { frames, walk: 0.04, turn_degrees: 12.0 }
    }

    /// A camera that stands still for `frames` frames.
    #[must_use]
    pub fn still(frames: usize) -> Self {
        Self { frames, walk: 0.0, turn_degrees: 0.0 }
    }

    /// The camera of frame `f`: `start` walked and turned by `f / (frames - 1)`
    /// of the path (smoothly: constant speed).
    ///
    /// # Errors
    /// A degenerate camera (never for a valid `start`).
    pub fn camera(&self, start: &Camera, diagonal: f64, f: usize) -> Result<Camera, ExperimentError> {
        let t = if self.frames > 1 { f as f64 / (self.frames - 1) as f64 } else { 0.0 };
        let eye = start.eye();
        let forward = start.view_direction();
        let flat = DVec3::new(forward.x, 0.0, forward.z).normalize_or(forward);
        let turn = DQuat::from_rotation_y(-(self.turn_degrees * t).to_radians());
        let eye = eye + flat * (self.walk * diagonal * t);
        let target = eye + turn * forward;
        Ok(Camera::look_at(
            eye,
            target,
            DVec3::Y,
            2.0 * (1.0 / start.clip_from_view().y_axis.y).atan(),
            start.viewport(),
            start.z_near(),
            start.z_far(),
        )?)
    }
}

/// One curve of the report: a method and, for the scene-optimized ones,
/// the optimizer's options (the trade-off plot has one point per method and
/// option set).
#[derive(Clone, Debug, PartialEq)]
pub struct Variant {
    /// The method.
    pub method: MethodSpec,
    /// The option set's name in the report (`default` for the defaults).
    pub options: String,
    /// The optimizer's options (scene-optimized methods only; `None` for
    /// the defaults with the method's search).
    pub optimize: Option<OptimizeOptions>,
}

impl Variant {
    /// A method with its default options.
    #[must_use]
    pub fn of(method: MethodSpec) -> Self {
        Self { method, options: "default".into(), optimize: None }
    }

    /// The scene optimizer (paper search) with `optimize`, named `options`.
    #[must_use]
    pub fn optimized(options: &str, optimize: OptimizeOptions) -> Self {
        Self { method: MethodSpec::OPTIMIZED, options: options.into(), optimize: Some(optimize) }
    }

    /// The option sets of the scene optimizer that `--stability-options`
    /// measures: the paper's rule and its alternatives, texel snapping and
    /// bounded rotation, alone and together.
    #[must_use]
    pub fn optimizer_option_sets() -> Vec<Self> {
        let paper = OptimizeOptions::paper();
        let snap = Some(TexelSnap::DEFAULT);
        let turn = Some(5.0);
        vec![
            Self::optimized("paper", paper.clone()),
            Self::optimized("median 1.0", OptimizeOptions { accept_ratio: 1.0, ..paper.clone() }),
            Self::optimized("median 0.5", OptimizeOptions { accept_ratio: 0.5, ..paper.clone() }),
            Self::optimized(
                "objective 0.8",
                OptimizeOptions { accept_measure: AcceptMeasure::Objective, ..paper.clone() },
            ),
            Self::optimized("hold", OptimizeOptions { hold: true, ..paper.clone() }),
            Self::optimized("snap", OptimizeOptions { snap, ..paper.clone() }),
            Self::optimized("turn 5", OptimizeOptions { max_turn_degrees: turn, ..paper.clone() }),
            Self::optimized("hold + snap", OptimizeOptions { hold: true, snap, ..paper.clone() }),
            Self::optimized(
                "hold + snap + turn 5",
                OptimizeOptions { hold: true, snap, max_turn_degrees: turn, ..paper.clone() },
            ),
            Self {
                method: MethodSpec::OPTIMIZED_ARGMIN,
                options: "hold".into(),
                optimize: Some(OptimizeOptions { hold: true, ..paper }),
            },
        ]
    }

    /// `method` or `method [options]`.
    #[must_use]
    pub fn label(&self) -> String {
        if self.options == "default" {
            self.method.name().to_string()
        } else {
            format!("{} [{}]", self.method.name(), self.options)
        }
    }
}

/// One method's figures along the path.
#[derive(Clone, Debug, PartialEq)]
pub struct StabilityRow {
    /// The method.
    pub method: MethodSpec,
    /// Its option set's name (`default` for the defaults).
    pub options: String,
    /// Flicker share per frame transition (`frames - 1` values).
    pub flicker: Vec<f64>,
    /// Shimmer share per frame transition: the part of the flicker the map
    /// change alone causes (this frame's masks against the previous frame's
    /// matrix rendered from this frame's camera; zero for a matrix that did
    /// not change).
    pub shimmer: Vec<f64>,
    /// Misclassified pixels per frame.
    pub misclassified: Vec<u64>,
}

impl StabilityRow {
    /// Mean flicker per frame transition.
    #[must_use]
    pub fn mean_flicker(&self) -> f64 {
        mean(self.flicker.iter().copied())
    }

    /// 95th percentile of the flicker (nearest rank).
    #[must_use]
    pub fn p95_flicker(&self) -> f64 {
        let mut v = self.flicker.clone();
        v.sort_by(f64::total_cmp);
        if v.is_empty() {
            return 0.0;
        }
        let rank = ((0.95 * v.len() as f64).ceil() as usize).clamp(1, v.len());
        v[rank - 1]
    }

    /// Mean shimmer per frame transition.
    #[must_use]
    pub fn mean_shimmer(&self) -> f64 {
        mean(self.shimmer.iter().copied())
    }

    /// Mean misclassified pixels per frame.
    #[must_use]
    pub fn mean_misclassified(&self) -> f64 {
        mean(self.misclassified.iter().map(|&m| m as f64))
    }
}

fn mean(values: impl Iterator<Item = f64>) -> f64 {
    let (sum, n) = values.fold((0.0, 0usize), |(s, n), v| (s + v, n + 1));
    if n == 0 {
        0.0
    } else {
        sum / n as f64
    }
}

/// How one method produces its matrix frame after frame.
enum Source {
    Fixed(MethodSpec),
    Loop(Box<ShadowLoop>),
}

impl StabilityRow {
    /// `method` or `method [options]`.
    #[must_use]
    pub fn label(&self) -> String {
        Variant { method: self.method, options: self.options.clone(), optimize: None }.label()
    }
}

/// Runs every method of `config` along `path` with light 0 of the
/// configuration ([`super::light_for`]) and the ray-cast truth.
///
/// # Errors
/// Scene, renderer and solver failures; a method that fails to solve on
/// some frame is a [`ExperimentError::Solver`].
pub fn measure(
    config: &ExperimentConfig,
    path: &CameraPath,
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<Vec<StabilityRow>, ExperimentError> {
    let variants: Vec<Variant> = config.methods.iter().map(|&m| Variant::of(m)).collect();
    measure_variants(config, &variants, path, device, queue, progress)
}

/// [`measure`] for each of `variants` (methods with option sets) instead of
/// `config.methods`.
///
/// # Errors
/// As [`measure`]; no variants is [`ExperimentError::Config`].
pub fn measure_variants(
    config: &ExperimentConfig,
    variants: &[Variant],
    path: &CameraPath,
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<Vec<StabilityRow>, ExperimentError> {
    if variants.is_empty() {
        return Err(ExperimentError::Config("no method to measure".into()));
    }
    if let Some(v) = variants.iter().find(|v| v.method.cascade().is_some()) {
        return Err(ExperimentError::Cascades {
            what: format!("--stability with {}", v.method),
            reason: "the stability walk measures methods with one map per light (examples/cascades.rs --walk measures cascades)",
        });
    }
    let config = ExperimentConfig { truth: Truth::RayCast, ..config.clone() };
    let mut runner = Runner::new(&config, device, queue)?;
    let start = runner.camera;
    let diagonal = runner.shared.scene.bounds().scene().diagonal();
    let light = super::light_for(&config, &runner.shared.scene, 0);
    let cameras: Vec<Camera> = (0..path.frames).map(|f| path.camera(&start, diagonal, f)).collect::<Result<_, _>>()?;
    let truths: Vec<ShadowMasks> = {
        let caster = runner.shared.caster.as_ref().ok_or_else(|| ExperimentError::Config("no ray caster".into()))?;
        cameras.iter().map(|c| caster.trace_masks(c, &[light], config.screen, config.screen)).collect()
    };
    let map = ShadowMapSize::square(config.map);
    let total = variants.len() * path.frames;
    let mut rows = Vec::new();
    for (m, variant) in variants.iter().enumerate() {
        let method = variant.method;
        let mut source = if method.parameterization(None).is_some() {
            Source::Fixed(method)
        } else {
            let optimize = variant.optimize.clone().unwrap_or_default();
            let optimize = OptimizeOptions { strategy: method.search().strategy(), ..optimize };
            let options = LoopOptions { optimize, lookup: method.lookup(), ..Default::default() };
            let mut shadows = ShadowLoop::new(LoopPolicy::Optimized, 1, options)?;
            let view = LoopView {
                camera: &cameras[0],
                lights: std::slice::from_ref(&light),
                bounds: runner.shared.scene.bounds(),
                map,
            };
            shadows.settle(&mut runner.renderer, &view, config.max_optimize_frames)?;
            Source::Loop(Box::new(shadows))
        };
        let mut row = StabilityRow {
            method,
            options: variant.options.clone(),
            flicker: Vec::new(),
            shimmer: Vec::new(),
            misclassified: Vec::new(),
        };
        let mut previous: Option<(ShadowMasks, crate::LightMatrix)> = None;
        for (f, camera) in cameras.iter().enumerate() {
            runner.camera = *camera;
            let matrix = match &mut source {
                Source::Fixed(kind) => {
                    let problem = runner.problem(light, config.map)?;
                    // PSM's near plane from the frame's nearest visible depth, as in the main experiment.
                    let nearest = super::nearest_view_depth(camera, &truths[f]);
                    runner.matrix(*kind, &problem, nearest)?.0
                }
                Source::Loop(shadows) => {
                    let view = LoopView {
                        camera,
                        lights: std::slice::from_ref(&light),
                        bounds: runner.shared.scene.bounds(),
                        map,
                    };
                    let frame = shadows.frame(&mut runner.renderer, &view)?;
                    frame.matrices[0]
                }
            };
            let masks = runner.masks_with(&matrix, method.lookup())?;
            row.misclassified.push(Counts::compare(&masks, &truths[f]).misclassified());
            if let Some((prev, prev_matrix)) = &previous {
                row.flicker.push(Flicker::between(0, prev, &truths[f - 1], &masks, &truths[f]).share());
                // The previous frame's map seen from this camera: what the
                // map change alone flipped.
                let shimmer = if *prev_matrix == matrix {
                    0.0
                } else {
                    let held = runner.masks_with(prev_matrix, method.lookup())?;
                    Flicker::between(0, &held, &truths[f], &masks, &truths[f]).share()
                };
                row.shimmer.push(shimmer);
            }
            previous = Some((masks, matrix));
            progress(m * path.frames + f + 1, total);
        }
        rows.push(row);
    }
    runner.camera = start;
    Ok(rows)
}

/// Writes `stability.csv`, `stability.md` and the two SVG plots to `out`.
///
/// # Errors
/// I/O failures.
pub fn write_report(
    out: &Path,
    config: &ExperimentConfig,
    path: &CameraPath,
    rows: &[StabilityRow],
) -> Result<String, ExperimentError> {
    std::fs::create_dir_all(out).map_err(|source| ExperimentError::Io { path: out.to_path_buf(), source })?;
    let mut csv = String::from("method,mean_flicker,p95_flicker,mean_misclassified,frames,mean_shimmer,options\n");
    for r in rows {
        let _ = writeln!(
            csv,
            "{},{:.6},{:.6},{:.1},{},{:.6},{}",
            r.method.name(),
            r.mean_flicker(),
            r.p95_flicker(),
            r.mean_misclassified(),
            r.misclassified.len(),
            r.mean_shimmer(),
            r.options
        );
    }
    write_atomic(&out.join("stability.csv"), csv.as_bytes())?;
    let md = markdown(config, path, rows);
    write_atomic(&out.join("stability.md"), md.as_bytes())?;
    write_atomic(&out.join("stability_tradeoff.svg"), tradeoff_svg(rows).as_bytes())?;
    write_atomic(&out.join("stability_frames.svg"), frames_svg(rows).as_bytes())?;
    Ok(md)
}

/// The report's table and how it was measured.
#[must_use]
pub fn markdown(config: &ExperimentConfig, path: &CameraPath, rows: &[StabilityRow]) -> String {
    let mut md = String::from("# Temporal stability\n\n");
    let _ = writeln!(
        md,
        "{} frames: a walk of {:.0} % of the scene diagonal while turning {}°; scene {}, {}² screen, {}² map, one {} \
         light (configuration 0), ray-cast truth. Flicker: share of pixels counted in two consecutive frames, whose \
         truth did not change, whose shadow bit did (mean and 95th percentile over the frame transitions). Shimmer: the \
         part the map change alone causes (the previous frame's matrix rendered from this frame's camera against \
         this frame's); the rest of the flicker is the camera's pixels moving over the map's fixed texels.\n",
        path.frames,
        path.walk * 100.0,
        path.turn_degrees,
        serde_json::to_string(&config.scene).unwrap_or_default(),
        config.screen,
        config.map,
        serde_json::to_string(&config.light).unwrap_or_default().trim_matches('"')
    );
    md.push_str(
        "| method | mean flicker | p95 flicker | mean shimmer | misclassified / frame |\n|---|---:|---:|---:|---:|\n",
    );
    for r in rows {
        let _ = writeln!(
            md,
            "| {} | {:.3} % | {:.3} % | {:.3} % | {:.0} |",
            r.label(),
            100.0 * r.mean_flicker(),
            100.0 * r.p95_flicker(),
            100.0 * r.mean_shimmer(),
            r.mean_misclassified()
        );
    }
    md.push_str("\n![trade-off](stability_tradeoff.svg)\n\n![flicker per frame](stability_frames.svg)\n");
    md
}

fn color(method: MethodSpec) -> String {
    let c = super::plots::color(method);
    format!("#{:02x}{:02x}{:02x}", c.0, c.1, c.2)
}

const W: f64 = 640.0;
const H: f64 = 400.0;
const PAD: f64 = 60.0;

fn svg_frame(title: &str, x_label: &str, y_label: &str, x_max: f64, y_max: f64) -> String {
    let mut s = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{W}\" height=\"{H}\" font-family=\"sans-serif\" \
         font-size=\"12\">\n<rect width=\"{W}\" height=\"{H}\" fill=\"white\"/>\n<text x=\"{}\" y=\"20\" \
         text-anchor=\"middle\" font-size=\"14\">{title}</text>\n",
        W / 2.0
    );
    let (x0, y0, x1, y1) = (PAD, H - PAD, W - 20.0, 40.0);
    let _ = writeln!(s, "<path d=\"M{x0} {y1} L{x0} {y0} L{x1} {y0}\" stroke=\"black\" fill=\"none\"/>");
    let _ = writeln!(s, "<text x=\"{}\" y=\"{}\" text-anchor=\"middle\">{x_label}</text>", (x0 + x1) / 2.0, H - 15.0);
    let _ = writeln!(
        s,
        "<text x=\"15\" y=\"{}\" text-anchor=\"middle\" transform=\"rotate(-90 15 {})\">{y_label}</text>",
        (y0 + y1) / 2.0,
        (y0 + y1) / 2.0
    );
    for k in 0..=4 {
        let fx = f64::from(k) / 4.0;
        let _ = writeln!(
            s,
            "<text x=\"{:.1}\" y=\"{}\" text-anchor=\"middle\">{:.3}</text>\n<text x=\"{}\" y=\"{:.1}\" \
             text-anchor=\"end\">{:.3}</text>",
            x0 + fx * (x1 - x0),
            y0 + 16.0,
            fx * x_max,
            x0 - 4.0,
            y0 - fx * (y0 - y1) + 4.0,
            fx * y_max
        );
    }
    s
}

fn scale(v: f64, max: f64, lo: f64, hi: f64) -> f64 {
    lo + (hi - lo) * if max > 0.0 { v / max } else { 0.0 }
}

/// Misclassified (x) against mean flicker in % (y), one point per method.
fn tradeoff_svg(rows: &[StabilityRow]) -> String {
    let x_max = rows.iter().map(StabilityRow::mean_misclassified).fold(0.0, f64::max) * 1.1;
    let y_max = rows.iter().map(|r| 100.0 * r.mean_flicker()).fold(0.0, f64::max) * 1.1;
    let mut s = svg_frame(
        "Flicker against misclassification",
        "misclassified pixels / frame",
        "mean flicker (%)",
        x_max,
        y_max,
    );
    for r in rows {
        let x = scale(r.mean_misclassified(), x_max, PAD, W - 20.0);
        let y = scale(100.0 * r.mean_flicker(), y_max, H - PAD, 40.0);
        let _ = writeln!(
            s,
            "<circle cx=\"{x:.1}\" cy=\"{y:.1}\" r=\"5\" fill=\"{}\"/><text x=\"{:.1}\" y=\"{:.1}\">{}</text>",
            color(r.method),
            x + 7.0,
            y - 7.0,
            r.label()
        );
    }
    s.push_str("</svg>\n");
    s
}

/// Flicker in % per frame transition, one line per method.
fn frames_svg(rows: &[StabilityRow]) -> String {
    let x_max = rows.iter().map(|r| r.flicker.len()).max().unwrap_or(0) as f64;
    let y_max = rows.iter().flat_map(|r| r.flicker.iter().map(|f| 100.0 * f)).fold(0.0, f64::max) * 1.1;
    let mut s = svg_frame("Flicker per frame", "frame", "flicker (%)", x_max, y_max);
    for (k, r) in rows.iter().enumerate() {
        let points: Vec<String> = r
            .flicker
            .iter()
            .enumerate()
            .map(|(i, f)| {
                format!(
                    "{:.1},{:.1}",
                    scale(i as f64 + 1.0, x_max, PAD, W - 20.0),
                    scale(100.0 * f, y_max, H - PAD, 40.0)
                )
            })
            .collect();
        let _ = writeln!(
            s,
            "<polyline points=\"{}\" fill=\"none\" stroke=\"{}\"/><text x=\"{}\" y=\"{}\" fill=\"{}\">{}</text>",
            points.join(" "),
            color(r.method),
            W - 150.0,
            50.0 + 14.0 * k as f64,
            color(r.method),
            r.label()
        );
    }
    s.push_str("</svg>\n");
    s
}

#[cfg(test)]
mod tests {
    use glam::UVec2;

    use super::*;

    #[test]
    fn percentile_and_means() {
        let row = StabilityRow {
            method: MethodSpec::FOCUSED,
            options: "default".into(),
            flicker: (1..=20).map(|i| f64::from(i) / 100.0).collect(),
            shimmer: vec![0.0, 0.5],
            misclassified: vec![10, 20, 30],
        };
        assert!((row.p95_flicker() - 0.19).abs() < 1e-12);
        assert!((row.mean_flicker() - 0.105).abs() < 1e-12);
        assert!((row.mean_misclassified() - 20.0).abs() < 1e-12);
        assert!((row.mean_shimmer() - 0.25).abs() < 1e-12);
    }

    #[test]
    fn path_starts_at_the_camera_and_walks_forward() {
        let start =
            Camera::look_at(DVec3::new(0.0, 2.0, 10.0), DVec3::ZERO, DVec3::Y, 1.0, UVec2::new(64, 64), 0.1, 100.0)
                .unwrap();
        let path = CameraPath { frames: 11, walk: 0.1, turn_degrees: 10.0 };
        let first = path.camera(&start, 100.0, 0).unwrap();
        assert!((first.eye() - start.eye()).length() < 1e-12);
        let last = path.camera(&start, 100.0, 10).unwrap();
        assert!((last.eye() - start.eye()).length() > 9.9);
        assert!((last.eye().z - start.eye().z) < -9.0, "walks towards the target");
        let still = CameraPath::still(5).camera(&start, 100.0, 4).unwrap();
        assert!((still.eye() - start.eye()).length() < 1e-12);
    }
}
