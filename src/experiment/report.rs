//! The experiment's report files from plain data: `summary.csv`,
//! `report.md`, and (through `plots` and `images`) the plots and pictures.
//! Nothing here touches the renderer: `finish` collects what the pictures
//! need first. `configs.csv` is `rows`'s.

use std::collections::{BTreeMap, BTreeSet};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Duration;

use super::finish::{equivalence_count, Completeness};
use super::images::{self, Picture};
use super::rows::{csv_text, ConfigRow};
use super::rundir::write_atomic;
use super::{plots, ExperimentConfig, ExperimentError, MethodSpec, RunStages};

/// Per-method statistics.
#[derive(Clone, Debug, PartialEq)]
pub struct MethodSummary {
    /// The method.
    pub method: MethodSpec,
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
    /// `100 (mean / mean_optimized - 1)`; `None` without the optimized method
    /// or when its mean is zero.
    pub percent_more_than_optimized: Option<f64>,
    /// Mean frames to settle (scene-optimized methods).
    pub mean_frames: f64,
    /// Mean absolute visibility error per counted pixel against the
    /// coverage truth, pooled over the configurations that have it.
    pub mean_visibility_error: Option<f64>,
    /// The antialiased lookup's pair lists (`+aaN` methods; from the
    /// `aa pairs …` notes of `configs.csv`), `None` for other methods.
    pub aa_lists: Option<AaListUse>,
}

/// Pair-list use of an antialiased method over a run's configurations.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct AaListUse {
    /// Most triangle–tile list entries of one frame (all its lights).
    pub peak_pairs: u64,
    /// The configuration of that frame.
    pub peak_config: usize,
    /// Pixels that kept the standard bit because their lists overflowed,
    /// summed over the configurations.
    pub overflow_pixels: u64,
    /// Pixels that kept the standard bit because their footprint was too
    /// wide (or their scan was cut), summed over the configurations.
    pub wide_pixels: u64,
    /// Configurations whose note held the counts.
    pub configs: usize,
}

/// Bytes per list entry (a `u32` triangle index).
pub const AA_PAIR_BYTES: u64 = 4;

/// `(pairs, overflow, wide)` from a note holding
/// `aa pairs P exact E (uncertain U) overflow O wide W` (and, since session
/// 14, ` silhouette T`: the marked silhouette texels).
#[must_use]
pub fn aa_note_counts(note: &str) -> Option<(u64, u64, u64)> {
    let rest = &note[note.find("aa pairs ")? + "aa pairs ".len()..];
    let words: Vec<&str> = rest.split_whitespace().collect();
    let after = |key: &str| -> Option<u64> {
        let i = words.iter().position(|w| *w == key)?;
        words.get(i + 1)?.trim_end_matches([';', ')']).parse().ok()
    };
    Some((words.first()?.parse().ok()?, after("overflow")?, after("wide")?))
}

/// The whole run in numbers.
#[derive(Clone, Debug, PartialEq)]
pub struct Summary {
    /// Per method, in config order.
    pub methods: Vec<MethodSummary>,
    /// For each method's worst 10% of configurations: every method's mean there.
    pub worst: Vec<(MethodSpec, Vec<f64>)>,
    /// Share of counted pixels where ray casting and the focused 4000² map agree.
    pub truth_agreement: Option<f64>,
    /// Resolution equivalence: (optimized map size, its mean error, focused size reaching it).
    pub equivalence: Vec<(u32, f64, Option<f64>)>,
    /// The focused ladder measured for the equivalence: (size, mean error).
    pub ladder: Vec<(u32, f64)>,
    /// The same for the scene-optimized method with another lookup in the
    /// run (e.g. `optimized+spsm`, issue 16): (method, map size, its mean
    /// error, focused size reaching it).
    pub lookup_equivalence: Vec<(MethodSpec, u32, f64, Option<f64>)>,
    /// Wall time of the run.
    pub elapsed: Duration,
    /// Warnings (configurations that counted 0 pixels, accepted setting
    /// differences of a resume); also in `report.md`.
    pub warnings: Vec<String>,
    /// Configurations without rows (a merge with `--allow-missing`).
    pub missing: Vec<usize>,
    /// The adapter and backend it ran on (e.g. `llvmpipe (...) (vulkan)`).
    pub adapter: String,
    /// Wall time per stage of this process's work (zero for a merge).
    pub stages: RunStages,
}

