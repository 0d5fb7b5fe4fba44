//! The experiment's files: `configs.csv` (written as configurations finish,
//! and read back by `--resume`), `summary.csv`, `report.md`, plots and images.

use std::collections::{BTreeMap, BTreeSet};
use std::fmt::Write as _;
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::time::Duration;

use super::{images, ConfigOutcome, ExperimentConfig, ExperimentError, MethodKind, Runner};
use crate::Light;

const CONFIGS_HEADER: &str =
    "config,method,light_x,light_y,light_z,counted,misclassified,false_shadow,false_lit,frames,truth_disagreement,truth_compared,note";

/// One row of `configs.csv`.
#[derive(Clone, Debug, PartialEq)]
pub struct ConfigRow {
    /// Configuration index.
    pub config: usize,
    /// Method.
    pub method: MethodKind,
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
    /// Fallback or error.
    pub note: String,
}

fn io(path: &Path) -> impl FnOnce(std::io::Error) -> ExperimentError + '_ {
    move |source| ExperimentError::Io { path: path.to_path_buf(), source }
}

fn opt(v: Option<u64>) -> String {
    v.map(|v| v.to_string()).unwrap_or_default()
}

impl ConfigRow {
    fn to_csv(&self) -> String {
        let [x, y, z] = self.light;
        let note = self.note.replace([',', '\n', '"'], ";");
        format!(
            "{},{},{x:.6},{y:.6},{z:.6},{},{},{},{},{},{},{},{note}",
            self.config,
            self.method.name(),
            opt(self.counted),
            opt(self.misclassified),
            opt(self.false_shadow),
            opt(self.false_lit),
            self.frames,
            opt(self.truth.map(|t| t.0)),
            opt(self.truth.map(|t| t.1)),
        )
    }

    fn parse(line: &str) -> Option<Self> {
        let f: Vec<&str> = line.splitn(13, ',').collect();
        if f.len() != 13 {
            return None;
        }
        let num = |s: &str| if s.is_empty() { Some(None) } else { s.parse().ok().map(Some) };
        let truth = match (num(f[10])?, num(f[11])?) {
            (Some(a), Some(b)) => Some((a, b)),
            _ => None,
        };
        Some(Self {
            config: f[0].parse().ok()?,
            method: MethodKind::parse(f[1])?,
            light: [f[2].parse().ok()?, f[3].parse().ok()?, f[4].parse().ok()?],
            counted: num(f[5])?,
            misclassified: num(f[6])?,
            false_shadow: num(f[7])?,
            false_lit: num(f[8])?,
            frames: f[9].parse().ok()?,
            truth,
            note: f[12].to_string(),
        })
    }
}

/// Appends rows to `configs.csv` as configurations finish.
pub(super) struct ConfigWriter {
    path: PathBuf,
    rows: Vec<ConfigRow>,
    done: BTreeSet<usize>,
}

fn settings_text(config: &ExperimentConfig) -> String {
    // Everything that changes a configuration's numbers: not the output
    // directory, --resume, or the number of configurations (each light is
    // seeded by its own index, so a run can also be resumed to more of them).
    let mut c = config.clone();
    c.out = PathBuf::new();
    c.resume = false;
    c.configs = 0;
    format!("{c:#?}\n")
}

