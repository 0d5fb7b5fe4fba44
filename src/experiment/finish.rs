//! What a run does after its configurations, shared by `run` and `merge`:
//! check that something was counted, measure the resolution equivalence and
//! render the best/median/worst pictures (the only GPU work here), then hand
//! plain data to the writers in `report`, `images` and `plots`, which never
//! touch the renderer.

use std::path::{Path, PathBuf};
use std::time::Instant;

use super::images::{error_overlay, Picture};
use super::report::{self, Equivalence, Summary};
use super::rows::ConfigRow;
use super::runner::means_in_order;
use super::{
    light_for, nearest_view_depth, workers, Counts, ExperimentConfig, ExperimentError, MethodSpec, RunStage, Runner,
};

/// How complete the rows of a report are.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub(super) struct Completeness {
    /// Configurations without rows (a merge with `--allow-missing`).
    pub missing: Vec<usize>,
    /// The shard directories merged, when this is a merge.
    pub merged_from: Vec<PathBuf>,
    /// The adapter and backend the run (or merge) rendered on.
    pub adapter: String,
}

/// Fails when no configuration counted a pixel (the camera sees nothing
/// lit, e.g. aimed at the sky or at a scene far from the origin); adds a
/// warning naming the configurations that counted 0.
pub(super) fn check_counted(rows: &[ConfigRow], warnings: &mut Vec<String>) -> Result<(), ExperimentError> {
    let mut configs: Vec<(usize, u64)> = Vec::new();
    for r in rows {
        let counted = r.counted.unwrap_or(0);
        match configs.last_mut() {
            Some((c, n)) if *c == r.config => *n = (*n).max(counted),
            _ => configs.push((r.config, counted)),
        }
    }
    let zero: Vec<usize> = configs.iter().filter(|&&(_, n)| n == 0).map(|&(c, _)| c).collect();
    if !configs.is_empty() && zero.len() == configs.len() {
        return Err(ExperimentError::NothingCounted { configs: configs.len() });
    }
    if !zero.is_empty() {
        let shown: Vec<String> = zero.iter().take(20).map(ToString::to_string).collect();
        warnings.push(format!(
            "{} of {} configurations counted 0 pixels (no visible receiver faces the light): {}{}",
            zero.len(),
            configs.len(),
            shown.join(", "),
            if zero.len() > 20 { ", ..." } else { "" }
        ));
    }
    Ok(())
}

