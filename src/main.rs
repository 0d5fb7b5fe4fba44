//! The `lixel` command line: `lixel experiment` (the misclassification
//! experiment, the project's main job), `lixel merge` (the report of a
//! sharded experiment) and `lixel methods` (every classical matrix on one
//! configuration, scored).

use std::path::PathBuf;
use std::process::ExitCode;

use clap::builder::TypedValueParser as _;
use clap::{Parser, Subcommand, ValueEnum};
use glam::{DVec3, UVec2};
use lixel::experiment::{
    self, ExperimentConfig, LightKind, MergeOptions, MethodSpec, Preset, Progress, SceneSource, Shard, TimingOptions,
    Truth,
};
use lixel::mesh::{SceneOptions, UpAxis};
use lixel::render::{Gpu, ShadowLookup};
use lixel::score::{badness_stats, plane_samples};
use lixel::{Aabb, Camera, Light, Parameterization, PsmOptions, SceneBounds, ShadowMapSize, ShadowProblem};

#[cfg(feature = "view")]
mod view_cli;

#[derive(Parser)]
#[command(
    name = "lixel",
    version,
    about = "Light matrices that give every screen pixel as much shadow-map resolution as possible"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Count misclassified shadow pixels of every method against exact ground
    /// truth (Chong & Gortler 2006, Table 1) and write a report directory.
    Experiment(Box<ExperimentArgs>),
    /// Merge the report directories of a sharded experiment (`experiment
    /// --shard`) into one report, as an unsharded run would have written it.
    Merge(MergeArgs),
    /// Compute every classical matrix for one walkthrough configuration and
    /// print how well each samples the visible floor (badness: screen pixels
    /// per texel, squared; lower is better).
    Methods(MethodsArgs),
    /// An interactive viewer: fly through the scene, switch methods, see
    /// texel density, the texel grid and errors against ray-cast truth.
    /// `--screenshot FILE --frames N` renders offscreen without a display.
    #[cfg(feature = "view")]
    View(Box<view_cli::ViewArgs>),
}

/// A `--lookup` value: `standard` (the depth compare) or a lookup mode's
/// name ([`ShadowLookup::name`]).
fn parse_lookup(name: &str) -> Result<ShadowLookup, String> {
    match name.trim() {
        "standard" => Ok(ShadowLookup::DepthCompare),
        other => ShadowLookup::parse(other).ok_or_else(|| {
            let names: Vec<&str> = ShadowLookup::ALL.iter().map(|l| l.name()).collect();
            format!("unknown lookup {other:?}; valid: standard, {}", names.join(", "))
        }),
    }
}

