//! `lixel experiment --stability` on a tiny scene: a still camera flickers
//! for no method (the scene-optimized loop included, once settled), a
//! moving one gives every method a row and writes the report files.
#![cfg(feature = "cli")]

#[path = "render_common/mod.rs"]
mod render_common;

use lixel::experiment::stability::{self, CameraPath};
use lixel::experiment::{ExperimentConfig, MethodSpec, Preset, SceneSource};

fn tiny(out: &std::path::Path) -> ExperimentConfig {
    ExperimentConfig {
        scene: SceneSource::Builtin { triangles: 2_000 },
        screen: 64,
        map: 128,
        max_optimize_frames: 12,
        out: out.to_path_buf(),
        methods: MethodSpec::ALL.to_vec(),
        ..ExperimentConfig::preset(Preset::Quick)
    }
}

#[test]
fn still_camera_has_zero_flicker_and_a_walk_writes_the_report() {
    let Some((device, queue)) = render_common::gpu() else { return };
    let dir = std::env::temp_dir().join(format!("lixel-stability-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let config = tiny(&dir);
    assert!(config.methods.contains(&MethodSpec::FOCUSED_SNAPPED) && config.methods.contains(&MethodSpec::OPTIMIZED));

    let rows = stability::measure(&config, &CameraPath::still(3), &device, &queue, &mut |_, _| {}).unwrap();
    assert_eq!(rows.len(), config.methods.len());
    for r in &rows {
        assert_eq!(r.flicker.len(), 2, "{}", r.method.name());
        assert_eq!(r.mean_flicker(), 0.0, "{} flickers with a still camera", r.method.name());
        assert_eq!(r.mean_shimmer(), 0.0, "{} shimmers with a still camera", r.method.name());
    }

    let path = CameraPath { frames: 3, walk: 0.05, turn_degrees: 10.0 };
    let rows = stability::measure(&config, &path, &device, &queue, &mut |_, _| {}).unwrap();
    // Frames differ: some pixel of some method changes while its truth does not.
    assert!(rows.iter().any(|r| r.mean_flicker() > 0.0), "a walking camera gave no flicker at all");
    stability::write_report(&dir, &config, &path, &rows).unwrap();
    let csv = std::fs::read_to_string(dir.join("stability.csv")).unwrap();
    assert!(csv.starts_with("method,mean_flicker,p95_flicker,mean_misclassified"));
    assert_eq!(csv.lines().count(), 1 + config.methods.len());
    for file in ["stability.md", "stability_tradeoff.svg", "stability_frames.svg"] {
        assert!(dir.join(file).is_file(), "{file} missing");
    }
    let _ = std::fs::remove_dir_all(&dir);
}
