//! Guard rails checked before any work: every size against the device's
//! limits and the machine's available memory (with the limit in the
//! message), and settings that are wrong however large the machine (zero
//! sizes, a field of view outside (0°, 180°), a method listed twice).
//! Without them a typo runs for hours or exhausts memory before failing.

use std::collections::BTreeSet;

use super::{ExperimentConfig, ExperimentError, SceneSource, Truth};

/// Host bytes per screen pixel while a configuration runs: the camera's
/// primary rays kept for the whole run (44 B), the ray-cast truth (traced
/// pixels and masks, 20 B), the focused truth and one method's masks
/// (12 B each), the colour read-back for pictures (4 B), rounded up for the
/// render targets' staging copies.
pub(super) const BYTES_PER_PIXEL: u64 = 104;

/// Host bytes per triangle of the built-in scene: the mesh (positions,
/// normals, indices), its merged copy and BVH for ray casting, and the
/// vertex buffers (host memory on software renderers). An estimate from
/// the data layout, on the high side.
pub(super) const BYTES_PER_TRIANGLE: u64 = 400;

/// Host bytes per triangle of each worker beyond the first (`--jobs`): its
/// own vertex and index buffers (host memory on software renderers). The
/// mesh and ray caster are shared.
pub(super) const WORKER_BYTES_PER_TRIANGLE: u64 = 200;

/// Host bytes per screen pixel of each worker beyond the first: its truth
/// and masks of the configuration in flight, its render targets, the
/// camera capture and their staging copies (the primary rays are shared).
pub(super) const WORKER_BYTES_PER_PIXEL: u64 = 160;

/// Host bytes of each worker's largest shadow maps: the equivalence
/// ladder's largest size, 16 bytes a texel (the map, its clear and the
/// driver's copies: the paper preset's second worker measured +570 MB
/// peak with the 4000² ladder, +320 MB without), the configurations' maps
/// being far smaller.
fn worker_map_bytes(config: &ExperimentConfig) -> u64 {
    let largest = if config.equivalence_configs > 0 {
        config.equivalence_ladder.iter().copied().max().unwrap_or(0).max(1024)
    } else {
        config.single_map()
    };
    u64::from(largest).pow(2).saturating_mul(16)
}

/// Triangles of a generated scene (a scene file's are known only once it
/// is loaded, after these checks: 0).
fn generated_triangles(config: &ExperimentConfig) -> u64 {
    match config.scene {
        SceneSource::Builtin { triangles } | SceneSource::Large { triangles } => triangles as u64,
        SceneSource::File { .. } => 0,
    }
}

/// The most triangles a scene may have: indices are 32-bit.
pub(super) const MAX_TRIANGLES: u64 = u32::MAX as u64 / 3;

/// Memory the machine can still give (Linux `MemAvailable`), if known.
#[must_use]
pub(super) fn available_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib.saturating_mul(1024))
}

fn gib(bytes: u64) -> String {
    format!("{:.1} GiB", bytes as f64 / f64::from(1u32 << 30))
}

fn config_error(message: String) -> ExperimentError {
    ExperimentError::Config(message)
}