/// The resolution-equivalence figures (empty when disabled).
pub(super) type Equivalence = (Vec<(u32, f64, Option<f64>)>, Vec<(u32, f64)>, Vec<(MethodSpec, u32, f64, Option<f64>)>);

/// The focused size whose mean error equals `target`, interpolated in
/// log-log between the ladder's sizes; `None` outside the ladder.
pub(super) fn crossing(ladder: &[(u32, f64)], target: f64) -> Option<f64> {
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
    warnings: Vec<String>,
) -> Summary {
    let per_method = |m: MethodSpec| -> BTreeMap<usize, u64> {
        rows.iter().filter(|r| r.method == m).filter_map(|r| Some((r.config, r.misclassified?))).collect()
    };
    let mean = |v: &[u64]| if v.is_empty() { f64::NAN } else { v.iter().sum::<u64>() as f64 / v.len() as f64 };
    let optimized_mean = mean(&per_method(MethodSpec::OPTIMIZED).into_values().collect::<Vec<_>>());
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
            let (error, pixels) = rows
                .iter()
                .filter(|r| r.method == m)
                .filter_map(|r| Some((r.visibility_error?, r.counted?)))
                .fold((0.0, 0u64), |(e, n), (re, rn)| (e + re, n + rn));
            MethodSummary {
                method: m,
                configs: values.len(),
                failures,
                mean: mean(&values),
                total: values.iter().sum(),
                median,
                // Undefined (not NaN or infinite) when the optimized method misclassified nothing.
                percent_more_than_optimized: (config.methods.contains(&MethodSpec::OPTIMIZED) && optimized_mean > 0.0)
                    .then(|| 100.0 * (mean(&values) / optimized_mean - 1.0)),
                mean_frames: mean(&frames),
                mean_visibility_error: (pixels > 0).then(|| error / pixels as f64),
                aa_lists: rows
                    .iter()
                    .filter(|r| r.method == m)
                    .filter_map(|r| Some((r.config, aa_note_counts(&r.note)?)))
                    .fold(None, |acc: Option<AaListUse>, (config, (pairs, overflow, wide))| {
                        let mut u = acc.unwrap_or_default();
                        if u.configs == 0 || pairs > u.peak_pairs {
                            (u.peak_pairs, u.peak_config) = (pairs, config);
                        }
                        u.overflow_pixels += overflow;
                        u.wide_pixels += wide;
                        u.configs += 1;
                        Some(u)
                    }),
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
        lookup_equivalence: equivalence.2,
        elapsed,
        warnings,
        missing: Vec::new(),
        adapter: String::new(),
        stages: RunStages::default(),
    }
}

/// `summary.csv`'s text.
fn summary_csv(summary: &Summary) -> String {
    let mut csv = String::from(
        "method,configs,mean_misclassified,total_misclassified,percent_more_than_optimized,median_misclassified,failures,mean_frames,mean_visibility_error\n",
    );
    for m in &summary.methods {
        let _ = writeln!(
            csv,
            "{},{},{:.3},{},{},{:.1},{},{:.2},{}",
            m.method.name(),
            m.configs,
            m.mean,
            m.total,
            m.percent_more_than_optimized.map(|p| format!("{p:.2}")).unwrap_or_default(),
            m.median,
            m.failures,
            m.mean_frames,
            m.mean_visibility_error.map(|v| format!("{v:.5}")).unwrap_or_default()
        );
    }
    csv
}

