//! The Table 2 harness on a small scene: every pipeline is timed in paired
//! rounds, the scene-optimized pipeline really analyses and optimizes, and the
//! report holds the table, the pooled ratios and the breakdown. (What the
//! ratios are is measured by `lixel experiment --timing`, not asserted.)
#![cfg(feature = "cli")]

#[path = "render_common/mod.rs"]
mod render_common;

use lixel::experiment::{self, ExperimentConfig, Preset, RatioEstimate, TimingOptions};
use lixel::render::ShadowLookup;

#[test]
fn timing_runs_every_pipeline_in_paired_rounds() {
    let Some((device, queue)) = render_common::gpu() else { return };
    let config = ExperimentConfig { screen: 96, ..ExperimentConfig::preset(Preset::Quick) };
    // SPSM and SGSM (issue 17: the timing harness includes it) as lookup pipelines.
    let lookups = vec![ShadowLookup::Spsm(Default::default()), ShadowLookup::Sgsm(Default::default())];
    let options =
        TimingOptions { lights: vec![1, 2], maps: vec![128], frames: 30, lookups, ..TimingOptions::default() };
    let mut seen = 0;
    let rows = experiment::run_timing(&config, &options, &device, &queue, |_| seen += 1).unwrap();
    assert_eq!((rows.len(), seen), (2, 2));
    for row in &rows {
        assert_eq!(row.map, 128);
        assert_eq!(row.rounds, 2, "30 frames are two 15-frame blocks");
        for blocks in &row.blocks {
            assert_eq!(blocks.len(), 2);
            assert!(blocks.iter().all(|d| !d.is_zero()));
        }
        // Ten analysis passes in 30 frames, one optimization per light each
        // (the first readbacks of a cell may still be in flight at its end).
        assert!((9..=10).contains(&row.analyses), "{row:?}");
        assert!(row.optimizations >= row.lights * 8, "{row:?}");
        let stages = &row.stages;
        assert!(stages[0].optimize.is_zero() && !stages[2].optimize.is_zero());
        assert!(stages.iter().all(|s| s.shadow.is_none()), "GPU stages are off by default");
        assert!(row.optimized_ratio() > 0.0 && row.optimized_ratio().is_finite());
        // The lookup pipelines (focused maps, SPSM and SGSM lookups) pair with focused too.
        assert_eq!(row.pipelines()[4..], ["focused + spsm", "focused + sgsm"]);
        assert_eq!((row.blocks.len(), row.stages.len(), row.cpu.len()), (6, 6, 6));
        for lookup in &options.lookups {
            let ratio = row.lookup_ratio(*lookup).unwrap();
            assert!(ratio > 0.0 && ratio.is_finite(), "{row:?}");
        }
        assert_eq!(row.lookup_ratio(ShadowLookup::DepthCompare), None);
        assert!(RatioEstimate::from_ratios(&row.round_ratios(4)).is_some());
        let estimate = RatioEstimate::from_ratios(&row.round_ratios(2)).unwrap();
        assert!(estimate.interval[0] <= estimate.ratio && estimate.ratio <= estimate.interval[1]);
    }
    let md = experiment::timing_markdown(&rows);
    assert_eq!(md.lines().filter(|l| l.starts_with("| 1 | 128²") || l.starts_with("| 2 | 128²")).count(), 2 + 12);
    assert!(md.contains("(focused + spsm) / focused: cells median"));
    assert!(md.contains("| focused + spsm ms |") && md.contains("| spsm / focused, paired rounds (95% CI) |"));
    assert!(md.contains("| focused + sgsm ms |") && md.contains("| sgsm / focused, paired rounds (95% CI) |"));
    assert!(md.contains("(focused + sgsm) / focused: cells median"));
    assert!(md.contains("scene-optimized / focused: cells median"));
    assert!(md.contains("over 4 paired rounds"));
    assert!(!md.contains("GPU shadow"), "no GPU columns without GPU stages");

    // With timestamps (where the device has them) the breakdown gets GPU stages.
    if device.features().contains(wgpu::Features::TIMESTAMP_QUERY) {
        let options = TimingOptions { lights: vec![1], gpu_stages: true, ..options };
        let rows = experiment::run_timing(&config, &options, &device, &queue, |_| {}).unwrap();
        for stage in &rows[0].stages {
            assert!(stage.gpu_frames > 0 && stage.shadow.is_some() && stage.camera.is_some(), "{stage:?}");
        }
        assert!(rows[0].stages[0].analysis.unwrap().is_zero() && !rows[0].stages[2].analysis.unwrap().is_zero());
        assert!(experiment::timing_markdown(&rows).contains("GPU shadow"));
    }
}

#[test]
fn ratio_estimates_are_geometric_means_with_intervals() {
    let e = RatioEstimate::from_ratios(&[1.0, 1.0, 1.0]).unwrap();
    assert_eq!((e.ratio, e.interval, e.pairs), (1.0, [1.0, 1.0], 3));
    let e = RatioEstimate::from_ratios(&[0.5, 2.0]).unwrap();
    assert!((e.ratio - 1.0).abs() < 1e-12);
    // logs ±ln 2: sample sd ln2·√2, half-width 1.96·ln2.
    let half = 1.96 * std::f64::consts::LN_2;
    assert!((e.interval[0] - (-half).exp()).abs() < 1e-12 && (e.interval[1] - half.exp()).abs() < 1e-12);
    assert!(RatioEstimate::from_ratios(&[1.0]).is_none());
    assert!(RatioEstimate::from_ratios(&[1.0, f64::NAN]).is_none());
    assert!(RatioEstimate::from_ratios(&[1.0, 0.0]).is_none());
}