#[derive(clap::Args)]
struct ExperimentArgs {
    /// Starting point for every setting below.
    #[arg(long, value_enum, default_value = "default")]
    preset: Preset,
    /// Light kind.
    #[arg(long, value_enum)]
    light: Option<LightKind>,
    #[command(flatten)]
    scene: SceneFileArgs,
    /// Triangle budget of the built-in scene.
    #[arg(long)]
    triangles: Option<usize>,
    /// Eye position x,y,z (default: built-in scene a little above the floor at
    /// its edge; --scene model from the front, 25° up, whole model in view).
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    eye: Option<DVec3>,
    /// Look-at point x,y,z (default: the scene centre).
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    target: Option<DVec3>,
    /// Vertical field of view in degrees, between 0 and 180.
    #[arg(long, allow_negative_numbers = true)]
    fov: Option<f64>,
    /// Number of configurations (light positions).
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..))]
    configs: Option<u64>,
    /// Seed of the light positions.
    #[arg(long)]
    seed: Option<u64>,
    /// Square screen resolution.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
    screen: Option<u32>,
    /// Square shadow-map resolution.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
    map: Option<u32>,
    /// Comma-separated methods: normal, focused, focused-snapped, lispsm, psm, plane-optimal, optimized, optimized-argmin,
    /// each optionally with a lookup suffix, e.g. focused+spsm (sub-pixel shadow maps), focused+sgsm (sub-geometry shadow maps);
    /// with --light directional --cascades N also the cascade methods csm, sdsm, sdsm-lispsm, optimized-cascades.
    #[arg(long, value_delimiter = ',')]
    methods: Option<Vec<String>>,
    /// Cascades per sun (1 to 8) for the cascade methods (csm, sdsm, sdsm-lispsm, optimized-cascades; added to the
    /// default --methods). At equal total texels: N maps of --map² per sun for them, one map of (map·√N)² for the others.
    #[arg(long)]
    cascades: Option<usize>,
    /// Ground truth.
    #[arg(long, value_enum)]
    truth: Option<Truth>,
    /// Configurations for the resolution equivalence (0 turns it off).
    #[arg(long)]
    equivalence: Option<usize>,
    /// Comma-separated shadow lookups (standard, spsm, sgsm): every method runs once with each,
    /// e.g. `--lookup standard,spsm` (default: each method's lookup as named in --methods).
    #[arg(long, value_delimiter = ',', value_parser = parse_lookup)]
    lookup: Option<Vec<ShadowLookup>>,
    /// Sub-samples per pixel of the coverage truth behind
    /// `mean_visibility_error` (8, 16, 32; 0 turns it off; default 32 for
    /// --preset quick, 0 otherwise: it costs 15-25 times the ray-cast truth).
    #[arg(long, value_parser = clap::builder::PossibleValuesParser::new(["0", "8", "16", "32"]).map(|s| s.parse::<u32>().unwrap_or(32)))]
    coverage_samples: Option<u32>,
    /// Report directory.
    #[arg(long, default_value = "report")]
    out: PathBuf,
    /// Continue an interrupted run in --out without redoing finished
    /// configurations (refused when a result-changing setting, the scene's
    /// content or the lixel version differs).
    #[arg(long, conflicts_with = "force")]
    resume: bool,
    /// Start afresh in an --out that holds a report: the old report is moved
    /// into --out/replaced-N/, never deleted.
    #[arg(long)]
    force: bool,
    /// Run shard I of N: the configurations k with k mod N = I, reported in
    /// --out/shard-I-of-N (merge them with `lixel merge`). `env` reads the
    /// index from SLURM_ARRAY_TASK_ID/SLURM_ARRAY_TASK_COUNT or
    /// JOB_COMPLETION_INDEX (with --shard-count).
    #[arg(long, value_name = "I/N|env")]
    shard: Option<String>,
    /// Number of shards, for `--shard env` under schedulers that do not
    /// export it (Kubernetes Indexed Jobs: the Job's completions).
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..))]
    shard_count: Option<u64>,
    /// Configurations run at once, each on a device of its own (a second
    /// lavapipe queue thread; on a GPU, one configuration's CPU work overlaps
    /// another's rendering). Default: the cores, at most 2, as many as
    /// memory allows. Results are the same for every value.
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..))]
    jobs: Option<u64>,
    /// Measure the frame-time table (the paper's Table 2) instead.
    #[arg(long)]
    timing: bool,
    /// Measure temporal stability (flicker along a scripted camera walk)
    /// instead: stability.csv, stability.md and SVG plots in --out.
    #[arg(long, conflicts_with = "timing")]
    stability: bool,
    /// Frames of the --stability camera path (default: 120, quick preset 12).
    #[arg(long)]
    stability_frames: Option<usize>,
    /// With --stability: also measure the scene optimizer's stability
    /// option sets (hysteresis rules, texel snapping, bounded rotation).
    #[arg(long, requires = "stability")]
    stability_options: bool,
    /// Frames timed per pipeline and cell of the timing table (rounded up to
    /// whole 15-frame blocks).
    #[arg(long, default_value_t = 60)]
    timing_frames: usize,
    /// Light counts of the timing table, comma-separated.
    #[arg(long, value_delimiter = ',', default_values_t = [1, 2, 3, 4])]
    timing_lights: Vec<usize>,
    /// Square map sizes of the timing table, comma-separated.
    #[arg(long, value_delimiter = ',', default_values_t = [500, 700, 1000])]
    timing_maps: Vec<u32>,
    /// Also report GPU time per stage (timestamp queries). On lavapipe they
    /// serialize the passes and add to every frame: read the frame times of
    /// such a run as a breakdown, not as the table.
    #[arg(long)]
    timing_gpu_stages: bool,
    /// Lookup modes timed as "focused + <lookup>" pipelines of the timing table, comma-separated
    /// (spsm, sgsm, aa8, aa16, aa32, ss8, ss16, ss32; default spsm).
    #[arg(long, value_delimiter = ',', value_parser = parse_lookup)]
    timing_lookups: Option<Vec<ShadowLookup>>,
    /// No progress bar.
    #[arg(long)]
    quiet: bool,
    /// wgpu backend: auto (Vulkan, else GL; `WGPU_BACKEND` when set), vulkan or gl.
    #[arg(long, value_enum, default_value = "auto")]
    backend: BackendArg,
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(crate) enum BackendArg {
    /// `WGPU_BACKEND` when set, else Vulkan (lavapipe without a GPU), else GL (llvmpipe).
    Auto,
    /// Vulkan only.
    Vulkan,
    /// OpenGL (ES) through EGL only.
    Gl,
}