/// Every file of a finished report in `dir`: `configs.csv` (rewritten in
/// canonical order, so a resumed or merged run matches an uninterrupted
/// one byte for byte), `summary.csv`, the plots, the pictures, `report.md`.
pub(super) fn write_all(
    dir: &Path,
    config: &ExperimentConfig,
    rows: &[ConfigRow],
    summary: &Summary,
    pictures: &[Picture],
    completeness: &Completeness,
) -> Result<(), ExperimentError> {
    write_atomic(&dir.join("configs.csv"), csv_text(rows).as_bytes())?;
    write_atomic(&dir.join("summary.csv"), summary_csv(summary).as_bytes())?;
    plots::sorted_errors(&dir.join("sorted-errors.png"), config, rows)?;
    if !summary.ladder.is_empty() {
        plots::equivalence(&dir.join("equivalence.png"), summary)?;
    }
    let written = images::write_pictures(dir, pictures)?;
    let mut md = markdown(config, summary, &written);
    if !completeness.merged_from.is_empty() {
        let dirs: Vec<String> = completeness.merged_from.iter().map(|d| format!("`{}`", d.display())).collect();
        let _ = writeln!(md, "\nMerged from {} shard directories: {}.", dirs.len(), dirs.join(", "));
    }
    write_atomic(&dir.join("report.md"), md.as_bytes())
}

/// A shard's report: its rows (canonical order) and a `report.md` that says
/// it is one part of a run, with its own partial table.
pub(super) fn write_shard(
    dir: &Path,
    config: &ExperimentConfig,
    rows: &[ConfigRow],
    summary: &Summary,
) -> Result<(), ExperimentError> {
    write_atomic(&dir.join("configs.csv"), csv_text(rows).as_bytes())?;
    let shard = config.shard.map(|s| s.to_string()).unwrap_or_default();
    let mut md = format!(
        "# Shard {shard} of a lixel experiment\n\nThis directory holds only the configurations of shard {shard}. \
         Merge every shard with `lixel merge DIR... --out DIR` for the report; the figures below are this shard's alone.\n\n"
    );
    md.push_str(&markdown(config, summary, &[]));
    write_atomic(&dir.join("report.md"), md.as_bytes())
}

/// The maps of the run: `MxM maps`, or with cascades, at equal total
/// texels, the cascade methods' and the others' sizes.
fn maps_phrase(config: &ExperimentConfig) -> String {
    let (m, s) = (config.map, config.single_map());
    if config.cascades == 0 {
        return format!("{m}x{m} maps");
    }
    format!(
        "{} cascades of {m}x{m} per sun for the cascade methods and one {s}x{s} map for the others (equal total texels)",
        config.cascades
    )
}