/// Checks `config` against `limits` (the device's) and `available` bytes
/// of memory (`None`: unknown, memory not checked).
///
/// # Errors
/// [`ExperimentError::Config`] or [`ExperimentError::TooLarge`] naming the flag.
pub(super) fn check(
    config: &ExperimentConfig,
    limits: &wgpu::Limits,
    available: Option<u64>,
) -> Result<(), ExperimentError> {
    for (flag, value) in
        [("--configs", config.configs as u64), ("--screen", config.screen.into()), ("--map", config.map.into())]
    {
        if value == 0 {
            return Err(config_error(format!("{flag} must be at least 1")));
        }
    }
    if config.methods.is_empty() {
        return Err(config_error("--methods is empty".into()));
    }
    let mut seen = BTreeSet::new();
    if let Some(twice) = config.methods.iter().find(|m| !seen.insert(**m)) {
        return Err(config_error(format!("--methods lists {} twice (each method runs once)", twice.name())));
    }
    let fov = config.fov_y_degrees;
    if !(fov > 0.0 && fov < 180.0) {
        return Err(config_error(format!(
            "--fov {fov} degrees: the vertical field of view must be between 0 and 180 degrees"
        )));
    }
    if let Some(s) = config.shard {
        if s.index >= s.count {
            return Err(config_error(format!("--shard {s}: the index must be below the count")));
        }
    }
    let max_texture = limits.max_texture_dimension_2d;
    let texture = |flag: &'static str, size: u32| {
        if size > max_texture {
            Err(ExperimentError::TooLarge {
                flag,
                value: size.to_string(),
                limit: format!("this GPU's largest texture is {max_texture}x{max_texture}"),
            })
        } else {
            Ok(())
        }
    };
    texture("--screen", config.screen)?;
    texture("--map", config.map)?;
    if config.cascades > 0 {
        texture("--map with --cascades (the one map of equal texels)", config.single_map())?;
    }
    super::check_cascades(config)?;
    if matches!(config.truth, Truth::Focused4000 | Truth::Both) {
        texture("--truth (the focused 4000x4000 map)", 4000)?;
    }
    if config.equivalence_configs > 0 {
        if let Some(&largest) = config.equivalence_ladder.iter().max() {
            texture("--equivalence (its focused ladder)", largest.max(1024))?;
        }
    }
    let triangles = generated_triangles(config);
    if triangles > MAX_TRIANGLES {
        return Err(ExperimentError::TooLarge {
            flag: "--triangles",
            value: triangles.to_string(),
            limit: format!("at most {MAX_TRIANGLES} (32-bit indices)"),
        });
    }
    if let Some(available) = available {
        let pixels = u64::from(config.screen) * u64::from(config.screen);
        let screen_bytes = pixels.saturating_mul(BYTES_PER_PIXEL);
        let scene_bytes = triangles.saturating_mul(BYTES_PER_TRIANGLE);
        if screen_bytes > available {
            return Err(ExperimentError::TooLarge {
                flag: "--screen",
                value: config.screen.to_string(),
                limit: format!(
                    "the ray-cast truth and masks need about {} ({BYTES_PER_PIXEL} bytes per pixel) but {} of memory is available",
                    gib(screen_bytes),
                    gib(available)
                ),
            });
        }
        if scene_bytes.saturating_add(screen_bytes) > available {
            return Err(ExperimentError::TooLarge {
                flag: "--triangles",
                value: triangles.to_string(),
                limit: format!(
                    "the scene needs about {} ({BYTES_PER_TRIANGLE} bytes per triangle) besides {} for the screen, but {} of memory is available",
                    gib(scene_bytes),
                    gib(screen_bytes),
                    gib(available)
                ),
            });
        }
    }
    Ok(())
}

/// The workers of a run of `configs` configurations: `config.jobs`, or
/// for 0 [`default_jobs`](super::default_jobs); never more than the
/// configurations. With `available` bytes known, the automatic count
/// drops to what fits and an explicit one that does not fit is refused.
///
/// # Errors
/// [`ExperimentError::TooLarge`] naming `--jobs`.
pub(super) fn workers(
    config: &ExperimentConfig,
    configs: usize,
    available: Option<u64>,
) -> Result<usize, ExperimentError> {
    let wanted = if config.jobs == 0 { super::default_jobs() } else { config.jobs };
    let wanted = wanted.min(configs).max(1);
    let Some(available) = available else { return Ok(wanted) };
    let triangles = generated_triangles(config);
    let pixels = u64::from(config.screen) * u64::from(config.screen);
    let first = triangles.saturating_mul(BYTES_PER_TRIANGLE).saturating_add(pixels.saturating_mul(BYTES_PER_PIXEL));
    let each = triangles
        .saturating_mul(WORKER_BYTES_PER_TRIANGLE)
        .saturating_add(pixels.saturating_mul(WORKER_BYTES_PER_PIXEL))
        .saturating_add(worker_map_bytes(config))
        .max(1);
    let fit = 1 + usize::try_from(available.saturating_sub(first) / each).unwrap_or(usize::MAX);
    if wanted <= fit {
        return Ok(wanted);
    }
    if config.jobs == 0 {
        return Ok(fit);
    }
    Err(ExperimentError::TooLarge {
        flag: "--jobs",
        value: config.jobs.to_string(),
        limit: format!(
            "each worker beyond the first needs about {} (its own vertex buffers, targets and maps) and the first {}, but {} of memory is available: at most {fit}",
            gib(each),
            gib(first),
            gib(available)
        ),
    })
}

