//! `configs.csv`: one row per configuration and method, appended (and
//! flushed to disk) as each configuration finishes, and read back by
//! `--resume` and `lixel merge`. Rewrites (a resume dropping an unfinished
//! configuration) are atomic.

use std::collections::{BTreeMap, BTreeSet};
use std::io::Write as _;
use std::path::{Path, PathBuf};

use super::identity::Identity;
use super::rundir::{io, write_atomic, RunDir};
use super::{ConfigOutcome, ExperimentConfig, ExperimentError, MethodSpec};
use crate::{Fallback, Light};

pub(super) const CONFIGS_HEADER: &str =
    "config,method,light_x,light_y,light_z,counted,misclassified,false_shadow,false_lit,frames,truth_disagreement,truth_compared,visibility_error_sum,note";

/// One row of `configs.csv`.
#[derive(Clone, Debug, PartialEq)]
pub struct ConfigRow {
    /// Configuration index.
    pub config: usize,
    /// Method.
    pub method: MethodSpec,
    /// Light position (point) or the direction it comes from, reversed (directional).
    pub light: [f64; 3],
    /// Pixels counted; `None` when the method failed.
    pub counted: Option<u64>,
    /// Misclassified pixels.
    pub misclassified: Option<u64>,
    /// Lit in the truth, shadowed by the method.
    pub false_shadow: Option<u64>,
    /// Shadowed in the truth, lit by the method.
    pub false_lit: Option<u64>,
    /// Frames the scene-optimized loop took.
    pub frames: usize,
    /// Pixels where the two truths disagree, and pixels compared (when both ran).
    pub truth: Option<(u64, u64)>,
    /// Summed absolute visibility error over the counted pixels, against the
    /// coverage truth (when it ran; rows written before it existed have none).
    pub visibility_error: Option<f64>,
    /// Fallback (a stable word, see `fallback_note`) or error.
    pub note: String,
}

/// The note of a fallback in `configs.csv`: a stable kebab-case word, with
/// the fallback's number after `=` where it has one.
#[must_use]
pub fn fallback_note(fallback: Fallback) -> String {
    match fallback {
        Fallback::NothingVisible => "nothing-visible".into(),
        Fallback::LightAlongView { sin_gamma } => format!("light-along-view sin_gamma={sin_gamma:.6}"),
        Fallback::PsmHullAroundLight => "psm-hull-around-light".into(),
        Fallback::PlaneOptimalBlended { blend } => format!("plane-optimal-blended blend={blend:.6}"),
        Fallback::PlaneDegenerate => "plane-degenerate".into(),
        Fallback::PlaneNotVisible => "plane-not-visible".into(),
        Fallback::NoUsableSamples => "no-usable-samples".into(),
        Fallback::OrthographicCamera => "orthographic-camera".into(),
    }
}

fn opt(v: Option<u64>) -> String {
    v.map(|v| v.to_string()).unwrap_or_default()
}

impl ConfigRow {
    pub(super) fn to_csv(&self) -> String {
        let [x, y, z] = self.light;
        let note = self.note.replace([',', '\n', '"'], ";");
        format!(
            "{},{},{x:.6},{y:.6},{z:.6},{},{},{},{},{},{},{},{},{note}",
            self.config,
            self.method.name(),
            opt(self.counted),
            opt(self.misclassified),
            opt(self.false_shadow),
            opt(self.false_lit),
            self.frames,
            opt(self.truth.map(|t| t.0)),
            opt(self.truth.map(|t| t.1)),
            // Enough digits that a resumed or merged run sums to the same figure.
            self.visibility_error.map(|v| format!("{v:.6}")).unwrap_or_default(),
        )
    }

    pub(super) fn parse(line: &str) -> Option<Self> {
        // 14 fields; 13 in files from before `visibility_error_sum` (notes never hold a comma).
        let mut f: Vec<&str> = line.splitn(14, ',').collect();
        let visibility = match f.len() {
            14 => f.remove(12),
            13 => "",
            _ => return None,
        };
        let num = |s: &str| if s.is_empty() { Some(None) } else { s.parse().ok().map(Some) };
        let truth = match (num(f[10])?, num(f[11])?) {
            (Some(a), Some(b)) => Some((a, b)),
            _ => None,
        };
        Some(Self {
            config: f[0].parse().ok()?,
            method: MethodSpec::parse(f[1])?,
            light: [f[2].parse().ok()?, f[3].parse().ok()?, f[4].parse().ok()?],
            counted: num(f[5])?,
            misclassified: num(f[6])?,
            false_shadow: num(f[7])?,
            false_lit: num(f[8])?,
            frames: f[9].parse().ok()?,
            truth,
            visibility_error: if visibility.is_empty() { None } else { Some(visibility.parse().ok()?) },
            note: f[12].to_string(),
        })
    }
}