/// `report.md`: the paper's Table 1 layout, then the rest.
#[must_use]
pub fn markdown(config: &ExperimentConfig, summary: &Summary, pictures: &[(MethodSpec, String, PathBuf)]) -> String {
    let names: Vec<String> = config.methods.iter().map(|m| m.name()).collect();
    let mut md = String::new();
    let _ = writeln!(md, "# Misclassified shadow pixels\n");
    if !summary.missing.is_empty() {
        let shown: Vec<String> = summary.missing.iter().map(ToString::to_string).collect();
        let _ = writeln!(
            md,
            "**PARTIAL REPORT: {} of {} configurations are missing ({}); every figure below covers only the others.**\n",
            summary.missing.len(),
            config.configs,
            shown.join(", ")
        );
    }
    for w in &summary.warnings {
        let _ = writeln!(md, "Warning: {w}\n");
    }
    let configs = summary.methods.first().map_or(0, |m| m.configs + m.failures);
    let _ = writeln!(
        md,
        "{configs} configurations ({} lights on a hemisphere of radius {} scene diagonals, seed {}), {}x{} screen, {}, scene {}, truth {}. Run time {:.1} s.\n",
        serde_json::to_string(&config.light).unwrap_or_default().trim_matches('"'),
        config.light_distance,
        config.seed,
        config.screen,
        config.screen,
        maps_phrase(config),
        serde_json::to_string(&config.scene).unwrap_or_default(),
        serde_json::to_string(&config.truth).unwrap_or_default().trim_matches('"'),
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
    let _ = writeln!(
        md,
        "\n| method | configs | mean | median | total | % more than optimized | failures | mean frames | mean visibility error |"
    );
    let _ = writeln!(md, "|---|---:|---:|---:|---:|---:|---:|---:|---:|");
    for m in &summary.methods {
        let _ = writeln!(
            md,
            "| {} | {} | {:.1} | {:.0} | {} | {} | {} | {:.2} | {} |",
            m.method.name(),
            m.configs,
            m.mean,
            m.median,
            m.total,
            m.percent_more_than_optimized.map(|p| format!("{p:+.1}%")).unwrap_or_else(|| "-".into()),
            m.failures,
            m.mean_frames,
            m.mean_visibility_error.map(|v| format!("{v:.4}")).unwrap_or_else(|| "-".into())
        );
    }
    if summary.methods.iter().any(|m| m.mean_visibility_error.is_some()) {
        let _ = writeln!(
            md,
            "\nMean visibility error: mean over counted pixels of |method's visibility − true share of the pixel's {} ray-cast sub-samples the light reaches| (a standard lookup's visibility is 0 or 1).",
            config.coverage_samples
        );
    }
    let lists: Vec<(&MethodSummary, AaListUse)> =
        summary.methods.iter().filter_map(|m| Some((m, m.aa_lists?))).collect();
    if !lists.is_empty() {
        let _ = writeln!(
            md,
            "\nPair lists of the antialiased lookups (triangle–tile entries, {AA_PAIR_BYTES} bytes each; a pixel whose lists overflowed keeps the standard bit and is counted):\n"
        );
        let _ = writeln!(md, "| method | configs | peak entries per frame | peak MiB | in configuration | overflow pixels | wide pixels |");
        let _ = writeln!(md, "|---|---:|---:|---:|---:|---:|---:|");
        for (m, u) in lists {
            let _ = writeln!(
                md,
                "| {} | {} | {} | {:.2} | {} | {} | {} |",
                m.method.name(),
                u.configs,
                u.peak_pairs,
                (u.peak_pairs * AA_PAIR_BYTES) as f64 / f64::from(1u32 << 20),
                u.peak_config,
                u.overflow_pixels,
                u.wide_pixels
            );
        }
    }
    if let Some(a) = summary.truth_agreement {
        let _ = writeln!(md, "\nRay casting and the focused 4000² map agree on {:.3}% of counted pixels.", 100.0 * a);
    }
    if !summary.equivalence.is_empty() {
        let _ = writeln!(md, "\n## Resolution equivalence (first {} configurations)\n", equivalence_count(config));
        let _ = writeln!(md, "| scene-optimized map | its mean error | focused map with the same mean error |");
        let _ = writeln!(md, "|---:|---:|---:|");
        for (size, mean, eq) in &summary.equivalence {
            let eq = eq.map(|s| format!("{s:.0}²")).unwrap_or_else(|| "outside the ladder".into());
            let _ = writeln!(md, "| {size}² | {mean:.1} | {eq} |");
        }
        for (method, size, mean, eq) in &summary.lookup_equivalence {
            let eq = eq.map(|s| format!("{s:.0}²")).unwrap_or_else(|| "outside the ladder".into());
            let _ = writeln!(md, "| {size}², {} | {mean:.1} | {eq} |", method.name());
        }
        let ladder: Vec<String> = summary.ladder.iter().map(|(s, e)| format!("{s}²: {e:.1}")).collect();
        let _ = writeln!(md, "\nFocused ladder: {}.", ladder.join(", "));
        let _ = writeln!(md, "\n![resolution equivalence](equivalence.png)");
    }
    let _ = writeln!(md, "\n## Sorted per-configuration errors\n\n![sorted errors](sorted-errors.png)\n");
    let _ = writeln!(
        md,
        "Each line is one method's misclassified pixels per configuration, sorted ascending; the y axis is logarithmic (of 1 + pixels).\n"
    );
    if !pictures.is_empty() {
        let _ = writeln!(md, "## Best, median and worst configuration per method\n");
        let _ = writeln!(md, "Grey: correct (light = lit, dark = shadow); red: false shadow; blue: false light.\n");
        for (m, which, path) in pictures {
            let file = path.file_name().map(|f| f.to_string_lossy().into_owned()).unwrap_or_default();
            let _ = writeln!(md, "- {} {which}: ![{file}](images/{file})", m.name());
        }
    }
    let stages = summary.stages.markdown(summary.elapsed);
    if !stages.is_empty() {
        let _ = writeln!(md, "\n## Where the time went\n");
        let _ = writeln!(md, "Wall time of this process's work per stage (a resumed run counts only what it ran).\n");
        md.push_str(&stages);
    }
    md
}

#[cfg(test)]
mod tests {
    use super::super::Preset;
    use super::*;

    #[test]
    fn the_equivalence_heading_gives_the_configurations_actually_used() {
        let config =
            ExperimentConfig { configs: 6, equivalence_configs: 100_000, ..ExperimentConfig::preset(Preset::Quick) };
        let summary = Summary {
            methods: Vec::new(),
            worst: Vec::new(),
            truth_agreement: None,
            equivalence: vec![(400, 10.0, None)],
            ladder: vec![(256, 20.0)],
            lookup_equivalence: vec![(
                MethodSpec::OPTIMIZED.with_lookup(crate::render::ShadowLookup::Spsm(Default::default())),
                400,
                15.0,
                Some(300.0),
            )],
            elapsed: Duration::ZERO,
            warnings: vec!["a warning".into()],
            missing: vec![3],
            adapter: String::new(),
            stages: RunStages::default(),
        };
        let md = markdown(&config, &summary, &[]);
        assert!(md.contains("Resolution equivalence (first 6 configurations)"), "{md}");
        assert!(md.contains("| 400², optimized+spsm | 15.0 | 300² |"), "{md}");
        assert!(
            md.contains("PARTIAL REPORT: 1 of 6 configurations are missing (3)") && md.contains("Warning: a warning")
        );
        assert!(!md.contains("Pair lists"), "no antialiased method, no pair-list table");
    }

    /// The pair-list table's counts come from the `aa pairs …` notes: the
    /// peak over configurations, overflow and wide pixels summed.
    #[test]
    fn pair_list_use_is_read_from_the_notes() {
        assert_eq!(aa_note_counts("aa pairs 17356 exact 3355 (uncertain 12) overflow 0 wide 6"), Some((17356, 0, 6)));
        assert_eq!(aa_note_counts("fallback; aa pairs 9 exact 1 (uncertain 0) overflow 2 wide 3"), Some((9, 2, 3)));
        assert_eq!(aa_note_counts("aa pairs 9 exact 1 (uncertain 0) overflow 2 wide 3 silhouette 40"), Some((9, 2, 3)));
        assert_eq!(aa_note_counts("fallback"), None);
        assert_eq!(aa_note_counts("aa pairs x exact 1"), None);
        let aa = MethodSpec::parse("focused+aa32").unwrap();
        let row = |config: usize, method: MethodSpec, note: &str| ConfigRow {
            config,
            method,
            light: [0.0; 3],
            counted: Some(10),
            misclassified: Some(1),
            false_shadow: Some(1),
            false_lit: Some(0),
            frames: 1,
            truth: None,
            visibility_error: None,
            note: note.to_owned(),
        };
        let rows = [
            row(0, aa, "aa pairs 100 exact 5 (uncertain 0) overflow 0 wide 1"),
            row(1, aa, "aa pairs 300 exact 5 (uncertain 0) overflow 4 wide 2"),
            row(2, aa, "aa pairs 200 exact 5 (uncertain 0) overflow 0 wide 0"),
            row(0, MethodSpec::FOCUSED, ""),
        ];
        let config =
            ExperimentConfig { methods: vec![MethodSpec::FOCUSED, aa], ..ExperimentConfig::preset(Preset::Quick) };
        let summary = summarize(&config, &rows, (Vec::new(), Vec::new(), Vec::new()), Duration::ZERO, Vec::new());
        assert_eq!(summary.methods[0].aa_lists, None);
        let want = AaListUse { peak_pairs: 300, peak_config: 1, overflow_pixels: 4, wide_pixels: 3, configs: 3 };
        assert_eq!(summary.methods[1].aa_lists, Some(want));
        let md = markdown(&config, &summary, &[]);
        assert!(md.contains("| focused+aa32 | 3 | 300 | 0.00 | 1 | 4 | 3 |"), "{md}");
    }
}