#[cfg(test)]
mod tests {
    use super::super::{MethodSpec, Preset};
    use super::*;

    fn quick() -> ExperimentConfig {
        ExperimentConfig::preset(Preset::Quick)
    }

    fn message(config: &ExperimentConfig) -> String {
        let limits = wgpu::Limits { max_texture_dimension_2d: 8192, ..wgpu::Limits::downlevel_defaults() };
        check(config, &limits, Some(8 << 30)).expect_err("must be refused").to_string()
    }

    #[test]
    fn the_quick_preset_passes() {
        let limits = wgpu::Limits { max_texture_dimension_2d: 8192, ..wgpu::Limits::downlevel_defaults() };
        check(&quick(), &limits, Some(8 << 30)).unwrap();
    }

    #[test]
    fn each_zero_size_names_its_flag() {
        assert!(message(&ExperimentConfig { configs: 0, ..quick() }).contains("--configs"));
        assert!(message(&ExperimentConfig { screen: 0, ..quick() }).contains("--screen"));
        assert!(message(&ExperimentConfig { map: 0, ..quick() }).contains("--map"));
        assert!(message(&ExperimentConfig { methods: vec![], ..quick() }).contains("--methods"));
    }

    #[test]
    fn sizes_beyond_the_device_or_memory_are_refused_with_the_limit() {
        let m = message(&ExperimentConfig { screen: 100_000, ..quick() });
        assert!(m.contains("--screen 100000") && m.contains("8192x8192"), "{m}");
        let m = message(&ExperimentConfig { map: 9000, ..quick() });
        assert!(m.contains("--map 9000") && m.contains("8192"), "{m}");
        let m = message(&ExperimentConfig { scene: SceneSource::Builtin { triangles: usize::MAX }, ..quick() });
        assert!(m.contains("--triangles") && m.contains("32-bit"), "{m}");
        // Within the index range but beyond 8 GiB of memory.
        let m = message(&ExperimentConfig { scene: SceneSource::Builtin { triangles: 1_000_000_000 }, ..quick() });
        assert!(m.contains("--triangles 1000000000") && m.contains("8.0 GiB of memory is available"), "{m}");
        let limits = wgpu::Limits { max_texture_dimension_2d: 8192, ..wgpu::Limits::downlevel_defaults() };
        let m = check(&ExperimentConfig { screen: 8192, ..quick() }, &limits, Some(1 << 30)).unwrap_err().to_string();
        assert!(m.contains("--screen 8192") && m.contains("bytes per pixel"), "{m}");
    }

    #[test]
    fn workers_fit_memory_and_configurations() {
        let paper = ExperimentConfig { jobs: 2, ..ExperimentConfig::preset(Preset::Paper) };
        assert_eq!(workers(&paper, 500, Some(64 << 30)).unwrap(), 2);
        assert_eq!(workers(&paper, 1, Some(64 << 30)).unwrap(), 1, "never more workers than configurations");
        assert_eq!(workers(&ExperimentConfig { jobs: 8, ..paper.clone() }, 500, None).unwrap(), 8);
        // 1.14 M triangles: the first worker needs ~0.5 GiB, each further one ~0.55.
        let m = workers(&ExperimentConfig { jobs: 4, ..paper.clone() }, 500, Some(1 << 30)).unwrap_err().to_string();
        assert!(m.contains("--jobs 4") && m.contains("at most 1"), "{m}");
        assert_eq!(workers(&ExperimentConfig { jobs: 3, ..paper.clone() }, 500, Some(2 << 30)).unwrap(), 3);
        // Automatic: as many as fit, at least one.
        let auto = ExperimentConfig { jobs: 0, ..paper };
        assert!(workers(&auto, 500, Some(64 << 30)).unwrap() >= 1);
        assert_eq!(workers(&auto, 500, Some(1 << 20)).unwrap(), 1);
    }

    #[test]
    fn duplicate_methods_and_bad_fields_of_view_are_refused() {
        let m = message(&ExperimentConfig { methods: vec![MethodSpec::FOCUSED, MethodSpec::FOCUSED], ..quick() });
        assert!(m.contains("focused twice"), "{m}");
        for fov in [-10.0, 0.0, 180.0, f64::NAN] {
            let m = message(&ExperimentConfig { fov_y_degrees: fov, ..quick() });
            assert!(m.contains("--fov") && m.contains("degrees"), "{m}");
        }
    }
}