impl ConfigWriter {
    /// Creates the report directory; with `resume`, keeps the finished
    /// configurations of an earlier run with the same settings.
    pub(super) fn open(config: &ExperimentConfig) -> Result<Self, ExperimentError> {
        std::fs::create_dir_all(&config.out).map_err(io(&config.out))?;
        let path = config.out.join("configs.csv");
        let settings_path = config.out.join("settings.txt");
        let settings = settings_text(config);
        let mut rows = Vec::new();
        if config.resume && path.exists() {
            let previous = std::fs::read_to_string(&settings_path).unwrap_or_default();
            if previous != settings {
                return Err(ExperimentError::Config(format!(
                    "--resume: {} was made with other settings; use the same flags or another --out",
                    config.out.display()
                )));
            }
            let text = std::fs::read_to_string(&path).map_err(io(&path))?;
            rows = text.lines().skip(1).filter_map(ConfigRow::parse).collect();
        }
        // Keep only configurations with a row for every method (an
        // interrupted one is redone).
        let mut per_config: BTreeMap<usize, usize> = BTreeMap::new();
        for r in &rows {
            *per_config.entry(r.config).or_default() += 1;
        }
        let done: BTreeSet<usize> =
            per_config.into_iter().filter(|&(_, n)| n == config.methods.len()).map(|(c, _)| c).collect();
        rows.retain(|r| done.contains(&r.config));
        std::fs::write(&settings_path, settings).map_err(io(&settings_path))?;
        let mut text = format!("{CONFIGS_HEADER}\n");
        for r in &rows {
            text.push_str(&r.to_csv());
            text.push('\n');
        }
        std::fs::write(&path, text).map_err(io(&path))?;
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

    pub(super) fn append(&mut self, index: usize, outcome: &ConfigOutcome) -> Result<(), ExperimentError> {
        let light = match outcome.light {
            Light::Directional { direction } => (-direction).to_array(),
            Light::Point { position } | Light::Spot { position, .. } => position.to_array(),
        };
        let mut file = std::fs::OpenOptions::new().append(true).open(&self.path).map_err(io(&self.path))?;
        for (method, result) in &outcome.results {
            let row = ConfigRow {
                config: index,
                method: *method,
                light,
                counted: result.counts.map(|c| c.counted),
                misclassified: result.counts.map(|c| c.misclassified()),
                false_shadow: result.counts.map(|c| c.false_shadow),
                false_lit: result.counts.map(|c| c.false_lit),
                frames: result.frames,
                truth: outcome.truth_disagreement,
                note: result.note.clone(),
            };
            writeln!(file, "{}", row.to_csv()).map_err(io(&self.path))?;
            self.rows.push(row);
        }
        self.done.insert(index);
        Ok(())
    }
}

/// Per-method statistics.
#[derive(Clone, Debug, PartialEq)]
pub struct MethodSummary {
    /// The method.
    pub method: MethodKind,
    /// Configurations with a count.
    pub configs: usize,
    /// Configurations where the method failed.
    pub failures: usize,
    /// Mean misclassified pixels.
    pub mean: f64,
    /// Total misclassified pixels.
    pub total: u64,
    /// Median misclassified pixels.
    pub median: f64,
    /// `100 (mean / mean_optimized - 1)`; `None` without the optimized method.
    pub percent_more_than_optimized: Option<f64>,
    /// Mean frames to settle (scene-optimized methods).
    pub mean_frames: f64,
}

/// The whole run in numbers.
#[derive(Clone, Debug, PartialEq)]
pub struct Summary {
    /// Per method, in config order.
    pub methods: Vec<MethodSummary>,
    /// For each method's worst 10% of configurations: every method's mean there.
    pub worst: Vec<(MethodKind, Vec<f64>)>,
    /// Share of counted pixels where ray casting and the focused 4000² map agree.
    pub truth_agreement: Option<f64>,
    /// Resolution equivalence: (optimized map size, its mean error, focused size reaching it).
    pub equivalence: Vec<(u32, f64, Option<f64>)>,
    /// The focused ladder measured for the equivalence: (size, mean error).
    pub ladder: Vec<(u32, f64)>,
    /// Wall time of the run.
    pub elapsed: Duration,
    /// The adapter and backend it ran on (e.g. `llvmpipe (...) (vulkan)`).
    pub adapter: String,
}

/// The resolution-equivalence figures (empty when disabled).
pub(super) type Equivalence = (Vec<(u32, f64, Option<f64>)>, Vec<(u32, f64)>);

pub(super) fn equivalence(runner: &mut Runner<'_>, config: &ExperimentConfig) -> Result<Equivalence, ExperimentError> {
    let count = config.equivalence_configs.min(config.configs);
    if count == 0 || !config.methods.contains(&MethodKind::Optimized) {
        return Ok((Vec::new(), Vec::new()));
    }
    let mut ladder = Vec::new();
    for &size in &config.equivalence_ladder {
        ladder.push((size, runner.mean_at_resolution(MethodKind::Focused, size, count)?));
    }
    let mut result = Vec::new();
    for size in [400u32, 1024] {
        let mean = runner.mean_at_resolution(MethodKind::Optimized, size, count)?;
        result.push((size, mean, crossing(&ladder, mean)));
    }
    Ok((result, ladder))
}

/// The focused size whose mean error equals `target`, interpolated in
/// log-log between the ladder's sizes; `None` outside the ladder.
fn crossing(ladder: &[(u32, f64)], target: f64) -> Option<f64> {
    ladder.windows(2).find_map(|w| {
        let ((s0, e0), (s1, e1)) = (w[0], w[1]);
        let (lo, hi) = (e0.min(e1), e0.max(e1));
        if !(target >= lo && target <= hi) || e0 <= 0.0 || e1 <= 0.0 || target <= 0.0 {
            return None;
        }
        if (e1 - e0).abs() < f64::EPSILON {
            return Some(f64::from(s0));
        }
        let t = (target.ln() - e0.ln()) / (e1.ln() - e0.ln());
        Some((f64::from(s0).ln() + t * (f64::from(s1).ln() - f64::from(s0).ln())).exp())
    })
}

pub(super) fn summarize(
    config: &ExperimentConfig,
    rows: &[ConfigRow],
    equivalence: Equivalence,
    elapsed: Duration,
) -> Summary {
    let per_method = |m: MethodKind| -> BTreeMap<usize, u64> {
        rows.iter().filter(|r| r.method == m).filter_map(|r| Some((r.config, r.misclassified?))).collect()
    };
    let mean = |v: &[u64]| if v.is_empty() { f64::NAN } else { v.iter().sum::<u64>() as f64 / v.len() as f64 };
    let optimized_mean = mean(&per_method(MethodKind::Optimized).into_values().collect::<Vec<_>>());
    let methods: Vec<MethodSummary> = config
        .methods
        .iter()
        .map(|&m| {
            let values: Vec<u64> = per_method(m).into_values().collect();
            let mut sorted = values.clone();
            sorted.sort_unstable();
            let median = if sorted.is_empty() { f64::NAN } else { sorted[sorted.len() / 2] as f64 };
            let frames: Vec<u64> = rows.iter().filter(|r| r.method == m).map(|r| r.frames as u64).collect();
            let failures = rows.iter().filter(|r| r.method == m && r.misclassified.is_none()).count();
            MethodSummary {
                method: m,
                configs: values.len(),
                failures,
                mean: mean(&values),
                total: values.iter().sum(),
                median,
                percent_more_than_optimized: config
                    .methods
                    .contains(&MethodKind::Optimized)
                    .then(|| 100.0 * (mean(&values) / optimized_mean - 1.0)),
                mean_frames: mean(&frames),
            }
        })
        .collect();
    // For each method's worst 10% of configurations, every method's mean there.
    let worst = config
        .methods
        .iter()
        .map(|&m| {
            let mut by_error: Vec<(usize, u64)> = per_method(m).into_iter().collect();
            by_error.sort_by_key(|&(c, e)| (std::cmp::Reverse(e), c));
            let k = by_error.len().div_ceil(10);
            let worst_configs: BTreeSet<usize> = by_error.iter().take(k).map(|&(c, _)| c).collect();
            let means = config
                .methods
                .iter()
                .map(|&other| {
                    let v: Vec<u64> = per_method(other)
                        .into_iter()
                        .filter(|(c, _)| worst_configs.contains(c))
                        .map(|(_, e)| e)
                        .collect();
                    mean(&v)
                })
                .collect();
            (m, means)
        })
        .collect();
    let mut seen = BTreeSet::new();
    let (mut disagree, mut compared) = (0u64, 0u64);
    for r in rows {
        if let Some((d, c)) = r.truth {
            if seen.insert(r.config) {
                disagree += d;
                compared += c;
            }
        }
    }
    let truth_agreement = (compared > 0).then(|| 1.0 - disagree as f64 / compared as f64);
    Summary {
        methods,
        worst,
        truth_agreement,
        equivalence: equivalence.0,
        ladder: equivalence.1,
        elapsed,
        adapter: String::new(),
    }
}

fn write(path: &Path, text: &str) -> Result<(), ExperimentError> {
    std::fs::write(path, text).map_err(io(path))
}

pub(super) fn write_all(
    runner: &mut Runner<'_>,
    config: &ExperimentConfig,
    rows: &[ConfigRow],
    summary: &Summary,
) -> Result<(), ExperimentError> {
    let out = &config.out;
    let mut csv = String::from(
        "method,configs,mean_misclassified,total_misclassified,percent_more_than_optimized,median_misclassified,failures,mean_frames\n",
    );
    for m in &summary.methods {
        let _ = writeln!(
            csv,
            "{},{},{:.3},{},{},{:.1},{},{:.2}",
            m.method.name(),
            m.configs,
            m.mean,
            m.total,
            m.percent_more_than_optimized.map(|p| format!("{p:.2}")).unwrap_or_default(),
            m.median,
            m.failures,
            m.mean_frames
        );
    }
    write(&out.join("summary.csv"), &csv)?;
    images::sorted_curves(&out.join("sorted-errors.png"), config, rows)?;
    let pictures = images::extremes(runner, config, rows)?;
    write(&out.join("report.md"), &markdown(config, summary, &pictures))?;
    Ok(())
}

/// `report.md`: the paper's Table 1 layout, then the rest.
#[must_use]
pub fn markdown(config: &ExperimentConfig, summary: &Summary, pictures: &[(MethodKind, String, PathBuf)]) -> String {
    let names: Vec<&str> = config.methods.iter().map(|m| m.name()).collect();
    let mut md = String::new();
    let _ = writeln!(md, "# Misclassified shadow pixels\n");
    let configs = summary.methods.first().map_or(0, |m| m.configs + m.failures);
    let _ = writeln!(
        md,
        "{configs} configurations ({:?} lights on a hemisphere of radius {} scene diagonals, seed {}), {}x{} screen, {}x{} maps, scene {:?}, truth {:?}. Run time {:.1} s.\n",
        config.light,
        config.light_distance,
        config.seed,
        config.screen,
        config.screen,
        config.map,
        config.map,
        config.scene,
        config.truth,
        summary.elapsed.as_secs_f64()
    );
    if !summary.adapter.is_empty() {
        let _ = writeln!(md, "Rendered on {}.\n", summary.adapter);
    }
    let _ = writeln!(
        md,
        "Mean misclassified pixels per configuration (lower is better); rows as in the paper's Table 1.\n"
    );
    let _ = writeln!(md, "| configurations | {} |", names.join(" | "));
    let _ = writeln!(md, "|---|{}", "---:|".repeat(names.len()));
    let cells = |v: &[f64]| v.iter().map(|x| format!("{x:.1}")).collect::<Vec<_>>().join(" | ");
    let all: Vec<f64> = summary.methods.iter().map(|m| m.mean).collect();
    let _ = writeln!(md, "| all | {} |", cells(&all));
    for (m, means) in &summary.worst {
        let _ = writeln!(md, "| worst 10% of {} | {} |", m.name(), cells(means));
    }
    let _ =
        writeln!(md, "\n| method | configs | mean | median | total | % more than optimized | failures | mean frames |");
    let _ = writeln!(md, "|---|---:|---:|---:|---:|---:|---:|---:|");
    for m in &summary.methods {
        let _ = writeln!(
            md,
            "| {} | {} | {:.1} | {:.0} | {} | {} | {} | {:.2} |",
            m.method.name(),
            m.configs,
            m.mean,
            m.median,
            m.total,
            m.percent_more_than_optimized.map(|p| format!("{p:+.1}%")).unwrap_or_else(|| "-".into()),
            m.failures,
            m.mean_frames
        );
    }
    if let Some(a) = summary.truth_agreement {
        let _ = writeln!(md, "\nRay casting and the focused 4000² map agree on {:.3}% of counted pixels.", 100.0 * a);
    }
    if !summary.equivalence.is_empty() {
        let _ = writeln!(md, "\n## Resolution equivalence (first {} configurations)\n", config.equivalence_configs);
        let _ = writeln!(md, "| scene-optimized map | its mean error | focused map with the same mean error |");
        let _ = writeln!(md, "|---:|---:|---:|");
        for (size, mean, eq) in &summary.equivalence {
            let eq = eq.map(|s| format!("{s:.0}²")).unwrap_or_else(|| "outside the ladder".into());
            let _ = writeln!(md, "| {size}² | {mean:.1} | {eq} |");
        }
        let ladder: Vec<String> = summary.ladder.iter().map(|(s, e)| format!("{s}²: {e:.1}")).collect();
        let _ = writeln!(md, "\nFocused ladder: {}.", ladder.join(", "));
    }
    let _ = writeln!(md, "\n## Sorted per-configuration errors\n\n![sorted errors](sorted-errors.png)\n");
    let _ = writeln!(md, "{}\n", images::legend(config));
    if !pictures.is_empty() {
        let _ = writeln!(md, "## Best, median and worst configuration per method\n");
        let _ = writeln!(md, "Grey: correct (light = lit, dark = shadow); red: false shadow; blue: false light.\n");
        for (m, which, path) in pictures {
            let file = path.file_name().map(|f| f.to_string_lossy().into_owned()).unwrap_or_default();
            let _ = writeln!(md, "- {} {which}: ![{file}](images/{file})", m.name());
        }
    }
    md
}