#[derive(clap::Args)]
struct MergeArgs {
    /// Report directories of the shards (`--out/shard-I-of-N` of each).
    #[arg(required = true)]
    dirs: Vec<PathBuf>,
    /// Directory of the merged report.
    #[arg(long)]
    out: PathBuf,
    /// Write the report even when configurations are missing (it is marked
    /// partial and lists them).
    #[arg(long)]
    allow_missing: bool,
    /// Move a previous report in --out aside (into --out/replaced-N/).
    #[arg(long)]
    force: bool,
}

#[derive(clap::Args)]
struct MethodsArgs {
    /// Light direction (directional) or position (--point), x,y,z.
    #[arg(long, value_parser = parse_vec3, default_value = "0.4,-1,0.2", allow_hyphen_values = true)]
    light: DVec3,
    /// Make the light a point light at --light.
    #[arg(long)]
    point: bool,
    /// Shadow-map size N x N.
    #[arg(long, default_value_t = 400)]
    map: u32,
    /// Pixel grid N x N for the floor samples.
    #[arg(long, default_value_t = 200)]
    samples: u32,
}

pub(crate) fn parse_vec3(s: &str) -> Result<DVec3, String> {
    let v: Vec<f64> = s
        .split(',')
        .map(|c| c.trim().parse::<f64>().map_err(|_| format!("{:?} is not a number (expected x,y,z)", c.trim())))
        .collect::<Result<_, _>>()?;
    match v[..] {
        [x, y, z] if v.iter().all(|c| c.is_finite()) => Ok(DVec3::new(x, y, z)),
        [_, _, _] => Err("x,y,z must be finite".into()),
        _ => Err(format!("expected three numbers x,y,z, got {}", v.len())),
    }
}

/// `--shard`: `I/N`, or `env` for the scheduler's variables.
fn shard(args: &ExperimentArgs) -> Result<Option<Shard>, String> {
    let count = args.shard_count.map(|c| usize::try_from(c).unwrap_or(usize::MAX));
    match args.shard.as_deref() {
        None if count.is_some() => Err("--shard-count needs --shard env".into()),
        None => Ok(None),
        Some("env") => Shard::from_env(|name| std::env::var(name).ok(), count).map(Some).map_err(|e| e.to_string()),
        Some(text) => Shard::parse(text).map(Some).map_err(|e| e.to_string()),
    }
}