/// Equivalence, pictures, summary and every report file in `dir`. A shard
/// writes only its rows and a note (the merge does the rest).
pub(super) fn finish(
    runners: &mut [Runner<'_>],
    config: &ExperimentConfig,
    dir: &Path,
    rows: &[ConfigRow],
    completeness: &Completeness,
    warnings: Vec<String>,
    started: Instant,
) -> Result<Summary, ExperimentError> {
    if config.shard.is_some() {
        let mut summary =
            report::summarize(config, rows, (Vec::new(), Vec::new(), Vec::new()), started.elapsed(), warnings);
        summary.adapter.clone_from(&completeness.adapter);
        report::write_shard(dir, config, rows, &summary)?;
        return Ok(summary);
    }
    let lap = Instant::now();
    let equivalence = equivalence(runners, config)?;
    let equivalence_done = Instant::now();
    let pictures = extremes(runners, config, rows)?;
    let runner = runners.first_mut().ok_or_else(|| ExperimentError::Config("no runner".into()))?;
    runner.stages.add(RunStage::Equivalence, equivalence_done - lap);
    runner.stages.lap(RunStage::Pictures, equivalence_done);
    let mut summary = report::summarize(config, rows, equivalence, started.elapsed(), warnings);
    summary.stages = runner.stages().clone();
    summary.missing.clone_from(&completeness.missing);
    summary.adapter.clone_from(&completeness.adapter);
    report::write_all(dir, config, rows, &summary, &pictures, completeness)?;
    Ok(summary)
}

/// Configurations the resolution equivalence uses.
pub(super) fn equivalence_count(config: &ExperimentConfig) -> usize {
    config.equivalence_configs.min(config.configs)
}

/// The resolution-equivalence figures (empty when disabled).
fn equivalence(runners: &mut [Runner<'_>], config: &ExperimentConfig) -> Result<Equivalence, ExperimentError> {
    let count = equivalence_count(config);
    if count == 0 || !config.methods.contains(&MethodSpec::OPTIMIZED) {
        return Ok((Vec::new(), Vec::new(), Vec::new()));
    }
    // One pass over the configurations: each truth is traced once for the
    // whole ladder and both optimized sizes.
    const OPTIMIZED_SIZES: [u32; 2] = [400, 1024];
    // The scene-optimized method with another lookup (e.g. `optimized+spsm`,
    // issue 16) in the run: at the first size only (a 1024² SPSM map costs
    // far more than a standard one on a CPU rasterizer).
    let with_lookups: Vec<MethodSpec> = config
        .methods
        .iter()
        .copied()
        .filter(|&m| {
            m != MethodSpec::OPTIMIZED && m.with_lookup(MethodSpec::OPTIMIZED.lookup()) == MethodSpec::OPTIMIZED
        })
        .collect();
    let runs: Vec<(MethodSpec, u32)> = config
        .equivalence_ladder
        .iter()
        .map(|&size| (MethodSpec::FOCUSED, size))
        .chain(OPTIMIZED_SIZES.iter().map(|&size| (MethodSpec::OPTIMIZED, size)))
        .chain(with_lookups.iter().map(|&m| (m, OPTIMIZED_SIZES[0])))
        .collect();
    // The ladder's maps (up to 4000²) need one layer, not the shared
    // frame's one per method.
    for runner in runners.iter_mut() {
        runner.renderer.release_maps();
    }
    // The configurations spread over the workers, summed in order.
    let indices: Vec<usize> = (0..count).collect();
    let mut per_config = vec![Vec::new(); count];
    workers::for_each(
        runners,
        &indices,
        |r, index| r.misclassified_at(&runs, index),
        |&index, counts| {
            per_config[index] = counts;
            Ok(())
        },
    )?;
    let means = means_in_order(runs.len(), &per_config);
    let (focused, rest) = means.split_at(config.equivalence_ladder.len());
    let (optimized, looked_up) = rest.split_at(OPTIMIZED_SIZES.len());
    let ladder: Vec<(u32, f64)> = config.equivalence_ladder.iter().copied().zip(focused.iter().copied()).collect();
    let result = OPTIMIZED_SIZES
        .iter()
        .zip(optimized)
        .map(|(&size, &mean)| (size, mean, report::crossing(&ladder, mean)))
        .collect();
    let lookups = with_lookups
        .iter()
        .zip(looked_up)
        .map(|(&m, &mean)| (m, OPTIMIZED_SIZES[0], mean, report::crossing(&ladder, mean)))
        .collect();
    Ok((result, ladder, lookups))
}

/// For every method: its best, median and worst configuration re-run, with
/// the errors overlaid.
fn extremes(
    runners: &mut [Runner<'_>],
    config: &ExperimentConfig,
    rows: &[ConfigRow],
) -> Result<Vec<Picture>, ExperimentError> {
    // Every (method, which, configuration) pick first, then one truth per
    // distinct configuration (a ray-cast truth costs more than a render, and
    // methods often share their best or worst configuration).
    let mut picks: Vec<(MethodSpec, &'static str, usize)> = Vec::new();
    for &m in &config.methods {
        let mut by_error: Vec<(u64, usize)> =
            rows.iter().filter(|r| r.method == m).filter_map(|r| Some((r.misclassified?, r.config))).collect();
        if by_error.is_empty() {
            continue;
        }
        by_error.sort_unstable();
        picks.push((m, "best", by_error[0].1));
        picks.push((m, "median", by_error[by_error.len() / 2].1));
        picks.push((m, "worst", by_error[by_error.len() - 1].1));
    }
    let mut configs: Vec<usize> = picks.iter().map(|p| p.2).collect();
    configs.sort_unstable();
    configs.dedup();
    // One truth per configuration, the configurations spread over the workers.
    let picture_of = |runner: &mut Runner<'_>, index: usize| -> Result<Vec<(usize, Picture)>, ExperimentError> {
        let light = light_for(config, runner.scene(), index);
        let (ray, focused) = runner.truths(light)?;
        let Some(truth) = ray.or(focused) else { return Ok(Vec::new()) };
        let nearest = nearest_view_depth(runner.camera(), &truth);
        let mut made = Vec::new();
        for (order, &(m, which, _)) in picks.iter().enumerate().filter(|(_, p)| p.2 == index) {
            let matrices = match runner.solve_method(m, light, config.single_map(), nearest) {
                Ok((matrices, ..)) => matrices,
                Err(ExperimentError::Solver(_)) => continue,
                Err(e) => return Err(e),
            };
            let masks = runner.method_masks_of(m, &matrices)?;
            let misclassified = Counts::compare(&masks, &truth).misclassified();
            let image = error_overlay(&masks, &truth);
            made.push((order, Picture { method: m, which, config: index, misclassified, image }));
        }
        Ok(made)
    };
    let mut made: Vec<(usize, Picture)> = Vec::new();
    workers::for_each(runners, &configs, picture_of, |_, pictures| {
        made.extend(pictures);
        Ok(())
    })?;
    // Back in method order, best, median, worst.
    made.sort_by_key(|(order, _)| *order);
    let pictures: Vec<Picture> = made.into_iter().map(|(_, p)| p).collect();
    Ok(pictures)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(config: usize, method: MethodSpec, counted: u64) -> ConfigRow {
        ConfigRow {
            config,
            method,
            light: [0.0; 3],
            counted: Some(counted),
            misclassified: Some(0),
            false_shadow: Some(0),
            false_lit: Some(0),
            frames: 1,
            truth: None,
            visibility_error: None,
            note: String::new(),
        }
    }

    #[test]
    fn zero_pixel_configurations_warn_and_an_all_zero_run_fails() {
        let mut warnings = Vec::new();
        let some = [row(0, MethodSpec::NORMAL, 0), row(1, MethodSpec::NORMAL, 50), row(2, MethodSpec::NORMAL, 0)];
        check_counted(&some, &mut warnings).unwrap();
        assert_eq!(warnings.len(), 1);
        assert!(warnings[0].starts_with("2 of 3 configurations counted 0 pixels") && warnings[0].ends_with("0, 2"));
        let none = [row(0, MethodSpec::NORMAL, 0), row(0, MethodSpec::FOCUSED, 0), row(1, MethodSpec::NORMAL, 0)];
        let e = check_counted(&none, &mut Vec::new()).unwrap_err();
        assert!(matches!(e, ExperimentError::NothingCounted { configs: 2 }), "{e}");
        assert!(e.to_string().contains("--eye x,y,z and --target x,y,z"));
    }
}