/// The rows of `configs.csv` in `dir` (unparsable lines, such as one cut by
/// a kill, are skipped).
pub(super) fn read_rows(dir: &Path) -> Result<Vec<ConfigRow>, ExperimentError> {
    let path = dir.join("configs.csv");
    let text = std::fs::read_to_string(&path).map_err(io(&path))?;
    Ok(text.lines().skip(1).filter_map(ConfigRow::parse).collect())
}

/// Keeps the configurations with a row for every method (an interrupted
/// one is redone); returns them.
pub(super) fn complete_configs(rows: &mut Vec<ConfigRow>, methods: usize) -> BTreeSet<usize> {
    let mut per_config: BTreeMap<usize, usize> = BTreeMap::new();
    for r in rows.iter() {
        *per_config.entry(r.config).or_default() += 1;
    }
    let done: BTreeSet<usize> = per_config.into_iter().filter(|&(_, n)| n == methods).map(|(c, _)| c).collect();
    rows.retain(|r| done.contains(&r.config));
    done
}

/// `configs.csv`'s full text for `rows`.
pub(super) fn csv_text(rows: &[ConfigRow]) -> String {
    let mut text = format!("{CONFIGS_HEADER}\n");
    for r in rows {
        text.push_str(&r.to_csv());
        text.push('\n');
    }
    text
}

/// Writes `settings.json` (the run's identity) in `dir`.
pub(super) fn write_settings(dir: &Path, identity: &Identity) -> Result<(), ExperimentError> {
    write_atomic(&dir.join("settings.json"), identity.to_json().as_bytes())
}

/// Appends rows to `configs.csv` as configurations finish.
pub(super) struct ConfigWriter {
    path: PathBuf,
    rows: Vec<ConfigRow>,
    done: BTreeSet<usize>,
}

impl ConfigWriter {
    /// Writes `settings.json` and `configs.csv` in the (locked) `dir`; with
    /// `resume`, keeps the finished configurations already there (the
    /// identity was checked by [`RunDir::prepare`]).
    pub(super) fn open(config: &ExperimentConfig, dir: &RunDir, identity: &Identity) -> Result<Self, ExperimentError> {
        let path = dir.path().join("configs.csv");
        let mut rows = if config.resume && path.exists() { read_rows(dir.path())? } else { Vec::new() };
        let done = complete_configs(&mut rows, config.methods.len());
        // Settings first: rows never exist without the identity they were made under.
        write_settings(dir.path(), identity)?;
        write_atomic(&path, csv_text(&rows).as_bytes())?;
        Ok(Self { path, rows, done })
    }

    pub(super) fn done(&self) -> &BTreeSet<usize> {
        &self.done
    }

    /// Every row, sorted by configuration then method order.
    pub(super) fn rows(&mut self) -> &[ConfigRow] {
        self.rows.sort_by_key(|r| (r.config, r.method));
        &self.rows
    }

    /// Appends one configuration's rows and flushes them to disk before
    /// counting it as done.
    pub(super) fn append(&mut self, index: usize, outcome: &ConfigOutcome) -> Result<(), ExperimentError> {
        let light = match outcome.light {
            Light::Directional { direction } => (-direction).to_array(),
            Light::Point { position } | Light::Spot { position, .. } => position.to_array(),
        };
        let new: Vec<ConfigRow> = outcome
            .results
            .iter()
            .map(|(method, result)| ConfigRow {
                config: index,
                method: *method,
                light,
                counted: result.counts.map(|c| c.counted),
                misclassified: result.counts.map(|c| c.misclassified()),
                false_shadow: result.counts.map(|c| c.false_shadow),
                false_lit: result.counts.map(|c| c.false_lit),
                frames: result.frames,
                truth: outcome.truth_disagreement,
                // Rounded as configs.csv stores it, so a summary from these rows
                // equals one from the file (resume, merge) to the last digit.
                visibility_error: result.visibility.map(|v| format!("{:.6}", v.sum).parse().unwrap_or(v.sum)),
                note: result.note.clone(),
            })
            .collect();
        let mut text = String::new();
        for row in &new {
            text.push_str(&row.to_csv());
            text.push('\n');
        }
        let mut file = std::fs::OpenOptions::new().append(true).open(&self.path).map_err(io(&self.path))?;
        // One write per configuration, then fsync: a kill leaves whole
        // configurations, or one cut line that resume drops.
        file.write_all(text.as_bytes()).and_then(|()| file.sync_data()).map_err(io(&self.path))?;
        self.rows.extend(new);
        self.done.insert(index);
        Ok(())
    }
}