/// A user's scene file and how to place it (`lixel experiment` and `lixel view`).
#[derive(clap::Args)]
pub(crate) struct SceneFileArgs {
    /// A scene file (.obj, .gltf, .glb) instead of the built-in scene; the
    /// default camera frames it and a floor under it receives its shadows.
    #[arg(long)]
    scene: Option<PathBuf>,
    /// The --scene file's up axis (z: converted to the y-up world).
    #[arg(long, value_enum, default_value = "y")]
    up: UpAxis,
    /// Uniform scale applied to the --scene file.
    #[arg(long, default_value_t = 1.0)]
    scale: f64,
    /// No floor under the --scene model.
    #[arg(long)]
    no_floor: bool,
}

impl SceneFileArgs {
    /// The scene file, if one was given.
    pub(crate) fn source(&self) -> Option<SceneSource> {
        let options = SceneOptions { up: self.up, scale: self.scale, floor: !self.no_floor };
        self.scene.as_ref().map(|path| SceneSource::File { path: path.clone(), options })
    }
}

fn experiment_config(args: &ExperimentArgs) -> Result<ExperimentConfig, String> {
    let mut c = ExperimentConfig::preset(args.preset);
    c.light = args.light.unwrap_or(c.light);
    if let Some(scene) = args.scene.source() {
        c.scene = scene;
    } else if let Some(t) = args.triangles {
        c.scene = match c.scene {
            SceneSource::Large { .. } => SceneSource::Large { triangles: t },
            _ => SceneSource::Builtin { triangles: t },
        };
    }
    c.eye = args.eye.or(c.eye);
    c.target = args.target.or(c.target);
    c.fov_y_degrees = args.fov.unwrap_or(c.fov_y_degrees);
    c.configs = args.configs.map_or(c.configs, |n| usize::try_from(n).unwrap_or(usize::MAX));
    c.seed = args.seed.unwrap_or(c.seed);
    c.screen = args.screen.unwrap_or(c.screen);
    c.map = args.map.unwrap_or(c.map);
    if let Some(names) = &args.methods {
        c.methods = names
            .iter()
            .map(|n| {
                MethodSpec::parse(n.trim()).ok_or_else(|| {
                    format!("--methods: unknown method {n:?}; valid methods: {}", MethodSpec::valid_names())
                })
            })
            .collect::<Result<_, _>>()?;
    }
    c.cascades = args.cascades.unwrap_or(c.cascades);
    if args.methods.is_none() && c.cascades > 0 && !c.methods.iter().any(|m| m.cascade().is_some()) {
        c.methods.extend(MethodSpec::CASCADED);
    }
    if let Some(lookups) = &args.lookup {
        let mut seen = std::collections::HashSet::new();
        c.methods = lookups
            .iter()
            .flat_map(|&l| c.methods.iter().map(move |m| m.with_lookup(l)))
            .filter(|m| seen.insert(*m))
            .collect();
    }
    if let Some(t) = args.truth {
        c.truth = t;
    }
    c.equivalence_configs = args.equivalence.unwrap_or(c.equivalence_configs);
    c.coverage_samples = args.coverage_samples.unwrap_or(c.coverage_samples);
    c.out.clone_from(&args.out);
    c.resume = args.resume;
    c.force = args.force;
    c.shard = shard(args)?;
    c.jobs = args.jobs.map_or(0, |j| usize::try_from(j).unwrap_or(usize::MAX));
    experiment::check_cascades(&c).map_err(|e| e.to_string())?;
    Ok(c)
}

/// A device on the chosen backend (lavapipe or llvmpipe on machines without a GPU).
pub(crate) fn gpu(backend: BackendArg) -> Result<Gpu, String> {
    let backends = match backend {
        BackendArg::Auto => None,
        BackendArg::Vulkan => Some(wgpu::Backends::VULKAN),
        BackendArg::Gl => Some(wgpu::Backends::GL),
    };
    Gpu::open(backends, "lixel").map_err(|e| e.to_string())
}

