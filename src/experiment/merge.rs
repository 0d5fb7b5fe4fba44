//! `lixel merge`: the report of a run made in shards. Every directory must
//! carry the same identity (settings except the shard, scene content,
//! binary version: the same check `--resume` makes), and every
//! configuration must come from exactly one directory. The merge then does
//! what the end of an unsharded run does, on this machine's GPU: the
//! resolution equivalence and the best/median/worst pictures are rendered
//! again here (a shard cannot know the global extremes), and the CSVs come
//! out byte-identical to an unsharded run's.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

use super::finish::{self, Completeness};
use super::identity::Identity;
use super::rows::{complete_configs, read_rows, write_settings};
use super::rundir::RunDir;
use super::{guard, workers, ExperimentConfig, ExperimentError, Summary};

/// How to merge.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct MergeOptions {
    /// The merged report's directory.
    pub out: PathBuf,
    /// Write a report even when configurations are missing (marked partial).
    pub allow_missing: bool,
    /// Move a previous report in `out` aside instead of refusing.
    pub force: bool,
}

/// The common identity of `dirs`, as the configuration of the merged run.
fn common_config(dirs: &[PathBuf], options: &MergeOptions) -> Result<ExperimentConfig, ExperimentError> {
    let first = dirs.first().ok_or_else(|| ExperimentError::Config("merge: no directories given".into()))?;
    let reference = Identity::read(first)?;
    let config = ExperimentConfig {
        shard: None,
        out: options.out.clone(),
        resume: false,
        force: options.force,
        ..reference.settings
    };
    // The merge renders with this binary and this scene file: both must be
    // the ones every shard used.
    let now = Identity::of(&config)?;
    for dir in dirs {
        let recorded = Identity::read(dir)?;
        let context = format!("merge: {} against {}", dir.display(), first.display());
        now.check_against(&recorded, &["shard"], &context)?;
    }
    Ok(config)
}

/// Merges the shard reports in `dirs` into `options.out`.
///
/// # Errors
/// [`ExperimentError::SettingsDiffer`] for shards of different runs,
/// [`ExperimentError::Incomplete`] for missing (unless `allow_missing`) or
/// duplicated configurations, [`ExperimentError::Locked`] when a shard or
/// the output is in use, and the failures of [`run`](super::run)'s end.
pub fn merge(
    dirs: &[PathBuf],
    options: &MergeOptions,
    device: &wgpu::Device,
    queue: &wgpu::Queue,
) -> Result<Summary, ExperimentError> {
    let started = Instant::now();
    let config = common_config(dirs, options)?;
    guard::check(&config, &device.limits(), guard::available_memory())?;
    // A shard still running holds its lock: refuse rather than read half of it.
    // (Each directory once: one given twice is reported as duplicated configurations.)
    let mut distinct: Vec<PathBuf> = dirs.iter().map(|d| d.canonicalize().unwrap_or_else(|_| d.clone())).collect();
    distinct.sort();
    distinct.dedup();
    let _inputs: Vec<RunDir> = distinct.iter().map(|d| RunDir::lock(d)).collect::<Result<_, _>>()?;
    let mut owner: BTreeMap<usize, Vec<&Path>> = BTreeMap::new();
    let mut rows = Vec::new();
    for dir in dirs {
        let mut these = read_rows(dir)?;
        for c in complete_configs(&mut these, config.methods.len()) {
            owner.entry(c).or_default().push(dir);
        }
        rows.extend(these);
    }
    let duplicated: Vec<usize> = owner.iter().filter(|(_, d)| d.len() > 1).map(|(&c, _)| c).collect();
    let missing: Vec<usize> = (0..config.configs).filter(|c| !owner.contains_key(c)).collect();
    let beyond: Vec<usize> = owner.keys().copied().filter(|&c| c >= config.configs).collect();
    if !duplicated.is_empty() || !beyond.is_empty() || (!missing.is_empty() && !options.allow_missing) {
        let missing = if options.allow_missing { Vec::new() } else { missing };
        let mut duplicated = duplicated;
        duplicated.extend(beyond);
        return Err(ExperimentError::Incomplete { missing, duplicated });
    }
    rows.sort_by_key(|r| (r.config, r.method));
    let identity = Identity::of(&config)?;
    let out = RunDir::prepare(&config, &identity)?;
    write_settings(out.path(), &identity)?;
    let mut warnings = Vec::new();
    finish::check_counted(&rows, &mut warnings)?;
    // Only the equivalence's configurations run again here, spread over
    // the default workers.
    let jobs = guard::workers(&config, finish::equivalence_count(&config), guard::available_memory())?;
    let mut runners = workers::runners(&config, device, queue, jobs, &mut warnings)?;
    let adapter = crate::render::device::describe(&device.adapter_info());
    let completeness = Completeness { missing, merged_from: dirs.to_vec(), adapter };
    finish::finish(&mut runners, &config, out.path(), &rows, &completeness, warnings, started)
}