/// Mesa's Vulkan and EGL drivers print "error: XDG_RUNTIME_DIR is invalid or
/// not set" when the variable is missing, which reads like a failure on a
/// healthy run. Without one, give them a private directory (mode 0700, as
/// the spec asks). Called before any wgpu call, while single-threaded.
fn ensure_runtime_dir() {
    let valid = std::env::var_os("XDG_RUNTIME_DIR").is_some_and(|d| std::path::Path::new(&d).is_dir());
    if valid {
        return;
    }
    let user = std::env::var("USER").unwrap_or_else(|_| "user".into());
    let dir = std::env::temp_dir().join(format!("lixel-runtime-{user}"));
    if std::fs::create_dir_all(&dir).is_err() {
        return;
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        if std::fs::set_permissions(&dir, std::fs::Permissions::from_mode(0o700)).is_err() {
            return;
        }
    }
    std::env::set_var("XDG_RUNTIME_DIR", &dir);
}

fn run_experiment(args: &ExperimentArgs) -> Result<(), String> {
    let config = experiment_config(args)?;
    if let SceneSource::File { path, .. } = &config.scene {
        // Loads the file once more than the run does: cheap next to the run,
        // and errors show before the device starts.
        let (_, report) = experiment::load_scene_with_report(&config.scene).map_err(|e| e.to_string())?;
        if let Some(report) = report {
            eprintln!("scene {}: {report}", path.display());
        }
    }
    let gpu = gpu(args.backend)?;
    let (device, queue) = (&gpu.device, &gpu.queue);
    eprintln!("adapter: {}", gpu.describe());
    if args.stability {
        use experiment::stability::{self, Variant};
        let mut path = stability::CameraPath::preset(args.preset);
        path.frames = args.stability_frames.unwrap_or(path.frames);
        let mut variants: Vec<Variant> = config.methods.iter().map(|&m| Variant::of(m)).collect();
        if args.stability_options {
            variants.extend(Variant::optimizer_option_sets());
        }
        eprintln!("stability: {} methods and option sets x {} frames...", variants.len(), path.frames);
        let quiet = args.quiet;
        let mut progress = |done: usize, total: usize| {
            if !quiet && (done.is_multiple_of(10) || done == total) {
                eprintln!("  {done}/{total} frames");
            }
        };
        let rows = stability::measure_variants(&config, &variants, &path, device, queue, &mut progress)
            .map_err(|e| e.to_string())?;
        let md = stability::write_report(&config.out, &config, &path, &rows).map_err(|e| e.to_string())?;
        println!("{md}\n(written to {})", config.out.display());
        return Ok(());
    }
    if args.timing {
        let options = TimingOptions {
            frames: args.timing_frames,
            lights: args.timing_lights.clone(),
            maps: args.timing_maps.clone(),
            gpu_stages: args.timing_gpu_stages,
            lookups: args.timing_lookups.clone().unwrap_or_else(|| TimingOptions::default().lookups),
            ..Default::default()
        };
        eprintln!(
            "timing {} cells of {} frames on scene {}...",
            options.lights.len() * options.maps.len(),
            options.frames,
            serde_json::to_string(&config.scene).unwrap_or_default()
        );
        let progress = |row: &experiment::TimingRow| {
            if !args.quiet {
                eprintln!(
                    "  {} lights, {}²: focused {:.1} ms, LiSPSM {:.1} ms, scene-optimized {:.1} ms ({:.3})",
                    row.lights,
                    row.map,
                    row.focused.as_secs_f64() * 1e3,
                    row.lispsm.as_secs_f64() * 1e3,
                    row.optimized.as_secs_f64() * 1e3,
                    row.optimized_ratio()
                );
            }
        };
        let rows = experiment::run_timing(&config, &options, device, queue, progress).map_err(|e| e.to_string())?;
        let table = experiment::timing_markdown(&rows);
        std::fs::create_dir_all(&config.out).map_err(|e| e.to_string())?;
        let path = config.out.join("timing.md");
        experiment::write_atomic(&path, table.as_bytes()).map_err(|e| e.to_string())?;
        println!("{table}\n(written to {})", path.display());
        return Ok(());
    }
    let bar = (!args.quiet).then(|| {
        let bar = indicatif::ProgressBar::new(0);
        bar.set_style(
            indicatif::ProgressStyle::with_template(
                "{elapsed_precise} [{bar:40}] {pos}/{len} configurations, ETA {eta}",
            )
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
        );
        bar
    });
    let mut progress = |p: Progress| {
        if let Some(index) = p.zero_pixels {
            let warning = format!(
                "warning: configuration {index} counted 0 pixels (no visible receiver faces its light; check --eye/--target)"
            );
            match &bar {
                Some(bar) => bar.println(warning),
                None => eprintln!("{warning}"),
            }
        }
        if let Some(bar) = &bar {
            bar.set_length(p.total as u64);
            bar.set_position(p.done as u64);
        }
    };
    let result = experiment::run(&config, device, queue, &mut progress);
    if let Some(bar) = bar {
        bar.finish();
    }
    let summary = result.map_err(|e| e.to_string())?;
    let dir = experiment::report_dir(&config);
    print_report(&dir, &summary);
    Ok(())
}

fn print_report(dir: &std::path::Path, summary: &experiment::Summary) {
    let report = std::fs::read_to_string(dir.join("report.md")).unwrap_or_default();
    println!("{report}");
    for w in &summary.warnings {
        eprintln!("warning: {w}");
    }
    eprintln!("report in {} ({:.1} s)", dir.display(), summary.elapsed.as_secs_f64());
}

fn run_merge(args: &MergeArgs) -> Result<(), String> {
    let gpu = gpu(BackendArg::Auto)?;
    let options = MergeOptions { out: args.out.clone(), allow_missing: args.allow_missing, force: args.force };
    let summary = experiment::merge(&args.dirs, &options, &gpu.device, &gpu.queue).map_err(|e| e.to_string())?;
    print_report(&args.out, &summary);
    if !summary.missing.is_empty() {
        eprintln!("warning: partial report: {} configurations missing", summary.missing.len());
    }
    Ok(())
}

fn run_methods(args: &MethodsArgs) -> Result<(), String> {
    // The paper's walkthrough: viewer a little above a floor with objects on it.
    let camera = Camera::look_at(
        DVec3::new(0.0, 1.7, 20.0),
        DVec3::new(0.0, 1.2, 0.0),
        DVec3::Y,
        60f64.to_radians(),
        UVec2::new(750, 750),
        0.1,
        200.0,
    )
    .map_err(|e| e.to_string())?;
    let floor = Aabb::from_corners(DVec3::new(-40.0, 0.0, -40.0), DVec3::new(40.0, 0.0, 40.0));
    let objects = Aabb::from_corners(DVec3::new(-30.0, 0.0, -30.0), DVec3::new(30.0, 6.0, 30.0));
    let bounds = SceneBounds { casters: objects, receivers: objects.union(&floor) };
    let light = if args.point { Light::point(args.light) } else { Light::directional(args.light) };
    let problem =
        ShadowProblem::new(camera, light, bounds, ShadowMapSize::square(args.map)).map_err(|e| e.to_string())?;
    let n = args.samples.max(2);
    let floor_plane = lixel::geometry::Plane::from_point_normal(DVec3::ZERO, DVec3::Y);
    let floor_samples = plane_samples(&camera, &floor_plane, &floor, UVec2::new(n, n));
    // What a depth readback would supply to PSM: the nearest visible receiver.
    let nearest = floor_samples.iter().map(|(p, _)| camera.view_depth(*p)).fold(f64::INFINITY, f64::min);
    println!(
        "{} floor samples (one per pixel of a {n}x{n} grid), {}x{} map, {light:?}",
        floor_samples.len(),
        args.map,
        args.map
    );
    println!("{:<15} {:>12} {:>12} {:>12}  fallback", "method", "median b", "mean b", "max b");
    let psm_near = Parameterization::Psm(PsmOptions { min_view_depth: nearest.is_finite().then_some(nearest) });
    let methods = Parameterization::ALL_DEFAULT.iter().map(|p| (p.method().name(), *p));
    for (name, parameterization) in methods.chain([("psm+readback", psm_near)]) {
        match problem.solve(&parameterization) {
            Ok(matrix) => {
                let stats = badness_stats(&matrix, &camera, floor_samples.iter().copied());
                let (median, mean, max) = stats.map_or((f64::NAN, f64::NAN, f64::NAN), |s| (s.median, s.mean, s.max));
                let fallback = matrix.fallback.map_or_else(|| "-".to_string(), |f| format!("{f:?}"));
                println!("{name:<15} {median:>12.4} {mean:>12.4} {max:>12.4}  {fallback}");
            }
            Err(e) => println!("{name:<15} error: {e}"),
        }
    }
    Ok(())
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    ensure_runtime_dir();
    let result = match &cli.command {
        Command::Experiment(args) => run_experiment(args),
        Command::Merge(args) => run_merge(args),
        Command::Methods(args) => run_methods(args),
        #[cfg(feature = "view")]
        Command::View(args) => view_cli::run(args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn config(args: &[&str]) -> Result<ExperimentConfig, String> {
        let cli = Cli::try_parse_from(["lixel", "experiment"].iter().chain(args)).map_err(|e| e.to_string())?;
        match cli.command {
            Command::Experiment(args) => experiment_config(&args),
            _ => Err("not an experiment".into()),
        }
    }

    #[test]
    fn cascades_add_the_cascade_methods_at_equal_texels() {
        let c = config(&["--light", "directional", "--cascades", "4", "--map", "512"]).unwrap();
        assert_eq!((c.cascades, c.map, c.single_map()), (4, 512, 1024));
        for m in MethodSpec::ALL.into_iter().chain(MethodSpec::CASCADED) {
            assert!(c.methods.contains(&m), "{m} missing");
        }
        let c = config(&["--light", "directional", "--cascades", "2", "--methods", "csm,optimized-cascades,focused"])
            .unwrap();
        assert_eq!(c.methods, [MethodSpec::CSM, MethodSpec::OPTIMIZED_CASCADES, MethodSpec::FOCUSED]);
        let c = config(&["--preset", "large", "--triangles", "5000"]).unwrap();
        assert_eq!(c.scene, SceneSource::Large { triangles: 5000 });
        assert_eq!(c.methods.iter().filter(|m| m.cascade().is_some()).count(), 4);
        let c = config(&["--light", "directional", "--cascades", "2", "--lookup", "standard,spsm"]).unwrap();
        let spsm = ShadowLookup::parse("spsm").unwrap();
        assert!(c.methods.contains(&MethodSpec::CSM) && c.methods.contains(&MethodSpec::CSM.with_lookup(spsm)));
        let c = config(&["--preset", "quick"]).unwrap();
        assert_eq!(c.cascades, 0);
        assert!(c.methods.iter().all(|m| m.cascade().is_none()));
    }

    #[test]
    fn cascade_methods_without_suns_or_cascades_are_refused() {
        let e = config(&["--methods", "sdsm"]).unwrap_err();
        assert!(e.contains("--methods sdsm") && e.contains("--light directional"), "{e}");
        let e = config(&["--light", "directional", "--methods", "csm"]).unwrap_err();
        assert!(e.contains("--cascades N"), "{e}");
        let e = config(&["--cascades", "2"]).unwrap_err();
        assert!(e.contains("--cascades 2") && e.contains("directional"), "{e}");
        let e = config(&["--light", "directional", "--cascades", "9"]).unwrap_err();
        assert!(e.contains("at most 8"), "{e}");
        assert!(config(&["--light", "directional", "--cascades", "x"]).is_err());
        let e = config(&["--methods", "optimized-cascades-argmin"]).unwrap_err();
        assert!(e.contains("unknown method"), "{e}");
    }
}
